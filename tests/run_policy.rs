//! Run to a settled label: the `[convergence]` policy extends the same trajectory window by
//! window up to its cap and stores how it ended; the window always holds the mobility lag; its
//! keys are validated; engines rebuilt from a saved state continue the run (event engine to
//! round-off, time engine physically).

use wetgran_testkit as common;

use wetgran_core::observe::trend::TrendState;
use wetgran_core::observe::{Ending, Verdict, run_observed, run_observed_from};
use wetgran_core::scene::Scene;
use wetgran_core::sim::{EngineState, run_scene};

/// A wet 2D gas cooling without a drive (the standard `s_crit`, `E_cb`, eps 0.9): `T_g`
/// drifts down for the whole run. Mobility over a lag of 2 time units, so that a window of 8
/// holds it.
fn cooling(duration: f64, extra: &str) -> String {
    format!(
        "dimension = 2\n[box]\nsize = [30.0, 9.0]\n[particles]\ncount = 60\npolydispersity = 0.06\n\
         [contact]\nrestitution = 0.9\n[capillary]\nmodel = \"thin_thread\"\n\
         [initial]\ntemperature_over_ecb = 20.0\nseed = 2\n[run]\nduration = {duration:?}\n\
         [observe]\nmobility_lag = 2.0\n{extra}"
    )
}

#[test]
fn a_drifting_run_is_extended_on_one_trajectory_up_to_the_cap() {
    // No drive: one period is one time unit; no transient, so the window is the whole first
    // stretch, W = 8, and the cap 24 allows checks at 8, 16 and 24.
    let s = common::scene(&cooling(8.0, "[convergence]\nmax_periods = 24.0\n"));
    let run = run_observed(&s, &Default::default(), &mut |_| {});
    let o = &run.observables;
    let trend = o.trend.as_ref().expect("every run stores its trend");
    let c = trend.policy.expect("a policy run stores how it ended");
    let label = &run.classification;
    // A cooling run is never stationary (here a gas that bonds into a cooling solid by the cap).
    assert_ne!(
        label.verdict(),
        Verdict::Stationary,
        "{} {:?}: {}",
        label.phase,
        label.decided_on.settling,
        label.decided_on.reason
    );
    assert_eq!(c.checks, 3, "{c:?}");
    // Cooling can change a label: the run goes on to its cap and says why it stopped.
    assert_eq!(c.ending, Ending::Cap);
    assert_eq!(trend.state, TrendState::Cooling);
    assert_eq!((c.first_check, c.cap), (8.0, 24.0));
    assert!((o.window_start - 16.0).abs() < 1e-9 && (o.window_end - 24.0).abs() < 1e-9);
    let t = &trend.tests[0];
    assert_eq!(t.quantity, "temperature_reduced");
    assert!(t.drift < 0.0 && !t.no_trend, "cooling: {t:?}");
    assert_eq!(trend.tests.len(), 3, "wet: T_g, bridges and Delta n_cb");
    // The regions' quantities are tested too, over the whole history.
    assert!(
        trend
            .region_tests
            .iter()
            .any(|t| t.quantity == "member_fraction")
    );
    // 20 samples per period over the last window of 8: 161 samples, both ends included.
    assert_eq!(o.window_samples, 161);
    // The extension continued the same trajectory: the state equals a fixed run of 24.
    let mut fixed = s.clone();
    fixed.convergence = None;
    fixed.run.duration = 24.0;
    let plain = run_scene(&fixed);
    assert_eq!(plain.final_state, run.report.final_state);
    assert_eq!(plain.events, run.report.events);
    // The series covers the whole run, the stationary averages only the last window.
    let series = o.series.as_ref().unwrap();
    assert_eq!(series.time.first().copied(), Some(0.0));
    assert!((series.time.last().unwrap() - 24.0).abs() < 1e-9);
    // The trend survives the JSON round trip of the store.
    let json = serde_json::to_string(o).unwrap();
    let back: wetgran_core::observe::Observables = serde_json::from_str(&json).unwrap();
    assert_eq!(back.trend.as_ref(), Some(trend));
}

