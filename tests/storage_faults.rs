//! Storage faults (issue 17, docs/reliability.md "Storage faults"), through the real binary: a
//! read-only database (file, or folder and filesystem), a full disk, a database locked by another
//! program for longer than the busy timeout, a damaged checkpoint. Each gives an error that names
//! the file and says which fault it is, loses no committed result, and leaves the file sound
//! (`PRAGMA integrity_check`); once the fault is gone `sweep resume` finishes the sweep.
//!
//! Methods: as root (CI), chmod does not stop writes, so a read-only file is `chattr +i` and a
//! read-only filesystem and a full disk are small tmpfs mounts (`mount -t tmpfs`, remounted
//! read-only or filled); as another user, chmod. Where a method is not available (no chattr on
//! that filesystem, mount not permitted) that case prints why it is skipped, and fails under
//! `CI=true` (CI runs as root, where every method is available).

mod store_inspect;
mod sweep_common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use store_inspect::{Snapshot, StoredJob, integrity, snapshot};
use sweep_common::*;

/// 3 x 4 grid of the tiny wet shaken system, 12 jobs of ~0.1-0.2 s, each result ~80 kB in the
/// database (observables with their time series, and the checkpoint).
fn sweep_file(dir: &Path, name: &str) -> PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    write(
        dir,
        &format!("{name}.toml"),
        &format!(
            "[sweep]\nname = \"{name}\"\nbase = \"tiny.toml\"\nperiods = 40\n\
             [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 4.0, 6.0]\n\
             [[axis]]\nkey = \"e_star\"\nvalues = [0.5, 1.0, 2.0, 4.0]\n"
        ),
    )
}

/// A 3-job sweep at `gammas` (for the read-only cases).
fn small_sweep(dir: &Path, name: &str, gammas: &str) -> PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    write(
        dir,
        &format!("{name}.toml"),
        &format!(
            "[sweep]\nname = \"{name}\"\nbase = \"tiny.toml\"\nperiods = 20\n\
             [[axis]]\nkey = \"gamma\"\nvalues = {gammas}\n"
        ),
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn ok(args: &[&str]) -> String {
    let o = run(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    stderr(&o)
}

fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("Uid:"))
                .and_then(|l| l.split_whitespace().nth(2).map(|u| u == "0"))
        })
        .unwrap_or(false)
}

/// Runs a system command; `Err` with its output when it fails or cannot start.
fn sys(cmd: &str, args: &[&str]) -> Result<(), String> {
    match Command::new(cmd).args(args).output() {
        Ok(o) if o.status.success() => Ok(()),
        Ok(o) => Err(format!(
            "`{cmd} {}` failed: {}",
            args.join(" "),
            String::from_utf8_lossy(&o.stderr).trim()
        )),
        Err(e) => Err(format!("`{cmd}` cannot start: {e}")),
    }
}

/// A tmpfs mounted on a folder for the length of a test (root only).
struct Tmpfs {
    dir: PathBuf,
}

impl Tmpfs {
    fn mount(dir: &Path, size: &str) -> Result<Tmpfs, String> {
        if !is_root() {
            return Err("not root: mount is not permitted".to_string());
        }
        std::fs::create_dir_all(dir).unwrap();
        sys(
            "mount",
            &[
                "-t",
                "tmpfs",
                "-o",
                &format!("size={size}"),
                "tmpfs",
                s(dir),
            ],
        )?;
        Ok(Tmpfs {
            dir: dir.to_path_buf(),
        })
    }

    fn remount(&self, opts: &str) {
        sys("mount", &["-o", &format!("remount,{opts}"), s(&self.dir)]).unwrap();
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        if sys("umount", &[s(&self.dir)]).is_err() {
            let _ = sys("umount", &["-l", s(&self.dir)]);
        }
    }
}

/// A result's observables, simulated time (bits) and events; a checkpoint's time (bits) and state.
type Numbers = (Option<(String, u64, i64)>, Option<(u64, String)>);

