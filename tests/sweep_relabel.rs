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
use wetgran_core::observe::convergence::BlockTest;
use wetgran_core::observe::{Phase, run_observed};
use wetgran_core::scene::Scene;

fn scene(gamma: f64, e_star: f64, restitution: f64, seed: u64) -> Scene {
    Scene::from_toml_str(
        &scene_toml(gamma, e_star, restitution, seed),
        "relabel test",
    )
    .expect("valid scene")
}

/// The scene file of [`scene`].
fn scene_toml(gamma: f64, e_star: f64, restitution: f64, seed: u64) -> String {
    format!(
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
    )
}

/// Observables of a homogeneous mobile state at `T_g / E_cb = t`: a real short run's record
/// with a flat profile, the temperature set and no stored error of it.
fn observables(template: &Value, t: f64) -> Value {
    let mut o = template.clone();
    o["granular_temperature_reduced"] = json!(t);
    o["mobility"]["diffusion"] = json!(0.5);
    let bins = o["profiles"]["n_cb"].as_array().unwrap().len();
    o["profiles"]["n_cb"] = json!(vec![1.0; bins]);
    o["profiles"]["packing"] = json!(vec![0.5; bins]);
    o["profiles"]["delta_n_cb"] = json!(0.0);
    o["profiles"]["delta_n_area"] = json!(0.0);
    // No stored temperature error unless `with_error` adds one.
    o["trend"]["tests"] = json!([]);
    o
}

/// `o` with a stored block error of its temperature, `rel` of its value (as the trend of a run
/// stores it).
fn with_error(mut o: Value, rel: f64) -> Value {
    let t = o["granular_temperature_reduced"].as_f64().unwrap();
    let tests = vec![BlockTest {
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
    }];
    o["trend"]["tests"] = serde_json::to_value(tests).unwrap();
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
    let template = serde_json::to_value(
        run_observed(&scene(30.0, 1.0, 1.0, 1), &Default::default(), &mut |_| {}).observables,
    )
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
}

/// The temperatures of the two elastic lines of the stored sweep below (errors of 1 %): by the
/// line rule `f f f g g`; the per-point fallback calls `E* = 1` (T = 2.5) a gas, as it does on
/// a line too short to decide.
const LINE: [(f64, f64); 5] = [
    (0.5, 0.6),
    (0.7, 1.2),
    (1.0, 2.5),
    (1.5, 80.0),
    (2.0, 120.0),
];