#[test]
fn the_window_holds_the_mobility_lag() {
    // A first check at 8 with the default lag of 10: the first window is lengthened to two
    // lags, and the mobility is measured, not replaced by the temperature.
    let s = common::scene(
        &cooling(8.0, "[convergence]\nmax_periods = 24.0\n")
            .replace("mobility_lag = 2.0", "mobility_lag = 10.0"),
    );
    let c = s.convergence.as_ref().unwrap().schedule(&s);
    assert_eq!((c.first_check, c.window), (20.0, 20.0));
    let run = run_observed(&s, &Default::default(), &mut |_| {});
    assert!(run.observables.mobility.is_some());
    assert_eq!(
        run.classification.decided_on.whole.mobility_from,
        wetgran_core::observe::Mobility::Displacement
    );
    // A fixed-length run cannot lengthen its window: the temperature decides, and the label is
    // flagged.
    let mut fixed = s.clone();
    fixed.convergence = None;
    let run = run_observed(&fixed, &Default::default(), &mut |_| {});
    assert!(run.observables.mobility.is_none());
    assert!(
        run.classification
            .decided_on
            .borderline
            .iter()
            .any(|b| b.contains("mobility not measured")),
        "{:?}",
        run.classification.decided_on.borderline
    );
}

#[test]
fn a_stationary_elastic_gas_stops_as_stationary_before_its_cap() {
    // Elastic dry disks without gravity in a periodic box: T_g is exactly constant.
    let s = common::scene(
        "dimension = 2\ngravity = 0.0\n[box]\nsize = [14.0, 14.0]\nboundary = [\"periodic\", \
         \"periodic\"]\n[particles]\ncount = 40\n[initial]\ntemperature = 1.0\nseed = 3\n\
         [run]\nduration = 2.0\n[observe]\nmobility_lag = 1.0\n\
         [convergence]\nmin_time = 10.0\nmax_periods = 40.0\n",
    );
    let run = run_observed(&s, &Default::default(), &mut |_| {});
    let trend = run.observables.trend.as_ref().unwrap();
    let c = trend.policy.unwrap();
    assert_eq!(
        run.classification.verdict(),
        Verdict::Stationary,
        "{:?}",
        run.classification.decided_on.settling
    );
    // Its mobility relaxes from the ballistic start over the first window or two; then every
    // quantity is flat and the run stops, well before the cap of 4 windows.
    assert!(
        c.checks <= 2,
        "{c:?} {:?}",
        run.classification.decided_on.settling
    );
    assert_eq!(c.ending, Ending::Stationary);
    assert_eq!(trend.state, TrendState::Stationary);
    assert!(trend.relaxed);
    // min_time beats run.duration: the checks are at 10, 20, ...
    assert!((run.report.simulated_time - 10.0 * c.checks as f64).abs() < 1e-9);
    assert_eq!(trend.tests.len(), 1, "dry: T_g only");
}

#[test]
fn fixed_length_runs_are_assessed_once_at_their_end() {
    let s = common::scene(&cooling(2.0, ""));
    let run = run_observed(&s, &Default::default(), &mut |_| {});
    let trend = run.observables.trend.as_ref().unwrap();
    assert!(trend.policy.is_none());
    assert!((trend.to - 2.0).abs() < 1e-9);
}

#[test]
fn convergence_keys_are_validated_with_their_names() {
    let bad = [
        ("blocks = 2", "convergence.blocks"),
        ("sigmas = 0.0", "convergence.sigmas"),
        ("rel_tolerance = 1.0", "convergence.rel_tolerance"),
        ("min_time = -1.0", "convergence.min_time"),
        ("min_periods = nan", "convergence.min_periods"),
        ("max_periods = 0.0", "convergence.max_periods"),
        ("window = 3", "window"),
    ];
    for (line, key) in bad {
        let text = cooling(8.0, &format!("[convergence]\nmin_periods = 6.0\n{line}\n"));
        let text = text.replace("min_periods = 6.0\nmin_periods", "min_periods");
        let e = Scene::from_toml_str(&text, "s.toml").unwrap_err();
        assert!(e.to_string().contains(key), "{line}: {e}");
    }
}

