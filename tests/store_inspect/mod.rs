//! Reading a wetgran database behind the store's back (plain SQL on its own connection, not the
//! store's queries), for the crash and storage-fault tests: every job's stored result and
//! checkpoint as text, each checked to parse and to agree with its job, and SQLite's full
//! integrity check.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::Path;

/// One job as stored: its status and, when it has them, its result and checkpoint rows
/// (numbers as bits, JSON as the stored text, so that equality is exact).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct StoredJob {
    pub status: String,
    pub result: Option<StoredResult>,
    /// (checkpoint time bits, state JSON).
    pub checkpoint: Option<(u64, String)>,
}

/// A result row without its wall time, owner and finish time (which differ between runs).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct StoredResult {
    pub phase: Option<String>,
    pub decided_on: Option<String>,
    pub observables: String,
    pub simulated_time: u64,
    pub events: i64,
}

/// Every job of the database by id, and the sweep points `(sweep, point, replica, job id)`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Snapshot {
    pub jobs: BTreeMap<String, StoredJob>,
    pub points: Vec<(String, i64, i64, String)>,
}

impl Snapshot {
    /// The jobs that have a result.
    pub(crate) fn done(&self) -> BTreeMap<&String, &StoredJob> {
        self.jobs
            .iter()
            .filter(|(_, j)| j.result.is_some())
            .collect()
    }
}

/// What differs between two stored jobs, field by field (empty when they are equal); long
/// texts are cut.
pub(crate) fn differences(a: &StoredJob, b: &StoredJob) -> String {
    let cut = |s: &str| s.chars().take(160).collect::<String>();
    let mut out = Vec::new();
    if a.status != b.status {
        out.push(format!("status {} vs {}", a.status, b.status));
    }
    match (&a.result, &b.result) {
        (Some(x), Some(y)) => {
            if x.phase != y.phase {
                out.push(format!("phase {:?} vs {:?}", x.phase, y.phase));
            }
            if x.decided_on != y.decided_on {
                out.push(format!(
                    "decided_on {} vs {}",
                    cut(x.decided_on.as_deref().unwrap_or("-")),
                    cut(y.decided_on.as_deref().unwrap_or("-"))
                ));
            }
            if x.observables != y.observables {
                out.push("observables".to_string());
            }
            if x.simulated_time != y.simulated_time {
                out.push(format!(
                    "simulated time {} vs {}",
                    f64::from_bits(x.simulated_time),
                    f64::from_bits(y.simulated_time)
                ));
            }
            if x.events != y.events {
                out.push(format!("events {} vs {}", x.events, y.events));
            }
        }
        (x, y) if x.is_some() != y.is_some() => out.push("one has no result".to_string()),
        _ => {}
    }
    if a.checkpoint != b.checkpoint {
        out.push("checkpoint".to_string());
    }
    out.join("; ")
}

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
}

/// Reads the database read-only and checks every row for consistency: a job is `done` exactly
/// when it has one result row; every result's JSON parses; every checkpoint parses as an engine
/// state whose time is the row's and the result's simulated time. Panics with what is wrong.
pub(crate) fn snapshot(db: &Path) -> Snapshot {
    use sqlx::Row;
    use sqlx::sqlite::SqliteConnectOptions;
    runtime().block_on(async {
        let opts = SqliteConnectOptions::new().filename(db).read_only(true);
        let mut conn = sqlx::ConnectOptions::connect(&opts).await.unwrap();
        let mut jobs = BTreeMap::new();
        for row in sqlx::query("SELECT id, status FROM jobs")
            .fetch_all(&mut conn)
            .await
            .unwrap()
        {
            let id: String = row.get(0);
            let status: String = row.get(1);
            jobs.insert(
                id,
                StoredJob {
                    status,
                    result: None,
                    checkpoint: None,
                },
            );
        }
        for row in sqlx::query(
            "SELECT job_id, phase, decided_on, observables, simulated_time, events FROM results",
        )
        .fetch_all(&mut conn)
        .await
        .unwrap()
        {
            let id: String = row.get(0);
            let r = StoredResult {
                phase: row.get(1),
                decided_on: row.get(2),
                observables: row.get(3),
                simulated_time: row.get::<f64, _>(4).to_bits(),
                events: row.get(5),
            };
            let o: serde_json::Value = serde_json::from_str(&r.observables)
                .unwrap_or_else(|e| panic!("job {id}: observables do not parse: {e}"));
            assert!(o.is_object(), "job {id}: observables {o}");
            if let Some(d) = &r.decided_on {
                serde_json::from_str::<serde_json::Value>(d)
                    .unwrap_or_else(|e| panic!("job {id}: decided_on does not parse: {e}"));
            }
            let job = jobs
                .get_mut(&id)
                .unwrap_or_else(|| panic!("a result of job {id}, which is not in the database"));
            assert!(job.result.is_none(), "job {id} has two results");
            job.result = Some(r);
        }
        for row in sqlx::query("SELECT job_id, time, state FROM checkpoints")
            .fetch_all(&mut conn)
            .await
            .unwrap()
        {
            let id: String = row.get(0);
            let time: f64 = row.get(1);
            let state: String = row.get(2);
            let parsed: wetgran_core::sim::EngineState = serde_json::from_str(&state)
                .unwrap_or_else(|e| panic!("job {id}: the checkpoint does not parse: {e}"));
            assert_eq!(parsed.time.to_bits(), time.to_bits(), "job {id}");
            let job = jobs.get_mut(&id).unwrap_or_else(|| {
                panic!("a checkpoint of job {id}, which is not in the database")
            });
            job.checkpoint = Some((time.to_bits(), state));
        }
        for (id, j) in &jobs {
            assert_eq!(
                j.status == "done",
                j.result.is_some(),
                "job {id}: status {} and {} result",
                j.status,
                if j.result.is_some() { "a" } else { "no" }
            );
            if let (Some(r), Some((t, _))) = (&j.result, &j.checkpoint) {
                assert_eq!(
                    r.simulated_time, *t,
                    "job {id}: the checkpoint is not the result's final state"
                );
            }
        }
        let points = sqlx::query(
            "SELECT s.name, p.point, p.replica, p.job_id FROM sweep_points p \
             JOIN sweeps s ON s.id = p.sweep_id ORDER BY s.name, p.point, p.replica",
        )
        .fetch_all(&mut conn)
        .await
        .unwrap()
        .into_iter()
        .map(|r| (r.get(0), r.get(1), r.get(2), r.get(3)))
        .collect();
        sqlx::Connection::close(conn).await.unwrap();
        Snapshot { jobs, points }
    })
}

/// SQLite's full `PRAGMA integrity_check` on a read-only connection (`["ok"]` for a sound
/// file).
pub(crate) fn integrity(db: &Path) -> Vec<String> {
    runtime().block_on(async {
        let opts = sqlx::sqlite::SqliteConnectOptions::new()
            .filename(db)
            .read_only(true);
        let mut conn = sqlx::ConnectOptions::connect(&opts).await.unwrap();
        let check = sqlx::query_scalar("PRAGMA integrity_check")
            .fetch_all(&mut conn)
            .await
            .unwrap();
        sqlx::Connection::close(conn).await.unwrap();
        check
    })
}
