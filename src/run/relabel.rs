//! Sweep-level classification: the per-point labels of a sweep's stored results, re-derived
//! from their stored observables with the line rule for fluid versus gas (docs/model.md 7,
//! `observe::line`). Points of one line share everything but `E*` and the seed: the same
//! Gamma, restitution, box, grains and run settings. A line needs at least
//! [`MIN_LINE_POINTS`] distinct `E*`; points on shorter lines (or in sweeps without a Gamma
//! axis) keep the per-point fallback, and say so in their `decided_on.fluid_gas`. On a line,
//! `observe::line::classify_line` decides: its homogeneous mobile points (solids and
//! coexistences kept out) make the curve, each with the block error of its temperature stored
//! by the run, and a line whose curve shows no transition beyond that scatter keeps its
//! per-point labels (`{"by": "line_without_transition"}`).

use crate::store::{PointRow, Store, StoreError, SweepRow};
use serde::Deserialize;
use std::collections::{BTreeMap, HashSet};
use wetgran_core::observe::line::classify_line;
use wetgran_core::observe::{Classification, Observables, Thresholds, classify};
use wetgran_core::scene::{DriveKind, Scene};

/// Fewest distinct `E*` that make a line (the inflection needs four).
pub const MIN_LINE_POINTS: usize = 4;

/// One point's new classification.
#[derive(Debug, Clone)]
pub struct Relabel {
    pub job_id: String,
    pub classification: Classification,
}

/// `(Gamma, E*)` of a shaken scene (docs/model.md 4.1), from its container motion.
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
/// looked at, not where it is. So does the transient: a sweep whose run length is in time
/// units gets a transient of a fixed fraction of it, a different number of periods per point.
fn line_key(scene: &Scene, gamma: f64) -> String {
    let mut s = scene.clone();
    s.run.duration = 0.0;
    s.run.sample_interval = 0.0;
    s.observe.transient_periods = 0.0;
    s.observe.transient_time = 0.0;
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
    relabel_parsed(
        points,
        &parse_observables(points),
        &given_or_own(thresholds),
    )
}

/// [`relabel`] once per variant of the thresholds, the observables parsed once: `variants[k]`
/// maps a point's own `[classify]` thresholds to those variant `k` labels it with (the line
/// rule reads the variant of the line's first point, as [`relabel`] reads its thresholds).
pub fn relabel_variants(
    points: &[PointRow],
    variants: &[&dyn Fn(&Thresholds) -> Thresholds],
) -> Vec<Vec<Relabel>> {
    let parsed = parse_observables(points);
    variants
        .iter()
        .map(|v| relabel_parsed(points, &parsed, v))
        .collect()
}

/// The thresholds a relabelling gives a point: `thresholds`, or the point's own.
fn given_or_own(thresholds: Option<&Thresholds>) -> impl Fn(&Thresholds) -> Thresholds + '_ {
    move |own| thresholds.unwrap_or(own).clone()
}

/// Each point's stored observables as this wetgran reads them (`None`: no result, or a layout
/// it cannot read), parsed once per relabelling.
fn parse_observables(points: &[PointRow]) -> Vec<Option<Observables>> {
    points
        .iter()
        .map(|row| {
            row.observables
                .as_ref()
                .and_then(|o| Observables::deserialize(o).ok())
        })
        .collect()
}

