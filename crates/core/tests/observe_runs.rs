//! Observers on real short runs: a small version of the 2D standard wet system (docs/model.md 1:
//! `s_crit` 0.0711, `E_cb` 0.2844, `sigma_p` 0.06, eps 0.9, height 9, three layers) shaken at
//! Gamma < 1 with small E* is solid, strongly driven and dilute it is a gas; observing never
//! changes a trajectory; bookkeeping identities of the profiles and counts; stationarity flags a
//! cooling run; 3D runs observe neighbour shells.

use wetgran_testkit as common;

use wetgran_core::observe::settling::Direction;
use wetgran_core::observe::trend::TrendState;
use wetgran_core::observe::{Phase, Verdict, run_observed, run_observed_with_frame};
use wetgran_core::sim::RunSettings;
use wetgran_core::sim::run_scene;
use wetgran_core::sim::threads::Threads;

/// The 2D standard wet system in a box `lx` wide with `n` grains, shaken at `(gamma, e_star)`.
fn standard_2d(lx: f64, n: usize, gamma: f64, e_star: f64, periods: f64, transient: f64) -> String {
    let v_w = (2.0 * e_star * 0.2844f64).sqrt();
    let period = 2.0 * std::f64::consts::PI / (gamma / v_w);
    format!(
        "dimension = 2\n[box]\nsize = [{lx:?}, 9.0]\n[particles]\ncount = {n}\npolydispersity = 0.06\n\
         [contact]\nrestitution = 0.9\n[capillary]\nmodel = \"thin_thread\"\n\
         [drive]\nkind = \"sine\"\ngamma = {gamma:?}\ne_star = {e_star:?}\n\
         [initial]\ntemperature_over_ecb = 20.0\nseed = 1\n\
         [run]\nduration = {:?}\n[observe]\ntransient_periods = {transient:?}\nlocation_changes = true\n",
        periods * period
    )
}

#[test]
fn gamma_below_one_with_small_e_star_is_solid() {
    let s = common::scene(&standard_2d(20.0, 54, 0.5, 0.3, 5.0, 3.0));
    let run = run_observed(&s, &Default::default(), &mut |_| {});
    let o = &run.observables;
    assert_eq!(
        run.classification.phase,
        Phase::S,
        "{}",
        run.classification.decided_on.reason
    );
    assert!(o.granular_temperature_reduced < 0.01, "{o:?}");
    assert!(
        o.bridges_per_particle > 1.5,
        "a bonded bed: {}",
        o.bridges_per_particle
    );
    let flc = o.location_changes.as_ref().unwrap().per_particle_per_period;
    assert!(flc <= s.classify.solid_flc, "{flc}");
    for l in &o.diffusion.as_ref().unwrap().layers {
        assert!(l.msd_end < 0.05, "grains stay in their cages: {l:?}");
    }
    assert!(run.report.invariant_violation.is_none());
}

#[test]
fn strongly_driven_dilute_system_is_gas() {
    let s = common::scene(&standard_2d(40.0, 60, 6.0, 10.0, 12.0, 4.0));
    let run = run_observed(&s, &Default::default(), &mut |_| {});
    let o = &run.observables;
    assert_eq!(
        run.classification.phase,
        Phase::G,
        "{}",
        run.classification.decided_on.reason
    );
    assert!(
        o.granular_temperature_reduced > 10.0,
        "{}",
        o.granular_temperature_reduced
    );
    assert!(o.bridges_per_particle < 0.3);
    let flc = o.location_changes.as_ref().unwrap().per_particle_per_period;
    assert!(flc > 0.5, "{flc}");
    for l in &o.diffusion.as_ref().unwrap().layers {
        assert!(l.coefficient > 0.1, "a gas diffuses: {l:?}");
    }
    // Collisions with the shaken walls keep it hot; ruptures balance formations.
    let k = &o.counts;
    assert!(k.wall_collisions > 0 && k.pair_per_wall.unwrap() > 0.0);
    let (f, r) = (k.bridge_formations as f64, k.bridge_ruptures as f64);
    assert!((f - r).abs() <= 0.05 * f + 20.0, "{k:?}");
}