/// Checkpoint of the event engine: a run of 2t and a run of t, saved, restored and run t more
/// agree to round-off (predictions are recomputed from positions advanced to the common time,
/// which rounds differently; a few collisions later the difference is still ~1e-12).
#[test]
fn checkpoint_continues_the_event_trajectory() {
    let t = 1.0;
    let s = common::scene(&cooling(t, ""));
    let first = run_scene(&s);
    let state = first.final_state.clone().unwrap();
    assert!(
        !state.bridges.is_empty(),
        "the test needs bridges to restore"
    );
    // The state survives the store's JSON exactly.
    let state: EngineState = serde_json::from_str(&serde_json::to_string(&state).unwrap()).unwrap();
    let (cont, _) = run_observed_from(
        &s,
        Some(&state),
        &wetgran_core::sim::RunSettings::every_sample(),
        &mut |_| {},
    );
    let mut long = s.clone();
    long.run.duration = 2.0 * t;
    let whole = run_scene(&long);
    let (a, b) = (
        cont.report.final_state.as_ref().unwrap(),
        whole.final_state.as_ref().unwrap(),
    );
    assert_eq!(a.time, 2.0 * t);
    // The same physical events; stale predictions (`invalidated`) depend on when they were
    // made, which the restore changes.
    let physical = |c: &wetgran_core::sim::EventCounts| {
        let mut c = c.clone();
        c.invalidated = 0;
        c
    };
    assert_eq!(physical(&a.counts), physical(&b.counts), "the same events");
    assert_eq!(a.bridges, b.bridges, "the same bridges");
    let dev = a
        .positions
        .iter()
        .zip(&b.positions)
        .chain(a.velocities.iter().zip(&b.velocities))
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(dev < 1e-9, "largest difference {dev:e}");
    // The ledger continues: the bookkeeping of the continued run matches the whole run.
    let (la, lb) = (&cont.report.energy_final, &whole.energy_final);
    assert!((la.total_accounted() - lb.total_accounted()).abs() < 1e-9);
    assert!((la.dissipated_ruptures - lb.dissipated_ruptures).abs() < 1e-9);
    // Observation starts at the state's time: the window is [t + transient, 2t].
    assert!((cont.observables.window_end - 2.0 * t).abs() < 1e-12);
    assert!(cont.observables.window_start >= t);
}

