use super::*;
use crate::observe::bins::LateralBins;
use crate::observe::convergence::block_test;
use crate::observe::convergence::tests::ar1;
use crate::observe::lateral::LateralSettings;
use crate::observe::trend::{BRIDGES, DELTA_N_CB, TEMPERATURE};
use crate::sim::Frame;

/// A history of 800 samples around `level` (noise 1 %, correlation time about 10 samples) that
/// changes by the fraction `by` over its length.
fn history(level: f64, by: f64, seed: u64) -> Vec<f64> {
    let n = 800;
    let scale = 0.01 * level * (1.0 - 0.81f64).sqrt();
    ar1(0.9, n, seed)
        .into_iter()
        .enumerate()
        .map(|(i, e)| level * (1.0 + by * i as f64 / n as f64) + scale * e)
        .collect()
}

/// The block test of `name` on a history that changes by `by`.
fn test(name: &str, level: f64, by: f64, seed: u64) -> BlockTest {
    block_test(name, &history(level, by, seed), 4, 3.0, 0.02, 0.05)
}

/// Block tests: flat for every quantity, except those in `moving` (name, change over the run).
fn tests(flat: &[&str], moving: &[(&str, f64)]) -> Vec<BlockTest> {
    let mut out: Vec<BlockTest> = flat
        .iter()
        .enumerate()
        .map(|(k, q)| test(q, 1.0, 0.0, 10 + k as u64))
        .collect();
    out.extend(
        moving
            .iter()
            .enumerate()
            .map(|(k, (q, by))| test(q, 1.0, *by, 50 + k as u64)),
    );
    out
}

const WHOLE: [&str; 5] = [TEMPERATURE, MOBILITY, MEMBER_FRACTION, BRIDGES, DELTA_N_CB];

/// The whole system's quantities flat, except `moving`.
fn whole_except(moving: &[(&str, f64)]) -> Vec<BlockTest> {
    let flat: Vec<&str> = WHOLE
        .into_iter()
        .filter(|q| moving.iter().all(|(m, _)| m != q))
        .collect();
    tests(&flat, moving)
}

#[test]
fn blocks_are_a_whole_fraction_of_the_period_and_fill_the_first_window() {
    // A fast drive: one period per block.
    assert_eq!(block_time(0.5, 30.0), 0.5);
    // A slow drive: the largest whole fraction of the period no longer than a time unit.
    assert!((block_time(3.0, 30.0) - 1.0).abs() < 1e-12);
    assert!((block_time(2.5, 30.0) - 2.5 / 3.0).abs() < 1e-12);
    // A short first window: at least 16 blocks in it.
    let b = block_time(1.58, 4.0);
    assert!(
        (b - 1.58 / 7.0).abs() < 1e-12 && 4.0 / b >= MIN_WINDOW_BLOCKS,
        "{b}"
    );
}

#[test]
fn directions_read_from_block_tests() {
    assert_eq!(Direction::of(&test("x", 1.0, 0.0, 1)), Direction::Flat);
    assert_eq!(Direction::of(&test("x", 1.0, 0.3, 2)), Direction::Rising);
    assert_eq!(Direction::of(&test("x", 1.0, -0.3, 3)), Direction::Falling);
    // Up in the middle half, back down: blocks disagree without a drift.
    let mut step = history(1.0, 0.0, 4);
    for v in &mut step[200..600] {
        *v += 0.2;
    }
    let t = block_test("x", &step, 4, 3.0, 0.02, 0.05);
    assert_eq!(Direction::of(&t), Direction::Unsteady, "{t:?}");
    // Seven values cannot fill four blocks of two.
    let short = block_test("x", &[1.0; 7], 4, 3.0, 0.02, 0.05);
    assert_eq!(Direction::of(&short), Direction::Unknown);
}

#[test]
fn a_solid_still_cooling_is_settled_a_fluid_still_cooling_is_not() {
    let cooling = whole_except(&[(TEMPERATURE, -0.4)]);
    let s = settle(Phase::S, None, &[], &cooling);
    assert_eq!(s.verdict, Verdict::LabelKept, "{s:?}");
    let f = settle(Phase::F, None, &[], &cooling);
    assert_eq!(f.verdict, Verdict::NotSettled);
    assert_eq!(
        f.unsettled_text(),
        vec!["whole (f): temperature_reduced falling"]
    );
    // A heating solid may melt.
    let heating = whole_except(&[(TEMPERATURE, 0.4)]);
    assert_eq!(
        settle(Phase::S, None, &[], &heating).verdict,
        Verdict::NotSettled
    );
    // A solid losing members may melt at its surface.
    let melting = whole_except(&[(MEMBER_FRACTION, -0.4)]);
    assert_eq!(
        settle(Phase::S, None, &[], &melting).verdict,
        Verdict::NotSettled
    );
}

