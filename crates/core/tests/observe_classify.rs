//! The classifier on synthetic observables: every phase, every threshold edge (mobility,
//! fluid/gas fallback, the coexistence noise baseline and contrast), region membership,
//! re-classification from stored numbers, legacy results, the line rule for fluid versus gas,
//! and the fluid-gas inflection line analysis on curves with a known answer.

use wetgran_core::observe::classify::{
    FluidGasFrom, LEGACY_DELTA_N_CB, classify_with, two_class_split,
};
use wetgran_core::observe::convergence::BlockTest;
use wetgran_core::observe::line::{LinePoint, classify_line, fluid_gas_jump};
use wetgran_core::observe::noise::range_quantile;
use wetgran_core::observe::trend::{Trend, TrendState};
use wetgran_core::observe::{
    LateralMobility, Mobility, NcbNormalisation, Observables, Phase, Profiles, Thresholds,
    WindowCounts, classify, fluid_gas_inflection,
};

/// Statistical error of every synthetic bin's time average.
const SE: f64 = 0.01;

/// Per-bin inputs of a synthetic result.
#[derive(Clone)]
struct Bins {
    n_cb: Vec<f64>,
    packing: Vec<f64>,
    /// `(D_lat, T_g/E_cb)` of all grains per bin.
    all: Vec<(f64, f64)>,
    /// `(D_lat, T_g/E_cb)` of the clustered grains per bin (`None`: no clustered grains).
    clustered: Vec<Option<(f64, f64)>>,
}

