//! Tests of the reports' lean read path (`store::PointSummary`, issue 35): on prepared
//! databases, the summaries read from columns give every report (`sweep status` text, phase
//! maps, trust marks, chain-model note, hysteresis) that the full rows give. Here, not in
//! `store`, because they use the reports (a higher layer than the store).
use crate::boundary::{Extraction, Observation, phase_map_with};
use crate::report::boundaries_text::{chain_model_note, untrusted_points};
use crate::report::plot_phase::{Landmarks, chain_model_f_max};
use crate::store::{
    PointSummary, StateCounts, Store, SweepRow, axis_keeps_report_scene, unconverged_summaries,
};
use crate::sweep::SweepFile;
use crate::sweep::job::JobResult;
use std::sync::Arc;
use wetgran_core::observe::Verdict;
use wetgran_core::scene::StartMode;

/// A sweep over the quickstart's base scene with `axes` (TOML `[[axis]]` tables), two
/// replicas, registered in a new database; its jobs finished, failed or left running by
/// their claim order, with results whose verdicts and trends cover every case the reports
/// tell apart (converged, not converged, no verdict, the stationarity check of older results,
/// a JSON null verdict, each trend state).
fn prepared(dir: &std::path::Path, axes: &str) -> (Store, SweepRow) {
    std::fs::write(
        dir.join("shaken_wet_2d.toml"),
        include_str!("../../scenes/shaken_wet_2d.toml"),
    )
    .unwrap();
    let text = format!(
        "[sweep]\nname = \"lean\"\nbase = \"shaken_wet_2d.toml\"\nreplicas = 2\n\
         periods = 2\n[scene]\nparticles.count = 20\nbox.size = [7.0, 9.0]\n\
         [observe]\ntransient_periods = 1\nsamples_per_period = 20\n{axes}"
    );
    let file = SweepFile::parse(&text, &dir.join("lean.toml")).unwrap();
    let jobs = file.expand().unwrap();
    let store = Store::open(&dir.join("w.sqlite")).unwrap();
    let row = store.register_sweep(&file, &jobs).unwrap();
    // (trend state, verdict) of each kind of result; None: not stored.
    let kinds = [
        (Some("stationary"), Some("stationary")),
        (Some("heating"), Some("label_kept")),
        (Some("undecided"), Some("not_settled")),
        (None, Some("not_settled")),
        (None, Some("stationary")),
        (Some("cooling"), None),
        (Some("cooling"), Some("label_kept")),
        (None, None),
    ];
    let phases = ["g", "f", "s", "g", "fgc", "f", "s"];
    let mut k = 0;
    while let Some(claim) = store.claim(&[row.id]).unwrap() {
        if k % 11 == 5 {
            store.fail(&claim, "it broke", 0.25).unwrap();
        } else if k % 13 == 12 {
            // Left running: neither done nor failed.
        } else {
            let result = JobResult {
                phase: (k % 9 != 4).then(|| phases[k % phases.len()].to_string()),
                decided_on: kinds[k % kinds.len()]
                    .1
                    .map(|v| serde_json::json!({"settling": {"verdict": v, "regions": []}})),
                observables: match kinds[k % kinds.len()].0 {
                    Some(state) => serde_json::json!({"trend": {"state": state}}),
                    None => serde_json::json!({}),
                },
                simulated_time: 1.0 + k as f64,
                wall_seconds: 0.5 + k as f64,
                events: 3,
                checkpoint: None,
            };
            assert!(store.finish(&claim, &result).unwrap());
        }
        k += 1;
    }
    (store, row)
}

