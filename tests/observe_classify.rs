//! The classifier on synthetic observables: every phase, every threshold edge, re-classification
//! from stored numbers; the fluid-gas inflection line analysis on curves with a known answer.

use wetgran::observe::{
    Mobility, Observables, Phase, Profiles, Stationarity, Thresholds, WindowCounts, classify,
    fluid_gas_inflection,
};

/// Observables with a homogeneous bridge profile (spread `delta`), global `f_lc` and `T_g/E_cb`.
fn homogeneous(flc: Option<f64>, t: f64, delta: f64) -> Observables {
    let bins = 10;
    let n_cb: Vec<f64> = (0..bins)
        .map(|b| if b == 0 { 3.0 + delta } else { 3.0 })
        .collect();
    synthetic(
        flc,
        t,
        n_cb,
        vec![flc.unwrap_or(0.0); bins],
        vec![Some(t); bins],
    )
}

fn synthetic(
    flc: Option<f64>,
    t: f64,
    n_cb: Vec<f64>,
    flc_bins: Vec<f64>,
    t_bins: Vec<Option<f64>>,
) -> Observables {
    let bins = n_cb.len();
    let spread = n_cb.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - n_cb.iter().copied().fold(f64::INFINITY, f64::min);
    Observables {
        dimension: 2,
        particles: 10 * bins,
        period: 1.0,
        window_start: 0.0,
        window_end: 10.0,
        window_samples: 200,
        sample_interval: 0.05,
        temperature_unit: 0.2844,
        temperature_unit_name: "E_cb".into(),
        granular_temperature_reduced: t,
        bridges_per_particle: 1.0,
        location_changes: flc.map(|f| wetgran::observe::LocationChanges {
            method: "delaunay".into(),
            count: 0,
            per_particle_per_period: f,
            sample_interval: 0.05,
        }),
        profiles: Profiles {
            bin_width: 4.0,
            centres: (0..bins).map(|b| 4.0 * b as f64 + 2.0).collect(),
            particles: vec![10.0; bins],
            packing: vec![0.5; bins],
            n_cb,
            temperature_reduced: t_bins,
            flc: flc.map(|_| flc_bins),
            delta_n_cb: spread,
            delta_n_area: 0.0,
        },
        diffusion: None,
        counts: WindowCounts {
            pair_collisions: 0,
            wall_collisions: 0,
            bridge_formations: 0,
            bridge_ruptures: 0,
            pair_per_wall: None,
        },
        stationarity: Stationarity {
            tolerance: 0.2,
            checks: vec![],
            stationary: true,
        },
        series: None,
        shear: None,
        convergence: None,
    }
}

/// Two regions: bins 0..5 dense (n_cb 6) with `(flc, T)`, bins 5..10 dilute (n_cb 0.5).
fn two_regions(dense: (f64, f64), dilute: (f64, f64)) -> Observables {
    let n = 10;
    let n_cb = (0..n).map(|b| if b < 5 { 6.0 } else { 0.5 }).collect();
    let f = (0..n)
        .map(|b| if b < 5 { dense.0 } else { dilute.0 })
        .collect();
    let t = (0..n)
        .map(|b| Some(if b < 5 { dense.1 } else { dilute.1 }))
        .collect();
    synthetic(
        Some(0.5 * (dense.0 + dilute.0)),
        0.5 * (dense.1 + dilute.1),
        n_cb,
        f,
        t,
    )
}

fn th() -> Thresholds {
    Thresholds::default()
}

#[test]
fn homogeneous_phases_and_their_threshold_edges() {
    let t = th();
    let (sf, gas) = (t.solid_flc, t.gas_temperature);
    // Solid versus mobile on f_lc: the edge value is solid.
    assert_eq!(
        classify(&homogeneous(Some(0.0), 0.5, 0.0), &t).phase,
        Phase::S
    );
    assert_eq!(
        classify(&homogeneous(Some(sf), 0.5, 0.0), &t).phase,
        Phase::S
    );
    let above = sf * (1.0 + 1e-12) + 1e-300;
    assert_eq!(
        classify(&homogeneous(Some(above), 0.5, 0.0), &t).phase,
        Phase::F
    );
    // f_lc decides mobility up to the gas temperature; hotter than that, bridges cannot hold
    // and a region with few location changes (a dilute gas at high Gamma) is a gas.
    assert_eq!(
        classify(&homogeneous(Some(sf), gas, 0.0), &t).phase,
        Phase::S
    );
    let c = classify(&homogeneous(Some(sf), gas * (1.0 + 1e-12), 0.0), &t);
    assert_eq!(c.phase, Phase::G);
    assert!(
        c.decided_on.reason.contains("too hot for bridges"),
        "{}",
        c.decided_on.reason
    );
    // Fluid versus gas on T_g/E_cb: the edge value is fluid.
    assert_eq!(
        classify(&homogeneous(Some(1.0), gas, 0.0), &t).phase,
        Phase::F
    );
    assert_eq!(
        classify(&homogeneous(Some(1.0), gas * (1.0 + 1e-12), 0.0), &t).phase,
        Phase::G
    );
}

