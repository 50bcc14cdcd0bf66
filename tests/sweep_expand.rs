//! Sweep files and their expansion into job specs: axes (lists, linear and log ranges),
//! replicas, run length in driving periods, content-hashed ids (stable across processes,
//! independent of key order and of spelled-out defaults), and errors naming file, line and key.

mod sweep_common;

use std::path::Path;
use sweep_common::*;
use wetgran::sweep::spec::{canonical_json, id_of_canonical};
use wetgran::sweep::{AxisKind, JobSpec, SweepFile};

fn sweep_text(header: &str, axes: &str) -> String {
    format!("[sweep]\nname = \"t\"\nbase = \"tiny.toml\"\n{header}\n{axes}")
}

fn load(dir: &Path, text: &str) -> SweepFile {
    let p = write(dir, "sweep.toml", text);
    SweepFile::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

fn err(dir: &Path, text: &str) -> String {
    let p = write(dir, "bad.toml", text);
    match SweepFile::load(&p).and_then(|s| s.expand().map(|_| ())) {
        Ok(()) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn axes_ranges_and_replicas_expand_to_the_full_grid() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let s = load(
        dir.path(),
        &sweep_text(
            "replicas = 2",
            "[[axis]]\nkey = \"gamma\"\nlinear = { from = 2.0, to = 4.0, steps = 3 }\n\
             [[axis]]\nkey = \"e_star\"\nlog = { from = 0.5, to = 8.0, steps = 5 }\n\
             [[axis]]\nkey = \"contact.restitution\"\nvalues = [0.8, 1.0]\n",
        ),
    );
    assert_eq!(s.axes[0].key, "drive.gamma");
    assert_eq!(s.axes[0].label, "Gamma");
    assert_eq!(s.axes[1].kind, AxisKind::Log);
    let lin: Vec<f64> = s.axes[0]
        .values
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(lin, vec![2.0, 3.0, 4.0]);
    // Log range: both ends exact, constant ratio (8 / 0.5)^(1/4) = 2.
    let log: Vec<f64> = s.axes[1]
        .values
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!((log[0], log[4]), (0.5, 8.0));
    for w in log.windows(2) {
        assert!((w[1] / w[0] - 2.0).abs() < 1e-12, "{log:?}");
    }
    let jobs = s.expand().unwrap();
    assert_eq!(jobs.len(), 3 * 5 * 2 * 2);
    // Row-major, last axis fastest, replicas innermost; every value lands in its scene key.
    for (k, j) in jobs.iter().enumerate() {
        assert_eq!(j.point, k / 2);
        assert_eq!(j.replica as usize, k % 2);
        let (ig, ie, ir) = (j.point / 10, (j.point / 2) % 5, j.point % 2);
        assert_eq!(j.coords[0].as_f64().unwrap(), lin[ig]);
        assert_eq!(j.coords[1].as_f64().unwrap(), log[ie]);
        let scene = &j.spec.scene;
        assert_eq!(scene.drive.gamma, Some(lin[ig]));
        assert_eq!(scene.drive.e_star, Some(log[ie]));
        assert_eq!(scene.contact.restitution, [0.8, 1.0][ir]);
        // Replica r: base seed (7) + r.
        assert_eq!(scene.initial.seed, 7 + j.replica as u64);
    }
    let mut ids: Vec<&str> = jobs.iter().map(|j| j.id.as_str()).collect();
    ids.sort();
    ids.dedup();
    assert_eq!(ids.len(), jobs.len(), "every job is distinct");
}

#[test]
fn run_length_transient_and_sampling_are_converted_from_driving_periods() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let s = load(
        dir.path(),
        &sweep_text(
            "periods = 12\n[observe]\ntransient_periods = 4\nsamples_per_period = 5\nbin_width = 4.0",
            "[[axis]]\nkey = \"gamma\"\nvalues = [1.5, 6.0]\n",
        ),
    );
    for j in s.expand().unwrap() {
        let gamma = j.coords[0].as_f64().unwrap();
        // docs/model.md 4.1, independently: v_w = sqrt(2 E* E_cb / m), omega = Gamma g / v_w.
        let e_cb: f64 = 4.0 * 0.0711;
        let v_w = (2.0 * 2.0 * e_cb).sqrt();
        let period = 2.0 * std::f64::consts::PI / (gamma / v_w);
        let run = &j.spec.scene.run;
        assert!((run.duration - 12.0 * period).abs() < 1e-9 * period);
        assert!((run.sample_interval - period / 5.0).abs() < 1e-12 * period);
        assert_eq!(j.spec.scene.observe.transient_periods, 4.0);
        assert_eq!(j.spec.scene.observe.samples_per_period, 5.0);
        assert_eq!(j.spec.scene.observe.bin_width, 4.0);
        assert!((j.spec.period() - period).abs() < 1e-12 * period);
    }
}

#[test]
fn ids_ignore_key_order_and_spelled_out_defaults_but_not_a_changed_value() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let axes = "[[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n";
    let a = load(dir.path(), &sweep_text("", axes)).expand().unwrap();
    // The same scene written inline, tables and keys in another order, defaults spelled out.
    let inline = "[[axis]]\nkey = \"drive.gamma\"\nvalues = [2.0, 3.0]\n\
         [sweep]\nname = \"other-name\"\n\
         [scene.run]\nduration = 10.0\nsample_interval = 0.0\n\
         [scene.initial]\nseed = 7\ntemperature_over_ecb = 20.0\n\
         [scene.drive]\ne_star = 2.0\nkind = \"sine\"\ngamma = 3.0\nwall_solver = \"exact\"\n\
         [scene.capillary]\nmodel = \"thin_thread\"\n\
         [scene.contact]\nwall_restitution = 1.0\nrestitution = 0.9\n\
         [scene.particles]\npolydispersity = 0.06\ncount = 40\nmass = 1.0\n\
         [scene.box]\nsize = [20.0, 9.0]\n\
         [scene]\ndimension = 2\ngravity = 1.0\n";
    let b = load(dir.path(), inline).expand().unwrap();
    let ids = |v: &[wetgran::sweep::SweepJob]| v.iter().map(|j| j.id.clone()).collect::<Vec<_>>();
    assert_eq!(ids(&a), ids(&b));
    // One changed parameter: a new job.
    let c = load(
        dir.path(),
        &sweep_text("[scene]\ncontact.restitution = 0.8", axes),
    )
    .expand()
    .unwrap();
    assert!(ids(&a).iter().all(|id| !ids(&c).contains(id)));
}