/// The numbers of a stored job (its result without the label, and its checkpoint): what a later
/// relabelling along a longer line may not change.
fn numbers(j: &StoredJob) -> Numbers {
    (
        j.result
            .as_ref()
            .map(|r| (r.observables.clone(), r.simulated_time, r.events)),
        j.checkpoint.clone(),
    )
}

/// Every job with a result in `before` has the same numbers in `after`.
fn kept(before: &Snapshot, after: &Snapshot) {
    for (id, j) in before.done() {
        assert_eq!(
            numbers(j),
            numbers(&after.jobs[id]),
            "the result of job {id} changed"
        );
    }
}

/// The job ids of the `] done ` lines of a runner's output (printed after the commit).
fn done_lines(text: &str) -> Vec<String> {
    text.lines()
        .filter(|l| l.contains("] done "))
        .map(|l| {
            let i = l.rfind("(job ").expect("a job id") + 5;
            l[i..i + 12].to_string()
        })
        .collect()
}

fn assert_done_lines_committed(lines: &[String], snap: &Snapshot) {
    let done: Vec<String> = snap.done().keys().map(|id| id[..12].to_string()).collect();
    let mut lines = lines.to_vec();
    lines.sort();
    assert_eq!(lines, done, "the committed jobs are those reported done");
}

/// A read-only command/write on `db`: exit code 1 (not "bad input" or "damaged"), the file
/// named, the fault said.
fn assert_refused(args: &[&str], db: &Path, fault: &str) {
    let o = run(args);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
    assert!(e.contains(s(db)), "{args:?} does not name the file: {e}");
    assert!(e.contains(fault), "{args:?} does not say `{fault}`: {e}");
    assert!(!e.contains("damaged"), "{args:?}: {e}");
}

#[test]
fn a_read_only_database_file_is_refused_by_name_and_keeps_its_results() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("ro.sqlite");
    let first = small_sweep(dir.path(), "first", "[2.0, 4.0, 6.0]");
    let second = small_sweep(dir.path(), "second", "[3.0, 5.0, 7.0]");
    ok(&["sweep", "run", s(&first), "--db", s(&db), "--jobs", "1"]);
    let before = snapshot(&db);
    // Read-only: `chattr +i` as root (chmod does not stop root), chmod 444 otherwise.
    let method = if is_root() {
        if let Err(why) = sys("chattr", &["+i", s(&db)]) {
            skip_unless_ci(
                "read-only file",
                &format!("{why} (no immutable flag on this filesystem)"),
            );
            return;
        }
        "chattr +i"
    } else {
        let mut p = std::fs::metadata(&db).unwrap().permissions();
        p.set_readonly(true);
        std::fs::set_permissions(&db, p).unwrap();
        "chmod 444"
    };
    eprintln!("read-only file by {method}");
    let add = ["sweep", "run", s(&second), "--db", s(&db), "--jobs", "1"];
    let retry = ["sweep", "resume", "--db", s(&db), "--retry-failed"];
    assert_refused(&add, &db, "the database is read-only");
    assert_refused(&retry, &db, "the database is read-only");
    if method == "chattr +i" {
        sys("chattr", &["-i", s(&db)]).unwrap();
    } else {
        let mut p = std::fs::metadata(&db).unwrap().permissions();
        #[allow(clippy::permissions_set_readonly_false)]
        p.set_readonly(false);
        std::fs::set_permissions(&db, p).unwrap();
    }
    assert_eq!(integrity(&db), ["ok"]);
    assert_eq!(snapshot(&db), before, "nothing changed");
    // Writable again: the second sweep runs, the first one's results untouched.
    ok(&add);
    let after = snapshot(&db);
    kept(&before, &after);
    assert_eq!(after.done().len(), 6);
}

