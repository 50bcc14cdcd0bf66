//! Fuzzed outputs (proptest), beside the fuzzed inputs of `fuzz_inputs.rs`: what a user may
//! type as an output path, and what a shared database may hold as text.
//!
//! - **Output paths.** A folder holds a database (with an `-shm` file, no `-wal` yet), an old
//!   output, a subfolder, and generated symbolic links (to the database, to each of its
//!   companions whether or not it exists, to the old output, to the subfolder, to nothing, to
//!   another link) and hard links (to the database, to the old output). A generated path (any
//!   of those names, a new name, names behind `sub/..`, `./`, a missing folder, the folder
//!   itself) is written through `wetgran::output` with the database protected, committed or
//!   dropped half-way. Whatever the path: the database and its `-shm` file keep their bytes and
//!   no `-wal` or `-journal` appears; a refused or dropped write changes nothing in the folder;
//!   a committed one changes exactly one regular file, to exactly the new bytes, and leaves no
//!   temporary file; no link is changed.
//! - **Stored text.** A sweep is registered with a generated name, file path, description and
//!   cost note, and one of its jobs fails with a generated error text: strings of terminal
//!   escape sequences, bidirectional overrides, C0 and C1 controls, zero-width and other
//!   format characters, line breaks, and any other code point. The human-readable reports of
//!   that database (`sweep status`, `show`, `boundaries`) contain no character that
//!   `wetgran::terminal` escapes other than their own line breaks, and exactly as many lines as
//!   the same reports of a database with plain text in those places (no line can be forged).
//!
//! Cases per property: proptest's `PROPTEST_CASES` (default 256); the seed is fixed as in
//! `fuzz_inputs.rs` unless `PROPTEST_RNG_SEED` names another.

use proptest::prelude::*;
use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use wetgran::output::{AtomicFile, Protected, write_file};
use wetgran::store::Store;
use wetgran::sweep::SweepFile;
use wetgran::terminal::is_unsafe;

const FUZZ_SEED: u64 = 20261202;

fn config() -> ProptestConfig {
    let mut config = ProptestConfig {
        failure_persistence: None,
        ..ProptestConfig::default()
    };
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        config.rng_seed = proptest::test_runner::RngSeed::Fixed(FUZZ_SEED);
    }
    config
}

// ----- output paths -------------------------------------------------------------------------

/// Where a generated link points (relative to the folder).
const LINK_TARGETS: [&str; 9] = [
    "w.sqlite",
    "w.sqlite-wal",
    "w.sqlite-shm",
    "w.sqlite-journal",
    "old.svg",
    "sub",
    "missing.svg",
    "link0",
    "sub/../w.sqlite",
];

/// One generated entry of the folder: a symbolic link (`Some(target)`) or a hard link to the
/// database (`None, true`) or to the old output (`None, false`).
#[derive(Debug, Clone)]
enum Entry {
    Symlink(usize),
    HardLink(bool),
}

fn entry() -> impl Strategy<Value = Entry> {
    prop_oneof![
        (0..LINK_TARGETS.len()).prop_map(Entry::Symlink),
        any::<bool>().prop_map(Entry::HardLink),
    ]
}

/// A generated output path: a prefix and a name.
fn output_path() -> impl Strategy<Value = (usize, usize)> {
    (0usize..4, 0usize..16)
}

/// Every entry under `dir`: its kind, its link target or its bytes.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, String> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let m = std::fs::symlink_metadata(&p).unwrap();
            let what = if m.file_type().is_symlink() {
                format!("link {}", std::fs::read_link(&p).unwrap().display())
            } else if m.is_dir() {
                stack.push(p.clone());
                "folder".to_string()
            } else {
                format!("file {:?}", std::fs::read(&p).unwrap())
            };
            out.insert(p.strip_prefix(dir).unwrap().to_path_buf(), what);
        }
    }
    out
}