#[test]
fn canonical_json_is_sorted_round_trips_and_hashes_to_the_id() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let jobs = load(
        dir.path(),
        &sweep_text(
            "",
            "[[axis]]\nkey = \"e_star\"\nlog = { from = 0.3, to = 3.0, steps = 3 }\n",
        ),
    )
    .expand()
    .unwrap();
    for j in &jobs {
        let text = j.spec.canonical_json();
        // Keys sorted at every level: re-canonicalising the parsed text changes nothing, and the
        // top-level keys appear in order.
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(canonical_json(&v), text);
        let pos: Vec<usize> = ["\"format\"", "\"scene\"", "\"classify\"", "\"observe\""]
            .iter()
            .map(|k| text.find(k).unwrap())
            .collect();
        assert!(pos.windows(2).all(|w| w[0] < w[1]), "{text}");
        // The spec alone reproduces the job, floats exactly.
        let back = JobSpec::from_json(&text, "test").unwrap();
        assert_eq!(back, j.spec);
        // A misspelt key is refused by name, with the keys allowed.
        let misspelt = text.replacen('{', "{\"start_fro\":\"x\",", 1);
        let err = JobSpec::from_json(&misspelt, "test").unwrap_err();
        assert!(
            err.starts_with("test: key `start_fro`: not a job spec: unknown field `start_fro`")
                && err.contains("expected one of `format`, `scene`, `start_from`"),
            "{err}"
        );
        // The id hashes the spec without its `[classify]` thresholds (they only label).
        let identity = canonical_json(&j.spec.identity());
        assert!(!identity.contains("\"classify\""), "{identity}");
        assert_eq!(id_of_canonical(&identity), j.id);
        assert_ne!(id_of_canonical(&text), j.id);
        // Independent SHA-256 where the system has one.
        if let Ok(out) = std::process::Command::new("sha256sum")
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .and_then(|mut c| {
                use std::io::Write;
                c.stdin.take().unwrap().write_all(identity.as_bytes())?;
                c.wait_with_output()
            })
        {
            let hex = String::from_utf8_lossy(&out.stdout);
            assert_eq!(hex.split_whitespace().next().unwrap(), j.id);
        }
    }
}