/// Checkpoint of the time engine: the restored engine has the saved positions, velocities,
/// bridges and energy (physical continuity; the Gear derivatives beyond the velocity are
/// re-initialised, so it is not the uninterrupted trajectory), and its ledger stays balanced.
#[test]
fn checkpoint_restores_the_time_engine_continuously() {
    let text = "dimension = 2\ngravity = 1.0\n[box]\nsize = [40.0, 9.0]\nboundary = [\"periodic\", \
                \"wall\"]\n[particles]\ncount = 120\npolydispersity = 0.06\n\
                [capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\ne_cb = 0.2844\n\
                [initial]\ntemperature_over_ecb = 2.0\nseed = 5\n[run]\nduration = 2.0\n\
                [engine]\nkind = \"time\"\n";
    let s = common::scene(text);
    let first = run_scene(&s);
    let state = first.final_state.clone().unwrap();
    assert!(
        !state.bridges.is_empty(),
        "the test needs bridges to restore"
    );
    // A zero-length continuation reports the restored state itself.
    let mut zero = s.clone();
    zero.run.duration = state.time;
    let restored = wetgran_core::sim::run_scene_watched(
        &zero,
        Some(&state),
        &wetgran_core::sim::RunSettings::every_sample(),
        1.0,
        &mut NoWatch,
        &mut |_| {},
    );
    let r = restored.final_state.unwrap();
    assert_eq!(r.time, state.time);
    assert_eq!(r.bridges, state.bridges);
    // Counts continue; contacts overlapping at the state count as new onsets.
    assert_eq!(r.counts.bridge_formations, state.counts.bridge_formations);
    assert_eq!(r.counts.bridge_ruptures, state.counts.bridge_ruptures);
    assert!(r.counts.pair_collisions >= state.counts.pair_collisions);
    let dev = r
        .positions
        .iter()
        .zip(&state.positions)
        .chain(r.velocities.iter().zip(&state.velocities))
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(dev < 1e-12, "{dev:e}");
    let (e0, e1) = (&first.energy_final, &restored.energy_initial);
    assert!((e0.kinetic - e1.kinetic).abs() < 1e-9 * e0.kinetic.abs().max(1.0));
    assert!((e0.potential - e1.potential).abs() < 1e-9 * e0.potential.abs().max(1.0));
    assert!((e0.total_accounted() - e1.total_accounted()).abs() < 1e-9 * e0.potential.abs());
    // Running on: time continues, the ledger stays as balanced as in the first stretch.
    let (cont, _) = run_observed_from(
        &s,
        Some(&state),
        &wetgran_core::sim::RunSettings::every_sample(),
        &mut |_| {},
    );
    assert!((cont.report.simulated_time - 2.0 * state.time).abs() < 1e-9);
    assert!(
        cont.report.energy_bookkeeping_error.abs()
            < 10.0 * first.energy_bookkeeping_error.abs().max(1e-6),
        "{} vs {}",
        cont.report.energy_bookkeeping_error,
        first.energy_bookkeeping_error
    );
}

struct NoWatch;
impl wetgran_core::sim::Watcher for NoWatch {
    fn observe(&mut self, _: &wetgran_core::sim::Frame) {}
}

mod store_inspect;
mod sweep_common;

