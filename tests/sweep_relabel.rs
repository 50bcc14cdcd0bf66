//! Sweep-level classification (`run::relabel`): the homogeneous points of a line of constant
//! Gamma are labelled fluid or gas by the line's jump (elastic) or inflection (inelastic) of
//! `T_g / E_cb(E*)` where it stands out of the stored errors; a line without one keeps the
//! per-point labels and says so; points of lines too short keep the per-point fallback and say
//! so; replicas (other seeds) belong to their point's line.

use serde_json::{Value, json};
use wetgran::run::relabel::{MIN_LINE_POINTS, relabel};
use wetgran::store::PointRow;
use wetgran::sweep::JobSpec;
use wetgran::sweep::spec::SPEC_FORMAT;
use wetgran_core::observe::classify::FluidGasFrom;
use wetgran_core::observe::convergence::{BlockTest, Convergence};
use wetgran_core::observe::{Phase, run_observed};
use wetgran_core::scene::Scene;

fn scene(gamma: f64, e_star: f64, restitution: f64, seed: u64) -> Scene {
    Scene::from_toml_str(
        &format!(
            r#"
dimension = 2
gravity = 1.0
[box]
size = [20.0, 9.0]
boundary = ["periodic", "wall"]
[particles]
count = 20
[contact]
restitution = {restitution}
[capillary]
model = "thin_thread"
s_crit = 0.0711
e_cb = 0.2844
[drive]
kind = "sine"
gamma = {gamma}
e_star = {e_star}
[engine]
min_rebound_speed = 0.03
[initial]
temperature_over_ecb = 20.0
seed = {seed}
[run]
duration = 2.0
[observe]
mobility_lag = 0.5
"#
        ),
        "relabel test",
    )
    .expect("valid scene")
}

/// Observables of a homogeneous mobile state at `T_g / E_cb = t`: a real short run's record
/// with a flat profile and the temperature set.
fn observables(template: &Value, t: f64) -> Value {
    let mut o = template.clone();
    o["granular_temperature_reduced"] = json!(t);
    o["mobility"]["diffusion"] = json!(0.5);
    let bins = o["profiles"]["n_cb"].as_array().unwrap().len();
    o["profiles"]["n_cb"] = json!(vec![1.0; bins]);
    o["profiles"]["packing"] = json!(vec![0.5; bins]);
    o["profiles"]["delta_n_cb"] = json!(0.0);
    o["profiles"]["delta_n_area"] = json!(0.0);
    o
}

/// `o` with a stored block error of its temperature, `rel` of its value (as a run to
/// stationarity stores it).
fn with_error(mut o: Value, rel: f64) -> Value {
    let t = o["granular_temperature_reduced"].as_f64().unwrap();
    let c = Convergence {
        converged: true,
        ending: None,
        window_start: 0.0,
        window_end: 2.0,
        checks: 1,
        first_check: 2.0,
        cap: 2.0,
        blocks: 4,
        sigmas: 3.0,
        rel_tolerance: 0.02,
        tests: vec![BlockTest {
            quantity: wetgran_core::observe::trend::TEMPERATURE.into(),
            mean: t,
            standard_error: rel * t,
            block_means: vec![t; 4],
            block_errors: vec![2.0 * rel * t; 4],
            max_pair_sigmas: 0.0,
            drift: 0.0,
            drift_error: 0.0,
            tolerance: 0.02 * t,
            agree: true,
            no_trend: true,
        }],
    };
    o["convergence"] = serde_json::to_value(c).unwrap();
    o
}

fn point(k: usize, scene: Scene, obs: Value) -> PointRow {
    PointRow {
        point: k as i64,
        replica: 0,
        coords: vec![],
        job_id: format!("job{k}"),
        status: "done".into(),
        spec: JobSpec {
            format: SPEC_FORMAT,
            scene,
            start_from: None,
        },
        attempts: 1,
        last_error: None,
        phase: Some("g".into()),
        decided_on: None,
        observables: Some(obs),
        simulated_time: Some(2.0),
        wall_seconds: Some(0.1),
        events: Some(1),
        finished_at: Some(0.0),
        result_owner: None,
        trend: None,
    }
}