/// [`relabel`] with the observables already parsed (`parsed[k]` those of `points[k]`), each
/// point labelled with `thresholds_of(its own [classify])`. The points are grouped by line in
/// one pass (a map from line key to members), so the work is one line key and one
/// classification per point whatever the number of lines.
fn relabel_parsed(
    points: &[PointRow],
    parsed: &[Option<Observables>],
    thresholds_of: &dyn Fn(&Thresholds) -> Thresholds,
) -> Vec<Relabel> {
    struct P<'a> {
        row: &'a PointRow,
        obs: &'a Observables,
        th: Thresholds,
        line: Option<(f64, f64)>,
    }
    let mut lines: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    let mut ps: Vec<P> = Vec::with_capacity(points.len());
    for (row, obs) in points.iter().zip(parsed) {
        let Some(obs) = obs else { continue };
        let scene = &row.spec.scene;
        let th = thresholds_of(&scene.classify);
        let line = (scene.drive.kind == DriveKind::Sine && obs.shear.is_none())
            .then(|| gamma_e_star(scene))
            .flatten();
        if let Some((g, _)) = line {
            lines.entry(line_key(scene, g)).or_default().push(ps.len());
        }
        ps.push(P { row, obs, th, line });
    }
    let mut out: Vec<Option<Classification>> = vec![None; ps.len()];
    for members in lines.values() {
        let mut distinct: Vec<f64> = members
            .iter()
            .map(|&k| ps[k].line.expect("member").1)
            .collect();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup();
        if distinct.len() < MIN_LINE_POINTS {
            continue;
        }
        let first = &ps[members[0]];
        let gamma = first.line.expect("member").0;
        let elastic = first.row.spec.scene.contact.restitution >= 1.0;
        let th = first.th.clone();
        let line: Vec<(f64, &Observables)> = members
            .iter()
            .map(|&k| (ps[k].line.expect("member").1, ps[k].obs))
            .collect();
        for (k, c) in members
            .iter()
            .zip(classify_line(gamma, &line, &th, elastic))
        {
            out[*k] = Some(c);
        }
    }
    ps.iter()
        .zip(out)
        .map(|(p, c)| Relabel {
            job_id: p.row.job_id.clone(),
            classification: c.unwrap_or_else(|| classify(p.obs, &p.th)),
        })
        .collect()
}

/// What a relabelling changed: label transitions `(from, to)` with their counts, the number of
/// results re-labelled and of those left alone.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Relabelled {
    pub results: usize,
    /// Results whose stored observables this wetgran cannot read (left as they are).
    pub unreadable: usize,
    /// Results whose thresholds decide mobility by `f_lc` but whose run did not count
    /// location changes: the classifier fell back to `T_g` for them; they need a re-run with
    /// `observe.location_changes = true` to be decided as asked.
    pub missing_flc: usize,
    /// Results measured before bonded-cluster regions, the short mobility lag and the
    /// bootstrap null of the profile (issue 31): the classifier decided them by the rules their
    /// observables allow (no cluster requirement, `D_lat` floor alone, the independent-bin
    /// noise model); a re-run measures what the current rules read.
    pub missing_regions: usize,
    pub changes: BTreeMap<(String, String), usize>,
}

impl Relabelled {
    /// Number of results whose label changed.
    pub fn changed(&self) -> usize {
        self.changes.values().sum()
    }

    /// `n result(s) re-labelled: 3 label(s) changed: f -> g 2, s -> f 1` (or `no label
    /// changed`).
    pub fn text(&self) -> String {
        let mut text = self.changes_text();
        if self.unreadable > 0 {
            text.push_str(&format!(
                "; {} result(s) left as they were (observables not readable by this wetgran)",
                self.unreadable
            ));
        }
        if self.missing_flc > 0 {
            text.push_str(&format!(
                "; {} result(s) have no f_lc (the location-change counter was off when they \
                 ran), so their mobility was decided by T_g, not by f_lc as asked: re-run them \
                 with observe.location_changes = true",
                self.missing_flc
            ));
        }
        if self.missing_regions > 0 {
            text.push_str(&format!(
                "; {} result(s) were measured before bonded-cluster regions and the two-lag \
                 mobility (docs/observables.md), so they were decided without the bonded-cluster \
                 requirement, the caged-motion test and the bootstrap noise level: re-run them \
                 (a new sweep database, or `sweep run` after deleting their results) to apply \
                 the current rules",
                self.missing_regions
            ));
        }
        text
    }

    fn changes_text(&self) -> String {
        if self.changes.is_empty() {
            return format!("{} result(s) re-labelled: no label changed", self.results);
        }
        let parts: Vec<String> = self
            .changes
            .iter()
            .map(|((from, to), n)| format!("{from} -> {to} {n}"))
            .collect();
        format!(
            "{} result(s) re-labelled: {} label(s) changed: {}",
            self.results,
            self.changed(),
            parts.join(", ")
        )
    }
}