#[test]
fn a_database_on_a_read_only_filesystem_is_refused_by_name_and_keeps_its_results() {
    let dir = tempfile::tempdir().unwrap();
    let mnt = dir.path().join("mnt");
    // A read-only filesystem: a tmpfs remounted read-only (root); a read-only folder otherwise.
    let fs = if is_root() {
        match Tmpfs::mount(&mnt, "16m") {
            Ok(t) => Some(t),
            Err(why) => {
                skip_unless_ci("read-only filesystem", &why);
                return;
            }
        }
    } else {
        std::fs::create_dir_all(&mnt).unwrap();
        None
    };
    let db = mnt.join("ro.sqlite");
    let first = small_sweep(dir.path(), "first", "[2.0, 4.0, 6.0]");
    let second = small_sweep(dir.path(), "second", "[3.0, 5.0, 7.0]");
    ok(&["sweep", "run", s(&first), "--db", s(&db), "--jobs", "1"]);
    let before = snapshot(&db);
    // A clean close by the store folds the WAL into the file and removes the -wal and -shm
    // files (the read-only snapshot leaves them), so that SQLite has to create them.
    drop(wetgran::store::Store::open_existing(&db).unwrap());
    for ext in ["sqlite-wal", "sqlite-shm"] {
        assert!(!db.with_extension(ext).exists(), "{ext} left");
    }
    let set_dir_mode = |mode: u32| {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&mnt, std::fs::Permissions::from_mode(mode)).unwrap();
    };
    match &fs {
        Some(t) => t.remount("ro"),
        None => set_dir_mode(0o555),
    }
    eprintln!(
        "read-only filesystem by {}",
        if fs.is_some() {
            "a tmpfs remounted read-only"
        } else {
            "chmod 555 on its folder"
        }
    );
    let add = ["sweep", "run", s(&second), "--db", s(&db), "--jobs", "1"];
    // SQLite cannot create the -shm file, so the integrity check at open fails (code 14):
    // a storage fault, not a damaged file (it was reported as damaged, exit status 2, before).
    let fault = "cannot open the database for writing (a read-only folder or filesystem";
    assert_refused(&add, &db, fault);
    assert_refused(&["sweep", "resume", "--db", s(&db)], &db, fault);
    // The viewing commands read it (read-only opens, immutable where the -wal and -shm files
    // cannot be created: docs/reliability.md, "Reading an archive").
    for view in [
        ["sweep", "status"],
        ["boundaries", "--json"],
        ["export", "--json"],
    ] {
        let mut args = view.to_vec();
        args.extend(["--db", s(&db)]);
        ok(&args);
    }
    match &fs {
        Some(t) => t.remount("rw"),
        None => set_dir_mode(0o755),
    }
    assert_eq!(integrity(&db), ["ok"]);
    assert_eq!(snapshot(&db), before, "nothing changed");
    ok(&add);
    let after = snapshot(&db);
    kept(&before, &after);
    assert_eq!(after.done().len(), 6);
}