#[test]
fn ids_are_stable_across_processes() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let p = write(
        dir.path(),
        "s.toml",
        &sweep_text(
            "replicas = 2",
            "[[axis]]\nkey = \"gamma\"\nlinear = { from = 1.5, to = 6.0, steps = 4 }\n",
        ),
    );
    let p = p.to_str().unwrap();
    let first = run(&["sweep", "expand", p, "--specs"]);
    let second = run(&["sweep", "expand", p, "--specs"]);
    assert!(first.status.success(), "{}", stderr(&first));
    assert_eq!(stdout(&first).lines().count(), 8);
    assert_eq!(first.stdout, second.stdout);
    // And the same as the library computes in this process.
    let jobs = SweepFile::load(Path::new(p)).unwrap().expand().unwrap();
    for (line, j) in stdout(&first).lines().zip(&jobs) {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        assert_eq!(v["id"], serde_json::json!(j.id));
    }
}

#[test]
fn sweep_file_errors_name_file_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let d = dir.path();
    let file = d.join("bad.toml").display().to_string();
    let cases: Vec<(String, &str, &str)> = vec![
        // TOML syntax error on line 4.
        (
            sweep_text("", "[[axis]]\nkey = \"gamma\nvalues = [1.0]\n"),
            ":6",
            "",
        ),
        // Unknown key in [sweep], line 4.
        (sweep_text("replica = 3", ""), ":4", "key `sweep.replica`"),
        // An axis value the scene rejects: the axis line and the scene key.
        (
            sweep_text("", "\n[[axis]]\nkey = \"gamma\"\nvalues = [2.0, -1.0]\n"),
            ":7",
            "key `drive.gamma`",
        ),
        // A log range through zero.
        (
            sweep_text(
                "",
                "[[axis]]\nkey = \"e_star\"\nlog = { from = 0.0, to = 3.0, steps = 3 }\n",
            ),
            ":7",
            "key `drive.e_star`",
        ),
        // A bad value in the inline [scene] table: its line in the sweep file.
        (
            sweep_text(
                "[scene]\ncapillary.s_crit = 0.05\nparticles.polydispersity = 0.9",
                "",
            ),
            ":6",
            "key `particles.polydispersity`",
        ),
        // Two axes on one key.
        (
            sweep_text(
                "",
                "[[axis]]\nkey = \"gamma\"\nvalues = [2.0]\n[[axis]]\nkey = \"drive.gamma\"\nvalues = [3.0]\n",
            ),
            ":9",
            "key `drive.gamma`",
        ),
        // Replicas and a seed axis at once.
        (
            sweep_text(
                "replicas = 2",
                "[[axis]]\nkey = \"initial.seed\"\nvalues = [1, 2]\n",
            ),
            ":6",
            "key `initial.seed`",
        ),
        // Transient not shorter than the run.
        (
            sweep_text("periods = 5\n[observe]\ntransient_periods = 5", ""),
            ":6",
            "key `observe.transient_periods`",
        ),
        // Missing base scene file: the line of `base`.
        (
            "[sweep]\nname = \"t\"\nbase = \"nowhere.toml\"\n".to_string(),
            ":3",
            "key `sweep.base`",
        ),
    ];
    for (text, line, key) in cases {
        let e = err(d, &text);
        assert!(
            e.starts_with(&format!("{file}{line}")),
            "expected {file}{line} in: {e}\nfor:\n{text}"
        );
        assert!(e.contains(key), "expected {key} in: {e}");
    }
    // A bad value in the base scene file names that file and line.
    write(
        d,
        "tiny_bad.toml",
        &TINY_SCENE.replace("count = 40", "count = 0"),
    );
    let e = err(d, "[sweep]\nname = \"t\"\nbase = \"tiny_bad.toml\"\n");
    let base = d.join("tiny_bad.toml").display().to_string();
    assert!(
        e.starts_with(&format!("{base}:6: key `particles.count`")),
        "{e}"
    );
}

