//! Damaged, foreign and unusual database files, and the books of interrupted runs, through the
//! binary (issue 47, items 4 to 6): a truncated, malformed, newer or log-less file and a path
//! that is not a regular file each get their own message and exit status 2 before anything is
//! written; a command that only reads never migrates a database (`wetgran upgrade` does);
//! Ctrl-C while a large grid registers stores nothing and leaves no large `-wal`; the run rows
//! of a runner that was stopped are closed as `interrupted` by the next writer. Each test is a
//! regression test of a hole the issue found on main `424f846`.

mod paused_child;
mod sweep_common;

use paused_child::{MARKER, child, run_child};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, ExitCode, Output, Stdio};
use std::time::{Duration, Instant};
use sweep_common::*;

fn main() -> ExitCode {
    if let Some(code) = run_child() {
        return code;
    }
    let args = libtest_mimic::Arguments::from_args();
    let trial = |name: &str, f: fn()| {
        libtest_mimic::Trial::test(name, move || {
            f();
            Ok(())
        })
    };
    let trials = vec![
        trial(
            "regression_truncated_and_malformed_databases_are_named_with_exit_status_2",
            regression_truncated_and_malformed_databases_are_named_with_exit_status_2,
        ),
        trial(
            "regression_a_newer_database_is_named_with_exit_status_2",
            regression_a_newer_database_is_named_with_exit_status_2,
        ),
        trial(
            "regression_paths_that_are_not_regular_files_are_refused_before_anything_opens_them",
            regression_paths_that_are_not_regular_files_are_refused_before_anything_opens_them,
        ),
        trial(
            "regression_a_copy_without_its_log_is_named_and_never_turned_into_an_empty_database",
            regression_a_copy_without_its_log_is_named_and_never_turned_into_an_empty_database,
        ),
        trial(
            "regression_viewers_never_migrate_and_upgrade_does",
            regression_viewers_never_migrate_and_upgrade_does,
        ),
        trial(
            "regression_ctrl_c_while_a_grid_registers_stores_nothing_and_leaves_no_large_log",
            regression_ctrl_c_while_a_grid_registers_stores_nothing_and_leaves_no_large_log,
        ),
        trial(
            "regression_run_rows_of_a_stopped_runner_are_closed_as_interrupted_by_the_next_writer",
            regression_run_rows_of_a_stopped_runner_are_closed_as_interrupted_by_the_next_writer,
        ),
    ];
    libtest_mimic::run(&args, trials).exit_code()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A sweep file over `TINY_SCENE` in `dir` with `e_star` taking `n` values and `periods`.
fn sweep_file(dir: &Path, name: &str, n: usize, periods: f64) -> PathBuf {
    write(dir, "scene.toml", TINY_SCENE);
    write(
        dir,
        &format!("{name}.toml"),
        &format!(
            "[sweep]\nname = \"{name}\"\nbase = \"scene.toml\"\nperiods = {periods}\n\
             [[axis]]\nkey = \"e_star\"\nlog = {{ from = 1.0, to = 8.0, steps = {n} }}\n"
        ),
    )
}

/// Four finished jobs in `dir/w.sqlite`.
fn finished(dir: &Path) -> PathBuf {
    let sweep = sweep_file(dir, "tiny", 4, 2.0);
    let db = dir.join("w.sqlite");
    let o = run(&["sweep", "run", s(&sweep), "--db", s(&db), "--jobs", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    db
}

/// One value of plain SQL read behind the store's back.
fn sql_value(db: &Path, query: &'static str) -> String {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let url = format!("sqlite://{}?mode=ro", db.display());
        let pool = sqlx::SqlitePool::connect(&url).await.unwrap();
        let v: Option<String> = sqlx::query_scalar(query).fetch_one(&pool).await.unwrap();
        pool.close().await;
        v.unwrap_or_default()
    })
}

fn sql_exec(db: &Path, statement: &'static str) {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let pool = sqlx::SqlitePool::connect(&format!("sqlite://{}", db.display()))
            .await
            .unwrap();
        sqlx::query(statement).execute(&pool).await.unwrap();
        pool.close().await;
    });
}

