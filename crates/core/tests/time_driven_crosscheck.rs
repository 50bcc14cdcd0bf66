//! Cross-check of the time-driven engine (Hertz, minimal capillary model) against the
//! event-driven one (hard spheres, thin-thread bridges) on the 2D wet shaken system (issue 6).
//!
//! Both engines start from the same initial state (same scene and seed) and are observed by the
//! same observers. The time-driven scene is the event-driven one with `engine.kind = "time"` and
//! nothing else: `contact.restitution = 0.9` is converted into the Hertz damping by the default
//! calibration (`sim::time_driven::damping`, `"auto"`: the mean energy loss over the impact
//! speeds of a Maxwellian gas at the initial temperature equals `1 - eps^2`; with the former
//! default, restitution 0.9 at impact speed 1, the time-driven gas ran about 30 % cooler), default
//! stiffness and step. Compared: the
//! lateral profiles of `T_g / E_cb` and of the packing fraction, time-averaged over the
//! stationary window, in the bins that are dilute (packing below [`DILUTE`]) in both runs; the
//! thin-thread model has no contact force, so dense regions may differ.
//!
//! The CI test runs the reduced system (N = 300 in 100 x 9) at a gas and at a coexistence seen
//! 30 periods after the hot start (a snapshot of the cooling: run longer, the point is a fluid;
//! crates/core/tests/engines_like.rs compares stationary phases).
//! The full 2D standard system (N = 1200 in 400 x 9) is opt-in:
//! `cargo test --release --test time_driven_crosscheck -- --ignored --nocapture`
//! (it also rewrites docs/tdmd-crosscheck.svg).

use wetgran_core::observe::{ObservedRun, run_observed};
use wetgran_core::scene::Scene;

use common::standard::{StandardWet, Transient, time_twin};
use wetgran_testkit as common;

/// Largest packing fraction of a bin counted as dilute.
const DILUTE: f64 = 0.3;

/// The 2D wet shaken system at (Gamma, E*), restitution 0.9, `n` grains in `lx x 9`.
fn base(gamma: f64, e_star: f64, n: usize, lx: f64, duration: f64) -> Scene {
    StandardWet::new(gamma, e_star, 0.9, duration, Transient::Periods(10.0))
        .sized(n, lx)
        .without_mobility()
        .scene()
}

/// Per dilute bin: (centre, T_g/E_cb event, time, packing event, time); and the means.
struct Comparison {
    rows: Vec<(f64, f64, f64, f64, f64)>,
    event: ObservedRun,
    time: ObservedRun,
}

fn compare(s: &Scene) -> Comparison {
    let event = run_observed(s, &Default::default(), &mut |_| {});
    let time = run_observed(&time_twin(s, None), &Default::default(), &mut |_| {});
    let (pe, pt) = (&event.observables.profiles, &time.observables.profiles);
    let mut rows = Vec::new();
    for b in 0..pe.centres.len() {
        if pe.packing[b] < DILUTE
            && pt.packing[b] < DILUTE
            && let (Some(te), Some(tt)) = (pe.temperature_reduced[b], pt.temperature_reduced[b])
        {
            rows.push((pe.centres[b], te, tt, pe.packing[b], pt.packing[b]));
        }
    }
    Comparison { rows, event, time }
}

/// Prints the comparison; returns the ratios (time over event) of the dilute-bin means of
/// `T_g / E_cb` and of the packing, and the largest relative deviation of one dilute bin.
fn summary(label: &str, c: &Comparison) -> (f64, f64, f64) {
    let n = c.rows.len() as f64;
    let te = c.rows.iter().map(|r| r.1).sum::<f64>() / n;
    let tt = c.rows.iter().map(|r| r.2).sum::<f64>() / n;
    let pe = c.rows.iter().map(|r| r.3).sum::<f64>() / n;
    let pt = c.rows.iter().map(|r| r.4).sum::<f64>() / n;
    println!(
        "{label}: {} dilute bins of {}; mean T_g/E_cb event {te:.3} time {tt:.3} (ratio {:.3}); mean packing event {pe:.4} time {pt:.4}; global T_g/E_cb event {:.3} time {:.3}; phases {} / {}; wall s {:.1} / {:.1}",
        c.rows.len(),
        c.event.observables.profiles.centres.len(),
        tt / te,
        c.event.observables.granular_temperature_reduced,
        c.time.observables.granular_temperature_reduced,
        c.event.classification.phase,
        c.time.classification.phase,
        c.event.report.wall_seconds,
        c.time.report.wall_seconds,
    );
    let worst = c
        .rows
        .iter()
        .map(|r| (r.2 / r.1 - 1.0).abs())
        .fold(0.0, f64::max);
    println!("  largest per-bin T_g deviation {worst:.3}");
    (tt / te, pt / pe, worst)
}