#[test]
fn a_heating_gas_keeps_its_label_only_while_nothing_condenses() {
    let heating = whole_except(&[(TEMPERATURE, 1.0)]);
    assert_eq!(
        settle(Phase::G, None, &[], &heating).verdict,
        Verdict::LabelKept
    );
    for condensing in [BRIDGES, DELTA_N_CB, MEMBER_FRACTION] {
        let t = whole_except(&[(TEMPERATURE, 1.0), (condensing, 0.5)]);
        let s = settle(Phase::G, None, &[], &t);
        assert_eq!(s.verdict, Verdict::NotSettled, "{condensing}");
        assert_eq!(
            s.unsettled_text(),
            vec![format!("whole (g): {condensing} rising")]
        );
    }
    // A cooling gas may condense.
    let cooling = whole_except(&[(TEMPERATURE, -0.4)]);
    assert_eq!(
        settle(Phase::G, None, &[], &cooling).verdict,
        Verdict::NotSettled
    );
}

/// A coexistence's tests: its whole-system and region quantities flat, except `moving`.
fn coexistence_except(moving: &[(&str, f64)]) -> Vec<BlockTest> {
    let all = [
        MEMBER_FRACTION,
        DELTA_N_CB,
        MEMBER_TEMPERATURE,
        MEMBER_MOBILITY,
        MEMBERS_STILL,
        UNBONDED_TEMPERATURE,
        UNBONDED_MOBILITY,
    ];
    let flat: Vec<&str> = all
        .into_iter()
        .filter(|q| moving.iter().all(|(m, _)| m != q))
        .collect();
    tests(&flat, moving)
}

#[test]
fn a_coexistence_is_settled_only_when_each_region_is() {
    // The drop of a fluid-gas coexistence still cooling may freeze: not settled, and the
    // verdict names the dense region.
    let cooling_drop = coexistence_except(&[(MEMBER_TEMPERATURE, -0.4)]);
    let fgc = settle(Phase::Fgc, Some((Phase::F, Phase::G)), &[], &cooling_drop);
    assert_eq!(fgc.verdict, Verdict::NotSettled);
    assert_eq!(
        fgc.unsettled_text(),
        vec!["dense (f): member_temperature falling"]
    );
    // A solid drop still cooling, its members stiffening, is still solid.
    let stiffening = coexistence_except(&[(MEMBER_TEMPERATURE, -0.4), (MEMBERS_STILL, 0.2)]);
    let sgc = settle(Phase::Sgc, Some((Phase::S, Phase::G)), &[], &stiffening);
    assert_eq!(sgc.verdict, Verdict::LabelKept, "{sgc:?}");
    // Drops merging into fewer, larger ones keep the coexistence; dissolving ones do not.
    let coarsening = coexistence_except(&[(DELTA_N_CB, 0.5)]);
    assert_eq!(
        settle(Phase::Fgc, Some((Phase::F, Phase::G)), &[], &coarsening).verdict,
        Verdict::LabelKept
    );
    let dissolving = coexistence_except(&[(DELTA_N_CB, -0.5)]);
    assert_eq!(
        settle(Phase::Fgc, Some((Phase::F, Phase::G)), &[], &dissolving).verdict,
        Verdict::NotSettled
    );
    // A drop still growing may swallow its vapour.
    let growing = coexistence_except(&[(MEMBER_FRACTION, 0.5)]);
    let s = settle(Phase::Sgc, Some((Phase::S, Phase::G)), &[], &growing);
    assert_eq!(s.verdict, Verdict::NotSettled);
    assert_eq!(
        s.unsettled_text(),
        vec!["whole (sgc): member_fraction rising"]
    );
    // The vapour of a solid-gas coexistence may heat.
    let hot_vapour = coexistence_except(&[(UNBONDED_TEMPERATURE, 0.5)]);
    assert_eq!(
        settle(Phase::Sgc, Some((Phase::S, Phase::G)), &[], &hot_vapour).verdict,
        Verdict::LabelKept
    );
}

#[test]
fn stationary_needs_every_named_quantity_flat_and_relaxed() {
    let flat = whole_except(&[]);
    assert_eq!(
        settle(Phase::F, None, &[], &flat).verdict,
        Verdict::Stationary
    );
    // A quantity the label names whose history had not relaxed: settled, not stationary.
    let unrelaxed = [TEMPERATURE.to_string()];
    assert_eq!(
        settle(Phase::S, None, &unrelaxed, &flat).verdict,
        Verdict::LabelKept
    );
    // One the label does not name does not count.
    let other = [MEMBER_TEMPERATURE.to_string()];
    assert_eq!(
        settle(Phase::F, None, &other, &flat).verdict,
        Verdict::Stationary
    );
}