#[test]
fn temperature_decides_mobility_when_asked_or_without_flc() {
    let mut t = th();
    let st = t.solid_temperature;
    // No f_lc observed: temperature is used, and recorded as used.
    let c = classify(&homogeneous(None, st, 0.0), &t);
    assert_eq!(c.phase, Phase::S);
    assert_eq!(c.decided_on.whole.mobility_from, Mobility::Temperature);
    assert_eq!(
        classify(&homogeneous(None, st * (1.0 + 1e-12), 0.0), &t).phase,
        Phase::F
    );
    // f_lc observed but mobility = temperature: a large f_lc does not matter.
    t.mobility = Mobility::Temperature;
    assert_eq!(
        classify(&homogeneous(Some(100.0), st, 0.0), &t).phase,
        Phase::S
    );
    assert_eq!(
        classify(&homogeneous(Some(0.0), 2.0 * st, 0.0), &t).phase,
        Phase::F
    );
}

#[test]
fn coexistence_edge_and_every_pair() {
    let t = th();
    let d = t.coexistence_delta_n_cb;
    // At the edge the system is homogeneous; a mobile, hot one is a gas.
    let c = classify(&homogeneous(Some(1.0), 5.0, d), &t);
    assert!(!c.decided_on.split);
    assert_eq!(c.phase, Phase::G);
    // Just above: split; the synthetic regions are then equal, so still g.
    let c = classify(&homogeneous(Some(1.0), 5.0, d * (1.0 + 1e-9)), &t);
    assert!(c.decided_on.split);
    assert_eq!(c.phase, Phase::G);
    let (s, f, g) = ((0.0, 0.01), (1.0, 0.5), (1.0, 10.0));
    assert_eq!(classify(&two_regions(s, f), &t).phase, Phase::Sfc);
    assert_eq!(classify(&two_regions(s, g), &t).phase, Phase::Sgc);
    assert_eq!(classify(&two_regions(f, g), &t).phase, Phase::Fgc);
    assert_eq!(classify(&two_regions(s, s), &t).phase, Phase::S);
    assert_eq!(classify(&two_regions(f, f), &t).phase, Phase::F);
    // The order of dense and dilute does not matter.
    assert_eq!(classify(&two_regions(g, s), &t).phase, Phase::Sgc);
    let c = classify(&two_regions(s, g), &t);
    let dense = c.decided_on.dense.as_ref().unwrap();
    let dilute = c.decided_on.dilute.as_ref().unwrap();
    assert_eq!((dense.phase, dense.bins), (Phase::S, 5));
    assert_eq!((dilute.phase, dilute.bins), (Phase::G, 5));
    assert_eq!(c.decided_on.split_n_cb, Some(3.25));
}

#[test]
fn every_phase_is_reachable() {
    let t = th();
    let cases = [
        (homogeneous(Some(0.0), 0.001, 0.0), Phase::S),
        (homogeneous(Some(1.0), 0.5, 0.0), Phase::F),
        (homogeneous(Some(1.0), 10.0, 0.0), Phase::G),
        (two_regions((0.0, 0.01), (1.0, 0.5)), Phase::Sfc),
        (two_regions((0.0, 0.01), (1.0, 10.0)), Phase::Sgc),
        (two_regions((1.0, 0.5), (1.0, 10.0)), Phase::Fgc),
    ];
    let got: Vec<Phase> = cases.iter().map(|(o, _)| classify(o, &t).phase).collect();
    let want: Vec<Phase> = cases.iter().map(|(_, p)| *p).collect();
    assert_eq!(got, want);
    assert_eq!(want, Phase::ALL.to_vec());
}

/// A stored result (JSON) is re-classified with other thresholds without re-simulating, and the
/// classification records the numbers and thresholds it used.
#[test]
fn reclassification_from_stored_numbers() {
    let obs = two_regions((0.05, 0.3), (1.0, 3.0));
    let json = serde_json::to_string(&obs).unwrap();
    let back: Observables = serde_json::from_str(&json).unwrap();
    assert_eq!(back, obs);
    let t = th();
    assert_eq!(classify(&back, &t).phase, Phase::Fgc);
    let strict = Thresholds {
        solid_flc: 0.1,
        ..th()
    };
    let c = classify(&back, &strict);
    assert_eq!(c.phase, Phase::Sgc);
    assert_eq!(c.decided_on.thresholds, strict);
    assert_eq!(c.decided_on.dense.as_ref().unwrap().flc, Some(0.05));
    let hot = Thresholds {
        gas_temperature: 5.0,
        ..th()
    };
    assert_eq!(classify(&back, &hot).phase, Phase::F);
    // The decision itself round-trips.
    let c2: wetgran::observe::Classification =
        serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
    assert_eq!(c2, c);
}

