//! Tests of the claim queue (`sweep_points.claim_rank`, migration `20261127000000_claim_queue`)
//! against the claim query it replaced, used here as the reference: on random databases of
//! continuation chains, jobs shared between two sweeps and points added later (refinement), after
//! every change of a job's state the next claimable row of each sweep must be the row the old
//! query picks (chain heads a pending successor waits for first, then grid order; a continuation
//! job only once its predecessor is done or failed). Also: a database written before the
//! migration gets the columns backfilled when it opens.

use super::queries;
use super::{MIGRATOR, Store};
use rand::{Rng, SeedableRng};
use sqlx::sqlite::{SqliteConnectOptions, SqliteConnection};
use sqlx::{Connection, Executor};

/// Seed of the random databases.
const QUEUE_SEED: u64 = 35;

/// The selection of the claim query before the queue (its `ORDER BY EXISTS (...)` over the spec
/// JSON): the reference the queue is checked against.
const OLD_NEXT: &str = "SELECT j.id FROM sweep_points p JOIN jobs j ON j.id = p.job_id
    WHERE p.sweep_id = ?1 AND j.status = 'pending'
      AND (json_extract(j.spec, '$.start_from') IS NULL
           OR EXISTS (SELECT 1 FROM jobs d
                      WHERE d.id = json_extract(j.spec, '$.start_from')
                        AND d.status IN ('done', 'failed')))
    ORDER BY EXISTS (SELECT 1 FROM jobs c
                     WHERE json_extract(c.spec, '$.start_from') = j.id
                       AND c.status = 'pending') DESC,
             p.point, p.replica
    LIMIT 1";

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
}

async fn connect(path: &std::path::Path) -> SqliteConnection {
    let opts = SqliteConnectOptions::new()
        .filename(path)
        .create_if_missing(true)
        .foreign_keys(true);
    SqliteConnection::connect_with(&opts).await.unwrap()
}

/// The spec JSON of job `k` with its predecessor.
fn spec(k: usize, from: Option<usize>) -> String {
    match from {
        Some(f) => format!("{{\"k\":{k},\"start_from\":\"j{f}\"}}"),
        None => format!("{{\"k\":{k}}}"),
    }
}

async fn add_job(conn: &mut SqliteConnection, k: usize, from: Option<usize>) {
    sqlx::query(queries::UPSERT_JOB)
        .bind(format!("j{k}"))
        .bind(spec(k, from))
        .bind(0.0)
        .bind(from.map(|f| format!("j{f}")))
        .execute(&mut *conn)
        .await
        .unwrap();
}

async fn add_point(conn: &mut SqliteConnection, sweep: i64, point: i64, k: usize) {
    sqlx::query(queries::INSERT_SWEEP_POINT)
        .bind(sweep)
        .bind(point)
        .bind(0)
        .bind("[]")
        .bind(format!("j{k}"))
        .execute(&mut *conn)
        .await
        .unwrap();
}

async fn next_new(conn: &mut SqliteConnection, sweep: i64) -> Option<String> {
    let row: Option<(String, i64, i64, String, String)> =
        sqlx::query_as(queries::NEXT_CLAIMABLE_POINT)
            .bind(sweep)
            .fetch_optional(&mut *conn)
            .await
            .unwrap();
    row.map(|r| r.0)
}

async fn next_old(conn: &mut SqliteConnection, sweep: i64) -> Option<String> {
    sqlx::query_scalar(OLD_NEXT)
        .bind(sweep)
        .fetch_optional(&mut *conn)
        .await
        .unwrap()
}

async fn set_status(conn: &mut SqliteConnection, job: &str, status: &str) {
    sqlx::query("UPDATE jobs SET status = ?2, owner = 'o' WHERE id = ?1")
        .bind(job)
        .bind(status)
        .execute(&mut *conn)
        .await
        .unwrap();
}