/// Checks one point: the same phase, and the dilute-bin means of `T_g / E_cb` within 20 % and of
/// the packing within 5 % (docs/accuracy.md has the measured values). Single bins scatter by up
/// to about 60 % over these short windows and are printed, not asserted.
fn check(label: &str, c: &Comparison) {
    let (t, p, worst) = summary(label, c);
    assert!(
        c.rows.len() >= 5,
        "{label}: only {} dilute bins",
        c.rows.len()
    );
    // The two engines have different capillary models (thin thread against minimal): their
    // labels must agree wherever neither decision lies at a threshold; at one (a contrast at
    // the coexistence floor, say) the label is uncertain by construction and only printed.
    let (ev, td) = (&c.event.classification, &c.time.classification);
    if ev.decided_on.borderline.is_empty() && td.decided_on.borderline.is_empty() {
        assert_eq!(ev.phase, td.phase, "{label}");
    } else {
        println!(
            "  ({label}: phases {} / {} at a borderline decision: {:?} / {:?}, not asserted)",
            ev.phase, td.phase, ev.decided_on.borderline, td.decided_on.borderline
        );
    }
    assert!((t - 1.0).abs() < 0.2, "{label}: T_g ratio {t}");
    assert!((p - 1.0).abs() < 0.05, "{label}: packing ratio {p}");
    println!("  ({label}: largest single-bin deviation {worst:.3}, not asserted)");
}

/// Reduced cross-check (N = 300 in 100 x 9): a gas (Gamma = 2, E* = 3, 60 time units) and a
/// fluid-gas coexistence (Gamma = 10, E* = 0.3, 30 periods), the points of docs/phases/.
#[test]
fn reduced_crosscheck_gas_and_coexistence() {
    check("gas", &compare(&base(2.0, 3.0, 300, 100.0, 60.0)));
    check("fgc", &compare(&base(10.0, 0.3, 300, 100.0, 7.786487)));
}

/// Full cross-check on the 2D standard wet system (N = 1200 in 400 x 9), same points; writes
/// docs/tdmd-crosscheck.svg (the lateral `T_g / E_cb` and packing profiles of both engines).
#[test]
#[ignore]
fn full_crosscheck_standard_system() {
    let gas = compare(&base(2.0, 3.0, 1200, 400.0, 60.0));
    let fgc = compare(&base(10.0, 0.3, 1200, 400.0, 7.786487));
    let root = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join("docs");
    let svg = profiles_svg(&[
        ("gas, Gamma 2, E* 3", &gas),
        ("fgc, Gamma 10, E* 0.3", &fgc),
    ]);
    std::fs::write(root.join("tdmd-crosscheck.svg"), svg).unwrap();
    check("gas (N = 1200)", &gas);
    check("fgc (N = 1200)", &fgc);
}

/// Per point: `T_g / E_cb` (top) and packing (bottom) against `x`, event (blue) and time (red);
/// dense bins (packing >= DILUTE in either run) drawn hollow.
fn profiles_svg(points: &[(&str, &Comparison)]) -> String {
    use std::fmt::Write as _;
    let (pw, ph, m) = (560.0, 200.0, 55.0);
    let w = m + points.len() as f64 * (pw + m);
    let h = 2.0 * (ph + m) + 40.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"11\">"
    );
    let _ = writeln!(s, "<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>");
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"18\" text-anchor=\"middle\" font-size=\"13\">Event-driven (blue: eps 0.9, thin thread) against time-driven (red: Hertz, minimal model); hollow: dense bins</text>",
        w / 2.0
    );
    for (col, (label, c)) in points.iter().enumerate() {
        let x0 = m + col as f64 * (pw + m);
        let pe = &c.event.observables.profiles;
        let pt = &c.time.observables.profiles;
        let lx = pe.centres.last().unwrap() + pe.bin_width / 2.0;
        for (row, name) in ["T_g / E_cb", "packing fraction"].iter().enumerate() {
            let y0 = 40.0 + row as f64 * (ph + m);
            let get = |p: &wetgran_core::observe::Profiles, b: usize| -> Option<f64> {
                if row == 0 {
                    p.temperature_reduced[b]
                } else {
                    Some(p.packing[b])
                }
            };
            let mut ymax = 0.0f64;
            for b in 0..pe.centres.len() {
                ymax = ymax
                    .max(get(pe, b).unwrap_or(0.0))
                    .max(get(pt, b).unwrap_or(0.0));
            }
            let ymax = ymax * 1.1;
            let px = |x: f64| x0 + x / lx * pw;
            let py = |y: f64| y0 + ph - y / ymax * ph;
            let _ = writeln!(
                s,
                "<rect x=\"{x0}\" y=\"{y0}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"#999\"/>"
            );
            let _ = writeln!(
                s,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{label}: {name} (0 .. {ymax:.3}) against x (0 .. {lx})</text>",
                x0 + pw / 2.0,
                y0 - 6.0
            );
            for (p, colour) in [(pe, "#1f77b4"), (pt, "#d62728")] {
                let mut pts = Vec::new();
                for b in 0..p.centres.len() {
                    if let Some(y) = get(p, b) {
                        let (cx, cy) = (px(p.centres[b]), py(y));
                        pts.push(format!("{cx:.1},{cy:.1}"));
                        let dense = pe.packing[b] >= DILUTE || pt.packing[b] >= DILUTE;
                        let fill = if dense { "none" } else { colour };
                        let _ = writeln!(
                            s,
                            "<circle cx=\"{cx:.1}\" cy=\"{cy:.1}\" r=\"3\" fill=\"{fill}\" stroke=\"{colour}\"/>"
                        );
                    }
                }
                let _ = writeln!(
                    s,
                    "<polyline points=\"{}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"1\"/>",
                    pts.join(" ")
                );
            }
        }
    }
    s.push_str("</svg>\n");
    s
}
