//! Archives and interruptions (issue 33, item 7), with the `wetgran` binary on database files:
//! every viewing command reads a database in a read-only folder and file without writing
//! anything beside it; a missing `--db` folder is named (exit status 2) by every command;
//! `WETGRAN_DB` gives the database (the flag wins); a runner killed with -9 shows as stale with
//! its heartbeat's age; Ctrl-C during `sweep run` says how to resume and exits with 130; `--json`
//! prints JSON on every command that prints a table.

mod sweep_common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use sweep_common::*;

/// A sweep of 2 x 3 jobs of the tiny wet system, `periods` driving periods each.
fn sweep_file(dir: &Path, name: &str, periods: u32) -> PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    write(
        dir,
        &format!("{name}.toml"),
        &format!(
            "[sweep]\nname = \"{name}\"\nbase = \"tiny.toml\"\nreplicas = 1\nperiods = {periods}\n\
             [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0, 4.0]\n\
             [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0]\n"
        ),
    )
}

/// Every file of a folder with its bytes.
fn contents(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().to_string(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

fn set_mode(path: &Path, mode: u32) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).unwrap();
}

/// Runs wetgran and fails with its output unless it exits with `code`.
fn expect(args: &[&str], code: i32) -> std::process::Output {
    let o = run(args);
    assert_eq!(
        o.status.code(),
        Some(code),
        "wetgran {}:\n{}{}",
        args.join(" "),
        stdout(&o),
        stderr(&o)
    );
    o
}

fn json_of(o: &std::process::Output) -> serde_json::Value {
    serde_json::from_str(&stdout(o)).unwrap_or_else(|e| panic!("not JSON ({e}):\n{}", stdout(o)))
}

#[test]
fn viewing_commands_read_a_read_only_archive_and_write_nothing_beside_it() {
    let work = tempfile::tempdir().unwrap();
    let archive = work.path().join("archive");
    std::fs::create_dir(&archive).unwrap();
    let sweep = sweep_file(work.path(), "ro", 2);
    let db = archive.join("w.sqlite");
    let d = db.to_str().unwrap();
    expect(&["sweep", "run", sweep.to_str().unwrap(), "--db", d], 0);
    let export = expect(&["export", "--db", d, "--json"], 0);
    let job = json_of(&export)[0]["job_id"].as_str().unwrap()[..10].to_string();

    // The archive: a read-only file in a read-only folder. Root ignores the bits, so what is
    // checked is that nothing beside the database is created and its bytes do not change.
    set_mode(&db, 0o444);
    set_mode(&archive, 0o555);
    let before = contents(&archive);
    let out = |name: &str| work.path().join(name).display().to_string();
    let (svg, csv) = (out("map.svg"), out("all.csv"));
    let commands: Vec<Vec<&str>> = vec![
        vec!["sweep", "status"],
        vec!["boundaries"],
        vec!["plot", "-o", &svg],
        vec!["export", "-o", &csv],
        vec!["inflection"],
        vec!["show", &job],
    ];
    for c in &commands {
        let mut args = c.clone();
        args.extend(["--db", d]);
        expect(&args, 0);
        if !c.contains(&"-o") {
            args.push("--json");
            json_of(&expect(&args, 0));
        }
    }
    let after = contents(&archive);
    set_mode(&archive, 0o755);
    set_mode(&db, 0o644);
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>(),
        "files appeared or vanished beside the database"
    );
    assert!(before == after, "the archive's bytes changed");
    assert!(std::fs::metadata(&svg).unwrap().len() > 0);
    assert!(std::fs::read_to_string(&csv).unwrap().lines().count() == 7);
    // A writing command on the archive is refused as read-only, not as damaged.
    set_mode(&archive, 0o555);
    set_mode(&db, 0o444);
    let o = run(&["reclassify", "--db", d]);
    set_mode(&archive, 0o755);
    set_mode(&db, 0o644);
    if o.status.success() {
        eprintln!("running as root: the permission bits do not stop a writer");
    } else {
        assert!(stderr(&o).contains("read-only"), "{}", stderr(&o));
    }
}

#[test]
fn every_command_names_a_missing_folder_with_exit_status_2() {
    let work = tempfile::tempdir().unwrap();
    let sweep = sweep_file(work.path(), "nf", 2);
    let s = sweep.to_str().unwrap();
    let db = work.path().join("no/such/folder/w.sqlite");
    let d = db.to_str().unwrap();
    let svg = work.path().join("m.svg").display().to_string();
    let commands: Vec<Vec<&str>> = vec![
        vec!["sweep", "run", s],
        vec!["sweep", "resume"],
        vec!["sweep", "status"],
        vec!["sweep", "refine"],
        vec!["sweep", "collect"],
        vec!["sweep", "submit", s, "--slurm", "--dry-run"],
        vec!["boundaries"],
        vec!["plot", "-o", &svg],
        vec!["export"],
        vec!["inflection"],
        vec!["show", "abcdef"],
        vec!["reclassify"],
    ];
    for c in commands {
        let mut args = c.clone();
        args.extend(["--db", d]);
        let o = expect(&args, 2);
        let err = stderr(&o);
        assert!(
            err.contains("the folder") && err.contains("does not exist"),
            "wetgran {}: {err}",
            args.join(" ")
        );
    }
    assert!(!work.path().join("no").exists());
}

