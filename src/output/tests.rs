//! The promises of `output` on real files: protected files refused by path, symbolic link and
//! hard link; outputs whole or absent; report folders replaced only where they are reports.

use super::folder::{MARKER, SiteFolder};
use super::*;
use std::os::unix::fs::PermissionsExt;

/// A folder with a stand-in database `w.sqlite` (the SQLite header and some bytes).
fn with_database() -> (tempfile::TempDir, PathBuf, Vec<u8>) {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("w.sqlite");
    let mut bytes = SQLITE_MAGIC.to_vec();
    bytes.extend(std::iter::repeat_n(7u8, 4096));
    std::fs::write(&db, &bytes).unwrap();
    (dir, db, bytes)
}

/// The names in a folder, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    v.sort();
    v
}

fn refused(r: Result<(), OutputError>) -> String {
    match r {
        Err(OutputError::Refused(m)) => m,
        other => panic!("not refused: {other:?}"),
    }
}

#[test]
fn an_output_resolving_to_the_database_or_its_companions_is_refused_and_nothing_changes() {
    let (dir, db, bytes) = with_database();
    let d = dir.path();
    std::os::unix::fs::symlink("w.sqlite", d.join("link.svg")).unwrap();
    std::os::unix::fs::symlink("link.svg", d.join("chain.svg")).unwrap();
    std::fs::hard_link(&db, d.join("hard.svg")).unwrap();
    std::fs::create_dir(d.join("sub")).unwrap();
    // A link to a companion that does not exist yet: writing it would create the log.
    std::os::unix::fs::symlink("../w.sqlite-wal", d.join("sub/wal.svg")).unwrap();
    let protected = Protected::database(&db);
    let before = names(d);
    for out in [
        db.clone(),
        d.join("link.svg"),
        d.join("chain.svg"),
        d.join("hard.svg"),
        d.join("sub/../w.sqlite"),
        d.join("w.sqlite-wal"),
        d.join("w.sqlite-shm"),
        d.join("w.sqlite-journal"),
        d.join("sub/wal.svg"),
    ] {
        let m = refused(write_file(&out, "<svg/>", &protected));
        assert!(m.contains(&out.display().to_string()), "{m}");
        assert!(m.contains("would overwrite"), "{m}");
        assert!(
            m.contains(&db.display().to_string()),
            "names the database: {m}"
        );
        assert_eq!(std::fs::read(&db).unwrap(), bytes);
    }
    assert!(refused(write_file(&d.join("hard.svg"), "x", &protected)).contains("hard link"));
    assert!(refused(write_file(&d.join("link.svg"), "x", &protected)).contains("symbolic link"));
    assert_eq!(names(d), before, "no file made or removed");
    // Any other database is refused as one, protected or not.
    let m = refused(write_file(&db, "x", &Protected::none()));
    assert!(m.contains("is an SQLite database"), "{m}");
    // Inputs named by a command are protected the same way.
    let scene = d.join("scene.toml");
    std::fs::write(&scene, "dimension = 2\n").unwrap();
    let p = Protected::none().and("the scene file", &scene);
    assert!(refused(write_file(&scene, "x", &p)).contains("the scene file"));
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), "dimension = 2\n");
}

#[test]
fn two_outputs_of_one_command_may_not_name_one_file() {
    let (dir, db, _) = with_database();
    let mut outs = Outputs::new(Protected::database(&db));
    outs.claim("-o", &dir.path().join("a.csv")).unwrap();
    std::os::unix::fs::symlink("a.csv", dir.path().join("b.csv")).unwrap();
    let m = refused(outs.claim("--series", &dir.path().join("b.csv")));
    assert!(m.contains("the same file as -o"), "{m}");
    // Devices may be named twice (`/dev/null`).
    outs.claim("--series", Path::new("/dev/null")).unwrap();
    outs.claim("--text", Path::new("/dev/null")).unwrap();
    let m = refused(outs.claim("-o", dir.path()));
    assert!(m.contains("is a folder"), "{m}");
    let m = refused(outs.claim("-o", &dir.path().join("no/such/file.svg")));
    assert!(m.contains("does not exist"), "{m}");
}

