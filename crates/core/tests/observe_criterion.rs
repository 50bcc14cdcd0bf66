//! Which criterion decided a label (`observe::criterion`), read from the classifier's record on
//! synthetic observables: every solid-or-mobile criterion (displacement, cage, members still
//! in their cage, f_lc, temperature as asked and as the fallback of an unmeasured mobility),
//! every fluid-or-gas criterion (line jump, inflection, coexistences, the gas-temperature
//! fallback, a coexistence region's temperature, a drop condensed by its much hotter vapour),
//! and E_par of a sheared scene; the stored record gives the same answer, and its summary holds
//! the numbers compared without float noise.

use wetgran_core::observe::classify::{FluidGasFrom, classify_with};
use wetgran_core::observe::criterion::{Criterion, DecidedBy, Region};
use wetgran_core::observe::line::classify_line;
use wetgran_core::observe::{
    CageCounts, Classification, LateralMobility, Mobility, NcbNormalisation, Observables, Phase,
    Profiles, Thresholds, WindowCounts, classify,
};

/// A result of 10 bins: `n_cb` and `(D_lat, T_g/E_cb)` per bin, every grain a cluster member
/// (`clustered` grains per bin of 10), one whole-system mobility `d` with a short lag whose
/// mobility is `d_short` (`None`: no short lag).
fn synthetic(n_cb: Vec<f64>, bins: Vec<(f64, f64)>, d: f64, d_short: Option<f64>) -> Observables {
    let spread = |v: &[f64]| {
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - v.iter().copied().fold(f64::INFINITY, f64::min)
    };
    let n = n_cb.len();
    let t = bins.iter().map(|b| b.1).sum::<f64>() / n as f64;
    Observables {
        dimension: 2,
        particles: 10 * n,
        period: 1.0,
        window_start: 0.0,
        window_end: 100.0,
        window_samples: 2000,
        sample_interval: 0.05,
        temperature_unit: 0.2844,
        temperature_unit_name: "E_cb".into(),
        granular_temperature_reduced: t,
        bridges_per_particle: 1.0,
        location_changes: None,
        mobility: Some(LateralMobility {
            lag: 10.0,
            diffusion: d,
            diffusion_clustered: None,
            short_lag: d_short.map(|_| 2.5),
            diffusion_short: d_short,
            diffusion_clustered_short: None,
            lags: 30.0,
        }),
        profiles: Profiles {
            bin_width: 4.0,
            bin_width_y: None,
            grid: None,
            centres: (0..n).map(|b| 4.0 * b as f64 + 2.0).collect(),
            centres_y: None,
            particles: vec![10.0; n],
            packing: n_cb.iter().map(|x| 0.1 * x).collect(),
            delta_n_cb: spread(&n_cb),
            delta_n_area: 0.1 * spread(&n_cb),
            n_cb,
            n_cb_normalisation: NcbNormalisation::PerAreaAveragedOverHeight,
            temperature_reduced: bins.iter().map(|x| Some(x.1)).collect(),
            temperature_clustered: bins.iter().map(|x| Some(x.1)).collect(),
            clustered: vec![10.0; n],
            diffusion: bins.iter().map(|x| Some(x.0)).collect(),
            diffusion_clustered: bins.iter().map(|x| Some(x.0)).collect(),
            flc: None,
            n_cb_standard_error: Some(0.01),
            packing_standard_error: Some(0.01),
            noise_blocks: 32,
            diffusion_short: vec![],
            diffusion_clustered_short: vec![],
            n_cb_null: None,
            packing_null: None,
            clusters: None,
            member_cages: None,
        },
        diffusion: None,
        counts: WindowCounts {
            pair_collisions: 0,
            wall_collisions: 0,
            bridge_formations: 0,
            bridge_ruptures: 0,
            pair_per_wall: None,
        },
        series: None,
        shear: None,
        trend: None,
    }
}

/// A homogeneous result: `D_lat = d` (short lag `d_short`), `T_g/E_cb = t` everywhere.
fn homogeneous(d: f64, d_short: Option<f64>, t: f64) -> Observables {
    synthetic(vec![3.0; 10], vec![(d, t); 10], d, d_short)
}