#[test]
fn a_quantity_without_a_test_is_left_out_one_without_data_is_unknown() {
    // A dry scene monitors no bridges and no contrast.
    let dry = tests(&[TEMPERATURE, MOBILITY, MEMBER_FRACTION], &[]);
    let s = settle(Phase::S, None, &[], &dry);
    assert_eq!(s.verdict, Verdict::Stationary);
    assert_eq!(s.regions[0].quantities.len(), 3);
    // A test that could not fill its blocks reads unknown and is not settled.
    let mut short = dry.clone();
    short.push(block_test(BRIDGES, &[2.0; 5], 4, 3.0, 0.02, 0.1));
    let s = settle(Phase::S, None, &[], &short);
    assert_eq!(s.verdict, Verdict::NotSettled);
    assert_eq!(
        s.unsettled_text(),
        vec!["whole (s): bridges_per_particle unknown"]
    );
    // A quantity with no values at all has NaN statistics; stored (NaN as JSON null) and read
    // back, it is still unknown.
    let empty = block_test(MOBILITY, &[], 4, 3.0, 0.02, 0.1);
    assert!(empty.mean.is_nan());
    let stored = serde_json::to_string(&empty).unwrap();
    assert!(stored.contains("\"mean\":null"), "{stored}");
    let read: BlockTest = serde_json::from_str(&stored).expect("a stored empty test reads back");
    assert_eq!(Direction::of(&read), Direction::Unknown);
    // Observables without any trend: nothing to settle on.
    assert_eq!(
        settle(Phase::G, None, &[], &[]).verdict,
        Verdict::Stationary
    );
}

/// A 2D frame in a 40 x 10 box periodic in x.
fn frame(x: &[(f64, f64)], v: &[(f64, f64)], bridges: Vec<(usize, usize)>, t: f64) -> Frame {
    let mut f = Frame::from_parts(
        2,
        vec![40.0, 10.0],
        vec![true, false],
        x.iter().flat_map(|p| [p.0, p.1]).collect(),
        v.iter().flat_map(|p| [p.0, p.1]).collect(),
        vec![0.5; x.len()],
        bridges,
    );
    f.time = t;
    f
}

#[test]
fn region_series_follow_members_and_the_other_grains() {
    // A still bonded row of six grains and four unbonded grains flying at +-2 along x in
    // pairs (their bin's non-member mean velocity 0): member fraction 0.6, members' temperature
    // 0, the others' m sum |v|^2 / (D (n - 1)) per bin, every member in its cage.
    let settings = LateralSettings {
        wet: true,
        unit: 1.0,
        sample_interval: 0.25,
        block_time: 1.0,
        lag: 2.0,
        bond_time: 0.5,
        cluster_min_size: 3,
    };
    let mut monitor = LateralObserver::new(LateralBins::new(1, 40.0), settings);
    let bonds: Vec<(usize, usize)> = (0..5).map(|i| (i, i + 1)).collect();
    for k in 0..80 {
        let t = 0.25 * k as f64;
        let mut x: Vec<(f64, f64)> = (0..6).map(|i| (10.0 + i as f64, 1.0)).collect();
        let mut v = vec![(0.0, 0.0); 6];
        for (j, s) in [2.0, -2.0, 2.0, -2.0].into_iter().enumerate() {
            x.push(((20.0 + s * t).rem_euclid(40.0), 5.0 + j as f64));
            v.push((s, 0.0));
        }
        monitor.observe(&frame(&x, &v, bonds.clone(), t));
    }
    let series = region_series(&monitor, 2, 1e-3, 0.05);
    let get = |name: &str| series.iter().find(|s| s.name == name).unwrap();
    // The first two samples precede the bond age of 0.5: the first block has fewer members.
    let fraction = get(MEMBER_FRACTION);
    assert!(
        fraction.values[1..]
            .iter()
            .all(|&f| (f - 0.6).abs() < 1e-12)
    );
    assert!(fraction.values[0] < 0.6);
    assert!(get(MEMBER_TEMPERATURE).values.iter().all(|&t| t == 0.0));
    // Four grains, mean velocity 0: 1 * 4 * 4 / (2 * 3) = 8/3 (from the second block on: the
    // first holds samples where the row was not yet bonded long enough to be members).
    let others = get(UNBONDED_TEMPERATURE);
    assert!(
        others.values[1..]
            .iter()
            .all(|&t| (t - 8.0 / 3.0).abs() < 1e-9),
        "{others:?}"
    );
    let still = get(MEMBERS_STILL);
    assert!(!still.values.is_empty());
    assert!(still.values.iter().all(|&f| f == 1.0), "{still:?}");
    // The unbonded grains fly 4 per lag of 2 against their (zero) mean: D = 16 / (2 * 2) = 4
    // (the first lags start before the row's grains were members).
    let d = get(UNBONDED_MOBILITY);
    assert!(d.values.len() > 10);
    assert!(
        d.values[1..].iter().all(|&x| (x - 4.0).abs() < 1e-9),
        "{d:?}"
    );
    // The lags end from t = 2 on: the first blocks have no mobility.
    assert!(d.time[0] > 2.0);
}
