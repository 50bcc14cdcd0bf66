//! Engines like for like (issue 18, item 10): a scene keeps its phase when only `engine.kind`
//! changes. The time-driven twin of an event-driven scene is the same scene with
//! `engine.kind = "time"` and nothing else: its `contact.restitution` is converted into the
//! Hertz damping by the default calibration (`sim::time_driven::damping`, `"auto"`: the mean
//! energy loss of a Maxwellian gas at the scene's characteristic temperature equals
//! `1 - eps^2`).
//!
//! Scenes: the 2D standard wet system of docs/model.md 1 (N = 1200 in 400 d x 9 d, `s_crit` 0.0711,
//! `E_cb` 0.2844, `sigma_p` 0.06, elastic walls, hot start `T_g / E_cb = 20`) with `eps = 0.96`
//! (`sweeps/shaken_2d_eps096.toml`), at a gas (Gamma 2, E* 3), a fluid (Gamma 30, E* 0.7) and a
//! fluid-gas coexistence (Gamma 30, E* 2.6; docs/validation.md, line eps = 0.96: fgc with the
//! event engine for seeds 1, 2 and 3, where E* = 1.9 is fgc for seed 1 only), 300 time units
//! each. Compared: the per-point phase label (`observe::classify`), the window mean of
//! `T_g / E_cb`, and the bins dilute in both runs (packing below [`DILUTE`]): their mean
//! `T_g / E_cb` and packing. docs/accuracy.md ("Engines like for like") has the measured table.
//!
//! CI runs the reduced gas and fluid (N = 300 in 100 d x 9 d, 60-80 time units): a coexistence
//! needs the long box and window (N = 300 in 100 d stays a gas at Gamma 30, E* 1.9 to 3; N = 600
//! in 200 d is fgc or g depending on the seed; docs/accuracy.md). The full system is
//! opt-in: `cargo test --release --test engines_like -- --ignored --nocapture`.

use wetgran_core::observe::{ObservedRun, run_observed};
use wetgran_core::scene::Scene;

use common::standard::{StandardWet, Transient, time_twin};
use wetgran_testkit as common;

/// Largest packing fraction of a bin counted as dilute.
const DILUTE: f64 = 0.3;
/// Restitution of the standard sweep `sweeps/shaken_2d_eps096.toml`.
const EPS: f64 = 0.96;

/// One point of the (Gamma, E*) plane and its run: `duration` and the transient, both in time
/// units (the scene counts the transient in driving periods).
#[derive(Clone, Copy)]
struct Point {
    label: &'static str,
    gamma: f64,
    e_star: f64,
    duration: f64,
    transient: f64,
}

const GAS: Point = Point {
    label: "gas",
    gamma: 2.0,
    e_star: 3.0,
    duration: 300.0,
    transient: 150.0,
};
const FLUID: Point = Point {
    label: "fluid",
    gamma: 30.0,
    e_star: 0.7,
    duration: 300.0,
    transient: 100.0,
};
const COEXISTENCE: Point = Point {
    label: "coexistence",
    gamma: 30.0,
    e_star: 2.6,
    duration: 300.0,
    transient: 100.0,
};

/// The event-driven scene of a point, `n` grains in `lx x 9` (location changes off: they are
/// not compared).
fn scene(p: Point, n: usize, lx: f64) -> Scene {
    let mut s = StandardWet::new(
        p.gamma,
        p.e_star,
        EPS,
        p.duration,
        Transient::Time(p.transient),
    )
    .sized(n, lx);
    s.location_changes = false;
    s.scene()
}

/// What is compared of one run.
#[derive(Debug, Clone)]
struct Summary {
    phase: String,
    temperature: f64,
    dilute_bins: usize,
    dilute_temperature: f64,
    dilute_packing: f64,
    delta_n_area: f64,
    bridges: f64,
    wall_seconds: f64,
}

/// Summaries of an event and a time run; dilute = packing below [`DILUTE`] in both.
fn summaries(event: &ObservedRun, time: &ObservedRun) -> (Summary, Summary) {
    let (pe, pt) = (&event.observables.profiles, &time.observables.profiles);
    let dilute: Vec<usize> = (0..pe.centres.len())
        .filter(|&b| {
            pe.packing[b] < DILUTE
                && pt.packing[b] < DILUTE
                && pe.temperature_reduced[b].is_some()
                && pt.temperature_reduced[b].is_some()
        })
        .collect();
    let one = |r: &ObservedRun| {
        let o = &r.observables;
        let p = &o.profiles;
        let n = dilute.len().max(1) as f64;
        Summary {
            phase: r.classification.phase.to_string(),
            temperature: o.granular_temperature_reduced,
            dilute_bins: dilute.len(),
            dilute_temperature: dilute
                .iter()
                .map(|&b| p.temperature_reduced[b].unwrap_or(0.0))
                .sum::<f64>()
                / n,
            dilute_packing: dilute.iter().map(|&b| p.packing[b]).sum::<f64>() / n,
            delta_n_area: p.delta_n_area,
            bridges: o.bridges_per_particle,
            wall_seconds: r.report.wall_seconds,
        }
    };
    (one(event), one(time))
}