#[test]
fn skip_invalid_leaves_out_points_failing_a_scene_constraint() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    // 20 d x 9 d holds a few hundred disks on the initial lattice, not 5000: each count is in
    // its own range, the combination with the box is not (Constraint::LatticeFull).
    let text = sweep_text(
        "skip_invalid = true",
        "[[axis]]\nkey = \"gamma\"\nvalues = [1.5, 6.0]\n[[axis]]\nkey = \"particles.count\"\nvalues = [40, 5000]\n",
    );
    let s = load(dir.path(), &text);
    let (jobs, skipped) = s.expand_with_skips().unwrap();
    assert_eq!(jobs.len(), 2);
    assert_eq!(skipped.len(), 2);
    for k in &skipped {
        assert_eq!(k.coords[1], serde_json::json!(5000));
        assert_eq!(k.reason.key, "particles.count");
        assert_eq!(
            k.reason.constraint,
            Some(wetgran_core::scene::Constraint::LatticeFull)
        );
    }
    // Without the switch the sweep is rejected.
    let e = err(dir.path(), &text.replace("skip_invalid = true", ""));
    assert!(e.contains("particles.count"), "{e}");
}

#[test]
fn a_refine_table_is_checked_with_file_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let axes = "[[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n\
                [[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0]\n";
    let with = |refine: &str| sweep_text("replicas = 2", &format!("{axes}[refine]\n{refine}"));
    let ok = load(dir.path(), &with("budget = 10\nresolution = 0.05\n"));
    let r = ok.refine.unwrap();
    assert_eq!((r.budget, r.rounds, r.max_replicas), (10, 4, 6));
    assert_eq!(r.resolution, 0.05);
    let e = err(dir.path(), &with("budget = 10\nresolution = 1.5\n"));
    assert!(
        e.contains("bad.toml:13: key `refine.resolution`: = 1.5 is out of range"),
        "{e}"
    );
    let e = err(dir.path(), &with("budget = 10\nmax_replicas = 1\n"));
    assert!(
        e.contains("key `refine.max_replicas`: = 1 is out of range"),
        "{e}"
    );
    let e = err(dir.path(), &with("budget = 2\nrounds = 3\n"));
    assert!(
        e.contains("key `refine.rounds`: = 3 is out of range"),
        "{e}"
    );
    let e = err(dir.path(), &with("budget = 2\nsteps = 3\n"));
    assert!(e.contains("steps"), "{e}");
}

#[test]
fn jobs_at_a_grid_point_are_the_grid_jobs_and_extra_replicas_take_the_next_seeds() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let sweep = load(
        dir.path(),
        &sweep_text(
            "replicas = 2",
            "[[axis]]\nkey = \"gamma\"\nvalues = [2.0, 3.0]\n",
        ),
    );
    let grid = sweep.expand().unwrap();
    let at = sweep.jobs_at(1, &grid[2].coords, 0..4).unwrap().unwrap();
    assert_eq!(at[..2], grid[2..4]);
    // TINY_SCENE has seed 7: replica r runs with seed 7 + r.
    let seeds: Vec<u64> = at.iter().map(|j| j.spec.scene.initial.seed).collect();
    assert_eq!(seeds, vec![7, 8, 9, 10]);
    // Between grid values: a valid job whose drive is the new value.
    let mid = sweep
        .jobs_at(1_000_000, &[serde_json::json!(2.5)], 0..1)
        .unwrap()
        .unwrap();
    assert_eq!(mid[0].spec.scene.drive.gamma, Some(2.5));
    assert_eq!(mid[0].point, 1_000_000);
}