fn check_output_path(
    entries: &[Entry],
    (prefix, name): (usize, usize),
    commit: bool,
) -> Result<(), TestCaseError> {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let db = d.join("w.sqlite");
    let mut db_bytes = b"SQLite format 3\0".to_vec();
    db_bytes.extend([1u8; 2048]);
    std::fs::write(&db, &db_bytes).unwrap();
    std::fs::write(d.join("w.sqlite-shm"), [9u8; 64]).unwrap();
    std::fs::write(d.join("old.svg"), "old").unwrap();
    std::fs::create_dir(d.join("sub")).unwrap();
    let mut names: Vec<String> = Vec::new();
    for (k, e) in entries.iter().enumerate() {
        let n = format!("link{k}");
        match e {
            Entry::Symlink(t) => std::os::unix::fs::symlink(LINK_TARGETS[*t], d.join(&n)).unwrap(),
            Entry::HardLink(to_db) => {
                let target = if *to_db { &db } else { &d.join("old.svg") };
                std::fs::hard_link(target, d.join(&n)).unwrap();
            }
        }
        names.push(n);
    }
    let fixed = [
        "w.sqlite",
        "w.sqlite-wal",
        "w.sqlite-shm",
        "w.sqlite-journal",
        "old.svg",
        "new.svg",
        "sub",
        "sub/x.svg",
        "nope/x.svg",
        ".",
    ];
    let all: Vec<String> = fixed.iter().map(|s| s.to_string()).chain(names).collect();
    let name = &all[name % all.len()];
    let path = match prefix {
        0 => d.join(name),
        1 => d.join("sub/..").join(name),
        2 => d.join(".").join(name),
        _ => d.join("sub").join("..").join(".").join(name),
    };
    let before = snapshot(d);
    let protected = Protected::database(&db);
    let result = if commit {
        write_file(&path, b"NEW", &protected)
    } else {
        // Written half-way, then dropped (a failure in the middle).
        AtomicFile::create(&path, &protected).map(|mut f| {
            let _ = f.write_all(b"NE");
        })
    };
    let after = snapshot(d);
    prop_assert_eq!(std::fs::read(&db).unwrap(), db_bytes, "{}", path.display());
    prop_assert_eq!(
        std::fs::read(d.join("w.sqlite-shm")).unwrap(),
        vec![9u8; 64]
    );
    prop_assert!(!d.join("w.sqlite-wal").exists() && !d.join("w.sqlite-journal").exists());
    let changed: Vec<&PathBuf> = after
        .iter()
        .filter(|(p, w)| before.get(*p) != Some(*w))
        .map(|(p, _)| p)
        .chain(before.keys().filter(|p| !after.contains_key(*p)))
        .collect();
    match (&result, commit) {
        (Ok(()), true) => {
            prop_assert_eq!(changed.len(), 1, "{}: {:?}", path.display(), changed);
            prop_assert_eq!(after[changed[0]].as_str(), format!("file {:?}", b"NEW"));
        }
        _ => prop_assert!(
            changed.is_empty(),
            "{}: {:?} ({result:?})",
            path.display(),
            changed
        ),
    }
    Ok(())
}

// ----- stored text --------------------------------------------------------------------------

/// A hostile string: pieces of terminal escapes, bidirectional overrides, controls, format
/// characters, line breaks, plain words and any code point.
fn hostile() -> impl Strategy<Value = String> {
    let piece = prop_oneof![
        Just("\u{1b}[2J".to_string()),
        Just("\u{1b}]0;pwned\u{7}".to_string()),
        Just("\u{9b}31m".to_string()),
        Just("\u{202e}".to_string()),
        Just("\u{2066}".to_string()),
        Just("\u{200b}\u{feff}".to_string()),
        Just("\0".to_string()),
        Just("\n".to_string()),
        Just("\r".to_string()),
        Just("\t".to_string()),
        Just("error: forged line".to_string()),
        Just("Γ ≥ 粒子".to_string()),
        any::<char>().prop_map(|c| c.to_string()),
    ];
    proptest::collection::vec(piece, 0..12).prop_map(|v| v.concat())
}