/// Runs a point with both engines (the time engine with the default calibration, or at one
/// impact speed) and prints a table row.
fn compare(p: Point, n: usize, lx: f64, speed: Option<f64>) -> (Summary, Summary) {
    let s = scene(p, n, lx);
    let event = run_observed(&s, &Default::default(), &mut |_| {});
    let time = run_observed(&time_twin(&s, speed), &Default::default(), &mut |_| {});
    let (e, t) = summaries(&event, &time);
    let cal = speed.map_or("auto".to_string(), |v| format!("speed {v}"));
    println!(
        "| {} (N = {n}, {cal}) | {} / {} | {:.3} / {:.3} ({:+.1} %) | {} | {:.3} / {:.3} | {:.4} / {:.4} | {:.3} / {:.3} | {:.2} / {:.2} | {:.1} / {:.1} |",
        p.label,
        e.phase,
        t.phase,
        e.temperature,
        t.temperature,
        100.0 * (t.temperature / e.temperature - 1.0),
        e.dilute_bins,
        e.dilute_temperature,
        t.dilute_temperature,
        e.dilute_packing,
        t.dilute_packing,
        e.delta_n_area,
        t.delta_n_area,
        e.bridges,
        t.bridges,
        e.wall_seconds,
        t.wall_seconds,
    );
    (e, t)
}

/// The tolerances (docs/accuracy.md): the same per-point label; the window mean of
/// `T_g / E_cb` within `t_tol`; the dilute bins' mean packing within `p_tol`.
fn check(p: Point, e: &Summary, t: &Summary, t_tol: f64, p_tol: f64) {
    assert_eq!(e.phase, t.phase, "{}: phase {e:?} against {t:?}", p.label);
    let rt = t.temperature / e.temperature;
    assert!(
        (rt - 1.0).abs() < t_tol,
        "{}: T_g/E_cb time/event {rt:.3} (event {e:?}, time {t:?})",
        p.label
    );
    assert!(
        e.dilute_bins >= 5,
        "{}: {} dilute bins",
        p.label,
        e.dilute_bins
    );
    let rp = t.dilute_packing / e.dilute_packing;
    assert!(
        (rp - 1.0).abs() < p_tol,
        "{}: dilute packing time/event {rp:.3}",
        p.label
    );
}

const HEADER: &str = "| point | phase event / time | T_g/E_cb event / time | dilute bins | dilute T_g/E_cb event / time | dilute packing event / time | Delta n_area event / time | bridges/grain event / time | wall s event / time |\n|---|---|---|---|---|---|---|---|---|";

/// Reduced gas (N = 300 in 100 d x 9 d, Gamma 2, E* 3, 80 time units, 30 of transient).
#[test]
fn reduced_gas_keeps_its_phase_when_only_the_engine_changes() {
    let p = Point {
        duration: 80.0,
        transient: 30.0,
        ..GAS
    };
    println!("{HEADER}");
    let (e, t) = compare(p, 300, 100.0, None);
    check(p, &e, &t, 0.1, 0.05);
}

/// Reduced fluid (N = 300 in 100 d x 9 d, Gamma 30, E* 0.7, 60 time units, 20 of transient).
#[test]
fn reduced_fluid_keeps_its_phase_when_only_the_engine_changes() {
    let p = Point {
        duration: 60.0,
        transient: 20.0,
        ..FLUID
    };
    println!("{HEADER}");
    let (e, t) = compare(p, 300, 100.0, None);
    check(p, &e, &t, 0.1, 0.05);
}

/// The 2D standard wet system (N = 1200 in 400 d x 9 d) at a gas, a fluid and a coexistence,
/// 300 time units each, the three points on their own threads.
#[test]
#[ignore]
fn full_standard_system_keeps_its_phases_when_only_the_engine_changes() {
    println!("{HEADER}");
    let rows: Vec<(Point, Summary, Summary)> = std::thread::scope(|sc| {
        let handles: Vec<_> = [GAS, FLUID, COEXISTENCE]
            .into_iter()
            .map(|p| {
                sc.spawn(move || {
                    let (e, t) = compare(p, 1200, 400.0, None);
                    (p, e, t)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (p, e, t) in &rows {
        check(*p, e, t, 0.1, 0.1);
    }
}

/// Contrast: the single-speed calibration at impact speed 1 (the former default) at the same
/// three points: the time-driven gas comes out cooler than the event-driven one by more than
/// the tolerance of the like-for-like check.
#[test]
#[ignore]
fn full_standard_system_at_speed_one_runs_cooler() {
    println!("{HEADER}");
    let rows: Vec<(Point, Summary, Summary)> = std::thread::scope(|sc| {
        let handles: Vec<_> = [GAS, FLUID, COEXISTENCE]
            .into_iter()
            .map(|p| {
                sc.spawn(move || {
                    let (e, t) = compare(p, 1200, 400.0, Some(1.0));
                    (p, e, t)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let (_, e, t) = &rows[0];
    assert!(
        t.temperature < 0.9 * e.temperature,
        "gas at speed 1: time {} against event {}",
        t.temperature,
        e.temperature
    );
}
