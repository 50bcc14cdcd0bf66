//! Sweep-level classification: the per-point labels of a sweep's stored results, re-derived
//! from their stored observables with the line rule for fluid versus gas (MODEL.md 7,
//! `observe::line`). Points of one line share everything but `E*` and the seed: the same
//! Gamma, restitution, box, grains and run settings. A line needs at least
//! [`MIN_LINE_POINTS`] distinct `E*`; points on shorter lines (or in sweeps without a Gamma
//! axis) keep the per-point fallback, and say so in their `decided_on.fluid_gas`.

use crate::observe::line::classify_line;
use crate::observe::{Classification, Observables, Thresholds, classify};
use crate::scene::{DriveKind, Scene};
use crate::store::PointRow;

/// Fewest distinct `E*` that make a line (the inflection needs four).
pub const MIN_LINE_POINTS: usize = 4;

/// One point's new classification.
#[derive(Debug, Clone)]
pub struct Relabel {
    pub job_id: String,
    /// The stored label before.
    pub old: Option<String>,
    pub classification: Classification,
}

/// `(Gamma, E*)` of a shaken scene (MODEL.md 4.1), from its container motion.
pub fn gamma_e_star(scene: &Scene) -> Option<(f64, f64)> {
    let (a, w) = scene.drive_motion()?;
    let energy_unit = if scene.is_wet() && scene.e_cb() > 0.0 {
        scene.e_cb()
    } else {
        scene.particles.mass * scene.gravity * scene.particles.diameter
    };
    let gamma = a * w * w / scene.gravity;
    let e_star = 0.5 * scene.particles.mass * (a * w) * (a * w) / energy_unit;
    (gamma.is_finite() && e_star.is_finite()).then_some((gamma, e_star))
}

/// The key of a point's line: the scene with its drive energy, seed, thresholds and run length
/// and sampling taken out, and Gamma to 9 significant digits. A sweep's `periods` and
/// `samples_per_period` set `run.duration` and `run.sample_interval` in driving periods, which
/// differ with `E*` along a line of constant Gamma; they say how long and how often a point was
/// looked at, not where it is.
fn line_key(scene: &Scene, gamma: f64) -> String {
    let mut s = scene.clone();
    s.run.duration = 0.0;
    s.run.sample_interval = 0.0;
    s.drive.amplitude = None;
    s.drive.omega = None;
    s.drive.gamma = None;
    s.drive.e_star = None;
    s.initial.seed = 0;
    s.classify = Thresholds::default();
    let json = serde_json::to_string(&s).expect("a scene serializes");
    format!("{gamma:.9e}|{json}")
}

/// Re-classifies every finished point of a sweep from its stored observables, with
/// `thresholds` (or each point's own `[classify]`) and the line rule where a line exists.
pub fn relabel(points: &[PointRow], thresholds: Option<&Thresholds>) -> Vec<Relabel> {
    struct P<'a> {
        row: &'a PointRow,
        obs: Observables,
        th: Thresholds,
        line: Option<(String, f64, f64)>,
    }
    let mut ps: Vec<P> = points
        .iter()
        .filter_map(|row| {
            let obs: Observables = serde_json::from_value(row.observables.clone()?).ok()?;
            let scene = &row.spec.scene;
            let th = thresholds
                .cloned()
                .unwrap_or_else(|| scene.classify.clone());
            let line = (scene.drive.kind == DriveKind::Sine && obs.shear.is_none())
                .then(|| gamma_e_star(scene))
                .flatten()
                .map(|(g, e)| (line_key(scene, g), g, e));
            Some(P { row, obs, th, line })
        })
        .collect();
    let mut out: Vec<Option<Classification>> = vec![None; ps.len()];
    let mut keys: Vec<String> = ps
        .iter()
        .filter_map(|p| p.line.as_ref().map(|l| l.0.clone()))
        .collect();
    keys.sort();
    keys.dedup();
    for key in keys {
        let members: Vec<usize> = (0..ps.len())
            .filter(|&k| ps[k].line.as_ref().is_some_and(|l| l.0 == key))
            .collect();
        let mut distinct: Vec<f64> = members
            .iter()
            .map(|&k| ps[k].line.as_ref().expect("member").2)
            .collect();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup();
        if distinct.len() < MIN_LINE_POINTS {
            continue;
        }
        let first = &ps[members[0]];
        let gamma = first.line.as_ref().expect("member").1;
        let elastic = first.row.spec.scene.contact.restitution >= 1.0;
        let th = first.th.clone();
        let line: Vec<(f64, &Observables)> = members
            .iter()
            .map(|&k| (ps[k].line.as_ref().expect("member").2, &ps[k].obs))
            .collect();
        for (k, c) in members
            .iter()
            .zip(classify_line(gamma, &line, &th, elastic))
        {
            out[*k] = Some(c);
        }
    }
    ps.iter_mut()
        .zip(out)
        .map(|(p, c)| Relabel {
            job_id: p.row.job_id.clone(),
            old: p.row.phase.clone(),
            classification: c.unwrap_or_else(|| classify(&p.obs, &p.th)),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression: with `sweep.periods` every point of a line of constant Gamma has its own
    /// run length and sample interval (both in periods of its own drive), and no point found a
    /// line: the line rule never ran on the shipped sweeps.
    #[test]
    fn a_line_spans_points_whose_run_length_is_set_in_periods() {
        let file = crate::sweep::SweepFile::parse(
            "[sweep]\nname = \"l\"\nperiods = 10\n[scene]\ndimension = 2\n[scene.box]\n\
             size = [20.0, 9.0]\n[scene.particles]\ncount = 10\n[scene.capillary]\n\
             model = \"thin_thread\"\n[scene.drive]\nkind = \"sine\"\n[scene.initial]\n\
             temperature = 1.0\n[[axis]]\nkey = \"gamma\"\nvalues = [30.0]\n\
             [[axis]]\nkey = \"e_star\"\nvalues = [0.5, 2.0]\n",
            std::path::Path::new("l.toml"),
        )
        .unwrap();
        let jobs = file.expand().unwrap();
        let (a, b) = (&jobs[0].spec.scene, &jobs[1].spec.scene);
        assert_ne!(a.run.duration, b.run.duration);
        assert_ne!(a.run.sample_interval, b.run.sample_interval);
        let (ga, _) = gamma_e_star(a).unwrap();
        let (gb, _) = gamma_e_star(b).unwrap();
        assert_eq!(line_key(a, ga), line_key(b, gb));
        // Another Gamma is another line.
        assert_ne!(line_key(a, ga), line_key(a, 2.0 * ga));
    }
}