/// Bins 0..5 dense (`n_cb` 6) with `(D, T)` `dense`, bins 5..10 dilute (`n_cb` 0.5).
fn two_regions(dense: (f64, f64), dilute: (f64, f64)) -> Observables {
    let region = |b: usize| if b < 5 { dense } else { dilute };
    synthetic(
        (0..10).map(|b| if b < 5 { 6.0 } else { 0.5 }).collect(),
        (0..10).map(region).collect(),
        0.5 * (dense.0 + dilute.0),
        None,
    )
}

/// The criterion of a classification, checked against its label and against the same record
/// read back from its stored JSON.
fn decided(c: &Classification) -> DecidedBy {
    let by = DecidedBy::of(&c.decided_on);
    assert_eq!(by.phase, c.phase, "{}", by.summary);
    let stored = serde_json::to_value(&c.decided_on).unwrap();
    assert_eq!(DecidedBy::of_json(&stored).as_ref(), Some(&by));
    by
}

#[test]
fn solid_or_mobile_criteria() {
    let th = Thresholds::default();
    // Below solid_diffusion: solid by displacement.
    let by = decided(&classify(&homogeneous(2.2e-4, Some(2.2e-4), 0.5), &th));
    assert_eq!(
        (by.phase, by.criterion),
        (Phase::S, Criterion::Displacement)
    );
    assert!(!by.fallback);
    assert!(
        by.summary.contains("D_lat 2.2e-4 <= solid_diffusion 0.001"),
        "{}",
        by.summary
    );
    // Above it, but the MSD saturates within a diameter (short-lag mobility 4 times the long
    // one over a lag ratio 4: exponent 0): solid by its cage.
    let by = decided(&classify(&homogeneous(5e-3, Some(2e-2), 0.5), &th));
    assert_eq!((by.phase, by.criterion), (Phase::S, Criterion::Cage));
    assert!(
        by.summary
            .contains("< diffusive_exponent 0.5 within a diameter"),
        "{}",
        by.summary
    );
    // Diffusing (exponent 1): mobile by displacement; fluid by the per-point fallback.
    let by = decided(&classify(&homogeneous(5e-3, Some(5e-3), 0.5), &th));
    assert_eq!(by.phase, Phase::F);
    assert_eq!(by.regions[0].mobility, Criterion::Displacement);
    assert_eq!(by.criterion, Criterion::GasTemperatureFallback);
    assert!(by.fallback);
    // No mobility stored although displacement was asked: the temperature fallback.
    let mut o = homogeneous(5e-3, None, 0.01);
    o.mobility = None;
    o.profiles.diffusion = vec![None; 10];
    let by = decided(&classify(&o, &th));
    assert_eq!(
        (by.phase, by.criterion),
        (Phase::S, Criterion::TemperatureFallback)
    );
    assert!(by.fallback);
    assert!(
        by.summary.contains("mobility not measured"),
        "{}",
        by.summary
    );
    // The same, asked for: temperature, not a fallback.
    let asked = Thresholds {
        mobility: Mobility::Temperature,
        ..Thresholds::default()
    };
    let by = decided(&classify(&o, &asked));
    assert_eq!((by.phase, by.criterion), (Phase::S, Criterion::Temperature));
    assert!(!by.fallback);
    // Location changes, as asked.
    let flc = Thresholds {
        mobility: Mobility::LocationChanges,
        ..Thresholds::default()
    };
    let mut o = homogeneous(5e-3, None, 0.5);
    o.location_changes = Some(wetgran_core::observe::LocationChanges {
        method: "delaunay".into(),
        count: 0,
        per_particle_per_period: 0.01,
        per_particle_per_time: None,
        sample_interval: 0.05,
    });
    let by = decided(&classify(&o, &flc));
    assert_eq!(
        (by.phase, by.criterion),
        (Phase::S, Criterion::LocationChanges)
    );
    assert!(by.summary.contains("f_lc 0.01 <= solid_flc 0.02"));
}

