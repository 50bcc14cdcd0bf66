//! A database written by an earlier wetgran is carried over by `reclassify` (issue 31): the
//! fixture `tests/fixtures/store-f2d47fe/wetgran.sqlite` was made by main at `f2d47fe` (before
//! bonded-cluster regions, the two-lag mobility and the bootstrap noise level) with
//! `wetgran sweep run old.toml --db wetgran.sqlite` over the files beside it. Its observables lack
//! what the current rules read; `reclassify` still labels every result from what is stored, and
//! says which results need a re-run.

mod sweep_common;

use sweep_common::*;

#[test]
fn reclassify_carries_an_old_database_over_and_names_the_results_to_rerun() {
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
    let db = db.to_str().unwrap();
    let o = run(&["reclassify", "--db", db]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
    assert!(text.contains("4 result(s) re-labelled"), "{text}");
    assert!(
        text.contains("4 result(s) were measured before bonded-cluster regions"),
        "{text}"
    );
    // The relabelled store still answers the reports.
    let b = run(&["boundaries", "--db", db]);
    assert!(b.status.success(), "{}", stderr(&b));
}