/// The observers read copies of the state: a run with them follows the same trajectory,
/// event for event, as a plain run; and the same scene gives the same observables twice.
#[test]
fn observing_changes_nothing_and_is_deterministic() {
    let s = common::scene(&standard_2d(40.0, 80, 3.0, 1.0, 6.0, 2.0));
    let plain = run_scene(&s);
    let a = run_observed(&s, &Default::default(), &mut |_| {});
    assert_eq!(a.report.events, plain.events);
    assert_eq!(a.report.energy_final, plain.energy_final);
    assert_eq!(a.report.samples, plain.samples);
    let b = run_observed(&s, &Default::default(), &mut |_| {});
    // Compared as stored (JSON, every number exact): a quantity with too few values to test
    // has NaN statistics, which `==` never finds equal.
    assert_eq!(
        serde_json::to_string(&a.observables).unwrap(),
        serde_json::to_string(&b.observables).unwrap()
    );
    assert_eq!(
        serde_json::to_string(&a.classification).unwrap(),
        serde_json::to_string(&b.classification).unwrap()
    );
}

/// Exact bookkeeping: the bins hold every grain and all its volume; with no transient the window
/// counts are the run's totals; the progress fraction runs from 0 to 1.
#[test]
fn profiles_and_counts_add_up() {
    let mut text = standard_2d(40.0, 80, 3.0, 3.0, 4.0, 0.0);
    text += "bin_width = 5.0\n";
    let s = common::scene(&text);
    let mut fractions = Vec::new();
    let (run, frame) = run_observed_with_frame(&s, &Default::default(), &mut |f| fractions.push(f));
    let o = &run.observables;
    let p = &o.profiles;
    assert_eq!(p.centres.len(), 8);
    let total: f64 = p.particles.iter().sum();
    assert!((total - 80.0).abs() < 1e-9, "{total}");
    let volume: f64 = frame
        .radii
        .iter()
        .map(|r| std::f64::consts::PI * r * r)
        .sum();
    let binned: f64 = p.packing.iter().map(|phi| phi * 5.0 * 9.0).sum();
    assert!(
        (binned - volume).abs() < 1e-9 * volume,
        "{binned} vs {volume}"
    );
    let e = &run.report.events;
    assert_eq!(o.counts.pair_collisions, e.pair_collisions);
    assert_eq!(o.counts.wall_collisions, e.wall_collisions);
    assert_eq!(o.counts.bridge_formations, e.bridge_formations);
    assert_eq!(o.counts.bridge_ruptures, e.bridge_ruptures);
    // The engine's bridge list, translated to scene order: as many as it counts, and every pair
    // within s_crit of contact (a wrong translation would pair distant grains).
    assert_eq!(frame.bridges.len(), run.report.bridges);
    assert!(!frame.bridges.is_empty());
    for &(i, j) in &frame.bridges {
        assert!(i < j);
        let dx = frame.min_image(0, frame.x(j)[0] - frame.x(i)[0]);
        let dz = frame.x(j)[1] - frame.x(i)[1];
        let gap = (dx * dx + dz * dz).sqrt() - frame.radii[i] - frame.radii[j];
        assert!(
            (-1e-6..=s.s_crit() + 1e-9).contains(&gap),
            "bridge {i}-{j} with gap {gap}"
        );
    }
    assert_eq!(fractions.first(), Some(&0.0));
    assert_eq!(fractions.last(), Some(&1.0));
    assert!(fractions.windows(2).all(|w| w[0] < w[1]));
    // 4 periods at 20 samples per period, both ends included.
    assert_eq!(o.window_samples, 81);
    let series = o.series.as_ref().unwrap();
    assert_eq!(series.time.len(), 81);
    assert_eq!(series.location_changes.len(), 80);
}

/// An undriven wet system cooling from T_g/E_cb = 20: its temperature falls (the trend state
/// is cooling, or coarsening where its drops grow too), and its label (a gas or a coexistence
/// still condensing) has not settled.
#[test]
fn cooling_run_is_flagged_not_settled() {
    let s = common::scene(
        "dimension = 2\n[box]\nsize = [30.0, 9.0]\n[particles]\ncount = 60\npolydispersity = 0.06\n\
         [contact]\nrestitution = 0.9\n[capillary]\nmodel = \"thin_thread\"\n\
         [initial]\ntemperature_over_ecb = 20.0\nseed = 2\n[run]\nduration = 8.0\n",
    );
    let run = run_observed(&s, &Default::default(), &mut |_| {});
    let trend = run.observables.trend.as_ref().unwrap();
    assert!(
        matches!(trend.state, TrendState::Cooling | TrendState::Coarsening),
        "{trend:?}"
    );
    let t = trend
        .tests
        .iter()
        .find(|t| t.quantity == wetgran_core::observe::trend::TEMPERATURE)
        .expect("the temperature is tested");
    assert_eq!(Direction::of(t), Direction::Falling, "{t:?}");
    let c = &run.classification;
    assert_ne!(c.phase, Phase::S, "{c:?}");
    assert_eq!(c.verdict(), Verdict::NotSettled, "{c:?}");
    assert!(!c.decided_on.settling.unsettled_text().is_empty());
}