#[test]
fn a_dense_region_still_in_its_cage_is_decided_by_its_members() {
    let th = Thresholds::default();
    // A bonded dense part whose mean D_lat is above solid_diffusion (an eroding edge) in a hot
    // vapour; 0.92 of its members' displacements within solid_diffusion of their cage.
    let mut o = two_regions((2.8e-3, 0.3), (0.5, 10.0));
    o.profiles.member_cages = Some(CageCounts {
        edges: vec![1e-4, 1e-3, 1e-2],
        measured: vec![100.0; 10],
        within: vec![vec![50.0, 92.0, 100.0]; 10],
    });
    let c = classify(&o, &th);
    let by = decided(&c);
    assert_eq!(
        (by.phase, by.criterion),
        (Phase::Sgc, Criterion::MembersStill)
    );
    assert_eq!(
        by.regions.iter().map(|r| r.region).collect::<Vec<_>>(),
        [Region::Dense, Region::Dilute]
    );
    assert_eq!(by.regions[1].fluid_gas, Some(Criterion::RegionTemperature));
    assert!(
        by.summary
            .contains("members still in their cage 0.92 >= still_members 0.8"),
        "{}",
        by.summary
    );
    // With the cut above 0.92 the members do not hold it, and it is mobile by displacement.
    let strict = Thresholds {
        still_members: 0.95,
        ..Thresholds::default()
    };
    let by = decided(&classify(&o, &strict));
    assert_eq!(by.phase, Phase::Fgc, "{}", by.summary);
    assert_eq!(by.regions[0].mobility, Criterion::Displacement);
}

#[test]
fn coexistence_regions_by_their_own_temperatures() {
    let th = Thresholds::default();
    // A hot drop (2.2 > gas_temperature) in a vapour 34 times hotter: condensed by the jump
    // between the regions.
    let by = decided(&classify(&two_regions((0.3, 2.2), (4.0, 75.0)), &th));
    assert_eq!(
        (by.phase, by.criterion),
        (Phase::Fgc, Criterion::DiluteHotter)
    );
    assert!(!by.fallback);
    assert!(by.summary.contains("34.1 times hotter"), "{}", by.summary);
    // A cool fluid drop in a gas: its own temperature.
    let by = decided(&classify(&two_regions((0.3, 0.9), (4.0, 75.0)), &th));
    assert_eq!(
        (by.phase, by.criterion),
        (Phase::Fgc, Criterion::RegionTemperature)
    );
}

#[test]
fn fluid_or_gas_criteria_of_a_line() {
    let th = Thresholds::default();
    let fluid = homogeneous(5e-2, Some(5e-2), 0.8);
    let line = |method: &str| FluidGasFrom::Line {
        gamma: 0.49999999999999994,
        method: method.into(),
        e_star_boundary: 1.1958,
    };
    for (method, want) in [
        ("jump", Criterion::LineJump),
        ("inflection", Criterion::LineInflection),
        ("coexistence", Criterion::LineCoexistences),
    ] {
        let by = decided(&classify_with(&fluid, &th, &|_| false, line(method)));
        assert_eq!((by.phase, by.criterion), (Phase::F, want));
        assert!(!by.fallback);
        assert!(
            by.summary.contains("Gamma 0.5:") && by.summary.contains("E* 1.2"),
            "{}",
            by.summary
        );
        assert!(!by.summary.contains("0.4999"), "{}", by.summary);
    }
    // A line whose curve shows no transition: the fallback decided.
    let none = FluidGasFrom::LineWithoutTransition {
        gamma: 30.0,
        method: "jump".into(),
        reason: "no step stands out".into(),
    };
    let by = decided(&classify_with(&fluid, &th, &|t| t > 2.0, none));
    assert_eq!(by.criterion, Criterion::GasTemperatureFallback);
    assert!(by.fallback);
    assert!(by.summary.contains("shows no jump"), "{}", by.summary);
    // A real line with a jump (1 % errors stored), and a point between its coexistences.
    let curve = [(0.5, 0.3), (0.7, 0.5), (1.0, 0.8), (1.5, 30.0), (2.0, 60.0)];
    let obs: Vec<Observables> = curve
        .iter()
        .map(|&(_, t)| with_error(homogeneous(1.0, Some(1.0), t), 0.01))
        .collect();
    let pts: Vec<(f64, &Observables)> = curve.iter().zip(&obs).map(|(c, o)| (c.0, o)).collect();
    let labels = classify_line(30.0, &pts, &th, true);
    let by: Vec<Criterion> = labels.iter().map(|c| decided(c).criterion).collect();
    assert_eq!(by, [Criterion::LineJump; 5]);
    assert_eq!(labels[4].phase, Phase::G);
}

