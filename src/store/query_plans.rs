//! Query plans of the store (issue 35): every statement of `sql/`, and every statement of the
//! triggers that keep the claim queue, is planned by SQLite (`EXPLAIN QUERY PLAN`) on a
//! populated database, and a full scan of `jobs`, `results` or `sweep_points` fails the test,
//! except for the few statements listed in [`WHOLE_TABLE`] that read a whole table by design
//! and run once per command, never per job or per result. The claim must walk the queue index
//! `sweep_points_claim` without sorting.
//!
//! The database is not `ANALYZE`d, as a user's never is: the plans are the ones SQLite picks
//! from the schema alone. On the same database every statement must prepare, with as many
//! parameters as its leading comment names (`queries.rs`).

use super::MIGRATOR;
use super::queries::ALL;
use sqlx::sqlite::{SqliteConnectOptions, SqliteConnection};
use sqlx::{AssertSqlSafe, Connection, Executor, Row, SqlSafeStr, Statement};

/// Statements that read a whole table by design, with the reason; each runs once per command.
const WHOLE_TABLE: &[(&str, &str)] = &[
    (
        "all_job_specs",
        "re-keying reads every job once per database",
    ),
    ("runs_per_job", "the audit of every run row"),
    (
        "finished_job_costs",
        "`sweep estimate` reads the cost of every finished job in the database",
    ),
];

/// The tables a full scan of which fails the test.
const GUARDED: &[&str] = &["jobs", "results", "sweep_points"];

/// SQL keywords that may follow a table name where no alias is given.
const NOT_ALIAS: &str = "WHERE JOIN LEFT INNER ON SET GROUP ORDER LIMIT VALUES SELECT AND OR \
                         USING DEFAULT RETURNING WHEN END";

/// The names a statement gives the guarded tables: the table names and their aliases
/// (`FROM jobs j`, `JOIN jobs AS c`).
fn guarded_names(sql: &str) -> Vec<String> {
    let tokens: Vec<&str> = sql
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|t| !t.is_empty())
        .collect();
    let mut names: Vec<String> = GUARDED.iter().map(|t| t.to_string()).collect();
    for (k, t) in tokens.iter().enumerate() {
        if !GUARDED.contains(t) {
            continue;
        }
        let mut next = k + 1;
        if tokens
            .get(next)
            .is_some_and(|n| n.eq_ignore_ascii_case("AS"))
        {
            next += 1;
        }
        if let Some(alias) = tokens.get(next)
            && !NOT_ALIAS
                .split_whitespace()
                .any(|w| w.eq_ignore_ascii_case(alias))
            && !GUARDED.contains(alias)
        {
            names.push(alias.to_string());
        }
    }
    names
}

/// One line of a plan: its detail, and whether it runs once per row of an enclosing query (it
/// sits under a `CORRELATED` subquery).
#[derive(Debug, Clone)]
struct PlanLine {
    detail: String,
    per_row: bool,
}

/// The lines of a statement's plan that make it grow with the tables:
/// - a full scan of a guarded table (`SCAN jobs`, `SCAN p`, `SCAN j USING COVERING INDEX ...`:
///   a walk of every row or every index entry);
/// - a search of `jobs_status` (every job of one status) run once per row of an enclosing query
///   (what made the claim of issue 35 cost O(N^2));
/// - a sort of every matching row (`USE TEMP B-TREE FOR ORDER BY`) where the statement reads a
///   guarded table: an `ORDER BY ... LIMIT` that no index serves.
fn growing(sql: &str, plan: &[PlanLine]) -> Vec<String> {
    let names = guarded_names(sql);
    let reads_guarded = sql
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .any(|t| GUARDED.contains(&t));
    plan.iter()
        .filter_map(|line| {
            let d = &line.detail;
            let scan = d
                .strip_prefix("SCAN ")
                .and_then(|rest| rest.split_whitespace().next())
                .is_some_and(|name| names.iter().any(|n| n == name));
            let status_walk = line.per_row
                && d.starts_with("SEARCH ")
                && (d.contains("USING INDEX jobs_status ")
                    || d.contains("USING COVERING INDEX jobs_status "));
            let sort = reads_guarded && d.starts_with("USE TEMP B-TREE FOR ORDER BY");
            let why = if scan {
                "full scan"
            } else if status_walk {
                "every job of one status, for each row"
            } else if sort {
                "sorts every matching row"
            } else {
                return None;
            };
            Some(format!("{why}: {d}"))
        })
        .collect()
}