/// Runs wetgran, killing it after `limit` (a command that hangs fails the test).
fn run_within(args: &[&str], limit: Duration) -> Output {
    let mut child = wetgran()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > limit {
            child.kill().unwrap();
            panic!("wetgran {args:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// Every command refuses `db` with exit status 2 and a message containing `want`, and leaves
/// its bytes (and the files beside it) as they were; `work` holds the sweep file and outputs.
fn every_command_refuses(db: &Path, work: &Path, want: &str) {
    let dir = work;
    // Never read a named pipe: it would wait for a writer.
    let before = db.is_file().then(|| std::fs::read(db).unwrap());
    let beside: Vec<PathBuf> = ["-wal", "-shm", "-journal"]
        .iter()
        .map(|x| PathBuf::from(format!("{}{x}", db.display())))
        .collect();
    let existed: Vec<bool> = beside.iter().map(|p| p.exists()).collect();
    let sweep = sweep_file(dir, "other", 2, 2.0);
    let plot = dir.join("p.svg");
    for args in [
        vec!["sweep", "status", "--db", s(db)],
        vec!["export", "--db", s(db), "--json"],
        vec!["boundaries", "--db", s(db)],
        vec!["plot", "--db", s(db), "-o", s(&plot)],
        vec!["sweep", "resume", "--db", s(db)],
        vec!["sweep", "run", s(&sweep), "--db", s(db)],
        vec!["reclassify", "--db", s(db)],
        vec!["upgrade", "--db", s(db)],
    ] {
        let o = run_within(&args, Duration::from_secs(60));
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(want), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(&db.display().to_string()),
            "{}",
            stderr(&o)
        );
        if let Some(b) = &before {
            assert_eq!(&std::fs::read(db).unwrap(), b, "{args:?}");
        }
        for (p, e) in beside.iter().zip(&existed) {
            assert_eq!(p.exists(), *e, "{args:?}: {}", p.display());
        }
        assert!(!plot.exists());
    }
}

/// Regression: a truncated database exited 1 with "database error: (code: 11) ... malformed"
/// instead of being named as damaged (exit 2); a malformed schema likewise.
fn regression_truncated_and_malformed_databases_are_named_with_exit_status_2() {
    let dir = tempfile::tempdir().unwrap();
    let db = finished(dir.path());
    let bytes = std::fs::read(&db).unwrap();
    let cut = dir.path().join("cut.sqlite");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    every_command_refuses(&cut, dir.path(), "is cut short");
    // The schema page overwritten (its header kept): SQLite reports it malformed.
    let bad = dir.path().join("bad.sqlite");
    let mut b = bytes.clone();
    for x in &mut b[100..4096] {
        *x = 0xa5;
    }
    std::fs::write(&bad, &b).unwrap();
    every_command_refuses(&bad, dir.path(), "is damaged");
}

/// Regression: a database of a newer wetgran was "database error ... newer" with exit 1.
fn regression_a_newer_database_is_named_with_exit_status_2() {
    let dir = tempfile::tempdir().unwrap();
    let db = finished(dir.path());
    sql_exec(
        &db,
        "INSERT INTO _sqlx_migrations (version, description, success, checksum, \
         execution_time) VALUES (99991231000000, 'future', 1, x'00', 0)",
    );
    every_command_refuses(&db, dir.path(), "written by a newer wetgran");
}

/// Regression: a FIFO as `--db` hung every command; `sweep run --db /dev/null` created
/// `/dev/null-journal`; a folder was a "database error".
fn regression_paths_that_are_not_regular_files_are_refused_before_anything_opens_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fifo = d.join("fifo.sqlite");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    every_command_refuses(&fifo, d, "a named pipe (FIFO)");
    let folder = d.join("folder.sqlite");
    std::fs::create_dir(&folder).unwrap();
    every_command_refuses(&folder, d, "it is a folder");
    let null = Path::new("/dev/null");
    let journal_before = Path::new("/dev/null-journal").exists();
    every_command_refuses(null, d, "a character device");
    assert_eq!(Path::new("/dev/null-journal").exists(), journal_before);
    // A file SQLite keeps beside a good database, replaced by a named pipe.
    let db = finished(d);
    let wal = d.join("w.sqlite-wal");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&wal)
            .status()
            .unwrap()
            .success()
    );
    let o = run_within(
        &["sweep", "status", "--db", s(&db)],
        Duration::from_secs(60),
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&wal.display().to_string()),
        "{}",
        stderr(&o)
    );
}

/// Starts `wetgran args` with a pause point, and waits for its marker on standard error.
fn start_paused(args: &[&str], point: &str, secs: &str) -> Child {
    let mut child = child(Some((point, secs)))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    loop {
        line.clear();
        assert!(err.read_line(&mut line).unwrap() > 0, "no pause at {point}");
        if line.starts_with(MARKER) {
            break;
        }
    }
    // The rest of standard error is drained so that the child never blocks on it.
    std::thread::spawn(move || std::io::copy(&mut err, &mut std::io::sink()));
    child
}

/// Regression: the main file of a database copied without its `-wal` while a run wrote it was
/// called "written by an older wetgran" (read-only), and a viewer migrated it in place into an
/// empty database (writable).
fn regression_a_copy_without_its_log_is_named_and_never_turned_into_an_empty_database() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sweep = sweep_file(d, "tiny", 4, 2.0);
    let db = d.join("w.sqlite");
    // Paused with the first result written, not committed: the schema is still in the log.
    let mut child = start_paused(
        &["sweep", "run", s(&sweep), "--db", s(&db), "--jobs", "1"],
        "checkpoint",
        "30",
    );
    let copy = d.join("copy.sqlite");
    std::fs::copy(&db, &copy).unwrap();
    child.kill().unwrap();
    child.wait().unwrap();
    every_command_refuses(&copy, d, "its write-ahead log");
}