/// The hostile texts of one case: name, file, description, cost, error.
type Texts = (String, String, String, String, String);

/// A database with one sweep of two jobs whose texts are `t` (one job failed with `t.4`).
fn forged_store(dir: &Path, t: &Texts) -> (Store, i64) {
    let text = "[sweep]\nname = \"s\"\n[scene]\ndimension = 2\n[scene.box]\nsize = [8.0, 4.0]\n\
                [scene.particles]\ncount = 4\n[scene.initial]\ntemperature = 1.0\n\
                [scene.run]\nduration = 1.0\n[[axis]]\nkey = \"initial.seed\"\nvalues = [1, 2]\n";
    let mut file = SweepFile::parse(text, &dir.join("s.toml")).unwrap();
    let jobs = file.expand().unwrap();
    file.name = t.0.clone();
    file.path = PathBuf::from(&t.1);
    file.description = Some(t.2.clone());
    file.cost = Some(t.3.clone());
    let store = Store::open(&dir.join("w.sqlite")).unwrap();
    let id = store.register_sweep(&file, &jobs).unwrap().id;
    let claim = store.claim(&[id]).unwrap().unwrap();
    store.fail(&claim, &t.4, 0.1).unwrap();
    (store, id)
}

/// The human-readable reports of the database's one sweep, joined.
fn reports(store: &Store) -> String {
    use wetgran::report::sweep_text::{StatusInput, sweep_status_text};
    let sweep = store.sweeps().unwrap().remove(0);
    let (points, spent) = store.status_summaries(&sweep).unwrap();
    let running = store.running_jobs(sweep.id).unwrap();
    let input = StatusInput {
        sweep: &sweep,
        counts: wetgran::store::StateCounts::of_summaries(&points),
        points: &points,
        spent,
        cores: 2,
        running: &running,
        now: wetgran::store::now(),
    };
    let mut out = sweep_status_text(&input);
    for p in store.points(sweep.id).unwrap() {
        out += &wetgran::report::point_text::job_text(
            &wetgran::terminal::escape(&sweep.name),
            &sweep.axes,
            &p,
        );
    }
    let how = wetgran::boundary::Extraction::default();
    let summaries = store.point_summaries(&sweep).unwrap();
    let obs: Vec<_> = summaries
        .iter()
        .map(wetgran::boundary::Observation::of_summary)
        .collect();
    if let Ok(map) = wetgran::boundary::phase_map_with(&sweep.axes, &obs, how) {
        out += &wetgran::report::boundaries_text::boundaries_table(
            &[(&sweep, map)],
            &[summaries],
            how,
        );
    }
    out
}

fn check_stored_text(t: &Texts) -> Result<(), TestCaseError> {
    let forged_dir = tempfile::tempdir().unwrap();
    let plain_dir = tempfile::tempdir().unwrap();
    let (forged, _) = forged_store(forged_dir.path(), t);
    let plain = (
        "name".to_string(),
        "file.toml".to_string(),
        "description".to_string(),
        "cost".to_string(),
        "error".to_string(),
    );
    let (plain_store, _) = forged_store(plain_dir.path(), &plain);
    let text = reports(&forged);
    let bad: Vec<char> = text
        .chars()
        .filter(|c| is_unsafe(*c) && *c != '\n')
        .collect();
    prop_assert!(bad.is_empty(), "unescaped {bad:?} in\n{text}");
    prop_assert_eq!(
        text.lines().count(),
        reports(&plain_store).lines().count(),
        "a line was forged:\n{}",
        text
    );
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn fuzzed_output_paths_never_touch_the_database_and_write_whole_or_nothing(
        entries in proptest::collection::vec(entry(), 0..6),
        path in output_path(),
        commit in any::<bool>(),
    ) {
        check_output_path(&entries, path, commit)?;
    }

    #[test]
    fn fuzzed_stored_text_reaches_the_reports_inert_and_forges_no_line(
        t in (hostile(), hostile(), hostile(), hostile(), hostile()),
    ) {
        check_stored_text(&t)?;
    }
}