#[test]
fn lines_of_constant_gamma_decide_fluid_versus_gas() {
    let template =
        serde_json::to_value(run_observed(&scene(30.0, 1.0, 1.0, 1), &mut |_| {}).observables)
            .unwrap();
    let mut rows = Vec::new();
    // Elastic line at Gamma = 30: T jumps thirty-fold between E* = 1 and 1.5 (errors of 1 %
    // stored). The per-point fallback (gas above T = 2) would call E* = 1 (T = 2.5) a gas.
    let elastic = [
        (0.5, 0.6),
        (0.7, 1.2),
        (1.0, 2.5),
        (1.5, 80.0),
        (2.0, 120.0),
    ];
    for (e, t) in elastic {
        rows.push(point(
            rows.len(),
            scene(30.0, e, 1.0, 1),
            with_error(observables(&template, t), 0.01),
        ));
    }
    // A replica (seed 2) of E* = 1 on the same line.
    rows.push(point(
        rows.len(),
        scene(30.0, 1.0, 1.0, 2),
        with_error(observables(&template, 2.4), 0.01),
    ));
    // Inelastic line at Gamma = 10: a sigmoid in log-log with its inflection at E* = 3.
    let e0: f64 = 3.0;
    for k in 0..8 {
        let e = 0.5 * 1.5f64.powi(k);
        let t = (0.5 + 2.0 * ((e.ln() - e0.ln()) / 0.6).tanh()).exp();
        rows.push(point(
            rows.len(),
            scene(10.0, e, 0.9, 1),
            with_error(observables(&template, t), 0.01),
        ));
    }
    // A line too short (Gamma = 5, two points): per-point fallback.
    for (e, t) in [(1.0, 1.0), (3.0, 3.0)] {
        rows.push(point(
            rows.len(),
            scene(5.0, e, 1.0, 1),
            observables(&template, t),
        ));
    }
    // The elastic line of Gamma = 30 again at Gamma = 20, without stored errors (results from
    // before the run-length policy): five points cannot estimate their scatter past the jump,
    // so the line has no transition and keeps its per-point labels.
    for (e, t) in elastic {
        rows.push(point(
            rows.len(),
            scene(20.0, e, 1.0, 1),
            observables(&template, t),
        ));
    }
    const { assert!(MIN_LINE_POINTS > 2) };
    let labels = relabel(&rows, None);
    assert_eq!(labels.len(), rows.len());
    let phase = |k: usize| labels[k].classification.phase;
    let from = |k: usize| labels[k].classification.decided_on.fluid_gas.clone();
    // Elastic line: f f f g g, the replica f.
    assert_eq!(
        (0..6).map(phase).collect::<Vec<_>>(),
        [Phase::F, Phase::F, Phase::F, Phase::G, Phase::G, Phase::F]
    );
    match from(2) {
        FluidGasFrom::Line {
            gamma,
            method,
            e_star_boundary,
        } => {
            assert!((gamma - 30.0).abs() < 1e-9);
            assert_eq!(method, "jump");
            assert!((e_star_boundary - 1.5f64.sqrt()).abs() < 1e-9);
        }
        other => panic!("{other:?}"),
    }
    // Inelastic line: fluid below the inflection, gas above, by the inflection.
    for k in 6..14 {
        let e = 0.5 * 1.5f64.powi((k - 6) as i32);
        assert!(
            matches!(&from(k), FluidGasFrom::Line { method, .. } if method == "inflection"),
            "{:?}",
            from(k)
        );
        if e < 2.5 {
            assert_eq!(phase(k), Phase::F, "E* = {e}");
        }
        if e > 3.5 {
            assert_eq!(phase(k), Phase::G, "E* = {e}");
        }
    }
    // The short line: per point.
    assert_eq!(from(14), FluidGasFrom::PointFallback);
    assert_eq!((phase(14), phase(15)), (Phase::F, Phase::G));
    // The line without errors: per-point labels (T above 2: g), and the line says why.
    assert_eq!(
        (16..21).map(phase).collect::<Vec<_>>(),
        [Phase::F, Phase::F, Phase::G, Phase::G, Phase::G]
    );
    for k in 16..21 {
        assert!(
            matches!(&from(k), FluidGasFrom::LineWithoutTransition { gamma, method, reason }
                if (gamma - 20.0).abs() < 1e-9 && method == "jump" && reason.contains("scatter")),
            "{:?}",
            from(k)
        );
    }
    // Old labels are reported for the caller to count changes.
    assert_eq!(labels[0].old.as_deref(), Some("g"));
}