/// The plan of one statement. Parameters are left unbound (NULL): the plan does not depend on
/// their values without `ANALYZE` statistics.
async fn plan_of(conn: &mut SqliteConnection, sql: &str) -> Vec<PlanLine> {
    let rows = sqlx::query(AssertSqlSafe(format!("EXPLAIN QUERY PLAN {sql}")))
        .fetch_all(&mut *conn)
        .await
        .unwrap_or_else(|e| panic!("EXPLAIN QUERY PLAN fails on\n{sql}\n{e}"));
    let nodes: Vec<(i64, i64, String)> = rows
        .iter()
        .map(|r| (r.get("id"), r.get("parent"), r.get("detail")))
        .collect();
    let correlated_above = |mut parent: i64| {
        while parent != 0 {
            let Some((_, up, detail)) = nodes.iter().find(|(id, _, _)| *id == parent) else {
                return false;
            };
            if detail.starts_with("CORRELATED") {
                return true;
            }
            parent = *up;
        }
        false
    };
    nodes
        .iter()
        .map(|(_, parent, detail)| PlanLine {
            detail: detail.clone(),
            per_row: correlated_above(*parent),
        })
        .collect()
}

/// A migrated database with two sweeps sharing jobs, continuation chains, results, runs,
/// checkpoints and cluster tasks.
async fn populated(dir: &std::path::Path) -> SqliteConnection {
    let opts = SqliteConnectOptions::new()
        .filename(dir.join("plans.sqlite"))
        .create_if_missing(true)
        .foreign_keys(true);
    let mut conn = SqliteConnection::connect_with(&opts).await.unwrap();
    MIGRATOR.run(&mut conn).await.unwrap();
    let mut script = String::from(
        "INSERT INTO sweeps (id, name, file, source, axes, replicas, created_at, updated_at) \
         VALUES (1, 'a', 'a.toml', '', '[]', 1, 0, 0), (2, 'b', 'b.toml', '', '[]', 1, 0, 0);\n",
    );
    for k in 0..300 {
        // Chains of three: every job but each third one continues from the one before.
        let from = if k % 3 == 0 {
            "NULL".to_string()
        } else {
            format!("'j{}'", k - 1)
        };
        let spec = if k % 3 == 0 {
            "{}".to_string()
        } else {
            format!("{{\"start_from\":\"j{}\"}}", k - 1)
        };
        let status = ["done", "failed", "running", "pending", "pending"][k % 5];
        script += &format!(
            "INSERT INTO jobs (id, spec, status, created_at, start_from) \
             VALUES ('j{k}', '{spec}', '{status}', 0, {from});\n\
             INSERT INTO sweep_points (sweep_id, point, replica, coords, job_id) \
             VALUES (1, {k}, 0, '[{k}]', 'j{k}');\n"
        );
        if k % 2 == 0 {
            script += &format!(
                "INSERT INTO sweep_points (sweep_id, point, replica, coords, job_id) \
                 VALUES (2, {k}, 0, '[{k}]', 'j{k}');\n"
            );
        }
        if status == "done" {
            script += &format!(
                "INSERT INTO results (job_id, phase, observables, simulated_time, wall_seconds, \
                 events, owner, finished_at) VALUES ('j{k}', 'g', '{{}}', 1, 1, 1, 'o', 0);\n\
                 INSERT INTO checkpoints (job_id, time, state, created_at) \
                 VALUES ('j{k}', 1, '{{}}', 0);\n"
            );
        }
        if status != "pending" {
            script +=
                &format!("INSERT INTO runs (job_id, owner, started_at) VALUES ('j{k}', 'o', 0);\n");
        }
    }
    script += "INSERT INTO submissions (id, sweep_id, dir, script, tasks, submitted_at) \
               VALUES (1, 1, 'd', 's', 10, 0);\n";
    for k in 0..10 {
        script += &format!(
            "INSERT INTO submission_tasks (submission_id, task, job_id) VALUES (1, {k}, 'j{k}');\n"
        );
    }
    (&mut conn).execute(AssertSqlSafe(script)).await.unwrap();
    conn
}

/// The statements of every trigger body, with `NEW.x` and `OLD.x` replaced by a literal so
/// that each can be planned on its own: `(trigger, statement)`.
async fn trigger_statements(conn: &mut SqliteConnection) -> Vec<(String, String)> {
    let rows = sqlx::query("SELECT name, sql FROM sqlite_master WHERE type = 'trigger'")
        .fetch_all(&mut *conn)
        .await
        .unwrap();
    let mut out = Vec::new();
    for r in rows {
        let name: String = r.get("name");
        let sql: String = r.get("sql");
        let upper = sql.to_ascii_uppercase();
        let begin = upper.find("\nBEGIN").expect("a trigger body") + "\nBEGIN".len();
        let end = upper.rfind("END").expect("a trigger body");
        let mut body = sql[begin..end].to_string();
        for prefix in ["NEW.", "OLD."] {
            while let Some(at) = body.find(prefix) {
                let tail = &body[at + prefix.len()..];
                let len = tail
                    .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                    .unwrap_or(tail.len());
                body.replace_range(at..at + prefix.len() + len, "'x'");
            }
        }
        for statement in body.split(';').map(str::trim).filter(|s| !s.is_empty()) {
            out.push((name.clone(), statement.to_string()));
        }
    }
    out
}

/// Runs `body` on a fresh database made by [`populated`].
fn on_populated(body: impl AsyncFnOnce(&mut SqliteConnection)) {
    let dir = tempfile::tempdir().unwrap();
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let mut conn = populated(dir.path()).await;
        body(&mut conn).await;
    });
}