#[test]
fn an_output_is_replaced_whole_keeps_its_mode_and_a_dropped_one_leaves_the_old_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map.svg");
    std::fs::write(&out, "old").unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
    let mut f = AtomicFile::create(&out, &Protected::none()).unwrap();
    f.write_all(b"half of the new").unwrap();
    // Before the commit the target is the old file; a temporary file sits beside it.
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "old");
    assert_eq!(names(dir.path()).len(), 2);
    drop(f);
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "old");
    assert_eq!(
        names(dir.path()),
        vec!["map.svg"],
        "the temporary file is gone"
    );
    write_file(&out, "new", &Protected::none()).unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
    let mode = std::fs::metadata(&out).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o640);
    assert_eq!(names(dir.path()), vec!["map.svg"]);
    // Through a symbolic link the file it names is replaced and the link stays.
    std::os::unix::fs::symlink("map.svg", dir.path().join("l.svg")).unwrap();
    write_file(&dir.path().join("l.svg"), "via link", &Protected::none()).unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "via link");
    assert!(
        std::fs::symlink_metadata(dir.path().join("l.svg"))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    // A device is written in place.
    write_file(Path::new("/dev/null"), "anything", &Protected::none()).unwrap();
}

#[test]
fn a_report_folder_replaces_only_its_own_kind_and_never_follows_links() {
    let (dir, db, _) = with_database();
    let d = dir.path();
    let protected = Protected::database(&db);
    let site = d.join("site");
    // A new folder: written whole, with the marker.
    let f = SiteFolder::create(&site, false, &protected).unwrap();
    f.write("index.html", "one").unwrap();
    f.write("points/point-9.html", "stale").unwrap();
    f.commit().unwrap();
    assert!(site.join(MARKER).is_file());
    // Again: the old pages are gone, the new ones there; nothing is left beside it.
    let f = SiteFolder::create(&site, false, &protected).unwrap();
    f.write("index.html", "two").unwrap();
    f.commit().unwrap();
    assert_eq!(
        std::fs::read_to_string(site.join("index.html")).unwrap(),
        "two"
    );
    assert!(!site.join("points/point-9.html").exists());
    assert_eq!(names(d), vec!["site", "w.sqlite"]);
    // A link planted in the old report is removed, not followed.
    std::fs::write(d.join("outside.txt"), "mine").unwrap();
    std::os::unix::fs::symlink("../outside.txt", site.join("lines.csv")).unwrap();
    let f = SiteFolder::create(&site, false, &protected).unwrap();
    f.write("lines.csv", "new").unwrap();
    f.commit().unwrap();
    assert_eq!(
        std::fs::read_to_string(d.join("outside.txt")).unwrap(),
        "mine"
    );
    // A folder without the marker is refused, with --force named, and left alone.
    let mine = d.join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("sweep.toml"), "my own").unwrap();
    let m = match SiteFolder::create(&mine, false, &protected) {
        Err(OutputError::Refused(m)) => m,
        other => panic!("{other:?}"),
    };
    assert!(m.contains("--force") && m.contains("mine"), "{m}");
    assert_eq!(
        std::fs::read_to_string(mine.join("sweep.toml")).unwrap(),
        "my own"
    );
    let f = SiteFolder::create(&mine, true, &protected).unwrap();
    f.write("index.html", "forced").unwrap();
    f.commit().unwrap();
    assert!(!mine.join("sweep.toml").exists());
    // A link as the target, a file as the target, the database's folder: refused even with
    // --force.
    std::os::unix::fs::symlink("site", d.join("via")).unwrap();
    for (target, why) in [
        (d.join("via"), "symbolic link"),
        (db.clone(), "not a folder"),
        (d.to_path_buf(), "holds the database"),
        (PathBuf::from("."), "names no folder"),
    ] {
        match SiteFolder::create(&target, true, &protected) {
            Err(OutputError::Refused(m)) => assert!(m.contains(why), "{m}"),
            other => panic!("{}: {other:?}", target.display()),
        }
    }
    // A file name from a database may not leave the folder; a failed report leaves no trace.
    let f = SiteFolder::create(&site, false, &protected).unwrap();
    for bad in ["../escape.html", "/etc/x", "points/../../x", "", MARKER] {
        assert!(
            matches!(f.write(bad, "x"), Err(OutputError::Refused(_))),
            "{bad}"
        );
    }
    drop(f);
    assert!(!d.join("escape.html").exists());
    assert_eq!(
        names(d),
        vec!["mine", "outside.txt", "site", "via", "w.sqlite"]
    );
    assert_eq!(
        std::fs::read_to_string(site.join("lines.csv")).unwrap(),
        "new"
    );
}