/// 3D: location changes come from neighbour shells, bins are square cells over (x, y).
#[test]
fn three_dimensional_run_observes_neighbour_shells() {
    let s = common::scene(
        "dimension = 3\n[box]\nsize = [8.0, 8.0, 6.0]\n[particles]\ncount = 120\n\
         [capillary]\nmodel = \"thin_thread\"\n[initial]\ntemperature_over_ecb = 5.0\nseed = 1\n\
         [run]\nduration = 3.0\n[observe]\nbin_width = 2.0\ntransient_periods = 1.0\nlocation_changes = true\n",
    );
    let run = run_observed(&s, &Default::default(), &mut |_| {});
    let o = &run.observables;
    let lc = o.location_changes.as_ref().unwrap();
    assert_eq!(lc.method, "neighbour_shell");
    assert!(lc.count > 0);
    assert_eq!(o.profiles.centres.len(), 16);
    assert_eq!(o.profiles.grid, Some((4, 4)));
    let total: f64 = o.profiles.particles.iter().sum();
    assert!((total - 120.0).abs() < 1e-9);
    // n_cb per bin = bridges / (cell area 2 x 2 * height 6); summed over bins times the cell
    // volume = bridges.
    let bridges: f64 = o.profiles.n_cb.iter().map(|n| n * 2.0 * 2.0 * 6.0).sum();
    let mean_bridges = o.bridges_per_particle * 120.0;
    assert!(
        (bridges - mean_bridges).abs() < 1e-9 * mean_bridges.max(1.0),
        "{bridges} {mean_bridges}"
    );
    assert_eq!(o.diffusion.as_ref().unwrap().layers.len(), 3);
}

/// The location-change counter runs beside the other observers on a pool of more than one
/// thread: the observables and the classification are the same on one thread and on two.
#[test]
fn observing_on_two_threads_gives_the_same_observables() {
    let s = common::scene(&standard_2d(20.0, 54, 2.0, 1.0, 4.0, 1.0));
    let on = |threads: usize| {
        let ctx = RunSettings::on(Threads::new(threads));
        let run = run_observed(&s, &ctx, &mut |_| {});
        (
            serde_json::to_string(&run.observables).expect("observables serialise"),
            run.classification.phase,
        )
    };
    let (one, two) = (on(1), on(2));
    assert!(one.0.contains("location_changes"), "{}", one.0);
    assert_eq!(one, two);
}

/// `observe.location_changes` is opt-in: left out, the counter does not run and `f_lc` is
/// absent (no value, no profile, no series); `classify.mobility =
/// "location_changes"` turns it on, and so does setting it. Each scene names the resolved
/// choice, and observing or not never changes the trajectory.
#[test]
fn location_changes_are_counted_only_when_asked_for() {
    let on = standard_2d(20.0, 54, 2.0, 1.0, 3.0, 1.0);
    assert!(on.contains("location_changes = true\n"));
    let off = on.replace("location_changes = true\n", "");
    let by_classifier = format!("{off}[classify]\nmobility = \"location_changes\"\n");
    let mut runs = Vec::new();
    for (text, counted) in [(&off, false), (&on, true), (&by_classifier, true)] {
        let s = common::scene(text);
        assert_eq!(s.observe.location_changes, Some(counted), "{text}");
        let o = run_observed(&s, &Default::default(), &mut |_| {}).observables;
        assert_eq!(o.location_changes.is_some(), counted, "{text}");
        assert_eq!(o.profiles.flc.is_some(), counted, "{text}");
        let series = o.series.as_ref().unwrap();
        assert_eq!(series.location_changes.is_empty(), !counted, "{text}");
        runs.push(o);
    }
    // The same trajectory, observed with and without the counter.
    assert_eq!(
        runs[0].granular_temperature_reduced,
        runs[1].granular_temperature_reduced
    );
    assert_eq!(runs[0].counts, runs[1].counts);
    assert_eq!(runs[0].profiles.n_cb, runs[1].profiles.n_cb);
    // Turned on by the classifier or by hand: the same counter, the same count.
    let lc = |o: &wetgran_core::observe::Observables| o.location_changes.clone().unwrap();
    assert!(lc(&runs[1]).count > 0);
    assert_eq!(lc(&runs[1]), lc(&runs[2]));
}