/// A sweep over two lines of constant Gamma (30 and 20) of [`LINE`]'s `E*`, in a new database.
fn stored_sweep(path: &std::path::Path) -> (wetgran::store::Store, wetgran::store::SweepRow) {
    let toml = scene_toml(30.0, 1.0, 1.0, 1);
    let scene_part: String = toml
        .lines()
        .map(|l| match l.strip_prefix('[') {
            Some(rest) if !rest.starts_with('[') => format!("[scene.{rest}"),
            _ => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let e: Vec<String> = LINE.iter().map(|(e, _)| e.to_string()).collect();
    let text = format!(
        "[sweep]\nname = \"inc\"\nperiods = 10\n[scene]\n{scene_part}\n[[axis]]\nkey = \"gamma\"\n\
         values = [30.0, 20.0]\n[[axis]]\nkey = \"e_star\"\nvalues = [{}]\n",
        e.join(", ")
    );
    let file = wetgran::sweep::SweepFile::parse(&text, std::path::Path::new("inc.toml")).unwrap();
    let store = wetgran::store::Store::open(path).unwrap();
    let row = store
        .register_sweep(&file, &file.expand().unwrap())
        .unwrap();
    (store, row)
}

/// `(Gamma, index in LINE)` of a claimed job.
fn where_on_line(claim: &wetgran::store::Claim) -> (f64, usize) {
    let (g, e) = wetgran::run::relabel::gamma_e_star(&claim.spec.scene).unwrap();
    let k = LINE
        .iter()
        .position(|(x, _)| (x - e).abs() < 1e-9 * x)
        .unwrap();
    (g, k)
}

/// Claims every job of the sweep, then stores the results of those `pick` selects, in the
/// order given, each labelled per point as the runner labels it.
fn finish_some(
    store: &wetgran::store::Store,
    claims: &[wetgran::store::Claim],
    template: &Value,
    pick: impl Fn(f64, usize) -> bool,
) {
    for c in claims {
        let (g, k) = where_on_line(c);
        if !pick(g, k) {
            continue;
        }
        let obs = with_error(observables(template, LINE[k].1), 0.01);
        let parsed: wetgran_core::observe::Observables =
            serde_json::from_value(obs.clone()).unwrap();
        let c1 = wetgran_core::observe::classify(&parsed, &c.spec.scene.classify);
        let result = wetgran::sweep::job::JobResult {
            phase: Some(c1.phase.to_string()),
            decided_on: Some(serde_json::to_value(&c1.decided_on).unwrap()),
            observables: obs,
            simulated_time: 2.0,
            wall_seconds: 0.1,
            events: 1,
            checkpoint: None,
        };
        assert!(store.finish(c, &result).unwrap());
    }
}

fn claim_all(
    store: &wetgran::store::Store,
    row: &wetgran::store::SweepRow,
) -> Vec<wetgran::store::Claim> {
    std::iter::from_fn(|| store.claim(&[row.id]).unwrap()).collect()
}

type Labels = std::collections::BTreeMap<String, (Option<String>, Option<Value>)>;

fn stored_labels(store: &wetgran::store::Store, row: &wetgran::store::SweepRow) -> Labels {
    store
        .points(row.id)
        .unwrap()
        .into_iter()
        .map(|p| (p.job_id, (p.phase, p.decided_on)))
        .collect()
}

/// The relabelling after a run (`relabel_changed`) reads only the lines holding results stored
/// since the last one, and whatever order the results came in, with a crash between storing
/// and relabelling or not, the stored labels end equal to a relabelling of every result.
#[test]
fn relabelling_only_the_changed_lines_equals_relabelling_everything() {
    use wetgran::run::relabel::{relabel_changed, relabel_stored};
    let template = serde_json::to_value(
        run_observed(&scene(30.0, 1.0, 1.0, 1), &Default::default(), &mut |_| {}).observables,
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();

    // All results at once, then one relabelling of what changed.
    let (a, row_a) = stored_sweep(&dir.path().join("a.sqlite"));
    let claims = claim_all(&a, &row_a);
    assert_eq!(claims.len(), 2 * LINE.len());
    finish_some(&a, &claims, &template, |_, _| true);
    assert_eq!(relabel_changed(&a, &row_a).unwrap().results, 2 * LINE.len());
    let want = stored_labels(&a, &row_a);
    // A full relabelling finds nothing to change.
    assert_eq!(
        relabel_stored(&a, std::slice::from_ref(&row_a), None)
            .unwrap()
            .changed(),
        0
    );
    assert_eq!(stored_labels(&a, &row_a), want);
    let e1 = |claims: &[wetgran::store::Claim], g: f64| {
        claims
            .iter()
            .find(|c| where_on_line(c) == (g, 2))
            .unwrap()
            .job_id
            .clone()
    };
    assert_eq!(want[&e1(&claims, 30.0)].0.as_deref(), Some("f"));

    // The other order: the low E* of both lines first (lines too short: per point), then the
    // rest of Gamma = 30, then the rest of Gamma = 20, relabelling after each batch.
    let (b, row_b) = stored_sweep(&dir.path().join("b.sqlite"));
    let mut claims = claim_all(&b, &row_b);
    claims.reverse();
    finish_some(&b, &claims, &template, |_, k| k < 3);
    assert_eq!(relabel_changed(&b, &row_b).unwrap().results, 6);
    assert_eq!(
        stored_labels(&b, &row_b)[&e1(&claims, 30.0)].0.as_deref(),
        Some("g"),
        "on a line too short E* = 1 is labelled per point"
    );
    finish_some(&b, &claims, &template, |g, k| g > 25.0 && k >= 3);
    // The two new results and the three earlier ones of their line; Gamma = 20 untouched.
    let r = relabel_changed(&b, &row_b).unwrap();
    assert_eq!(r.results, LINE.len());
    assert_eq!(r.changes.get(&("g".into(), "f".into())), Some(&1));
    assert_eq!(
        stored_labels(&b, &row_b)[&e1(&claims, 20.0)].0.as_deref(),
        Some("g")
    );
    finish_some(&b, &claims, &template, |g, k| g < 25.0 && k >= 3);
    assert_eq!(relabel_changed(&b, &row_b).unwrap().results, LINE.len());
    assert_eq!(stored_labels(&b, &row_b), want);
    // Nothing stored since: nothing read.
    assert_eq!(relabel_changed(&b, &row_b).unwrap().results, 0);

    // A crash between storing the second batch and relabelling it: the next relabelling (here
    // in a new process's store) still sees those results.
    let path_c = dir.path().join("c.sqlite");
    let (c, row_c) = stored_sweep(&path_c);
    let claims = claim_all(&c, &row_c);
    finish_some(&c, &claims, &template, |_, k| k < 3);
    relabel_changed(&c, &row_c).unwrap();
    finish_some(&c, &claims, &template, |_, k| k >= 3);
    drop(c);
    let c = wetgran::store::Store::open(&path_c).unwrap();
    assert_eq!(relabel_changed(&c, &row_c).unwrap().results, 2 * LINE.len());
    assert_eq!(stored_labels(&c, &row_c), want);
}