#[test]
fn shear_sweeps_take_f_max_and_an_indexed_box_size_as_axes() {
    // docs/model.md 4.2 / issue 7: sweeps over F_max and L_x (`l_x` = `box.size[0]`).
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "shear.toml",
        include_str!("../tests/scenes/good/shear_3d.toml"),
    );
    let text = "[sweep]\nname = \"s\"\nbase = \"shear.toml\"\n\
                [[axis]]\nkey = \"f_max\"\nvalues = [0.2, 0.8]\n\
                [[axis]]\nkey = \"l_x\"\nvalues = [12.0, 16.0]\n";
    let jobs = load(dir.path(), text).expand().unwrap();
    assert_eq!(jobs.len(), 4);
    let mut seen: Vec<(f64, f64)> = jobs
        .iter()
        .map(|j| {
            let s = &j.spec.scene;
            assert_eq!(s.container.size[1..], [12.0, 6.0]);
            (s.drive.f_max.unwrap(), s.container.size[0])
        })
        .collect();
    seen.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(seen, [(0.2, 12.0), (0.2, 16.0), (0.8, 12.0), (0.8, 16.0)]);
    // An index past the array is an error naming the key.
    let bad = text.replace("key = \"l_x\"", "key = \"box.size[5]\"");
    let e = err(dir.path(), &bad);
    assert!(e.contains("box.size[5]"), "{e}");
}

/// Regression (issue 18, engines like for like): the time engine's default damping calibration
/// changed from impact speed 1 to `"auto"`; a time-engine job that converts a restitution spells
/// the calibration out, so its id cannot match a result stored under the old default. Jobs with
/// explicit damping, and event-engine jobs, are unchanged.
#[test]
fn a_time_engine_job_spells_out_its_damping_calibration() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = |contact: &str, kind: &str| {
        let text = format!(
            "[sweep]\nname = \"t\"\n[scene]\ndimension = 2\n[scene.box]\nsize = [20.0, 9.0]\n\
             [scene.particles]\ncount = 10\n[scene.contact]\n{contact}\n[scene.engine]\nkind = \"{kind}\"\n\
             [scene.initial]\ntemperature = 1.0\n[scene.run]\nduration = 1.0\n"
        );
        let p = dir.path().join("t.toml");
        std::fs::write(&p, text).unwrap();
        let job = wetgran::sweep::SweepFile::load(&p)
            .unwrap()
            .expand()
            .unwrap()
            .remove(0);
        let c = serde_json::to_value(&job.spec.scene.contact).unwrap();
        (c.get("restitution_speed").cloned(), job.id)
    };
    let (speed, _) = sweep("restitution = 0.9", "time");
    assert_eq!(speed, Some(serde_json::json!("auto")));
    let (speed, _) = sweep("damping = 1e-4", "time");
    assert_eq!(speed, None);
    let (speed, _) = sweep("restitution = 0.9", "event");
    assert_eq!(speed, None);
    let (speed, _) = sweep("restitution = 0.9\nrestitution_speed = 2.5", "time");
    assert_eq!(speed, Some(serde_json::json!(2.5)));
}

