//! Scene validation at load, one test per rule.
//!
//! The inputs live next to their expectations: every file in `tests/scenes/bad/` is a complete
//! scene with exactly one bad value, and carries one or more leading comment lines
//! `# expect: <fragment>`; loading it must fail with an error whose `Display` starts with the
//! file's path and contains every fragment (the key, the offending value and the allowed range).
//! Every file in `tests/scenes/good/` (and every example scene in `scenes/`) must load.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

use wetgran_core::scene::Scene;

/// `tests/scenes/<kind>` at the root of the workspace.
fn scene_dir(kind: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .join("tests")
        .join("scenes")
        .join(kind)
}

/// The `.toml` files of a directory, sorted.
fn toml_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .map(|entry| entry.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    files
}

/// The fragments of the `# expect:` lines.
fn expected_fragments(text: &str) -> Vec<&str> {
    text.lines()
        .filter_map(|line| line.strip_prefix("# expect:"))
        .map(str::trim)
        .collect()
}

/// Loads `bad/<name>.toml` and checks that it is rejected with the expected message.
fn check_bad(name: &str) {
    let path = scene_dir("bad").join(format!("{name}.toml"));
    let text =
        fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let expected = expected_fragments(&text);
    assert!(
        !expected.is_empty() && expected.iter().all(|f| !f.is_empty()),
        "{}: needs at least one non-empty `# expect: <fragment>` line",
        path.display()
    );
    let message = match Scene::load(&path) {
        Ok(_) => panic!(
            "{} loaded, but must be rejected with an error containing {expected:?}",
            path.display()
        ),
        Err(e) => e.to_string(),
    };
    let origin = format!("{}: ", path.display());
    assert!(
        message.starts_with(&origin),
        "the error does not start with the file name {origin:?}:\n{message}"
    );
    let missing: Vec<&str> = expected
        .iter()
        .copied()
        .filter(|f| !message.contains(f))
        .collect();
    assert!(
        missing.is_empty(),
        "the error of {} lacks {missing:?}; the full error:\n{message}",
        path.display()
    );
}

/// One test per file in `tests/scenes/bad/`, named after it; `BAD_SCENES` lists them all.
macro_rules! bad_scenes {
    ($($name:ident),* $(,)?) => {
        const BAD_SCENES: &[&str] = &[$(stringify!($name)),*];

        mod bad {
            $(
                #[test]
                fn $name() {
                    super::check_bad(stringify!($name));
                }
            )*
        }
    };
}

bad_scenes! {
    // Dimension and gravity.
    dimension_not_2_or_3,
    gravity_negative,
    gravity_infinite,
    gravity_tiny_leaves_event_times_no_digits,
    dimension_wrong_type,
    // Box.
    box_size_wrong_length,
    box_size_zero,
    box_size_negative,
    box_size_infinite,
    box_size_too_many_cells,
    box_size_huge,
    box_boundary_wrong_length,
    box_boundary_unknown_kind,
    periodic_vertical_with_gravity,
    periodic_axis_too_small,
    // Particles.
    count_zero,
    count_exceeds_lattice,
    count_wrong_type,
    count_negative,
    diameter_negative,
    diameter_nan,
    mass_zero,
    mass_tiny_leaves_the_motion_no_digits,
    polydispersity_above_max,
    polydispersity_at_max,
    polydispersity_negative,
    // Contact.
    restitution_above_one,
    restitution_negative,
    restitution_nan,
    wall_restitution_above_one,
    wall_restitution_negative,
    // Capillary bridges.
    capillary_model_unknown,
    s_crit_zero,
    s_crit_negative,
    e_cb_negative,
    s_crit_with_model_none,
    e_cb_with_model_none,
    e_cb_missing_without_gravity,
    // Initial state.
    temperature_both_keys,
    temperature_missing,
    temperature_negative,
    temperature_over_ecb_negative,
    temperature_over_ecb_dry,
    temperature_over_ecb_zero_ecb,
    lattice_spacing_below_one,
    seed_negative,
    // Run.
    duration_zero,
    duration_missing,
    duration_wrong_type,
    sample_interval_negative,
    max_events_zero,
    // Engine.
    engine_tc_negative,
    engine_min_rebound_zero_with_gravity,
    temperature_absurd,
    capillary_rupture_rule_without_bridges,
    engine_min_rebound_too_large,
    engine_min_rebound_zero_with_bridges,
    engine_inelastic_without_collapse_remedy,
    engine_overlap_tolerance_too_large,
    run_sample_interval_too_small,
    drive_amplitude_without_sine,
    drive_gamma_without_e_star,
    drive_both_pairs,
    drive_amplitude_negative,
    drive_gamma_zero,
    drive_e_star_below_amplitude_floor,
    drive_amplitude_below_floor,
    drive_omega_above_ceiling,
    drive_gap_below_d_max,
    drive_root_tolerance_negative,
    drive_wall_solver_unknown,
    drive_table_cells_too_few,
    drive_table_key_without_table,
    drive_table_v_max_below_v_min,
    drive_table_corner_tolerance_zero,
    shear_in_2d,
    shear_f_max_negative,
    shear_f_max_missing,
    shear_slab_width_too_large,
    shear_slab_width_tiny,
    shear_box_wall_in_x,
    shear_with_amplitude,
    shear_f_max_without_shear,
    classify_shear_e_par_negative,
    engine_min_rebound_speed_negative,
    engine_overlap_tolerance_zero,
    engine_overlap_tolerance_below_round_off,
    engine_cell_size_negative,
    engine_cell_size_too_small,
    // Engine kind (time-driven engine, issue 6).
    engine_kind_unknown,
    time_engine_with_tc,
    time_engine_restitution_and_damping,
    time_engine_restitution_too_small,
    time_engine_restitution_speed_zero,
    event_engine_with_restitution_speed,
    time_engine_restitution_temperature_zero,
    time_engine_restitution_speed_and_temperature,
    time_engine_restitution_speed_unknown_word,
    event_engine_with_restitution_temperature,
    time_engine_with_wall_solver,
    time_engine_with_max_events,
    time_engine_dt_too_large,
    time_engine_dt_longer_than_a_hertz_contact,
    time_engine_restitution_calibrated_at_no_temperature,
    time_engine_dt_does_not_resolve_the_damping,
    time_engine_dt_does_not_resolve_given_damping,
    time_engine_skin_zero,
    time_engine_stiffness_too_small,
    time_engine_damping_negative,
    time_engine_integrator_unknown,
    event_engine_with_dt,
    time_engine_with_shear_slab_width,
    event_engine_with_stiffness,
    time_engine_box_too_narrow,
    // Observers and classification.
    observe_transient_too_long,
    observe_transient_negative,
    observe_bin_width_zero,
    observe_samples_per_period_zero,
    observe_layers_zero,
    observe_lc_max_edge_below_one,
    observe_lc_flip_margin_negative,
    observe_lc_leave_not_above_enter,
    observe_unknown_key,
    classify_solid_flc_negative,
    classify_gas_below_solid,
    classify_delta_n_cb_infinite,
    classify_mobility_unknown,
    observe_mobility_lag_zero,
    observe_bins_3d_unknown,
    observe_location_changes_off_but_classified_by_it,
    classify_coexistence_level_one,
    classify_coexistence_contrast_above_one,
    classify_still_members_above_one,
    classify_line_jump_ratio_one,
    classify_solid_diffusion_negative,
    // Format.
    unknown_key_top_level,
    unknown_key_in_table,
    unknown_table,
    toml_syntax_error,
}

