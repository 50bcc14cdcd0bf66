//! The sweep runner's wall-table cache (issue 16): a sweep with the `table` wall solver over many
//! drives keeps at most the cap of `RunOptions::table_cache_mib` in cached tables, while the
//! tables it builds add up to several times the cap.

mod sweep_common;

use sweep_common::*;
use wetgran::run::{RunOptions, run_sweeps};
use wetgran::store::Store;
use wetgran::sweep::SweepFile;

#[test]
fn a_table_solver_sweep_over_many_drives_stays_under_the_cache_cap() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    // 4 x 3 drives (A, omega), each with its own floor and lid table of 16 x 16 cells per edge.
    let file = write(
        dir.path(),
        "tables.toml",
        "[sweep]\nname = \"tables\"\nbase = \"tiny.toml\"\nperiods = 2\n\
         [scene]\ndrive.wall_solver = \"table\"\ndrive.table_cells = [16, 16]\n\
         [observe]\ntransient_periods = 1\nlocation_changes = false\ndiffusion = false\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0, 4.0, 6.0]\n\
         [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0, 4.0]\n",
    );
    let sweep = SweepFile::load(&file).unwrap_or_else(|e| panic!("{e}"));
    let store = Store::open(&dir.path().join("t.db")).unwrap();
    let row = store
        .register_sweep(&sweep, &sweep.expand().unwrap())
        .unwrap();
    let cap_mib = 1;
    let summary = run_sweeps(
        &store,
        std::slice::from_ref(&row),
        &RunOptions {
            jobs: 2,
            retry_failed: false,
            show_progress: false,
            table_cache_mib: cap_mib,
            on_extend: None,
        },
    )
    .unwrap();
    assert_eq!(summary.done, 12, "{summary:?}");
    assert_eq!(summary.failed, 0, "{summary:?}");
    // Every drive's floor and lid table built once, none twice (replicas = 1).
    assert_eq!(summary.tables_built, 24, "{summary:?}");
    let cap = cap_mib << 20;
    assert!(summary.table_cache_peak_bytes > 0, "{summary:?}");
    assert!(
        summary.table_cache_peak_bytes <= cap,
        "cache held {} bytes, cap {cap}",
        summary.table_cache_peak_bytes
    );
    // The bound bites: the tables built add up to more than twice the cap.
    let w = wetgran_core::physics::shaken_wall::WallMotion {
        amplitude: 1.0,
        omega: 1.0,
        g: 1.0,
    };
    let spec = wetgran_core::physics::wall_table::TableSpec {
        phase_cells: 16,
        velocity_cells: 16,
        v_min: 0.05,
        v_max: 50.0,
        corner_tolerance: Some(1e-3),
    };
    let one = wetgran_core::physics::wall_table::WallTable::build(w, spec).bytes();
    assert!(24 * one > 2 * cap, "one table {one} bytes");
}