#[test]
fn a_full_disk_stops_the_run_by_name_and_loses_no_committed_result() {
    let dir = tempfile::tempdir().unwrap();
    let mnt = dir.path().join("mnt");
    // 1 MiB holds the schema and a few results (each ~80 kB in the WAL and again at a
    // checkpoint of the WAL), not the 12 of the sweep.
    let fs = match Tmpfs::mount(&mnt, "1m") {
        Ok(t) => t,
        Err(why) => {
            skip_unless_ci(
                "full disk",
                &format!("{why} (a small tmpfs is the only way this test fills a disk)"),
            );
            return;
        }
    };
    let file = sweep_file(dir.path(), "full");
    let db = mnt.join("full.sqlite");
    let o = run(&["sweep", "run", s(&file), "--db", s(&db), "--jobs", "1"]);
    let e = both(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains(&format!(
            "{}: database error: the disk holding the database is full",
            s(&db)
        )),
        "{e}"
    );
    let lines = done_lines(&e);
    assert!(
        !lines.is_empty() && lines.len() < 12,
        "the disk fills after some results: {e}"
    );
    assert_eq!(integrity(&db), ["ok"]);
    let before = snapshot(&db);
    assert_done_lines_committed(&lines, &before);
    // Space again: the resume finishes the sweep without recomputing what was committed.
    fs.remount("size=64m");
    ok(&["sweep", "resume", "--db", s(&db), "--jobs", "1"]);
    let after = snapshot(&db);
    assert_eq!(after.done().len(), 12);
    kept(&before, &after);
    // Committed before the fault: run once. The job whose commit failed: run again.
    let store = wetgran::store::Store::open_existing(&db).unwrap();
    for (job, runs) in store.runs_per_job().unwrap() {
        if before.jobs[&job].result.is_some() {
            assert_eq!(runs, 1, "job {job}");
        } else {
            assert!((1..=2).contains(&runs), "job {job}: {runs} runs");
        }
    }
    drop(store);
    // The same numbers as a run on a disk with room.
    let reference = dir.path().join("reference.sqlite");
    ok(&[
        "sweep",
        "run",
        s(&file),
        "--db",
        s(&reference),
        "--jobs",
        "1",
    ]);
    let want = snapshot(&reference);
    for (id, j) in &want.jobs {
        assert_eq!(numbers(j), numbers(&after.jobs[id]), "job {id}");
    }
    eprintln!(
        "full disk (tmpfs of 1 MiB): {} of 12 results committed before the disk filled, all \
         kept; the resume finished 12 of 12 with the numbers of a run with room",
        lines.len()
    );
}

/// Another program's connection holding the write lock (`BEGIN EXCLUSIVE`) until dropped.
struct Holder {
    rt: tokio::runtime::Runtime,
    conn: Option<sqlx::SqliteConnection>,
}

impl Holder {
    fn lock(db: &Path) -> Holder {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap();
        let conn = rt.block_on(async {
            let opts = sqlx::sqlite::SqliteConnectOptions::new()
                .filename(db)
                .busy_timeout(Duration::from_secs(30));
            let mut conn = sqlx::ConnectOptions::connect(&opts).await.unwrap();
            sqlx::query("BEGIN EXCLUSIVE")
                .execute(&mut conn)
                .await
                .unwrap();
            conn
        });
        Holder {
            rt,
            conn: Some(conn),
        }
    }

    fn release(mut self) {
        let mut conn = self.conn.take().unwrap();
        self.rt.block_on(async {
            sqlx::query("ROLLBACK").execute(&mut conn).await.unwrap();
            sqlx::Connection::close(conn).await.unwrap();
        });
    }
}

#[test]
fn a_database_locked_past_the_busy_timeout_stops_the_run_by_name_and_loses_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let file = sweep_file(dir.path(), "locked");
    let db = dir.path().join("locked.sqlite");
    // A busy timeout of 1 s (default 30 s) keeps the test short.
    let (mut child, mut lines) = spawn_merged(
        wetgran()
            .args(["sweep", "run", s(&file), "--db", s(&db), "--jobs", "1"])
            .env(wetgran::store::BUSY_TIMEOUT_VAR, "1"),
    );
    let mut seen = String::new();
    // After the second committed job, another program takes the write lock and keeps it.
    let mut done = 0;
    while done < 2 {
        let line = lines.next().expect("the runner stopped early").unwrap();
        done += usize::from(line.contains("] done "));
        seen += &line;
        seen.push('\n');
    }
    let holder = Holder::lock(&db);
    let t0 = Instant::now();
    for line in lines {
        seen += &line.unwrap();
        seen.push('\n');
    }
    let status = child.wait().unwrap();
    let waited = t0.elapsed();
    assert_eq!(status.code(), Some(1), "{seen}");
    assert!(
        seen.contains(&format!(
            "{}: database error: the database is locked by another program for longer than the \
             busy timeout (1 s;",
            s(&db)
        )),
        "{seen}"
    );
    assert!(waited < Duration::from_secs(60), "{waited:?}");
    holder.release();
    assert_eq!(integrity(&db), ["ok"]);
    let before = snapshot(&db);
    let lines = done_lines(&seen);
    assert!(lines.len() >= 2 && lines.len() < 12, "{seen}");
    assert_done_lines_committed(&lines, &before);
    ok(&["sweep", "resume", "--db", s(&db), "--jobs", "1"]);
    let after = snapshot(&db);
    assert_eq!(after.done().len(), 12);
    kept(&before, &after);
    eprintln!(
        "locked database: the runner stopped {:.1} s after the lock was taken (busy timeout 1 \
         s), {} of 12 results committed before, all kept; the resume finished 12 of 12",
        waited.as_secs_f64(),
        lines.len()
    );
}