#[test]
fn the_queue_picks_what_the_old_claim_query_picked() {
    let dir = tempfile::tempdir().unwrap();
    let rt = runtime();
    rt.block_on(async {
        let mut conn = connect(&dir.path().join("q.sqlite")).await;
        MIGRATOR.run(&mut conn).await.unwrap();
        (&mut conn)
            .execute(
                "INSERT INTO sweeps (id, name, file, source, axes, replicas, created_at, \
                 updated_at) VALUES (1, 'a', 'a', '', '[]', 1, 0, 0), \
                 (2, 'b', 'b', '', '[]', 1, 0, 0)",
            )
            .await
            .unwrap();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(QUEUE_SEED);
        let mut jobs = 0usize;
        let mut next_point = [0i64, 0];
        let (mut checks, mut claims) = (0, 0);
        for round in 0..6 {
            // Register a batch of jobs: chains of 1 to 4 links, inserted in a random order (a
            // successor may come before its predecessor), each chain in sweep 1, 2 or both.
            let mut batch = Vec::new();
            for _ in 0..rng.gen_range(5..12) {
                let len = rng.gen_range(1..5);
                let sweeps: &[i64] = match rng.gen_range(0..3) {
                    0 => &[1],
                    1 => &[2],
                    _ => &[1, 2],
                };
                for link in 0..len {
                    let from = (link > 0).then(|| jobs - 1);
                    batch.push((jobs, from, sweeps));
                    jobs += 1;
                }
            }
            for i in (1..batch.len()).rev() {
                batch.swap(i, rng.gen_range(0..=i));
            }
            for &(k, from, sweeps) in &batch {
                add_job(&mut conn, k, from).await;
                for &s in sweeps {
                    // Later rounds add their points before the grid's (a refinement round's
                    // points are numbered above, but a shared job may sit anywhere).
                    let point = if round % 2 == 0 {
                        next_point[s as usize - 1]
                    } else {
                        -1 - next_point[s as usize - 1]
                    };
                    next_point[s as usize - 1] += 1;
                    add_point(&mut conn, s, point, k).await;
                }
            }
            // Work the queue: claim, finish, fail, requeue, retry, in random turns.
            for _ in 0..60 {
                for s in [1, 2] {
                    assert_eq!(
                        next_new(&mut conn, s).await,
                        next_old(&mut conn, s).await,
                        "sweep {s}, round {round}"
                    );
                    checks += 1;
                }
                let s = rng.gen_range(1..=2);
                match rng.gen_range(0..10) {
                    0..=5 => {
                        if let Some(job) = next_new(&mut conn, s).await {
                            let spec: Option<String> = sqlx::query_scalar(queries::CLAIM_JOB)
                                .bind(&job)
                                .bind("o")
                                .bind(1.0)
                                .fetch_optional(&mut conn)
                                .await
                                .unwrap();
                            assert!(spec.is_some(), "a queued job is pending");
                            claims += 1;
                        }
                    }
                    6..=8 => {
                        let running: Vec<String> =
                            sqlx::query_scalar("SELECT id FROM jobs WHERE status = 'running'")
                                .fetch_all(&mut conn)
                                .await
                                .unwrap();
                        if !running.is_empty() {
                            let job = &running[rng.gen_range(0..running.len())];
                            let to = ["done", "done", "failed", "pending"][rng.gen_range(0..4)];
                            set_status(&mut conn, job, to).await;
                        }
                    }
                    _ => {
                        sqlx::query(queries::RETRY_FAILED_JOBS)
                            .bind(s)
                            .execute(&mut conn)
                            .await
                            .unwrap();
                    }
                }
            }
        }
        assert!(claims > 100, "{claims} claims");
        assert!(checks > 600);
        let stale: i64 = sqlx::query_scalar(
            "SELECT count(*) FROM sweep_points p JOIN jobs j ON j.id = p.job_id \
             WHERE (p.claim_rank IS NOT NULL) != (j.status = 'pending' AND \
             (j.start_from IS NULL OR EXISTS (SELECT 1 FROM jobs d WHERE d.id = j.start_from \
             AND d.status IN ('done', 'failed'))))",
        )
        .fetch_one(&mut conn)
        .await
        .unwrap();
        assert_eq!(stale, 0, "queue rows out of step with their jobs");
    });
}

#[test]
fn a_database_from_before_the_queue_is_backfilled_when_it_opens() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("old.sqlite");
    let rt = runtime();
    rt.block_on(async {
        let mut conn = connect(&db).await;
        // The migrations before the queue, applied as an older wetgran did.
        sqlx::query("PRAGMA application_id = 1464291918")
            .execute(&mut conn)
            .await
            .unwrap();
        MIGRATOR.run_to(20261123150000, &mut conn).await.unwrap();
        (&mut conn)
            .execute(
                "INSERT INTO sweeps (id, name, file, source, axes, replicas, created_at, \
                 updated_at) VALUES (1, 's', 's', '', '[]', 1, 0, 0);
                 INSERT INTO meta (key, value) VALUES ('job_ids', 'spec-without-classify');",
            )
            .await
            .unwrap();
        // A chain j0 -> j1 -> j2 with j0 done, a lone job j3, a chain j4 -> j5 untouched.
        for (k, from, status) in [
            (0, None, "done"),
            (1, Some(0), "pending"),
            (2, Some(1), "pending"),
            (3, None, "pending"),
            (4, None, "pending"),
            (5, Some(4), "pending"),
        ] {
            sqlx::query("INSERT INTO jobs (id, spec, status, created_at) VALUES (?1, ?2, ?3, 0)")
                .bind(format!("j{k}"))
                .bind(spec(k, from))
                .bind(status)
                .execute(&mut conn)
                .await
                .unwrap();
            sqlx::query(
                "INSERT INTO sweep_points (sweep_id, point, replica, coords, job_id) \
                 VALUES (1, ?1, 0, '[]', ?2)",
            )
            .bind(k as i64)
            .bind(format!("j{k}"))
            .execute(&mut conn)
            .await
            .unwrap();
        }
        conn.close().await.unwrap();
    });
    drop(rt);
    // The meta key `job_ids` marks these made-up ids as current: opening migrates, never
    // re-keys.
    let store = Store::open_existing(&db).unwrap();
    let (from, ranks): (Vec<Option<String>>, Vec<Option<i64>>) = store.rt.block_on(async {
        let from = sqlx::query_scalar("SELECT start_from FROM jobs ORDER BY id")
            .fetch_all(&store.pool)
            .await
            .unwrap();
        let ranks = sqlx::query_scalar(
            "SELECT claim_rank FROM sweep_points WHERE sweep_id = 1 ORDER BY point",
        )
        .fetch_all(&store.pool)
        .await
        .unwrap();
        (from, ranks)
    });
    let j = |k: usize| Some(format!("j{k}"));
    assert_eq!(from, vec![None, j(0), j(1), None, None, j(4)]);
    // j1 (its predecessor done, j2 waiting on it) and j4 (j5 waiting) are chain heads; j3 is
    // claimable; j2 and j5 wait.
    assert_eq!(ranks, vec![None, Some(0), None, Some(1), Some(0), None]);
}