/// The labels a relabelling computed, keyed by job, and what it noticed about the results it
/// read.
#[derive(Default)]
struct Tally {
    /// `job -> (old phase, new phase, new decided_on)`, the decision only where the label or
    /// its decision numbers changed (what is written).
    labels: BTreeMap<String, (Option<String>, String, Option<serde_json::Value>)>,
    unreadable: HashSet<String>,
    missing_flc: HashSet<String>,
    missing_regions: HashSet<String>,
}

impl Tally {
    /// Relabels `points` (whole lines of one sweep) and records the outcome.
    fn add(&mut self, points: &[PointRow], thresholds: Option<&Thresholds>) {
        let parsed = parse_observables(points);
        for (p, obs) in points.iter().zip(&parsed) {
            if p.observables.is_some() && obs.is_none() {
                // Observables this wetgran cannot read (another version's layout) keep their
                // label.
                self.unreadable.insert(p.job_id.clone());
            }
            let th = thresholds.unwrap_or(&p.spec.scene.classify);
            if th.mobility == wetgran_core::observe::Mobility::LocationChanges
                && p.observables.as_ref().is_some_and(|o| {
                    o.get("location_changes")
                        .is_none_or(serde_json::Value::is_null)
                })
            {
                self.missing_flc.insert(p.job_id.clone());
            }
            if p.observables
                .as_ref()
                .is_some_and(|o| o.pointer("/profiles/clusters").is_none())
            {
                self.missing_regions.insert(p.job_id.clone());
            }
        }
        let before: BTreeMap<&str, &PointRow> =
            points.iter().map(|p| (p.job_id.as_str(), p)).collect();
        for l in relabel_parsed(points, &parsed, &given_or_own(thresholds)) {
            let p = before[l.job_id.as_str()];
            let phase = l.classification.phase.to_string();
            let decided_on =
                serde_json::to_value(&l.classification.decided_on).expect("decision serializes");
            let write = p.phase.as_deref() != Some(phase.as_str())
                || p.decided_on.as_ref() != Some(&decided_on);
            self.labels.insert(
                l.job_id.clone(),
                (p.phase.clone(), phase, write.then_some(decided_on)),
            );
        }
    }

    /// The summary, and the labels to write: those that changed or whose decision numbers did.
    fn finish(self) -> (Relabelled, Vec<(String, String, serde_json::Value)>) {
        let mut out = Relabelled {
            unreadable: self.unreadable.len(),
            missing_flc: self.missing_flc.len(),
            missing_regions: self.missing_regions.len(),
            ..Relabelled::default()
        };
        let mut updates = Vec::new();
        for (job_id, (old_phase, phase, decided_on)) in self.labels {
            out.results += 1;
            let old = old_phase.unwrap_or_else(|| "-".to_string());
            if old != phase {
                *out.changes.entry((old, phase.clone())).or_insert(0) += 1;
            }
            if let Some(decided_on) = decided_on {
                updates.push((job_id, phase, decided_on));
            }
        }
        (out, updates)
    }
}

/// Re-labels every stored result of `sweeps` from its stored observables with `thresholds`, or
/// with the job's own `[classify]` thresholds when `None`, the fluid-gas line rule included
/// (`run::relabel`, docs/model.md 7); writes only labels that changed or whose decision numbers
/// changed, and clears the sweeps' marks of results not yet relabelled
/// (`store::relabel_queue`). A job shared by several of the given sweeps is counted once (the
/// last sweep's lines decide its label). `wetgran reclassify` and the registration of a sweep
/// file (whose `[classify]` may be new) relabel this way; after a run, a refinement round or an
/// extension the callers use [`relabel_changed`].
pub fn relabel_stored(
    store: &Store,
    sweeps: &[SweepRow],
    thresholds: Option<&Thresholds>,
) -> Result<Relabelled, StoreError> {
    let mut tally = Tally::default();
    for s in sweeps {
        let specs = store.point_specs(s.id)?;
        let keys: Vec<Option<String>> =
            specs.iter().map(|p| spec_line_key(&p.spec.scene)).collect();
        let every: Vec<(&str, Option<&str>)> = specs
            .iter()
            .zip(&keys)
            .map(|(p, k)| (p.job_id.as_str(), k.as_deref()))
            .collect();
        for group in line_groups(&every) {
            tally.add(&store.points_of_jobs(s.id, &group)?, thresholds);
        }
    }
    let (out, updates) = tally.finish();
    let clear: Vec<(i64, Option<Vec<String>>)> = sweeps.iter().map(|s| (s.id, None)).collect();
    store.relabel_and_clear(&updates, &clear)?;
    Ok(out)
}

