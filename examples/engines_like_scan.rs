//! Measurement harness of docs/model-choices.md ("Engines like for like"): one point of the 2D
//! wet shaken system (N grains in Lx x 9, sigma_p 0.06, standard s_crit and E_cb, elastic walls,
//! hot start T_g/E_cb = 20, seed from $SEED, default 1) run by the event engine and by the time
//! engine under several restitution calibrations; prints the phase, T_g/E_cb, the dilute bins
//! (packing below 0.3 in this run), the packing range, bridges per grain, D_lat and Delta n_cb.
//!
//! ```sh
//! cargo run --release --example engines_like_scan -- EPS GAMMA E_STAR N LX DURATION \
//!     TRANSIENT_PERIODS CAL...
//! ```
//!
//! Each CAL is `event` (the event engine), `auto` (time engine, default calibration), `vV`
//! (time engine, `contact.restitution_speed = V`) or `tT` (time engine,
//! `contact.restitution_temperature = T`, units of m g d).
use wetgran_core::observe::run_observed;
use wetgran_core::scene::{EngineKind, Scene};

use wetgran_testkit::standard::{STANDARD_SEED, StandardWet, Transient};

/// The scene of the point: the standard system builder of the tests, location changes off.
fn base(
    eps: f64,
    gamma: f64,
    e_star: f64,
    n: usize,
    lx: f64,
    duration: f64,
    transient: f64,
) -> Scene {
    let seed = std::env::var("SEED").map_or(Ok(STANDARD_SEED), |s| s.parse());
    let mut s = StandardWet::new(gamma, e_star, eps, duration, Transient::Periods(transient))
        .sized(n, lx)
        .seed(seed.unwrap_or_else(|e| panic!("SEED: {e}")));
    s.location_changes = false;
    s.scene()
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 9 {
        eprintln!(
            "usage: engines_like_scan EPS GAMMA E_STAR N LX DURATION TRANSIENT_PERIODS CAL... \
             (CAL: event, auto, vSPEED, tTEMPERATURE)"
        );
        std::process::exit(2);
    }
    let eps: f64 = a[1].parse().unwrap();
    let gamma: f64 = a[2].parse().unwrap();
    let e_star: f64 = a[3].parse().unwrap();
    let n: usize = a[4].parse().unwrap();
    let lx: f64 = a[5].parse().unwrap();
    let duration: f64 = a[6].parse().unwrap();
    let transient: f64 = a[7].parse().unwrap();
    let cals: Vec<String> = a[8..].to_vec();
    let s = base(eps, gamma, e_star, n, lx, duration, transient);
    for cal in &cals {
        let mut t = s.clone();
        if cal != "event" {
            t.engine.kind = EngineKind::Time;
            if let Some(v) = cal.strip_prefix("v") {
                t.contact.restitution_speed = Some(wetgran_core::scene::RestitutionSpeed::Speed(
                    v.parse().unwrap(),
                ));
            } else if let Some(tc) = cal.strip_prefix("t") {
                t.contact.restitution_temperature = Some(tc.parse().unwrap());
            }
            t.validate("t").unwrap();
        }
        let ad = if cal != "event" {
            wetgran_core::sim::time_driven::damping::contact_damping(&t).0
        } else {
            0.0
        };
        let r = run_observed(&t, &Default::default(), &mut |_| {});
        let o = &r.observables;
        let p = &o.profiles;
        let mut dil = (0.0, 0.0, 0usize);
        for b in 0..p.centres.len() {
            if p.packing[b] < 0.3
                && let Some(tb) = p.temperature_reduced[b]
            {
                dil.0 += tb;
                dil.1 += p.packing[b];
                dil.2 += 1;
            }
        }
        let (pmin, pmax) = p
            .packing
            .iter()
            .fold((9.0f64, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        println!(
            "eps {eps} G {gamma} E* {e_star} N {n} {cal:>8} A_d {ad:.3e}: phase {} Tg/Ecb {:.3} dilute({}) T {:.3} pack {:.4} | pack range {:.3}-{:.3} bridges/p {:.3} Dlat {:?} dncb {:.3} verdict {} wall {:.1}s",
            r.classification.phase,
            o.granular_temperature_reduced,
            dil.2,
            dil.0 / dil.2.max(1) as f64,
            dil.1 / dil.2.max(1) as f64,
            pmin,
            pmax,
            o.bridges_per_particle,
            o.mobility.as_ref().map(|m| m.diffusion),
            p.delta_n_cb,
            r.classification.verdict(),
            r.report.wall_seconds
        );
    }
}