#[test]
fn phase_names() {
    let names: Vec<String> = Phase::ALL.iter().map(|p| p.to_string()).collect();
    assert_eq!(names, ["s", "f", "g", "sfc", "sgc", "fgc"]);
    for p in Phase::ALL {
        assert_eq!(serde_json::to_string(&p).unwrap(), format!("\"{p}\""));
        assert_eq!(p.to_string().parse::<Phase>().unwrap(), p);
    }
    assert!("solid".parse::<Phase>().is_err());
}

/// `ln(T/E_cb) = a + b tanh((ln E* - ln E0) / w)`: the log-log slope peaks at `E0`.
#[test]
fn inflection_of_a_known_sigmoid() {
    for (e0, w) in [(3.0f64, 0.7f64), (0.5, 1.2), (20.0, 0.4)] {
        let pts: Vec<(f64, f64)> = (0..25)
            .map(|k| {
                let e = 0.01 * 1.5f64.powi(k);
                (e, (-2.0 + 2.5 * ((e.ln() - e0.ln()) / w).tanh()).exp())
            })
            .collect();
        let inf = fluid_gas_inflection(&pts).expect("inside the range");
        // Located to a tenth of the point spacing in ln E* (ln 1.5 = 0.405).
        assert!(
            (inf.e_star / e0).ln().abs() < 0.1 * 1.5f64.ln(),
            "E0 = {e0}: found {}",
            inf.e_star
        );
        assert!(inf.bracket.0 <= inf.e_star * 1.5 && inf.bracket.1 >= inf.e_star / 1.5);
        // Order of the points does not matter.
        let mut rev = pts.clone();
        rev.reverse();
        assert_eq!(fluid_gas_inflection(&rev), Some(inf));
    }
    // A curve that only steepens (the inflection lies beyond the range) has none.
    let convex: Vec<(f64, f64)> = (1..10)
        .map(|k| (k as f64, (k as f64).powi(2).exp()))
        .collect();
    assert_eq!(fluid_gas_inflection(&convex), None);
    assert_eq!(fluid_gas_inflection(&convex[..3]), None);
}

/// The dense/dilute split uses every bin, not only the two extremes: one outlier bin does not
/// pull the split to itself.
#[test]
fn split_is_two_classes_not_the_range_midpoint() {
    use wetgran::observe::classify::two_class_split;
    let n_cb = [6.0, 6.0, 6.0, 6.0, 6.0, 1.0, 1.0, 1.0, 1.0, 12.0];
    assert_eq!(two_class_split(&n_cb), 3.5);
    assert_eq!(two_class_split(&[2.0, 4.0]), 3.0);
    assert_eq!(two_class_split(&[5.0]), 5.0);
    // Solid bins (dense, f_lc 0) next to fluid ones (f_lc 1), one very dense solid bin: sfc.
    let f = (0..10)
        .map(|b| if b < 5 || b == 9 { 0.0 } else { 1.0 })
        .collect();
    let t = (0..10)
        .map(|b| Some(if b < 5 || b == 9 { 0.01 } else { 0.5 }))
        .collect();
    let obs = synthetic(Some(0.4), 0.2, n_cb.to_vec(), f, t);
    let c = classify(&obs, &th());
    assert_eq!(c.phase, Phase::Sfc, "{}", c.decided_on.reason);
    assert_eq!(c.decided_on.dense.as_ref().unwrap().bins, 6);
}

#[test]
fn sheared_scenes_are_solid_or_fluid_by_e_par() {
    use wetgran::observe::shear::ShearObservables;
    let th = Thresholds::default();
    for (e_par, want) in [(0.02, Phase::S), (0.1, Phase::S), (0.5, Phase::F)] {
        // Whatever the unsheared rules say (a hot, split system here), E_par decides.
        let mut obs = two_regions((0.5, 5.0), (0.0, 0.0));
        obs.shear = Some(ShearObservables {
            e_par,
            e_perp: 0.01,
            cycles: Vec::new(),
            series: Vec::new(),
        });
        let c = classify(&obs, &th);
        assert_eq!(c.phase, want, "E_par = {e_par}: {}", c.decided_on.reason);
        assert_eq!(c.decided_on.shear_e_par, Some(e_par));
        assert!(c.decided_on.reason.starts_with("sheared"));
    }
}