/// Jobs read and re-classified at once by a relabelling: whole lines of constant Gamma are
/// gathered until a group holds at least this many jobs. The rows of a group are held with
/// their observables parsed (tens of kB a result), so a sweep is relabelled in memory that
/// does not grow with it (10^5 results read at once held 6.8 GB).
const GROUP_JOBS: usize = 2_000;

/// `(job id, line key)` pairs cut into groups of whole lines (every job of a line in one
/// group; jobs on no line in groups of their own), each group at most [`GROUP_JOBS`] jobs
/// unless one line is longer; each job once, lines in key order.
fn line_groups(jobs: &[(&str, Option<&str>)]) -> Vec<Vec<String>> {
    let mut lines: BTreeMap<Option<&str>, Vec<&str>> = BTreeMap::new();
    for &(job, key) in jobs {
        lines.entry(key).or_default().push(job);
    }
    let mut groups: Vec<Vec<String>> = Vec::new();
    let mut current: Vec<String> = Vec::new();
    for (key, mut members) in lines {
        members.sort_unstable();
        members.dedup();
        let chunks: Vec<&[&str]> = match key {
            Some(_) => vec![&members[..]],
            None => members.chunks(GROUP_JOBS).collect(),
        };
        for chunk in chunks {
            if !current.is_empty() && current.len() + chunk.len() > GROUP_JOBS {
                groups.push(std::mem::take(&mut current));
            }
            current.extend(chunk.iter().map(|j| j.to_string()));
        }
    }
    if !current.is_empty() {
        groups.push(current);
    }
    groups
}

/// The line key of a job's point, from its spec alone: `None` for a point that is on no line
/// (not sinusoidally shaken). A point whose observables say it was sheared is kept off its line
/// by [`relabel`]; the key here only has to put every member of a line under one key.
fn spec_line_key(scene: &Scene) -> Option<String> {
    (scene.drive.kind == DriveKind::Sine)
        .then(|| gamma_e_star(scene))
        .flatten()
        .map(|(g, _)| line_key(scene, g))
}