/// No file in `bad/` is forgotten by `bad_scenes!`, and every listed name has its file.
#[test]
fn every_bad_scene_is_listed() {
    let dir = scene_dir("bad");
    let on_disk: BTreeSet<String> = toml_files(&dir)
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    let listed: BTreeSet<String> = BAD_SCENES.iter().map(|s| s.to_string()).collect();
    assert_eq!(listed.len(), BAD_SCENES.len(), "a name is listed twice");
    let unlisted: Vec<_> = on_disk.difference(&listed).collect();
    let absent: Vec<_> = listed.difference(&on_disk).collect();
    assert!(
        unlisted.is_empty() && absent.is_empty(),
        "files in {} not listed in bad_scenes!: {unlisted:?}; listed without a file: {absent:?}",
        dir.display()
    );
    let stray: Vec<_> = fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_none_or(|x| x != "toml"))
        .collect();
    assert!(
        stray.is_empty(),
        "files without .toml in {}: {stray:?}",
        dir.display()
    );
}

/// Loads every `.toml` file of `dir`; returns how many, panics listing every failure.
fn assert_all_load(dir: &Path) -> usize {
    let files = toml_files(dir);
    let failures: Vec<String> = files
        .iter()
        .filter_map(|p| Scene::load(p).err().map(|e| e.to_string()))
        .collect();
    assert!(
        failures.is_empty(),
        "valid scenes were rejected:\n{}",
        failures.join("\n")
    );
    files.len()
}

#[test]
fn good_scenes_load() {
    let n = assert_all_load(&scene_dir("good"));
    assert!(n >= 5, "expected at least 5 good scenes, found {n}");
}

/// The example scenes shipped in `scenes/` are valid too, and so are the phase points of
/// `docs/phases/`.
#[test]
fn example_scenes_load() {
    let root = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
    let n = assert_all_load(&root.join("scenes"));
    assert!(n >= 1, "no example scene found");
    let n = assert_all_load(&root.join("docs").join("phases"));
    assert!(
        n >= 4,
        "expected the phase points of docs/phases.md, found {n}"
    );
}

/// The good scenes carry no `# expect:` line (it would mean a misplaced bad scene).
#[test]
fn good_scenes_expect_nothing() {
    for path in toml_files(&scene_dir("good")) {
        let text = fs::read_to_string(&path).unwrap();
        assert!(
            expected_fragments(&text).is_empty(),
            "{} is in good/ but has `# expect:` lines",
            path.display()
        );
    }
}

/// A file that cannot be read is reported with its path.
#[test]
fn missing_file_names_the_path() {
    let path = scene_dir("bad").join("no_such_scene.toml");
    let message = Scene::load(&path)
        .expect_err("a missing file must not load")
        .to_string();
    assert!(
        message.starts_with(&format!("{}: ", path.display())),
        "{message}"
    );
    assert!(message.contains("cannot read the scene file"), "{message}");
}

/// The error's fields agree with its message: the key of a rejected value is the dotted key.
#[test]
fn error_fields_name_origin_and_key() {
    let path = scene_dir("bad").join("polydispersity_above_max.toml");
    let err = Scene::load(&path).expect_err("must be rejected");
    assert_eq!(err.origin, path.display().to_string());
    assert_eq!(err.key, "particles.polydispersity");
    assert!(err.message.contains("0.6"), "{}", err.message);
}