fn synthetic(d: f64, t: f64, b: Bins, wet: bool) -> Observables {
    let bins = b.n_cb.len();
    let spread = |v: &[f64]| {
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - v.iter().copied().fold(f64::INFINITY, f64::min)
    };
    Observables {
        dimension: 2,
        particles: 10 * bins,
        period: 1.0,
        window_start: 0.0,
        window_end: 100.0,
        window_samples: 2000,
        sample_interval: 0.05,
        temperature_unit: if wet { 0.2844 } else { 1.0 },
        temperature_unit_name: if wet { "E_cb" } else { "m g d" }.into(),
        granular_temperature_reduced: t,
        bridges_per_particle: 1.0,
        location_changes: None,
        mobility: Some(LateralMobility {
            lag: 10.0,
            diffusion: d,
            diffusion_clustered: None,
            short_lag: None,
            diffusion_short: None,
            diffusion_clustered_short: None,
            lags: 30.0,
        }),
        profiles: Profiles {
            bin_width: 4.0,
            bin_width_y: None,
            grid: None,
            centres: (0..bins).map(|b| 4.0 * b as f64 + 2.0).collect(),
            centres_y: None,
            particles: vec![10.0; bins],
            packing: b.packing.clone(),
            delta_n_cb: spread(&b.n_cb),
            delta_n_area: spread(&b.packing),
            n_cb: b.n_cb,
            n_cb_normalisation: NcbNormalisation::PerAreaAveragedOverHeight,
            temperature_reduced: b.all.iter().map(|x| Some(x.1)).collect(),
            temperature_clustered: b.clustered.iter().map(|x| x.map(|y| y.1)).collect(),
            clustered: b
                .clustered
                .iter()
                .map(|x| if x.is_some() { 8.0 } else { 0.0 })
                .collect(),
            diffusion: b.all.iter().map(|x| Some(x.0)).collect(),
            diffusion_clustered: b.clustered.iter().map(|x| x.map(|y| y.0)).collect(),
            flc: None,
            n_cb_standard_error: Some(SE),
            packing_standard_error: Some(SE),
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

/// A homogeneous system of 10 bins at `n_cb = 3` with one bin higher by `delta`; mobility `d`,
/// temperature `t` everywhere.
fn homogeneous(d: f64, t: f64, delta: f64) -> Observables {
    let n_cb: Vec<f64> = (0..10)
        .map(|b| if b == 0 { 3.0 + delta } else { 3.0 })
        .collect();
    let b = Bins {
        packing: vec![0.5; 10],
        all: vec![(d, t); 10],
        clustered: vec![Some((d, t)); 10],
        n_cb,
    };
    synthetic(d, t, b, true)
}

/// Two regions: bins 0..5 dense (n_cb 6) whose grains are all clustered with `(D, T)`, bins
/// 5..10 dilute (n_cb 0.5) with `(D, T)` and no clustered grains.
fn two_regions(dense: (f64, f64), dilute: (f64, f64)) -> Observables {
    let region = |b: usize| if b < 5 { dense } else { dilute };
    let b = Bins {
        n_cb: (0..10).map(|b| if b < 5 { 6.0 } else { 0.5 }).collect(),
        packing: (0..10).map(|b| if b < 5 { 0.7 } else { 0.1 }).collect(),
        all: (0..10).map(region).collect(),
        clustered: (0..10).map(|b| (b < 5).then_some(dense)).collect(),
    };
    synthetic(
        0.5 * (dense.0 + dilute.0),
        0.5 * (dense.1 + dilute.1),
        b,
        true,
    )
}

fn th() -> Thresholds {
    Thresholds::default()
}

/// `o` with a stored block error of its temperature, `rel` of its value (the trend's block test,
/// where the line rule reads it).
fn with_error(mut o: Observables, rel: f64) -> Observables {
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

/// Points `(E*, T_g/E_cb)` without stored errors.
fn bare(line: &[(f64, f64)]) -> Vec<LinePoint> {
    line.iter().map(|&(e, t)| LinePoint::new(e, t)).collect()
}

#[test]
fn homogeneous_phases_and_their_threshold_edges() {
    let t = th();
    let (sd, gas) = (t.solid_diffusion, t.gas_temperature);
    // Solid versus mobile on D_lat: the edge value is solid.
    assert_eq!(classify(&homogeneous(0.0, 0.5, 0.0), &t).phase, Phase::S);
    assert_eq!(classify(&homogeneous(sd, 0.5, 0.0), &t).phase, Phase::S);
    let above = sd * (1.0 + 1e-12);
    let c = classify(&homogeneous(above, 0.5, 0.0), &t);
    assert_eq!(c.phase, Phase::F);
    assert_eq!(c.decided_on.whole.mobility_from, Mobility::Displacement);
    // A solid stays solid however hot its rattling (a bed vibrated at high Gamma).
    assert_eq!(classify(&homogeneous(sd, 50.0, 0.0), &t).phase, Phase::S);
    // Fluid versus gas per point (no line): T_g/E_cb against gas_temperature, edge is fluid,
    // and the label says it came from the per-point fallback.
    let c = classify(&homogeneous(1.0, gas, 0.0), &t);
    assert_eq!(c.phase, Phase::F);
    assert_eq!(c.decided_on.fluid_gas, FluidGasFrom::PointFallback);
    assert_eq!(
        classify(&homogeneous(1.0, gas * (1.0 + 1e-12), 0.0), &t).phase,
        Phase::G
    );
}

#[test]
fn other_mobility_measures_when_asked_or_without_displacement() {
    let mut t = th();
    let st = t.solid_temperature;
    // No displacement observed: temperature is used, and recorded as used.
    let mut o = homogeneous(1.0, st, 0.0);
    o.mobility = None;
    o.profiles.diffusion = vec![None; 10];
    let c = classify(&o, &t);
    assert_eq!(c.phase, Phase::S);
    assert_eq!(c.decided_on.whole.mobility_from, Mobility::Temperature);
    // mobility = temperature: a large D_lat does not matter.
    t.mobility = Mobility::Temperature;
    assert_eq!(classify(&homogeneous(100.0, st, 0.0), &t).phase, Phase::S);
    assert_eq!(
        classify(&homogeneous(0.0, 2.0 * st, 0.0), &t).phase,
        Phase::F
    );
    // mobility = location_changes: f_lc per period against solid_flc.
    t.mobility = Mobility::LocationChanges;
    let mut o = homogeneous(100.0, 0.5, 0.0);
    o.location_changes = Some(wetgran_core::observe::LocationChanges {
        method: "delaunay".into(),
        count: 0,
        per_particle_per_period: t.solid_flc,
        per_particle_per_time: None,
        sample_interval: 0.05,
    });
    let c = classify(&o, &t);
    assert_eq!(c.phase, Phase::S);
    assert_eq!(c.decided_on.whole.mobility_from, Mobility::LocationChanges);
}

#[test]
fn coexistence_needs_the_noise_baseline_and_the_contrast() {
    let t = th();
    // Ten bins with error SE each: the level quantile of the homogeneous spread.
    let q = SE * range_quantile(10, t.coexistence_level);
    assert!(q > 4.0 * SE && q < 7.0 * SE, "{q}");
    // A bump at the noise threshold is noise, whatever its contrast would say.
    let c = classify(&homogeneous(1.0, 5.0, q), &t);
    assert!(!c.decided_on.split, "{}", c.decided_on.reason);
    let test = c.decided_on.coexistence.as_ref().unwrap();
    assert!((test.noise_threshold.unwrap() - q).abs() < 1e-12);
    // A bump far above the noise but small against the mean (3 -> 3.5: contrast 0.14 < 0.5)
    // is a persistent inhomogeneity of one phase, not a coexistence.
    let c = classify(&homogeneous(1.0, 5.0, 0.5), &t);
    assert!(!c.decided_on.split);
    assert!(c.decided_on.coexistence.as_ref().unwrap().contrast < t.coexistence_contrast);
    // Large and above the noise: split.
    let c = classify(&homogeneous(1.0, 5.0, 10.0), &t);
    assert!(c.decided_on.split, "{}", c.decided_on.reason);
    // The absolute floor, where set, is a further condition.
    let strict = Thresholds {
        coexistence_delta_n_cb: 20.0,
        ..th()
    };
    assert!(
        !classify(&homogeneous(1.0, 5.0, 10.0), &strict)
            .decided_on
            .split
    );
}

#[test]
fn every_coexistence_pair() {
    let t = th();
    let (s, f, g) = ((0.0, 0.01), (1.0, 0.5), (1.0, 10.0));
    assert_eq!(classify(&two_regions(s, f), &t).phase, Phase::Sfc);
    assert_eq!(classify(&two_regions(s, g), &t).phase, Phase::Sgc);
    assert_eq!(classify(&two_regions(f, g), &t).phase, Phase::Fgc);
    assert_eq!(classify(&two_regions(s, s), &t).phase, Phase::S);
    assert_eq!(classify(&two_regions(f, f), &t).phase, Phase::F);
    let c = classify(&two_regions(s, g), &t);
    let dense = c.decided_on.dense.as_ref().unwrap();
    let dilute = c.decided_on.dilute.as_ref().unwrap();
    assert_eq!((dense.phase, dense.bins), (Phase::S, 5));
    assert_eq!(dense.grains, "clustered");
    assert_eq!((dilute.phase, dilute.bins), (Phase::G, 5));
    assert_eq!(c.decided_on.split_n_cb, Some(3.25));
}

/// The issue's case: a bonded cluster in a hot gas. The gas grains that cross the cluster's
/// bins make those bins hot; its bonded grains are cold and immobile. Classified by its
/// clustered grains the cluster is solid (sgc); by everything in its bins it would read as gas.
#[test]
fn the_dense_region_is_its_clustered_grains_not_the_passers_by() {
    let mut o = two_regions((0.0, 0.01), (5.0, 150.0));
    for b in 0..5 {
        o.profiles.temperature_reduced[b] = Some(4.2);
        o.profiles.diffusion[b] = Some(3.0);
    }
    let c = classify(&o, &th());
    assert_eq!(c.phase, Phase::Sgc, "{}", c.decided_on.reason);
    // Without the clustered accumulators (old results), the bins' grains decide: the heated
    // bins read as mobile and hotter than the gas threshold; only the jump to the far hotter
    // vapour keeps them condensed (fgc, not the solid the bonded grains show).
    o.profiles.clustered.clear();
    o.profiles.temperature_clustered.clear();
    o.profiles.diffusion_clustered.clear();
    let c = classify(&o, &th());
    assert_eq!(c.phase, Phase::Fgc, "{}", c.decided_on.reason);
    assert_eq!(c.decided_on.dense.as_ref().unwrap().grains, "all");
}

/// A dry bed (no bridges, n_cb = 0 everywhere) with a dense cluster and a dilute region is a
/// coexistence by its packing profile.
#[test]
fn dry_coexistence_by_packing() {
    let mut o = two_regions((0.0, 0.01), (1.0, 10.0));
    o.temperature_unit_name = "m g d".into();
    o.profiles.n_cb = vec![0.0; 10];
    o.profiles.delta_n_cb = 0.0;
    let c = classify(&o, &th());
    assert_eq!(c.phase, Phase::Sgc, "{}", c.decided_on.reason);
    assert_eq!(
        c.decided_on.coexistence.as_ref().unwrap().profile,
        "packing"
    );
    // The same with a flat packing profile is homogeneous.
    o.profiles.packing = vec![0.4; 10];
    o.profiles.delta_n_area = 0.0;
    assert!(!classify(&o, &th()).decided_on.split);
}

#[test]
fn every_phase_is_reachable() {
    let t = th();
    let cases = [
        (homogeneous(0.0, 0.001, 0.0), Phase::S),
        (homogeneous(1.0, 0.5, 0.0), Phase::F),
        (homogeneous(1.0, 10.0, 0.0), Phase::G),
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
    let obs = two_regions((0.004, 0.3), (1.0, 3.0));
    let json = serde_json::to_string(&obs).unwrap();
    let back: Observables = serde_json::from_str(&json).unwrap();
    assert_eq!(back, obs);
    assert_eq!(classify(&back, &th()).phase, Phase::Fgc);
    let strict = Thresholds {
        solid_diffusion: 0.01,
        ..th()
    };
    let c = classify(&back, &strict);
    assert_eq!(c.phase, Phase::Sgc);
    assert_eq!(c.decided_on.thresholds, strict);
    assert_eq!(c.decided_on.dense.as_ref().unwrap().diffusion, Some(0.004));
    let hot = Thresholds {
        gas_temperature: 5.0,
        ..th()
    };
    assert_eq!(classify(&back, &hot).phase, Phase::F);
    let c2: wetgran_core::observe::Classification =
        serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
    assert_eq!(c2, c);
}

/// Results stored before block statistics (no standard errors, `n_cb` summed over the height)
/// still parse and are tested against the legacy absolute threshold.
#[test]
fn legacy_results_use_the_legacy_threshold() {
    let mut o = homogeneous(1.0, 5.0, LEGACY_DELTA_N_CB);
    o.profiles.n_cb_standard_error = None;
    let mut v = serde_json::to_value(&o).unwrap();
    let p = v["profiles"].as_object_mut().unwrap();
    for key in [
        "n_cb_normalisation",
        "n_cb_standard_error",
        "packing_standard_error",
        "noise_blocks",
        "temperature_clustered",
        "clustered",
        "diffusion",
        "diffusion_clustered",
    ] {
        p.remove(key);
    }
    v.as_object_mut().unwrap().remove("mobility");
    let old: Observables = serde_json::from_value(v).unwrap();
    assert_eq!(
        old.profiles.n_cb_normalisation,
        NcbNormalisation::PerLateralMeasureSummedOverHeight
    );
    assert!(!classify(&old, &th()).decided_on.split);
    let mut above = old.clone();
    above.profiles.delta_n_cb = LEGACY_DELTA_N_CB * 1.01;
    above.profiles.n_cb[0] = 3.0 + LEGACY_DELTA_N_CB * 1.01;
    assert!(classify(&above, &th()).decided_on.split);
}

/// The reasons of a line's labels carry the numbers rounded (three significant digits), not the
/// float noise of a grid (`Gamma = 0.49999999999999994`, `E* = 1.1943617542...`).
#[test]
fn line_reasons_round_their_numbers() {
    let t = th();
    let gamma = 0.1 * 5.0 - 1e-16 * 0.6; // 0.49999999999999994
    assert_ne!(gamma, 0.5);
    let e = |k: i32| 0.3 * 4.0f64.powf(k as f64 / 3.0);
    let curve = [
        (e(0), 0.3),
        (e(1), 0.5),
        (e(2), 0.8),
        (e(3), 30.0),
        (e(4), 60.0),
    ];
    let obs: Vec<Observables> = curve
        .iter()
        .map(|&(_, temp)| with_error(homogeneous(1.0, temp, 0.0), 0.01))
        .collect();
    let pts: Vec<(f64, &Observables)> = curve.iter().zip(&obs).map(|(c, o)| (c.0, o)).collect();
    for c in classify_line(gamma, &pts, &t, true) {
        let r = &c.decided_on.reason;
        assert!(r.contains("line at Gamma = 0.5: "), "{r}");
        assert!(!r.contains("0.4999") && !r.contains("1.19436"), "{r}");
        // Every number in the line's part has at most four significant digits (p-values in
        // scientific notation aside).
        let line_part = &r[r.find("line at Gamma").unwrap()..];
        for word in line_part
            .split(|ch: char| !(ch.is_ascii_digit() || ch == '.' || ch == 'e' || ch == '-'))
        {
            if let Ok(x) = word.parse::<f64>()
                && !word.contains('e')
            {
                let digits = word.trim_start_matches(['-', '0', '.']).replace('.', "");
                assert!(digits.len() <= 4, "{word} in {r} ({x})");
            }
        }
    }
}

/// Along a line of constant Gamma, fluid versus gas follows the jump of `T_g/E_cb(E*)`
/// (elastic) or its inflection (inelastic), for every homogeneous point of the line, whatever
/// the per-point threshold says; solid points do not make the jump.
#[test]
fn fluid_gas_along_a_line() {
    let t = th();
    // Elastic: T jumps from 0.8 to 30 between E* = 1 and 1.5 (errors of 1 % stored); a
    // per-point threshold of 2 would also put 1.5 (T = 1.5 in the curve below) on the fluid
    // side.
    let curve = [
        (0.3, 0.002, 0.0),
        (0.5, 0.3, 1.0),
        (0.7, 0.5, 1.0),
        (1.0, 0.8, 1.0),
        (1.5, 30.0, 1.0),
        (2.0, 60.0, 1.0),
    ];
    let obs: Vec<Observables> = curve
        .iter()
        .map(|&(_, temp, d)| with_error(homogeneous(d, temp, 0.0), 0.01))
        .collect();
    let pts: Vec<(f64, &Observables)> = curve.iter().zip(&obs).map(|(c, o)| (c.0, o)).collect();
    let labels: Vec<Phase> = classify_line(30.0, &pts, &t, true)
        .iter()
        .map(|c| c.phase)
        .collect();
    assert_eq!(
        labels,
        [Phase::S, Phase::F, Phase::F, Phase::F, Phase::G, Phase::G]
    );
    let c = &classify_line(30.0, &pts, &t, true)[3];
    match &c.decided_on.fluid_gas {
        FluidGasFrom::Line {
            gamma,
            method,
            e_star_boundary,
        } => {
            assert_eq!((*gamma, method.as_str()), (30.0, "jump"));
            assert!((e_star_boundary - 1.5f64.sqrt()).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
    // Without stored errors a line of five points cannot estimate its scatter (the jump
    // spoils two of its three residuals): no transition, per-point labels, and it says why.
    let old: Vec<Observables> = curve
        .iter()
        .map(|&(_, temp, d)| homogeneous(d, temp, 0.0))
        .collect();
    let pts_old: Vec<(f64, &Observables)> = curve.iter().zip(&old).map(|(c, o)| (c.0, o)).collect();
    for c in classify_line(30.0, &pts_old, &t, true) {
        assert!(
            matches!(&c.decided_on.fluid_gas,
                FluidGasFrom::LineWithoutTransition { method, reason, .. }
                    if method == "jump" && reason.contains("scatter")),
            "{:?}",
            c.decided_on.fluid_gas
        );
    }
    // The jump must be large: a smooth line has none, and keeps the per-point labels.
    let smooth: Vec<(f64, f64)> = (0..8)
        .map(|k| (0.5 + 0.25 * k as f64, 0.5 + 0.3 * k as f64))
        .collect();
    assert!(fluid_gas_jump(&bare(&smooth), t.line_jump_ratio).is_err());
    let obs: Vec<Observables> = smooth
        .iter()
        .map(|&(_, temp)| with_error(homogeneous(1.0, temp, 0.0), 0.01))
        .collect();
    let pts: Vec<(f64, &Observables)> = smooth.iter().zip(&obs).map(|(c, o)| (c.0, o)).collect();
    for (c, (_, temp)) in classify_line(30.0, &pts, &t, true).iter().zip(&smooth) {
        assert!(matches!(
            c.decided_on.fluid_gas,
            FluidGasFrom::LineWithoutTransition { .. }
        ));
        let want = if *temp > t.gas_temperature {
            Phase::G
        } else {
            Phase::F
        };
        assert_eq!(c.phase, want, "{}", c.decided_on.reason);
    }
    // Inelastic: the inflection of a sigmoid in log-log decides; the per-point threshold (2)
    // would have put the boundary elsewhere (T = 2 lies at E* = 1.26 here). No errors stored:
    // the line's scatter stands in, and the reason says so. Half a bridge per grain: neither a
    // gas's nor a fluid's own evidence (rule 5), so the line alone decides.
    let e0: f64 = 3.0;
    let sig: Vec<(f64, f64)> = (0..12)
        .map(|k| {
            let e = 0.3 * 1.4f64.powi(k);
            (
                e,
                (0.7 + 2.5 * ((e.ln() - e0.ln()) / 0.7).tanh()).exp() / 10.0,
            )
        })
        .collect();
    let obs: Vec<Observables> = sig
        .iter()
        .map(|&(_, temp)| Observables {
            bridges_per_particle: 0.5,
            ..homogeneous(1.0, temp, 0.0)
        })
        .collect();
    let pts: Vec<(f64, &Observables)> = sig.iter().zip(&obs).map(|(c, o)| (c.0, o)).collect();
    let cs = classify_line(10.0, &pts, &t, false);
    for ((e, _), c) in sig.iter().zip(&cs) {
        let want = if *e > 3.0 * 1.1 {
            Phase::G
        } else if *e < 3.0 / 1.1 {
            Phase::F
        } else {
            c.phase
        };
        assert_eq!(c.phase, want, "E* = {e}: {}", c.decided_on.reason);
        assert!(matches!(c.decided_on.fluid_gas, FluidGasFrom::Line { .. }));
        assert!(
            c.decided_on
                .reason
                .contains("estimated from the line's scatter"),
            "{}",
            c.decided_on.reason
        );
    }
}

/// The issue's fluid-only line: `T_g / E_cb` rises eightfold between its first two points, but
/// the line has no transition; every point keeps its per-point label (f) and says why.
#[test]
fn a_fluid_only_line_has_no_boundary() {
    let t = th();
    let line = [(0.3, 0.05), (0.5, 0.4), (0.7, 0.6), (1.0, 0.9)];
    for rel in [None, Some(0.03)] {
        let obs: Vec<Observables> = line
            .iter()
            .map(|&(_, temp)| {
                let o = homogeneous(1.0, temp, 0.0);
                rel.map_or(o.clone(), |r| with_error(o, r))
            })
            .collect();
        let pts: Vec<(f64, &Observables)> = line.iter().zip(&obs).map(|(c, o)| (c.0, o)).collect();
        for elastic in [true, false] {
            for c in classify_line(30.0, &pts, &t, elastic) {
                assert_eq!(c.phase, Phase::F, "{}", c.decided_on.reason);
                assert!(
                    matches!(
                        c.decided_on.fluid_gas,
                        FluidGasFrom::LineWithoutTransition { .. }
                    ),
                    "{:?}",
                    c.decided_on.fluid_gas
                );
                assert!(c.decided_on.reason.contains("no transition"));
            }
        }
    }
}

/// A gas label needs `T_g` on the gas branch, not only `E*` above the boundary: a replica above
/// the jump that stayed cold (T_g/E_cb = 3, hotter than the per-point threshold) stays fluid and
/// says why; its hot twin is gas.
#[test]
fn above_the_boundary_but_off_the_gas_branch_stays_fluid() {
    let t = th();
    let curve = [
        (0.5, 0.3),
        (0.7, 0.5),
        (1.0, 0.8),
        (1.5, 30.0),
        (2.0, 60.0),
        (2.5, 100.0),
        (2.5, 3.0),
        (3.0, 150.0),
    ];
    let obs: Vec<Observables> = curve
        .iter()
        .map(|&(_, temp)| with_error(homogeneous(1.0, temp, 0.0), 0.02))
        .collect();
    let pts: Vec<(f64, &Observables)> = curve.iter().zip(&obs).map(|(c, o)| (c.0, o)).collect();
    let cs = classify_line(30.0, &pts, &t, true);
    let phases: Vec<Phase> = cs.iter().map(|c| c.phase).collect();
    assert_eq!(
        phases,
        [
            Phase::F,
            Phase::F,
            Phase::F,
            Phase::G,
            Phase::G,
            Phase::G,
            Phase::F,
            Phase::G
        ]
    );
    assert!(
        cs[6].decided_on.reason.contains("below the gas branch"),
        "{}",
        cs[6].decided_on.reason
    );
    assert!(matches!(
        cs[6].decided_on.fluid_gas,
        FluidGasFrom::Line { .. }
    ));
}

/// The two Gamma = 30 lines of docs/validation.md (validated against the literature) through
/// `classify_line`, their stored `T_g / E_cb` with errors of 3 %, the coexistences as two-region
/// observables: the labels of the tables come back. eps = 1: the coexistences (0.9 to 1.3) are
/// kept out of the curve, whose jump then lies between 0.7 and 1.6 (it holds the literature's
/// 1.2). eps = 0.96: the homogeneous fluids (up to 1.6, `T_g / E_cb` up to 3.9, above the
/// per-point threshold) and the homogeneous gas at 3.0 show no inflection; the coexistences
/// from 1.9 to 2.6 mark the boundary (between 1.6 and 1.9, the literature's inflection at 1.82),
/// the fluids stay f and the gas above them reads g. The same without stored errors.
#[test]
fn the_validated_gamma_30_lines_keep_their_labels() {
    let t = th();
    let fgc = |temp: f64, rel: Option<f64>| {
        let mut o = two_regions((0.3, 1.5), (4.0, 30.0));
        o.granular_temperature_reduced = temp;
        rel.map_or(o.clone(), |r| with_error(o, r))
    };
    let eps1 = [
        (0.5, 1.217, Phase::F),
        (0.7, 1.888, Phase::F),
        (0.9, 3.897, Phase::Fgc),
        (1.1, 11.530, Phase::Fgc),
        (1.3, 54.479, Phase::Fgc),
        (1.6, 216.025, Phase::G),
        (1.9, 458.565, Phase::G),
        (2.2, 885.862, Phase::G),
        (2.6, 3182.864, Phase::G),
        (3.0, 3950.394, Phase::G),
    ];
    let eps096 = [
        (0.5, 0.849, Phase::F),
        (0.7, 1.211, Phase::F),
        (0.9, 1.645, Phase::F),
        (1.1, 2.156, Phase::F),
        (1.3, 2.767, Phase::F),
        (1.6, 3.943, Phase::F),
        (1.9, 5.711, Phase::Fgc),
        (2.2, 7.723, Phase::Fgc),
        (2.6, 10.433, Phase::Fgc),
        // Homogeneous under the bonded-cluster rule (0.17 cluster members in its dense bins),
        // above and hotter than every coexistence: gas (docs/validation.md, the rerun table).
        (3.0, 13.677, Phase::G),
    ];
    // Stored without errors (as the tables' runs were), the eps = 1 curve's scatter estimate
    // (0.30 in ln T) hides its jump, and its coexistences mark the boundary instead.
    for (line, elastic, rel, method, bracket) in [
        (&eps1, true, Some(0.03), "jump", (0.7, 1.6)),
        (&eps096, false, Some(0.03), "coexistence", (1.6, 1.9)),
        (&eps1, true, None, "coexistence", (0.7, 0.9)),
        (&eps096, false, None, "coexistence", (1.6, 1.9)),
    ] {
        let obs: Vec<Observables> = line
            .iter()
            .map(|&(_, temp, p)| {
                if p == Phase::Fgc {
                    fgc(temp, rel)
                } else {
                    let o = homogeneous(1.0, temp, 0.0);
                    rel.map_or(o.clone(), |r| with_error(o, r))
                }
            })
            .collect();
        let pts: Vec<(f64, &Observables)> = line.iter().zip(&obs).map(|(c, o)| (c.0, o)).collect();
        let cs = classify_line(30.0, &pts, &t, elastic);
        for (&(e, _, want), c) in line.iter().zip(&cs) {
            assert_eq!(c.phase, want, "E* = {e}: {}", c.decided_on.reason);
            match &c.decided_on.fluid_gas {
                FluidGasFrom::Line {
                    method: m,
                    e_star_boundary: b,
                    ..
                } => {
                    assert_eq!(m, method);
                    assert!(bracket.0 < *b && *b < bracket.1, "{b}");
                }
                other => panic!("E* = {e}: {other:?}"),
            }
        }
        println!("errors {rel:?}, {method}: {}", cs[0].decided_on.reason);
    }
}

/// The elastic jump is the step between the two fitted branches at the gap's middle, not the
/// widest ratio: the seeds study's Gamma = 30 line (docs/validation.md) has its largest ratio
/// deep in the heating gas (28 over 1.6 -> 2.6) and its jump at 1.1 -> 1.6 (ratio 17); the
/// 10-point eps = 1 line keeps its boundary 1.1 -> 1.3, E* = 1.196, without stored errors.
#[test]
fn the_jump_of_a_heating_elastic_gas_is_its_step_not_its_widest_ratio() {
    let t = th();
    let seeds: Vec<LinePoint> = [(0.7, 2.0), (1.1, 7.3), (1.6, 124.0), (2.6, 3500.0)]
        .iter()
        .map(|&(e, temp)| LinePoint {
            e_star: e,
            t: temp,
            rel_error: Some(0.05),
        })
        .collect();
    let j = fluid_gas_jump(&seeds, t.line_jump_ratio).unwrap();
    assert_eq!(j.bracket, (1.1, 1.6));
    assert!((j.ratio - 124.0 / 7.3).abs() < 1e-9);
    let line = [
        (0.5, 1.217),
        (0.7, 1.888),
        (0.9, 3.897),
        (1.1, 11.530),
        (1.3, 54.479),
        (1.6, 216.025),
        (1.9, 458.565),
        (2.2, 885.862),
        (2.6, 3182.864),
        (3.0, 3950.394),
    ];
    let j = fluid_gas_jump(&bare(&line), t.line_jump_ratio).unwrap();
    assert_eq!(j.bracket, (1.1, 1.3));
    assert!((j.e_star - 1.196).abs() < 1e-3, "{}", j.e_star);
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
        let inf = fluid_gas_inflection(&bare(&pts)).expect("inside the range");
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
        assert_eq!(fluid_gas_inflection(&bare(&rev)), Ok(inf));
    }
    // A curve that only steepens (the inflection lies beyond the range) has none.
    let convex: Vec<(f64, f64)> = (1..10)
        .map(|k| (k as f64, (k as f64).powi(2).exp()))
        .collect();
    assert!(fluid_gas_inflection(&bare(&convex)).is_err());
    assert!(fluid_gas_inflection(&bare(&convex[..3])).is_err());
}

/// The dense/dilute split uses every bin, not only the two extremes: one outlier bin does not
/// pull the split to itself.
#[test]
fn split_is_two_classes_not_the_range_midpoint() {
    let n_cb = [6.0, 6.0, 6.0, 6.0, 6.0, 1.0, 1.0, 1.0, 1.0, 12.0];
    assert_eq!(two_class_split(&n_cb), 3.5);
    assert_eq!(two_class_split(&[2.0, 4.0]), 3.0);
    assert_eq!(two_class_split(&[5.0]), 5.0);
    // Solid bins (dense, D 0) next to fluid ones (D 1), one very dense solid bin: sfc.
    let solid = |b: usize| b < 5 || b == 9;
    let b = Bins {
        n_cb: n_cb.to_vec(),
        packing: vec![0.5; 10],
        all: (0..10)
            .map(|b| if solid(b) { (0.0, 0.01) } else { (1.0, 0.5) })
            .collect(),
        clustered: (0..10)
            .map(|b| Some(if solid(b) { (0.0, 0.01) } else { (1.0, 0.5) }))
            .collect(),
    };
    let obs = synthetic(0.4, 0.2, b, true);
    let c = classify(&obs, &th());
    assert_eq!(c.phase, Phase::Sfc, "{}", c.decided_on.reason);
    assert_eq!(c.decided_on.dense.as_ref().unwrap().bins, 6);
}

#[test]
fn sheared_scenes_are_solid_or_fluid_by_e_par() {
    use wetgran_core::observe::shear::ShearObservables;
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

/// Inputs close to their thresholds are flagged: the label is uncertain there.
#[test]
fn borderline_decisions_are_flagged() {
    let t = th();
    let c = classify(&homogeneous(1.5 * t.solid_diffusion, 0.5, 0.0), &t);
    assert_eq!(c.phase, Phase::F);
    assert_eq!(
        c.decided_on.borderline.len(),
        1,
        "{:?}",
        c.decided_on.borderline
    );
    assert!(c.decided_on.borderline[0].contains("D_lat"));
    let c = classify(&homogeneous(0.6 * t.solid_diffusion, 0.5, 0.0), &t);
    assert_eq!(c.phase, Phase::S);
    assert_eq!(c.decided_on.borderline.len(), 1);
    // Far from every threshold: clear.
    assert!(
        classify(&homogeneous(100.0 * t.solid_diffusion, 0.5, 0.0), &t)
            .decided_on
            .borderline
            .is_empty()
    );
    assert!(
        classify(&two_regions((0.0, 0.01), (1.0, 10.0)), &t)
            .decided_on
            .borderline
            .is_empty()
    );
    // A bonded dense part just above or below `cluster_fraction` (members 2.5 and 1.5 of the
    // 10 grains of each dense bin): the split hangs on it, flagged either way; 8 of 10: clear.
    let members = |m: f64| {
        let mut o = two_regions((0.0, 0.01), (1.0, 10.0));
        o.profiles.clusters = Some((0.2, 3));
        for (c, n) in o.profiles.clustered.iter_mut().zip(&o.profiles.n_cb) {
            *c = if *n > 1.0 { m } else { 0.0 };
        }
        classify(&o, &t)
    };
    for (m, split) in [(2.5, true), (1.5, false)] {
        let c = members(m);
        assert_eq!(c.decided_on.split, split, "{}", c.decided_on.reason);
        assert!(
            c.decided_on
                .borderline
                .iter()
                .any(|b| b.contains("cluster_fraction")),
            "{m}: {:?}",
            c.decided_on.borderline
        );
    }
    assert!(members(8.0).decided_on.borderline.is_empty());
}

/// A bonded drop in its vapour: the drop's clustered grains are a little hotter than the gas
/// threshold, but their vapour is far hotter still: fgc. A gas with a weak density modulation
/// (both regions hot, within the jump ratio of each other) stays g.
#[test]
fn a_hot_drop_in_a_much_hotter_vapour_is_a_fluid_gas_coexistence() {
    let t = th();
    let c = classify(&two_regions((0.3, 2.2), (4.0, 75.0)), &t);
    assert_eq!(c.phase, Phase::Fgc, "{}", c.decided_on.reason);
    let c = classify(&two_regions((2.0, 95.0), (4.0, 233.0)), &t);
    assert_eq!(c.phase, Phase::G, "{}", c.decided_on.reason);
    // The line rule does not touch coexistences: above the line's boundary the drop stays.
    let obs = two_regions((0.3, 2.2), (4.0, 75.0));
    let c = wetgran_core::observe::classify::classify_with(
        &obs,
        &t,
        &|_| true,
        FluidGasFrom::PointFallback,
    );
    assert_eq!(c.phase, Phase::Fgc);
}

/// `decided_on.fluid_gas` as stored by earlier versions still reads, and the new "no
/// transition" record round-trips under its tag.
#[test]
fn fluid_gas_records_old_and_new_deserialize() {
    let old: FluidGasFrom = serde_json::from_str(r#"{"by": "point_fallback"}"#).unwrap();
    assert_eq!(old, FluidGasFrom::PointFallback);
    let line: FluidGasFrom = serde_json::from_str(
        r#"{"by": "line", "gamma": 30.0, "method": "jump", "e_star_boundary": 1.196}"#,
    )
    .unwrap();
    assert!(matches!(line, FluidGasFrom::Line { e_star_boundary, .. } if e_star_boundary == 1.196));
    let none = FluidGasFrom::LineWithoutTransition {
        gamma: 10.0,
        method: "inflection".into(),
        reason: "a power law fits the line".into(),
    };
    let v = serde_json::to_value(&none).unwrap();
    assert_eq!(v["by"], "line_without_transition");
    assert_eq!(serde_json::from_value::<FluidGasFrom>(v).unwrap(), none);
}

/// What a line of constant Gamma said about a point: fluid (`false`) or gas (`true`) at a jump
/// between E* = 1 and 2.
fn line_said(o: &Observables, gas: bool) -> wetgran_core::observe::Classification {
    let from = FluidGasFrom::Line {
        gamma: 10.0,
        method: "jump".into(),
        e_star_boundary: 1.5,
    };
    classify_with(o, &th(), &|_| gas, from)
}

/// Rule 5: a line may not call fluid what is hot and nearly bridgeless, nor gas what is cold
/// and bonded; the point's own evidence decides and the conflict is flagged. The eps = 0.96 line
/// at Gamma = 10 read f at T_g/E_cb 12.8-26 with fewer than 0.15 bridges per grain.
#[test]
fn a_point_s_own_evidence_bounds_the_line() {
    let hot = Observables {
        bridges_per_particle: 0.12,
        ..homogeneous(1.0, 12.8, 0.0)
    };
    let c = line_said(&hot, false);
    assert_eq!(c.phase, Phase::G, "{}", c.decided_on.reason);
    assert!(matches!(
        c.decided_on.fluid_gas,
        FluidGasFrom::OwnEvidence {
            line_said: Phase::F,
            ..
        }
    ));
    assert!(
        c.decided_on.borderline.iter().any(|b| b.contains("rule 5")),
        "{:?}",
        c.decided_on.borderline
    );
    assert!(c.decided_on.reason.contains("own evidence"));
    // Cold and bonded: a fluid, whatever the line said.
    let cold = Observables {
        bridges_per_particle: 1.5,
        ..homogeneous(1.0, 0.6, 0.0)
    };
    assert_eq!(line_said(&cold, true).phase, Phase::F);
    // Between the two (T_g/E_cb 5, half a bridge per grain, or hot but bonded) the line decides.
    for (t, b) in [(5.0, 0.5), (12.8, 0.5), (0.6, 0.5)] {
        let o = Observables {
            bridges_per_particle: b,
            ..homogeneous(1.0, t, 0.0)
        };
        for gas in [false, true] {
            let c = line_said(&o, gas);
            assert_eq!(c.phase == Phase::G, gas, "T {t}, bridges {b}");
            assert!(matches!(c.decided_on.fluid_gas, FluidGasFrom::Line { .. }));
            assert!(
                c.decided_on
                    .borderline
                    .iter()
                    .all(|x| !x.contains("rule 5"))
            );
        }
    }
    // A dry point has no bridges to weigh: the line decides.
    let mut dry = hot.clone();
    dry.temperature_unit_name = "m g d".into();
    assert_eq!(line_said(&dry, false).phase, Phase::F);
}

/// A fluid-gas decision by the per-point fallback is flagged when the temperature lies within a
/// factor 2 of `gas_temperature`, and not otherwise; a solid-mobile decision that fell back to
/// the temperature because the mobility was not measured is flagged.
#[test]
fn fallback_decisions_near_their_threshold_are_borderline() {
    let near = classify(&homogeneous(1.0, 2.5, 0.0), &th());
    assert_eq!(near.phase, Phase::G);
    assert!(
        near.decided_on
            .borderline
            .iter()
            .any(|b| b.contains("gas_temperature")),
        "{:?}",
        near.decided_on.borderline
    );
    for t in [0.5, 8.0] {
        let far = classify(&homogeneous(1.0, t, 0.0), &th());
        assert!(
            far.decided_on
                .borderline
                .iter()
                .all(|b| !b.contains("gas_temperature")),
            "T {t}: {:?}",
            far.decided_on.borderline
        );
    }
    let mut unmeasured = homogeneous(1.0, 0.5, 0.0);
    unmeasured.mobility = None;
    let c = classify(&unmeasured, &th());
    assert_eq!(c.decided_on.whole.mobility_from, Mobility::Temperature);
    assert!(
        c.decided_on
            .borderline
            .iter()
            .any(|b| b.contains("mobility not measured")),
        "{:?}",
        c.decided_on.borderline
    );
}