/// Re-labels, with each job's own thresholds, only the results of `sweep` stored, replaced or
/// added to it since its last relabelling (the marks of `store::relabel_queue`) and every
/// result on the lines of constant Gamma that hold them; every other stored label is a
/// function of stored observables that did not change, and of lines that did not change, so it
/// is left as it is. The runner's callers relabel this way after every change of the stored
/// results (a run, a refinement round, an extension), and the marks are written with the
/// results and cleared with the labels, so that every stored label is the same function of
/// the stored observables whatever order (or crash) the results came in: the labels equal
/// those of [`relabel_stored`] with `None` thresholds.
pub fn relabel_changed(store: &Store, sweep: &SweepRow) -> Result<Relabelled, StoreError> {
    let pending = store.relabel_pending(sweep.id)?;
    if pending.is_empty() {
        return Ok(Relabelled::default());
    }
    let specs = store.point_specs(sweep.id)?;
    let pending_set: HashSet<&str> = pending.iter().map(String::as_str).collect();
    let keys: Vec<Option<String>> = specs.iter().map(|p| spec_line_key(&p.spec.scene)).collect();
    let touched: HashSet<&str> = specs
        .iter()
        .zip(&keys)
        .filter(|(p, _)| pending_set.contains(p.job_id.as_str()))
        .filter_map(|(_, k)| k.as_deref())
        .collect();
    let members: Vec<(&str, Option<&str>)> = specs
        .iter()
        .zip(&keys)
        .filter(|(p, k)| {
            pending_set.contains(p.job_id.as_str())
                || k.as_deref().is_some_and(|k| touched.contains(k))
        })
        .map(|(p, k)| (p.job_id.as_str(), k.as_deref()))
        .collect();
    let mut tally = Tally::default();
    for group in line_groups(&members) {
        tally.add(&store.points_of_jobs(sweep.id, &group)?, None);
    }
    let (out, updates) = tally.finish();
    store.relabel_and_clear(&updates, &[(sweep.id, Some(pending))])?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regressions: with `sweep.periods` every point of a line of constant Gamma has its own
    /// run length and sample interval (both in periods of its own drive); with the run length in
    /// time units the default transient is a fixed fraction of the run, so a different number of
    /// periods at every `E*`. In both, no point found a line: the line rule never ran.
    #[test]
    fn a_line_spans_points_whose_run_length_is_set_in_periods_or_in_time() {
        for (run, periods) in [("periods = 10\n", true), ("", false)] {
            let duration = if periods {
                ""
            } else {
                "[scene.run]\nduration = 40.0\n"
            };
            let text = format!(
                "[sweep]\nname = \"l\"\n{run}[scene]\ndimension = 2\n[scene.box]\n\
                 size = [20.0, 9.0]\n[scene.particles]\ncount = 10\n[scene.capillary]\n\
                 model = \"thin_thread\"\n[scene.drive]\nkind = \"sine\"\n[scene.initial]\n\
                 temperature = 1.0\n{duration}[[axis]]\nkey = \"gamma\"\nvalues = [30.0]\n\
                 [[axis]]\nkey = \"e_star\"\nvalues = [0.5, 2.0]\n"
            );
            let file = crate::sweep::SweepFile::parse(&text, std::path::Path::new("l.toml"));
            let jobs = file.unwrap().expand().unwrap();
            let (a, b) = (&jobs[0].spec.scene, &jobs[1].spec.scene);
            if periods {
                assert_ne!(a.run.duration, b.run.duration);
                assert_ne!(a.run.sample_interval, b.run.sample_interval);
            } else {
                assert_eq!(a.run.duration, b.run.duration);
                assert_ne!(a.observe.transient_periods, b.observe.transient_periods);
            }
            let (ga, _) = gamma_e_star(a).unwrap();
            let (gb, _) = gamma_e_star(b).unwrap();
            assert_eq!(line_key(a, ga), line_key(b, gb));
            // Another Gamma is another line.
            assert_ne!(line_key(a, ga), line_key(a, 2.0 * ga));
        }
    }

    #[test]
    fn groups_hold_whole_lines_each_job_once() {
        let ids: Vec<String> = (0..3 * GROUP_JOBS).map(|k| format!("j{k:06}")).collect();
        // Two long lines, many short ones, and jobs on no line; a job listed twice.
        let mut jobs: Vec<(&str, Option<&str>)> = Vec::new();
        let keys: Vec<String> = (0..600).map(|k| format!("line{k:03}")).collect();
        for (k, id) in ids.iter().enumerate() {
            let key = match k {
                _ if k < GROUP_JOBS + 10 => Some("long"),
                _ if k < GROUP_JOBS + 1_210 => Some(keys[k % 600].as_str()),
                _ => None,
            };
            jobs.push((id, key));
        }
        jobs.push((&ids[0], Some("long")));
        let groups = line_groups(&jobs);
        let mut seen: Vec<&String> = groups.iter().flatten().collect();
        assert_eq!(seen.len(), ids.len());
        seen.sort();
        seen.dedup();
        assert_eq!(seen.len(), ids.len());
        for (id, key) in &jobs {
            let Some(key) = key else { continue };
            let home = groups
                .iter()
                .position(|g| g.iter().any(|j| j == id))
                .unwrap();
            for (other, k) in &jobs {
                if k.as_ref() == Some(key) {
                    assert!(groups[home].iter().any(|j| j == other), "{key} split");
                }
            }
        }
        // Only the line longer than a group makes a group over the size.
        let over: Vec<usize> = groups
            .iter()
            .map(Vec::len)
            .filter(|&n| n > GROUP_JOBS)
            .collect();
        assert_eq!(over, vec![GROUP_JOBS + 10]);
    }
}