#[test]
fn a_point_between_the_line_coexistences_took_the_fallback() {
    let th = Thresholds::default();
    // An inelastic line without an inflection (a power law), with fluid-gas coexistences at
    // E* 1 and 2: the homogeneous point at E* 1.5 lies between them and keeps the per-point
    // label; those outside are decided by the coexistences.
    let fgc = two_regions((0.3, 0.9), (4.0, 75.0));
    let points: Vec<(f64, Observables)> = vec![
        (0.3, homogeneous(1.0, Some(1.0), 0.3)),
        (0.5, homogeneous(1.0, Some(1.0), 0.5)),
        (0.7, homogeneous(1.0, Some(1.0), 0.7)),
        (1.0, fgc.clone()),
        (1.5, homogeneous(1.0, Some(1.0), 1.5)),
        (2.0, fgc),
        (3.0, homogeneous(1.0, Some(1.0), 300.0)),
    ];
    let pts: Vec<(f64, &Observables)> = points.iter().map(|(e, o)| (*e, o)).collect();
    let labels = classify_line(10.0, &pts, &th, false);
    let by: Vec<Criterion> = labels.iter().map(|c| decided(c).criterion).collect();
    assert_eq!(
        by[0],
        Criterion::LineCoexistences,
        "{}",
        labels[0].decided_on.reason
    );
    assert_eq!(
        by[4],
        Criterion::GasTemperatureFallback,
        "{}",
        labels[4].decided_on.reason
    );
    assert_eq!(
        by[6],
        Criterion::LineCoexistences,
        "{}",
        labels[6].decided_on.reason
    );
}

#[test]
fn sheared_scenes_are_decided_by_e_par() {
    use wetgran_core::observe::shear::ShearObservables;
    let mut o = two_regions((0.5, 5.0), (0.0, 0.0));
    o.shear = Some(ShearObservables {
        e_par: 0.0123456,
        e_perp: 0.01,
        cycles: Vec::new(),
        series: Vec::new(),
    });
    let by = decided(&classify(&o, &Thresholds::default()));
    assert_eq!((by.phase, by.criterion), (Phase::S, Criterion::EPar));
    assert!(by.regions.is_empty());
    assert!(
        by.summary.contains("0.0123 <= shear_e_par 0.1"),
        "{}",
        by.summary
    );
}

#[test]
fn names_letters_and_unreadable_records() {
    let mut letters: Vec<char> = Criterion::ALL.iter().map(|c| c.letter()).collect();
    letters.sort();
    letters.dedup();
    assert_eq!(letters.len(), Criterion::ALL.len());
    for c in Criterion::ALL {
        assert_eq!(serde_json::to_value(c).unwrap(), c.name());
        assert_eq!(c.is_fallback(), c.name().ends_with("_fallback"));
    }
    // Another version's record (or a synthetic one) has no criterion.
    assert!(DecidedBy::of_json(&serde_json::json!({"synthetic": true})).is_none());
}

/// `o` with a stored block error of its temperature, `rel` of its value.
fn with_error(mut o: Observables, rel: f64) -> Observables {
    use wetgran_core::observe::convergence::BlockTest;
    use wetgran_core::observe::trend::{Trend, TrendState};
    let t = o.granular_temperature_reduced;
    o.trend = Some(Trend {
        state: TrendState::Stationary,
        relaxed_at: 0.0,
        relaxed: true,
        from: 0.0,
        to: 100.0,
        region_tests: Vec::new(),
        unrelaxed: Vec::new(),
        policy: None,
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
    });
    o
}
