//! What a user types as an output, through the binary (issue 47, items 1 to 3): an output that
//! resolves to the database (by its path, a symbolic link or a hard link, or one of its
//! `-wal`/`-shm`/`-journal` files) is refused with exit status 2 naming both paths, and the
//! database keeps its bytes; outputs are whole or absent; `report -o` replaces only a report it
//! wrote, never follows a link and leaves no stale page; text from a database reaches the
//! terminal inert. Each test is a regression test of a hole the issue found on main `424f846`.

mod sweep_common;

use std::path::{Path, PathBuf};
use std::process::Output;
use sweep_common::*;

/// A sweep of 8 real jobs (2 Gamma x 4 E*, two periods each) run into `dir/w.sqlite`.
fn finished_sweep(dir: &Path) -> PathBuf {
    write(dir, "scene.toml", TINY_SCENE);
    let sweep = write(
        dir,
        "s.toml",
        "[sweep]\nname = \"tiny\"\nbase = \"scene.toml\"\nperiods = 2\n\
         description = \"a tiny sweep\"\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0, 4.0, 8.0]\n",
    );
    let db = dir.join("w.sqlite");
    let o = run(&[
        "sweep",
        "run",
        sweep.to_str().unwrap(),
        "--db",
        db.to_str().unwrap(),
        "--jobs",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    db
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs plain SQL on the database behind the store's back (to forge what a shared database
/// may hold).
fn sql(db: &Path, statements: &[&'static str]) {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        use sqlx::Connection as _;
        // One connection, so that a `PRAGMA` holds for the statements after it.
        let url = format!("sqlite://{}", db.display());
        let mut conn = sqlx::SqliteConnection::connect(&url).await.unwrap();
        for st in statements {
            sqlx::query(*st).execute(&mut conn).await.unwrap();
        }
        conn.close().await.unwrap();
    });
}

fn refused(o: &Output, names: &[&Path]) {
    assert_eq!(o.status.code(), Some(2), "{}", stderr(o));
    for n in names {
        assert!(
            stderr(o).contains(&n.display().to_string()),
            "names {}: {}",
            n.display(),
            stderr(o)
        );
    }
}

/// Regression (data loss on main): `plot -o w.sqlite` left an SVG where the results were;
/// `export -o` of the default database left a 0-byte file; `lines --csv` and
/// `export --series` overwrote it too, and links to it were written through.
#[test]
fn regression_an_output_resolving_to_the_database_is_refused_and_the_database_is_kept() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let db = finished_sweep(d);
    let bytes = std::fs::read(&db).unwrap();
    std::os::unix::fs::symlink("w.sqlite", d.join("link.svg")).unwrap();
    std::os::unix::fs::symlink("w.sqlite", d.join("link.csv")).unwrap();
    std::fs::hard_link(&db, d.join("hard.svg")).unwrap();
    std::fs::create_dir(d.join("sub")).unwrap();
    let wal = d.join("w.sqlite-wal");
    let cases: Vec<(Vec<String>, PathBuf)> = vec![
        (vec!["plot".into(), "-o".into(), s(&db).into()], db.clone()),
        (
            vec!["plot".into(), "-o".into(), s(&wal).into()],
            wal.clone(),
        ),
        (
            vec!["plot".into(), "-o".into(), s(&d.join("link.svg")).into()],
            d.join("link.svg"),
        ),
        (
            vec!["plot".into(), "-o".into(), s(&d.join("hard.svg")).into()],
            d.join("hard.svg"),
        ),
        (
            vec![
                "plot".into(),
                "-o".into(),
                s(&d.join("sub/../w.sqlite-shm")).into(),
            ],
            d.join("sub/../w.sqlite-shm"),
        ),
        (
            vec!["lines".into(), "--csv".into(), s(&db).into()],
            db.clone(),
        ),
        (
            vec!["lines".into(), "-o".into(), s(&d.join("link.csv")).into()],
            d.join("link.csv"),
        ),
        (
            vec!["export".into(), "-o".into(), s(&db).into()],
            db.clone(),
        ),
        (
            vec!["export".into(), "--series".into(), s(&db).into()],
            db.clone(),
        ),
        (
            vec![
                "export".into(),
                "--series".into(),
                "/dev/null".into(),
                "--text".into(),
                s(&db).into(),
            ],
            db.clone(),
        ),
        (
            vec!["report".into(), "-o".into(), s(d).into(), "--force".into()],
            d.to_path_buf(),
        ),
    ];
    for (args, out) in &cases {
        let mut all: Vec<&str> = args.iter().map(String::as_str).collect();
        all.extend(["--db", s(&db)]);
        let o = run(&all);
        refused(&o, &[out, &db]);
        assert_eq!(std::fs::read(&db).unwrap(), bytes, "{all:?}");
        assert!(!wal.exists(), "{all:?}: nothing opened the database");
    }
    // `show`: its snapshot and profiles, named by a link.
    let job = stdout(&run(&["export", "--db", s(&db)]))
        .lines()
        .nth(1)
        .and_then(|l| l.split(',').find(|f| f.len() == 64).map(str::to_string))
        .expect("a job id in the export");
    for flag in ["--snapshot", "--profiles"] {
        let o = run(&[
            "show",
            "--db",
            s(&db),
            &job[..12],
            flag,
            s(&d.join("link.svg")),
        ]);
        refused(&o, &[&d.join("link.svg"), &db]);
    }
    // The default database of the working folder (`wetgran.sqlite`).
    std::fs::rename(&db, d.join("wetgran.sqlite")).unwrap();
    let o = wetgran()
        .args(["export", "-o", "wetgran.sqlite"])
        .current_dir(d)
        .env_remove("WETGRAN_DB")
        .output()
        .unwrap();
    refused(&o, &[Path::new("wetgran.sqlite")]);
    assert_eq!(std::fs::read(d.join("wetgran.sqlite")).unwrap(), bytes);
    // An input file is protected as well: `simulate --profiles` over its scene.
    let scene = d.join("scene.toml");
    let before = std::fs::read(&scene).unwrap();
    let o = run(&["simulate", s(&scene), "--profiles", s(&scene)]);
    refused(&o, &[&scene]);
    assert_eq!(std::fs::read(&scene).unwrap(), before);
}

/// Regression: outputs were written in place, so a failure half-way left a cut file (and two
/// flags naming one file wrote into each other).
#[test]
fn regression_outputs_are_whole_or_absent_and_two_flags_may_not_name_one_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let db = finished_sweep(d);
    let (out, series) = (d.join("out.csv"), d.join("series.csv"));
    std::fs::write(&out, "old export\n").unwrap();
    std::fs::write(&series, "old series\n").unwrap();
    let before: Vec<String> = listing(d);
    // The text file is a device that is always full: the export fails at its first flush,
    // after the other two files are written; neither replaces its old version.
    let o = run(&[
        "export",
        "--db",
        s(&db),
        "-o",
        s(&out),
        "--series",
        s(&series),
        "--text",
        "/dev/full",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("/dev/full: cannot write"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "old export\n");
    assert_eq!(std::fs::read_to_string(&series).unwrap(), "old series\n");
    assert_eq!(listing(d), before, "no temporary file is left");
    // Done right, each is replaced whole and keeps its mode.
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o600)).unwrap();
    let o = run(&["export", "--db", s(&db), "-o", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(&out).unwrap();
    assert_eq!(csv.lines().count(), 9, "a header and 8 rows: {csv}");
    assert_eq!(
        std::fs::metadata(&out).unwrap().permissions().mode() & 0o777,
        0o600
    );
    let o = run(&["lines", "--db", s(&db), "-o", s(&out), "--csv", s(&out)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("the same file as -o"), "{}", stderr(&o));
}

/// The names in a folder, sorted, without the database's `-wal` and `-shm` files (a reader
/// leaves them, empty, where the folder can be written).
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| !n.ends_with("-wal") && !n.ends_with("-shm"))
        .collect();
    v.sort();
    v
}

/// Regression: `report -o DIR` wrote into whatever was there: a user's `sweep.toml` replaced, a
/// link inside written through (a file outside overwritten), stale pages of an earlier sweep
/// kept, a partial site after a failure.
#[test]
fn regression_report_replaces_only_its_own_folder_follows_no_link_and_keeps_no_stale_page() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let db = finished_sweep(d);
    let mine = d.join("mine");
    std::fs::create_dir_all(mine.join("points")).unwrap();
    std::fs::write(mine.join("sweep.toml"), "my own").unwrap();
    std::fs::write(d.join("outside.txt"), "secret").unwrap();
    std::os::unix::fs::symlink("../outside.txt", mine.join("lines.csv")).unwrap();
    std::fs::write(mine.join("points/point-999.html"), "stale").unwrap();
    let report = |out: &Path, force: bool| {
        let mut args = vec!["report", "--db", s(&db), "-o", s(out), "--no-snapshots"];
        if force {
            args.push("--force");
        }
        run(&args)
    };
    // A folder it did not write: refused, untouched.
    let o = report(&mine, false);
    refused(&o, &[&mine]);
    assert!(stderr(&o).contains("--force"), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(mine.join("sweep.toml")).unwrap(),
        "my own"
    );
    assert!(mine.join("points/point-999.html").exists());
    // Forced: replaced whole; the link is removed, not written through.
    let o = report(&mine, true);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(d.join("outside.txt")).unwrap(),
        "secret"
    );
    assert!(!mine.join("points/point-999.html").exists());
    assert!(mine.join(".wetgran-report").is_file());
    assert!(
        std::fs::read_to_string(mine.join("sweep.toml"))
            .unwrap()
            .contains("name = \"tiny\"")
    );
    // Its own report is replaced without --force; a page planted since is gone.
    std::fs::write(mine.join("points/point-999.html"), "stale").unwrap();
    let o = report(&mine, false);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!mine.join("points/point-999.html").exists());
    assert_eq!(
        listing(d),
        vec!["mine", "outside.txt", "s.toml", "scene.toml", "w.sqlite"],
        "no temporary folder is left beside it"
    );
    // A link as the target, the working folder: refused even with --force.
    std::os::unix::fs::symlink("mine", d.join("via")).unwrap();
    refused(&report(&d.join("via"), true), &[&d.join("via")]);
    let o = wetgran()
        .args(["report", "--db", s(&db), "-o", ".", "--force"])
        .current_dir(d.join("mine/points"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let o = wetgran()
        .args(["report", "--db", s(&db), "-o", s(&mine), "--force"])
        .current_dir(mine.join("points"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("working folder"), "{}", stderr(&o));
    // A failure half-way (a job id from a shared database that names a path outside the
    // folder) leaves the old report as it was, and nothing beside it.
    let old_index = std::fs::read(mine.join("index.html")).unwrap();
    sql(
        &db,
        &[
            "PRAGMA foreign_keys = OFF",
            "UPDATE results SET job_id = '../../evil' || job_id WHERE rowid = 1",
            "UPDATE sweep_points SET job_id = '../../evil' || job_id WHERE job_id IN \
           (SELECT substr(job_id, 11) FROM results WHERE rowid = 1)",
            "UPDATE jobs SET id = '../../evil' || id WHERE id IN \
           (SELECT substr(job_id, 11) FROM results WHERE rowid = 1)",
        ],
    );
    let o = run(&["report", "--db", s(&db), "-o", s(&mine)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("not a plain path inside the folder"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(mine.join("index.html")).unwrap(), old_index);
    assert!(!d.join("evil").exists() && !dir.path().parent().unwrap().join("evil").exists());
    assert_eq!(
        listing(d),
        vec![
            "mine",
            "outside.txt",
            "s.toml",
            "scene.toml",
            "via",
            "w.sqlite"
        ]
    );
}

/// Regression: `sweep status` printed a shared database's description, cost note and file raw:
/// escape sequences cleared the screen and retitled the terminal, U+202E reversed the text.
#[test]
fn regression_text_from_a_database_reaches_the_terminal_inert() {
    let dir = tempfile::tempdir().unwrap();
    let db = finished_sweep(dir.path());
    sql(
        &db,
        &[
            "UPDATE sweeps SET description = 'evil' || char(27) || ']0;pwned' || char(7) || \
           char(27) || '[2J' || char(8238) || 'txet' || char(0) || 'end', \
           cost = 'c' || char(27) || '[31mred' || char(155) || 'x', \
           file = 'f' || char(10) || 'error: forged line', \
           name = 'tiny' || char(27) || '[1m'",
            "UPDATE jobs SET status = 'failed', last_error = 'x' || char(27) || '[2J' || char(10) \
           || 'forged' WHERE rowid = 1",
        ],
    );
    let status = run(&["sweep", "status", "--db", s(&db)]);
    assert!(status.status.success(), "{}", stderr(&status));
    let text = stdout(&status);
    let job = stdout(&run(&["export", "--db", s(&db), "--all"]))
        .lines()
        .nth(1)
        .and_then(|l| l.split(',').find(|f| f.len() == 64).map(str::to_string))
        .unwrap();
    let show = run(&["show", "--db", s(&db), &job[..12]]);
    let boundaries = run(&["boundaries", "--db", s(&db)]);
    let missing = run(&[
        "plot",
        "--db",
        s(&db),
        "--sweep",
        "nope\u{1b}[2J",
        "-o",
        s(&dir.path().join("m.svg")),
    ]);
    for (what, out) in [
        ("status", text.clone()),
        ("show", stdout(&show)),
        ("boundaries", stdout(&boundaries)),
        ("plot (error)", stderr(&missing)),
    ] {
        let bad: Vec<char> = out
            .chars()
            .filter(|c| wetgran::terminal::is_unsafe(*c) && *c != '\n')
            .collect();
        assert!(bad.is_empty(), "{what}: raw {bad:?} in\n{out}");
    }
    assert!(
        text.contains("evil\\u{1b}]0;pwned\\u{7}\\u{1b}[2J\\u{202e}txet\\u{0}end"),
        "{text}"
    );
    assert!(text.contains("(f\\nerror: forged line;"), "{text}");
    assert!(
        !text.lines().any(|l| l.starts_with("error: forged")),
        "{text}"
    );
    assert!(
        !stdout(&show).lines().any(|l| l.starts_with("forged")),
        "{}",
        stdout(&show)
    );
    // JSON stays exact (serde_json escapes the control characters itself).
    let json = stdout(&run(&["sweep", "status", "--db", s(&db), "--json"]));
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(
        v[0]["description"].as_str().unwrap(),
        "evil\u{1b}]0;pwned\u{7}\u{1b}[2J\u{202e}txet\u{0}end"
    );
}