/// Asserts that the summaries read from the columns are those of the full rows, in every
/// field and in every report made of them.
fn assert_same_reports(store: &Store, row: &SweepRow) {
    let lean = store.point_summaries(row).unwrap();
    let full = store.points(row.id).unwrap();
    let of_full: Vec<PointSummary> = full.iter().map(PointSummary::of_row).collect();
    assert_eq!(lean.len(), full.len());
    // The full rows' own verdicts (what `Store::points` callers read) agree too.
    for ((a, b), p) in lean.iter().zip(&of_full).zip(&full) {
        assert_eq!(a.trust(), p.trust());
        assert_eq!(
            (
                a.point, a.replica, &a.coords, &a.job_id, &a.status, a.attempts
            ),
            (
                b.point, b.replica, &b.coords, &b.job_id, &b.status, b.attempts
            )
        );
        assert_eq!(
            (&a.last_error, a.start, &a.phase),
            (&b.last_error, b.start, &b.phase)
        );
        assert_eq!(
            (a.wall_seconds, a.trend, a.verdict, a.trust()),
            (b.wall_seconds, b.trend, b.verdict, b.trust()),
            "job {}",
            a.job_id
        );
        // What the reports read of the scene.
        assert_eq!(
            crate::boundary::drive_at(&a.scene, 3.0, 1.5),
            crate::boundary::drive_at(&b.scene, 3.0, 1.5)
        );
        assert_eq!(Landmarks::of(&a.scene), Landmarks::of(&b.scene));
        assert_eq!(chain_model_f_max(&a.scene), chain_model_f_max(&b.scene));
        assert_eq!(
            a.scene.shear_slabs().is_some(),
            b.scene.shear_slabs().is_some()
        );
    }
    let c = store.counts(row.id).unwrap();
    assert_eq!(StateCounts::of_summaries(&lean), c);
    let spent = store.time_spent(row.id).unwrap();
    let (again, spent_of_rows) = store.status_summaries(row).unwrap();
    assert_eq!(again.len(), lean.len());
    assert!(
        (spent - spent_of_rows).abs() < 1e-9,
        "{spent} {spent_of_rows}"
    );
    let input = |points| crate::report::sweep_text::StatusInput {
        sweep: row,
        counts: c,
        points,
        spent,
        cores: 2,
        running: &[],
        now: 0.0,
    };
    let status = crate::report::sweep_text::sweep_status_text(&input(&lean));
    assert_eq!(
        status,
        crate::report::sweep_text::sweep_status_text(&input(&of_full))
    );
    assert_eq!(
        unconverged_summaries(&lean),
        unconverged_summaries(&of_full)
    );
    for how in [
        Extraction::default(),
        Extraction {
            include_unconverged: true,
        },
    ] {
        let lean_obs: Vec<Observation> = lean.iter().map(Observation::of_summary).collect();
        let full_obs: Vec<Observation> = of_full.iter().map(Observation::of_summary).collect();
        let a = phase_map_with(&row.axes, &lean_obs, how).unwrap();
        let b = phase_map_with(&row.axes, &full_obs, how).unwrap();
        assert_eq!(
            serde_json::to_string(&a).unwrap(),
            serde_json::to_string(&b).unwrap()
        );
    }
    assert_eq!(untrusted_points(&lean), untrusted_points(&of_full));
    assert_eq!(chain_model_note(&lean), chain_model_note(&of_full));
    let hysteresis = crate::store::hysteresis::by_start(&row.axes, &lean);
    assert_eq!(
        hysteresis,
        crate::store::hysteresis::by_start(&row.axes, &of_full)
    );
}

const PLANE: &str = "[[axis]]\nkey = \"gamma\"\nvalues = [1.0, 4.0, 8.0]\n\
                     [[axis]]\nkey = \"e_star\"\nvalues = [0.5, 2.0]\n";

#[test]
fn summaries_give_the_reports_of_the_full_rows() {
    let dir = tempfile::tempdir().unwrap();
    let axes = format!("{PLANE}[[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"cold\"]\n");
    let (store, row) = prepared(dir.path(), &axes);
    let lean = store.point_summaries(&row).unwrap();
    assert_eq!(lean.len(), 24);
    // The cases the reports tell apart are all there.
    for status in ["done", "failed", "running"] {
        assert!(lean.iter().any(|p| p.status == status), "{status}");
    }
    for v in [
        Some(Verdict::Stationary),
        Some(Verdict::LabelKept),
        Some(Verdict::NotSettled),
        None,
    ] {
        assert!(
            lean.iter().any(|p| p.status == "done" && p.verdict == v),
            "{v:?}"
        );
    }
    assert!(lean.iter().any(|p| p.start == StartMode::Cold));
    assert!(lean.iter().any(|p| p.start == StartMode::Hot));
    // Axes that leave the scene as the base sets it: one scene for the sweep.
    assert!(lean.iter().all(|p| Arc::ptr_eq(&p.scene, &lean[0].scene)));
    assert_same_reports(&store, &row);
}

#[test]
fn axes_that_change_what_the_reports_read_give_each_job_its_own_scene() {
    assert!(!axis_keeps_report_scene("gravity"));
    assert!(!axis_keeps_report_scene("capillary.e_cb"));
    assert!(axis_keeps_report_scene("drive.gamma"));
    let dir = tempfile::tempdir().unwrap();
    let axes = format!("{PLANE}[[axis]]\nkey = \"particles.mass\"\nvalues = [1.0, 2.0]\n");
    let (store, row) = prepared(dir.path(), &axes);
    let lean = store.point_summaries(&row).unwrap();
    let full = store.points(row.id).unwrap();
    for (a, b) in lean.iter().zip(&full) {
        assert_eq!(a.scene.particles.mass, b.spec.scene.particles.mass);
    }
    assert!(lean.iter().any(|p| p.scene.particles.mass == 2.0));
    assert_same_reports(&store, &row);
}