#[test]
fn no_query_or_trigger_scans_jobs_results_or_sweep_points() {
    on_populated(async |conn| {
        let mut failures = Vec::new();
        let mut planned = 0;
        for (stem, text) in ALL {
            let statement: String = text
                .lines()
                .filter(|l| !l.starts_with("--"))
                .collect::<Vec<_>>()
                .join("\n");
            let head = statement.trim_start().to_ascii_uppercase();
            if head.starts_with("PRAGMA") || head.starts_with("BEGIN") {
                continue;
            }
            if WHOLE_TABLE.iter().any(|(s, _)| s == stem) {
                continue;
            }
            let plan = plan_of(conn, &statement).await;
            planned += 1;
            for line in growing(&statement, &plan) {
                failures.push(format!("{stem}.sql: {line}\n    plan: {plan:?}"));
            }
        }
        let triggers = trigger_statements(conn).await;
        assert!(
            triggers.len() >= 6,
            "the claim queue's triggers: {triggers:?}"
        );
        for (name, statement) in &triggers {
            let plan = plan_of(conn, statement).await;
            planned += 1;
            for line in growing(statement, &plan) {
                failures.push(format!("trigger {name}: {line}\n    plan: {plan:?}"));
            }
        }
        assert!(planned > 40, "only {planned} statements planned");
        assert!(
            failures.is_empty(),
            "statements that grow with the tables:\n{}",
            failures.join("\n")
        );
    });
}

#[test]
fn the_claim_walks_the_queue_index_without_sorting() {
    on_populated(async |conn| {
        let plan = plan_of(conn, super::queries::NEXT_CLAIMABLE_POINT).await;
        let details: Vec<&str> = plan.iter().map(|l| l.detail.as_str()).collect();
        assert!(
            details
                .iter()
                .any(|l| l.starts_with("SEARCH p USING INDEX sweep_points_claim (sweep_id=?")),
            "{details:?}"
        );
        assert!(
            !details.iter().any(|l| l.contains("TEMP B-TREE")),
            "the claim sorts its candidates: {details:?}"
        );
        let plan = plan_of(conn, super::queries::CLAIM_JOB).await;
        assert!(
            plan.iter()
                .any(|l| l.detail == "SEARCH jobs USING INDEX sqlite_autoindex_jobs_1 (id=?)"),
            "{plan:?}"
        );
    });
}

#[test]
fn the_detector_sees_aliases_covering_scans_status_walks_and_sorts() {
    let sql = "SELECT 1 FROM sweep_points p JOIN jobs AS c ON c.id = p.job_id, results";
    let names = guarded_names(sql);
    for n in ["p", "c", "jobs", "results", "sweep_points"] {
        assert!(names.iter().any(|x| x == n), "{n} in {names:?}");
    }
    let line = |detail: &str, per_row: bool| PlanLine {
        detail: detail.to_string(),
        per_row,
    };
    let plan = vec![
        line("SCAN c", false),
        line("SEARCH p USING INDEX sweep_points_job (job_id=?)", false),
        line("SCAN results USING COVERING INDEX x", false),
        line("SCAN s", false),
        line("SEARCH jobs USING INDEX jobs_status (status=?)", false),
        line("SEARCH c USING INDEX jobs_status (status=?)", true),
        line("USE TEMP B-TREE FOR ORDER BY", true),
    ];
    assert_eq!(
        growing(sql, &plan),
        vec![
            "full scan: SCAN c".to_string(),
            "full scan: SCAN results USING COVERING INDEX x".to_string(),
            "every job of one status, for each row: SEARCH c USING INDEX jobs_status (status=?)"
                .to_string(),
            "sorts every matching row: USE TEMP B-TREE FOR ORDER BY".to_string(),
        ]
    );
}

/// The `?N` named in a query's leading comment lines.
fn documented_parameters(text: &str) -> Vec<usize> {
    let mut out = Vec::new();
    for line in text.lines().take_while(|l| l.starts_with("--")) {
        for part in line.split('?').skip(1) {
            let digits: String = part.chars().take_while(char::is_ascii_digit).collect();
            if let Ok(n) = digits.parse() {
                out.push(n);
            }
        }
    }
    out
}

#[test]
fn every_query_prepares_against_a_migrated_database() {
    on_populated(async |conn| {
        for (stem, text) in ALL {
            let statement = (&mut *conn)
                .prepare(text.into_sql_str())
                .await
                .unwrap_or_else(|e| panic!("{stem}.sql does not prepare: {e}"));
            let count = statement
                .parameters()
                .map_or(0, |p| p.either(|types| types.len(), |n| n));
            let documented = documented_parameters(text);
            let want: Vec<usize> = (1..=count).collect();
            assert_eq!(
                documented, want,
                "{stem}.sql: its comment names parameters {documented:?}, the statement has \
                 {count}"
            );
            assert!(
                text.lines()
                    .any(|l| !l.trim().is_empty() && !l.starts_with("--")),
                "{stem}.sql: no statement"
            );
        }
    });
}