/// The sweep `cool` of two cooling gases that never settle, capped at 8 periods, written to
/// `dir` and run with one worker; returns its database.
fn cool_sweep_run(dir: &std::path::Path) -> std::path::PathBuf {
    use sweep_common::*;
    write(dir, "cool.toml", &cooling(4.0, ""));
    let sweep = write(
        dir,
        "cool_sweep.toml",
        "[sweep]\nname = \"cool\"\nbase = \"cool.toml\"\n[observe]\ntransient_periods = 0.0\n\
         [convergence]\nmax_periods = 8.0\n\
         [[axis]]\nkey = \"contact.restitution\"\nvalues = [0.8, 0.9]\n",
    );
    let db = dir.join("w.sqlite");
    let (sweep_s, db_s) = (sweep.to_str().unwrap(), db.to_str().unwrap());
    let o = run(&["sweep", "run", sweep_s, "--db", db_s, "--jobs", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    db
}

/// A sweep with a policy stores the verdict and a checkpoint with every result; `sweep status`
/// counts the unconverged; `sweep resume --extend` continues them from their checkpoints (time
/// goes on, bridges carried over) and replaces their results.
#[test]
fn unconverged_jobs_are_counted_and_extended_from_their_checkpoints() {
    use sweep_common::*;
    let dir = tempfile::tempdir().unwrap();
    let db = cool_sweep_run(dir.path());
    let db_s = db.to_str().unwrap();
    let store = wetgran::store::Store::open_existing(&db).unwrap();
    let s = store.sweep("cool").unwrap();
    let before = store.points(s.id).unwrap();
    assert_eq!(
        wetgran::store::unconverged_summaries(&store.point_summaries(&s).unwrap()),
        (2, 2),
        "cooling never settles"
    );
    // The trend state is stored in its column and shown. The gas cools, and as it cools its
    // grains cluster (Delta n_cb rises): cooling or coarsening, never stationary.
    let trends: Vec<_> = before.iter().map(|p| p.trend).collect();
    assert!(
        trends
            .iter()
            .all(|t| matches!(t, Some(TrendState::Cooling | TrendState::Coarsening))),
        "{trends:?}"
    );
    let o = run(&["sweep", "status", "--db", db_s]);
    assert!(
        stdout(&o).contains(
            "0 of 2 result(s) passed the run policy's convergence test, 2 stopped at its cap"
        ),
        "{}",
        stdout(&o)
    );
    assert!(stdout(&o).contains("  trend  "), "{}", stdout(&o));
    // Runs at their cap: the hint to extend them (left out where none is, issue 45).
    assert!(
        stdout(&o).contains("stopped at its cap (`sweep resume --extend` runs those further"),
        "{}",
        stdout(&o)
    );
    let o = run(&["show", &before[0].job_id, "--db", db_s]);
    let shown = format!("trend       {}", before[0].trend.unwrap());
    assert!(stdout(&o).contains(&shown), "{}", stdout(&o));
    let states: Vec<EngineState> = before
        .iter()
        .map(|p| {
            store
                .checkpoint(&p.job_id)
                .unwrap()
                .expect("a checkpoint per result")
        })
        .collect();
    for (p, st) in before.iter().zip(&states) {
        assert_eq!(
            Some(st.time),
            p.simulated_time,
            "the checkpoint is the final state"
        );
        assert_eq!(st.time, 8.0);
    }
    drop(store);
    let o = run(&["sweep", "resume", "cool", "--db", db_s, "--extend", "16"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("extended 2 unconverged job(s)"),
        "{}",
        both(&o)
    );
    let store = wetgran::store::Store::open_existing(&db).unwrap();
    let after = store.points(s.id).unwrap();
    for ((p, q), old) in before.iter().zip(&after).zip(&states) {
        assert_eq!(p.job_id, q.job_id, "the same job, its result replaced");
        let t = q.simulated_time.unwrap();
        assert!(t > 8.0 && t <= 16.0 + 1e-9, "{t}");
        let o = q.observables.as_ref().unwrap();
        assert!(
            o["window_start"].as_f64().unwrap() >= 8.0,
            "{}",
            o["window_start"]
        );
        let new = store.checkpoint(&q.job_id).unwrap().unwrap();
        assert_eq!(new.time, t);
        // Counts and the ledger continue from the old checkpoint.
        assert!(new.counts.pair_collisions > old.counts.pair_collisions);
        assert!(new.ledger.dissipated_restitution > old.ledger.dissipated_restitution);
    }
    assert_eq!(store.runs_per_job().unwrap().len(), 2);
    drop(store);
    // The cap in time units: the same jobs go on to at most 24 (undriven: one period is one
    // time unit, so 24 periods would be the same cap; the flags exclude each other).
    let o = run(&[
        "sweep",
        "resume",
        "cool",
        "--db",
        db_s,
        "--extend",
        "24",
        "--extend-time",
        "24",
    ]);
    assert!(!o.status.success(), "both caps at once are refused");
    let o = run(&[
        "sweep",
        "resume",
        "cool",
        "--db",
        db_s,
        "--extend-time",
        "24",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let store = wetgran::store::Store::open_existing(&db).unwrap();
    let times: Vec<f64> = store
        .points(s.id)
        .unwrap()
        .iter()
        .map(|q| q.simulated_time.unwrap())
        .collect();
    // A job the first extension left unconverged (the cooling gas stays so) went on past 16.
    assert!(times.iter().all(|&t| t <= 24.0 + 1e-9), "{times:?}");
    assert!(times.iter().any(|&t| t > 16.0 + 1e-9), "{times:?}");
    let o = run(&["sweep", "resume", "cool", "--db", db_s, "--extend-time=-1"]);
    assert!(
        stderr(&o).contains("--extend-time = -1 is out of range"),
        "{}",
        stderr(&o)
    );
}

/// The cold start: a bonded bed at rest (bridges between the lattice's close pairs, T_g = 0)
/// that stays cold and bonded where the hot start of the same scene is a hot gas at first.
#[test]
fn the_cold_start_is_a_bonded_bed_at_rest() {
    let text = cooling(1.0, "");
    let hot = common::scene(&text);
    let cold = common::scene(&text.replace("seed = 2\n", "seed = 2\nstart = \"cold\"\n"));
    assert_eq!(cold.initial.start, wetgran_core::scene::StartMode::Cold);
    let state = wetgran_core::sim::initial::cold_state(&cold);
    // Every listed pair is closer than s_crit, and no close pair is missing (brute force).
    let s_crit = cold.s_crit();
    let gap = |i: usize, j: usize| {
        let dx = state.positions[2 * i] - state.positions[2 * j];
        let dx = dx - 30.0 * (dx / 30.0).round();
        let dz = state.positions[2 * i + 1] - state.positions[2 * j + 1];
        (dx * dx + dz * dz).sqrt() - state.radii[i] - state.radii[j]
    };
    let mut expect = Vec::new();
    for i in 0..state.len() {
        for j in i + 1..state.len() {
            if gap(i, j) < s_crit {
                expect.push((i, j));
            }
        }
    }
    assert!(!expect.is_empty());
    assert_eq!(state.bridges, expect);
    let c = run_scene(&cold);
    let h = run_scene(&hot);
    assert_eq!(c.samples[0].bridges, expect.len(), "starts bonded");
    assert_eq!(c.samples[0].granular_temperature, 0.0, "starts at rest");
    assert_eq!(h.samples[0].bridges, 0);
    assert!(c.bridges >= expect.len() / 2, "still bonded: {}", c.bridges);
    let e_cb = cold.e_cb();
    assert!(
        c.granular_temperature / e_cb < 0.5 && h.granular_temperature / e_cb > 2.0,
        "cold {} hot {}",
        c.granular_temperature / e_cb,
        h.granular_temperature / e_cb
    );
    assert!(c.invariant_violation.is_none());
}

/// Hot and cold start compared by an `initial.start` axis: without a drive the cold bed stays
/// a solid while the hot start is still a cooling gas in which bonded clusters form (28 % of
/// its dense bins' grains are cluster members, at T_g/E_cb 1.6 against 7.4 in the rest: fgc),
/// so the point is hysteretic, and `sweep status` says so.
#[test]
fn hot_and_cold_starts_that_disagree_are_hysteretic() {
    use sweep_common::*;
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "cool.toml", &cooling(2.0, ""));
    let sweep = write(
        dir.path(),
        "hc_sweep.toml",
        "[sweep]\nname = \"hc\"\nbase = \"cool.toml\"\n[observe]\ntransient_periods = 1.0\nmobility_lag = 0.25\n\
         [[axis]]\nkey = \"initial.start\"\nvalues = [\"hot\", \"cold\"]\n",
    );
    let db = dir.path().join("w.sqlite");
    let (sweep_s, db_s) = (sweep.to_str().unwrap(), db.to_str().unwrap());
    let o = run(&["sweep", "run", sweep_s, "--db", db_s, "--jobs", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let store = wetgran::store::Store::open_existing(&db).unwrap();
    let s = store.sweep("hc").unwrap();
    let groups = wetgran::store::hysteresis::by_start(&s.axes, &store.point_summaries(&s).unwrap());
    assert_eq!(groups.len(), 1, "{groups:?}");
    let g = &groups[0];
    use wetgran_core::scene::StartMode;
    assert_eq!(g.by_start[&StartMode::Cold], vec!["s".to_string()], "{g:?}");
    assert_eq!(
        g.by_start[&StartMode::Hot],
        vec!["fgc".to_string()],
        "{g:?}"
    );
    assert!(g.hysteretic);
    let o = run(&["sweep", "status", "--db", db_s]);
    assert!(
        stdout(&o).contains("1 of 1 point(s) hysteretic"),
        "{}",
        stdout(&o)
    );
    // The point is listed with the labels of each start.
    assert!(stdout(&o).contains("hot fgc, cold s"), "{}", stdout(&o));
}