/// Regression: a viewer (`sweep status`, `boundaries`, ...) migrated a database of an older
/// wetgran in place where it could write it. It is refused now with the command that upgrades
/// it, and `wetgran upgrade` does.
fn regression_viewers_never_migrate_and_upgrade_does() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("old.sqlite");
    std::fs::copy(
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/fixtures/store-f2d47fe/wetgran.sqlite"
        ),
        &db,
    )
    .unwrap();
    let bytes = std::fs::read(&db).unwrap();
    let migrations = || sql_value(&db, "SELECT CAST(count(*) AS TEXT) FROM _sqlx_migrations");
    let before = migrations();
    for args in [
        vec!["sweep", "status", "--db", s(&db)],
        vec!["boundaries", "--db", s(&db)],
        vec!["export", "--db", s(&db)],
        vec!["inflection", "--db", s(&db)],
    ] {
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("written by an older wetgran"),
            "{}",
            stderr(&o)
        );
        assert!(stderr(&o).contains(&format!("wetgran upgrade --db {}", db.display())));
        assert_eq!(std::fs::read(&db).unwrap(), bytes, "{args:?}");
    }
    assert_eq!(migrations(), before);
    let o = run(&["upgrade", "--db", s(&db)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o)
            .contains("upgraded (migrations 20261127150000, 20261202000000 not applied before)"),
        "{}",
        stdout(&o)
    );
    assert_ne!(migrations(), before);
    let o = run(&["upgrade", "--db", s(&db)]);
    assert!(stdout(&o).contains("up to date"), "{}", stdout(&o));
    let o = run(&["sweep", "status", "--db", s(&db)]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Regression: Ctrl-C while a large grid registered printed a `sweep resume` hint for a sweep
/// that was never stored and left the rolled-back transaction's pages in a large `-wal`
/// (705 MB at 10^6 points), after an expansion that showed no progress.
fn regression_ctrl_c_while_a_grid_registers_stores_nothing_and_leaves_no_large_log() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sweep = sweep_file(d, "big", 12_000, 2.0);
    let db = d.join("w.sqlite");
    let mut child = child(Some(("register:2", "3")))
        .args(["sweep", "run", s(&sweep), "--db", s(&db), "--jobs", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let (mut text, mut line) = (String::new(), String::new());
    while err.read_line(&mut line).unwrap() > 0 {
        if line.starts_with(MARKER) {
            // 2000 jobs inserted, not committed (the log holds the schema's commits): Ctrl-C.
            assert!(std::fs::metadata(d.join("w.sqlite-wal")).unwrap().len() > 0);
            let kill = std::process::Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .status()
                .unwrap();
            assert!(kill.success());
        }
        text.push_str(&line);
        line.clear();
    }
    assert_eq!(child.wait().unwrap().code(), Some(130), "{text}");
    assert!(
        text.contains("expanding grid points: 12000 of 12000"),
        "{text}"
    );
    assert!(text.contains("nothing of it was stored"), "{text}");
    assert!(!text.contains("sweep resume"), "{text}");
    // The log is checkpointed and truncated, then removed by the clean close: at 10^6 points
    // it held the rolled-back registration's spilled pages (705 MB).
    let wal = std::fs::metadata(d.join("w.sqlite-wal")).map_or(0, |m| m.len());
    assert_eq!(wal, 0, "-wal of {wal} bytes left");
    let o = run(&["sweep", "status", "--db", s(&db)]);
    assert!(stdout(&o).contains("no sweeps yet"), "{}", stdout(&o));
}

/// The outcomes of the `runs` table, `outcome:count` sorted (`open` for none).
fn run_outcomes(db: &Path) -> String {
    sql_value(
        db,
        "SELECT group_concat(o || ':' || n, ' ') FROM (SELECT coalesce(outcome, 'open') AS o, \
         count(*) AS n FROM runs GROUP BY 1 ORDER BY 1)",
    )
}

/// Regression: after SIGINT or SIGKILL the run rows of the jobs that were running stayed open
/// (no outcome) until a resume re-queued those jobs, and a viewer showed them as running
/// attempts. The next writer (here `reclassify`) closes them as `interrupted`; a viewer
/// changes nothing; a resume runs the job again with a new row.
fn regression_run_rows_of_a_stopped_runner_are_closed_as_interrupted_by_the_next_writer() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sweep = sweep_file(d, "tiny", 4, 2.0);
    let db = d.join("w.sqlite");
    for signal in ["-KILL", "-INT"] {
        let _ = std::fs::remove_file(&db);
        // Paused inside the second job's commit: one result stored, one run open.
        let mut child = start_paused(
            &["sweep", "run", s(&sweep), "--db", s(&db), "--jobs", "1"],
            "checkpoint:2",
            "30",
        );
        let kill = std::process::Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
        child.wait().unwrap();
        assert_eq!(run_outcomes(&db), "done:1 open:1", "{signal}");
        let o = run(&["sweep", "status", "--db", s(&db)]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(
            run_outcomes(&db),
            "done:1 open:1",
            "a viewer writes nothing"
        );
        let o = run(&["reclassify", "--db", s(&db)]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(run_outcomes(&db), "done:1 interrupted:1", "{signal}");
        let o = run(&["sweep", "resume", "--db", s(&db), "--jobs", "1"]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(run_outcomes(&db), "done:4 interrupted:1", "{signal}");
    }
}