#[test]
fn a_damaged_checkpoint_is_reported_and_never_used() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    // A cap of one window: the jobs that drift end unsettled, for `--extend`.
    let file = write(
        dir.path(),
        "cap.toml",
        "[sweep]\nname = \"cap\"\nbase = \"tiny.toml\"\nperiods = 40\n\
         [convergence]\nmax_periods = 40\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 6.0]\n\
         [[axis]]\nkey = \"e_star\"\nlog = { from = 0.5, to = 4.0, steps = 3 }\n",
    );
    let db = dir.path().join("cap.sqlite");
    ok(&["sweep", "run", s(&file), "--db", s(&db), "--jobs", "1"]);
    let store = wetgran::store::Store::open_existing(&db).unwrap();
    let sweep = store.sweep("cap").unwrap();
    let unconverged: Vec<String> = store
        .points(sweep.id)
        .unwrap()
        .into_iter()
        .filter(|p| p.trust() != wetgran_core::observe::Verdict::Stationary)
        .map(|p| p.job_id)
        .collect();
    drop(store);
    assert!(unconverged.len() >= 2, "{unconverged:?}");
    // Cut one checkpoint in half, behind the store's back.
    let victim = unconverged[0].clone();
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let opts = sqlx::sqlite::SqliteConnectOptions::new().filename(&db);
        let mut conn = sqlx::ConnectOptions::connect(&opts).await.unwrap();
        sqlx::query(
            "UPDATE checkpoints SET state = substr(state, 1, length(state) / 2) WHERE job_id = ?1",
        )
        .bind(&victim)
        .execute(&mut conn)
        .await
        .unwrap();
        sqlx::Connection::close(conn).await.unwrap();
    });
    let before = {
        let store = wetgran::store::Store::open_existing(&db).unwrap();
        let s = store.sweep("cap").unwrap();
        store.points(s.id).unwrap()
    };
    let out = run(&[
        "sweep",
        "resume",
        "--db",
        s(&db),
        "--extend",
        "120",
        "--jobs",
        "1",
    ]);
    let log = both(&out);
    // The other extensions are stored; the exit status says that one failed.
    assert_eq!(out.status.code(), Some(4), "{log}");
    assert!(
        log.contains("error: 1 extension(s) failed (the others are stored)"),
        "{log}"
    );
    assert!(
        log.contains(&format!("the checkpoint of job {victim} is not readable")),
        "{log}"
    );
    assert!(
        log.contains(&format!("{} unconverged job(s)", unconverged.len() - 1)),
        "{log}"
    );
    assert!(log.contains("; 1 failed"), "{log}");
    // Its result is the one from before; the others were extended.
    let store = wetgran::store::Store::open_existing(&db).unwrap();
    let s = store.sweep("cap").unwrap();
    for (b, a) in before.iter().zip(store.points(s.id).unwrap()) {
        if a.job_id == victim {
            assert_eq!(a.simulated_time, b.simulated_time);
            assert_eq!(a.observables, b.observables);
        } else if unconverged.contains(&a.job_id) {
            assert!(a.simulated_time > b.simulated_time, "{a:?}");
        }
    }
    assert_eq!(integrity(&db), ["ok"]);
}