#[test]
fn wetgran_db_gives_the_database_and_the_flag_wins() {
    let work = tempfile::tempdir().unwrap();
    let sweep = sweep_file(work.path(), "env", 2);
    let db = work.path().join("w.sqlite");
    let d = db.to_str().unwrap();
    let o = wetgran()
        .args(["sweep", "run", sweep.to_str().unwrap()])
        .env("WETGRAN_DB", d)
        .current_dir(work.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        db.exists(),
        "sweep run did not take the database from WETGRAN_DB"
    );
    let status = |env: &str, flag: Option<&str>| {
        let mut c = wetgran();
        c.args(["sweep", "status"]).env("WETGRAN_DB", env);
        if let Some(f) = flag {
            c.args(["--db", f]);
        }
        c.current_dir(work.path()).output().unwrap()
    };
    let o = status(d, None);
    assert!(stdout(&o).contains("sweep env"), "{}", stderr(&o));
    let missing = work.path().join("gone/w.sqlite");
    let o = status(missing.to_str().unwrap(), Some(d));
    assert!(o.status.success(), "the flag must win: {}", stderr(&o));
    let o = status(missing.to_str().unwrap(), None);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("does not exist"), "{}", stderr(&o));
    let help = stdout(&run(&["sweep", "status", "--help"]));
    assert!(help.contains("WETGRAN_DB"), "{help}");
}

/// Starts `sweep run` on one worker and returns it once `done` jobs were committed and the
/// next one is running, with the stderr lines read so far.
fn runner_midway(sweep: &Path, db: &Path, done: usize) -> (std::process::Child, String) {
    let (child, mut lines) = spawn_merged(
        wetgran()
            .args(["sweep", "run", sweep.to_str().unwrap(), "--db"])
            .arg(db)
            .args(["--jobs", "1"]),
    );
    let mut seen = String::new();
    let mut n = 0;
    while n < done {
        let line = lines
            .next()
            .unwrap_or_else(|| panic!("the runner stopped early:\n{seen}"))
            .unwrap();
        n += usize::from(line.contains("] done "));
        seen += &line;
        seen.push('\n');
    }
    // The rest of stderr is drained by a thread, so that the runner never blocks on it.
    let rest = std::thread::spawn(move || lines.map_while(Result::ok).collect::<Vec<_>>());
    std::mem::forget(rest);
    (child, seen)
}

#[test]
fn a_runner_killed_with_9_shows_as_stale_with_its_heartbeat_age() {
    let work = tempfile::tempdir().unwrap();
    let sweep = sweep_file(work.path(), "stale", 250);
    let db = work.path().join("w.sqlite");
    let d = db.to_str().unwrap();
    let (mut child, _) = runner_midway(&sweep, &db, 1);
    // Until the next job is claimed.
    let t0 = std::time::Instant::now();
    let running = || {
        json_of(&expect(&["sweep", "status", "--db", d, "--json"], 0))[0]["jobs"]["running"]
            .as_u64()
    };
    while running() != Some(1) {
        assert!(t0.elapsed().as_secs() < 30, "no job claimed");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let text = stdout(&expect(&["sweep", "status", "--db", d], 0));
    assert!(text.contains("0 running, 1 stale"), "{text}");
    assert!(
        text.contains("its process is gone, last heartbeat") && text.contains(" ago"),
        "{text}"
    );
    assert!(
        !text.contains("left on"),
        "no time left while no runner works:\n{text}"
    );
    let v = json_of(&expect(&["sweep", "status", "--db", d, "--json"], 0));
    assert_eq!(v[0]["jobs"]["stale"], 1, "{v}");
    assert_eq!(v[0]["jobs"]["running"], 0, "{v}");
    assert_eq!(v[0]["runner_working"], false, "{v}");
    assert_eq!(v[0]["stale_runners"][0]["process_gone"], true, "{v}");
    assert!(
        v[0]["stale_runners"][0]["heartbeat_age_s"]
            .as_f64()
            .unwrap()
            >= 0.0
    );
}

#[test]
fn ctrl_c_during_a_run_says_how_to_resume_and_exits_with_130() {
    let work = tempfile::tempdir().unwrap();
    let sweep = sweep_file(work.path(), "intr", 250);
    let db = work.path().join("w.sqlite");
    let (mut child, mut lines) = spawn_merged(
        wetgran()
            .args(["sweep", "run", sweep.to_str().unwrap(), "--db"])
            .arg(&db)
            .args(["--jobs", "1"]),
    );
    let mut seen = String::new();
    while !seen.contains("] done ") {
        let line = lines
            .next()
            .unwrap_or_else(|| panic!("the runner stopped early:\n{seen}"))
            .unwrap();
        seen += &line;
        seen.push('\n');
    }
    let pid = child.id().to_string();
    assert!(
        std::process::Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .unwrap()
            .success()
    );
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let status = child.wait().unwrap();
    let err = rest.join("\n");
    assert_eq!(status.code(), Some(130), "{seen}{err}");
    let hint = format!("wetgran sweep resume intr --db {}", db.display());
    assert!(err.contains(&hint), "no `{hint}` in:\n{err}");
    // The printed command continues the sweep to its end.
    let o = expect(
        &["sweep", "resume", "intr", "--db", db.to_str().unwrap()],
        0,
    );
    let v = json_of(&expect(
        &["sweep", "status", "--db", db.to_str().unwrap(), "--json"],
        0,
    ));
    assert_eq!(v[0]["jobs"]["done"], 6, "{v}\n{}", stderr(&o));
}