/// The location-change observer is off unless asked for, and a job spec names the choice: left
/// out it reads `false`; `classify.mobility = "location_changes"` turns it on (another job: its
/// observables hold `f_lc`); `location_changes = true` spelled out is the same job as that (the
/// thresholds are not part of the id).
#[test]
fn a_job_spec_names_whether_it_counts_location_changes() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let axes = "[[axis]]\nkey = \"gamma\"\nvalues = [2.0]\n";
    let job = |header: &str| {
        load(dir.path(), &sweep_text(header, axes))
            .expand()
            .unwrap()
            .remove(0)
    };
    let default = job("");
    assert_eq!(default.spec.scene.observe.location_changes, Some(false));
    assert!(
        default
            .spec
            .canonical_json()
            .contains("\"location_changes\":false")
    );
    let by_classifier = job("[classify]\nmobility = \"location_changes\"");
    assert_eq!(
        by_classifier.spec.scene.observe.location_changes,
        Some(true)
    );
    assert_ne!(by_classifier.id, default.id);
    let by_hand = job("[observe]\nlocation_changes = true");
    assert_eq!(by_hand.spec.scene.observe.location_changes, Some(true));
    assert_eq!(by_hand.id, by_classifier.id);
    // Switched off by hand while the classifier reads f_lc: an error naming the key.
    let e = err(
        dir.path(),
        &sweep_text(
            "[observe]\nlocation_changes = false\n[classify]\nmobility = \"location_changes\"",
            axes,
        ),
    );
    assert!(e.contains("observe.location_changes"), "{e}");
}

/// Regression: three message slips and two gaps of sweep files. `initial.start = "a|b"` lost
/// its reason (every line with a `|` was taken for TOML's source snippet); a `[convergence]`
/// error named the base scene file without a line; `replicas = 4294967297` was refused with the
/// range of a `u32` instead of the key's; a name starting with `-` was accepted (and printed in
/// hints that the parser then read as an option); `E* = 1e-20` was accepted (its floor moves
/// by 1.9e-21 d, inside the wall solvers' tolerance).
#[test]
fn regression_sweep_file_errors_keep_their_reason_line_and_range() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "tiny.toml", TINY_SCENE);
    let file = d.join("bad.toml").display().to_string();
    let cases: Vec<(String, &str, Vec<&str>)> = vec![
        (
            sweep_text("[scene.initial]\nstart = \"a|b\"", ""),
            ":5",
            vec!["key `initial.start`", "unknown variant `a|b`", "`hot`"],
        ),
        (
            sweep_text(
                "",
                "[[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"a|b\"]\n",
            ),
            ":6",
            vec!["unknown variant `a|b`"],
        ),
        // Without `periods` the table joins the scene; with it, it is read after conversion.
        (
            sweep_text("", "[convergence]\nmax_periods = 10\nbogus = 3\n"),
            ":7",
            vec!["key `convergence.bogus`", "unknown field `bogus`"],
        ),
        (
            sweep_text(
                "periods = 20",
                "[convergence]\nmax_periods = 40\nbogus = 3\n",
            ),
            ":7",
            vec!["key `convergence.bogus`", "unknown field `bogus`"],
        ),
        (
            sweep_text("periods = 20", "\n[convergence]\nblocks = 100\n"),
            ":7",
            vec!["key `convergence.blocks`"],
        ),
        (
            sweep_text("replicas = 4294967297", ""),
            ":4",
            vec![
                "key `sweep.replicas`",
                "= 4294967297 is out of range: must be in [1, 10000]",
            ],
        ),
        (
            sweep_text("[refine]\nbudget = 10\nmax_replicas = 4294967297", ""),
            ":6",
            vec![
                "key `refine.max_replicas`",
                "must be in [sweep.replicas = 1, 10000]",
            ],
        ),
        (
            "[sweep]\nname = \"-rf\"\nbase = \"tiny.toml\"\n".to_string(),
            ":2",
            vec!["key `sweep.name`", "must not start with '-'"],
        ),
        (
            "[sweep]\nname = \"..\"\nbase = \"tiny.toml\"\n".to_string(),
            ":2",
            vec!["key `sweep.name`"],
        ),
        (
            sweep_text("", "[[axis]]\nkey = \"e_star\"\nvalues = [2.0, 1e-20]\n"),
            ":6",
            vec![
                "key `drive.e_star`",
                "= 1e-20 is out of range",
                "must be 0 or >= 1e-6 d",
            ],
        ),
    ];
    for (text, line, wants) in cases {
        let e = err(d, &text);
        assert!(
            e.starts_with(&format!("{file}{line}:")),
            "{e}\n--- for:\n{text}"
        );
        for want in wants {
            assert!(e.contains(want), "{want:?} missing: {e}\n--- for:\n{text}");
        }
    }
}
