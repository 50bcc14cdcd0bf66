//! How far each phase boundary of a sweep moves when one label-deciding threshold is varied
//! (`wetgran boundaries --sensitivity`, and a table of `wetgran report`), from the stored
//! observables alone: nothing is simulated.
//!
//! **Relabelling.** The sweep's results are relabelled as `wetgran reclassify` relabels them
//! (`run::relabel`: the per-point classifier, then the fluid-gas line rule along lines of
//! constant Gamma), once with each job's own `[classify]` thresholds (the baseline) and once
//! per variant: one threshold of [`THRESHOLDS`] varied by a factor of [`FACTORS`], every other
//! threshold as the job's own. A job whose observables this wetgran cannot read keeps its
//! stored label in every map.
//!
//! **Varying a threshold** by a factor `k` ([`Scaling`]):
//! - a magnitude (a mobility, a temperature, an exponent, a fraction near 0, a ratio): `x k`;
//! - a fraction near 1 (`still_members`) and a quantile level (`coexistence_level`): the
//!   distance to 1 (the tail probability) is scaled, `1 - (1 - x) k`;
//! - `coexistence_contrast`, the smallest `(dense - dilute) / dense`: the excess of the dense
//!   over the dilute mean, `dense / dilute - 1 = c / (1 - c)`, is scaled (0.5 becomes 1/3 and
//!   2/3), since scaling `c` itself reaches the end of its range at `k = 2`;
//!
//! each then clamped to the range the scene validation allows (`diffusive_exponent <= 1`, the
//! fractions in `[0, 1]`, `coexistence_level > 0.5`, `line_jump_ratio > 1`,
//! `solid_temperature <= gas_temperature`).
//!
//! **Boundary displacement.** Both label sets make a phase map (`boundary::phase_map_with`, the
//! same extraction as `boundaries`). For each boundary (a phase pair in one slice, e.g. one
//! branch) the displacement is taken both ways: for each boundary point of either map, the
//! nearest boundary point of the same pair and slice in the other map, nearest in the plane of
//! the map with each axis divided by the span of the slice's points (log axes in decades, as
//! refinement scales them); the components of that offset along each axis (decades of `E*`,
//! units of Gamma) are the displacements, summarised by their median and maximum (the maximum
//! over both ways is the Hausdorff distance along each axis). A boundary that one map has and
//! the other does not *appears* or *vanishes*; one whose points coincide is *unchanged*. The
//! boundary points are midpoints of the edges between grid points, so a boundary that moves by
//! one grid cell moves by one grid spacing.

use crate::boundary::{BoundaryPoint, Extraction, Observation, PhaseMap, PlaneAxis, Slice};
use crate::run::relabel::relabel_variants;
use crate::store::{PointRow, PointSummary, SweepRow};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use wetgran_core::observe::Thresholds;
use wetgran_core::observe::criterion::sig as short;

/// The factors each threshold is varied by, one at a time.
pub const FACTORS: [f64; 2] = [0.5, 2.0];

/// The `[classify]` thresholds that decide labels, in the order they are reported. Left out:
/// `coexistence_delta_n_cb` (0 by default, and scaling 0 leaves it 0), `mobility` and
/// `coexistence_by` (choices, not numbers).
pub const THRESHOLDS: [&str; 15] = [
    "solid_diffusion",
    "diffusive_exponent",
    "still_members",
    "cluster_fraction",
    "coexistence_level",
    "coexistence_contrast",
    "gas_temperature",
    "line_jump_ratio",
    "solid_temperature",
    "solid_flc",
    "shear_e_par",
    "gas_evidence_temperature",
    "gas_evidence_bridges",
    "fluid_evidence_temperature",
    "fluid_evidence_bridges",
];

/// How a threshold is varied by a factor `k` (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scaling {
    /// `x k`.
    Value,
    /// `1 - (1 - x) k`.
    DistanceToOne,
    /// `c / (1 - c)` times `k`.
    DensityExcess,
}

/// How the threshold `key` is varied.
pub fn scaling(key: &str) -> Scaling {
    match key {
        "still_members" | "coexistence_level" => Scaling::DistanceToOne,
        "coexistence_contrast" => Scaling::DensityExcess,
        _ => Scaling::Value,
    }
}

/// The value of the threshold `key` (one of [`THRESHOLDS`]).
pub fn value(th: &Thresholds, key: &str) -> f64 {
    *slot(&mut th.clone(), key)
}

fn slot<'a>(th: &'a mut Thresholds, key: &str) -> &'a mut f64 {
    match key {
        "solid_diffusion" => &mut th.solid_diffusion,
        "diffusive_exponent" => &mut th.diffusive_exponent,
        "still_members" => &mut th.still_members,
        "cluster_fraction" => &mut th.cluster_fraction,
        "coexistence_level" => &mut th.coexistence_level,
        "coexistence_contrast" => &mut th.coexistence_contrast,
        "gas_temperature" => &mut th.gas_temperature,
        "line_jump_ratio" => &mut th.line_jump_ratio,
        "solid_temperature" => &mut th.solid_temperature,
        "solid_flc" => &mut th.solid_flc,
        "shear_e_par" => &mut th.shear_e_par,
        "gas_evidence_temperature" => &mut th.gas_evidence_temperature,
        "gas_evidence_bridges" => &mut th.gas_evidence_bridges,
        "fluid_evidence_temperature" => &mut th.fluid_evidence_temperature,
        "fluid_evidence_bridges" => &mut th.fluid_evidence_bridges,
        other => panic!("`{other}` is not a varied threshold"),
    }
}

/// `th` with the threshold `key` varied by the factor `k` (module doc), clamped to its range.
pub fn varied(th: &Thresholds, key: &str, k: f64) -> Thresholds {
    let x = value(th, key);
    let v = match scaling(key) {
        Scaling::Value => x * k,
        Scaling::DistanceToOne => 1.0 - (1.0 - x) * k,
        Scaling::DensityExcess if x >= 1.0 => 1.0,
        Scaling::DensityExcess => {
            let excess = x / (1.0 - x) * k;
            excess / (1.0 + excess)
        }
    };
    let v = match key {
        "diffusive_exponent" => v.min(1.0),
        "still_members" | "cluster_fraction" | "coexistence_contrast" => v.clamp(0.0, 1.0),
        // The level's open range (0.5, 1): just above its lower end.
        "coexistence_level" => v.max(0.5 + 1e-9),
        "line_jump_ratio" => v.max(1.0 + 1e-9),
        "gas_temperature" => v.max(th.solid_temperature),
        "solid_temperature" => v.min(th.gas_temperature),
        // A gas's own evidence stays hotter than a fluid's.
        "gas_evidence_temperature" => v.max(th.fluid_evidence_temperature * (1.0 + 1e-9)),
        "fluid_evidence_temperature" => v.min(th.gas_evidence_temperature * (1.0 - 1e-9)),
        _ => v,
    };
    let mut out = th.clone();
    *slot(&mut out, key) = v;
    out
}

/// What happened to one boundary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Unchanged,
    Moved,
    Appears,
    Vanishes,
}

/// One boundary (a phase pair in one slice) under one variation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Moved {
    /// The slice's fixed coordinates in words (empty: the only slice).
    pub slice: String,
    /// The branch (start mode) of the slice, where the sweep has an `initial.start` axis.
    pub branch: Option<String>,
    pub pair: String,
    pub status: Status,
    /// Boundary points in the baseline and in the varied map.
    pub points: [usize; 2],
    /// Median and maximum displacement along x (decades on a log axis) and y (module doc);
    /// `None` where the boundary appears or vanishes.
    pub x_median: Option<f64>,
    pub x_max: Option<f64>,
    pub y_median: Option<f64>,
    pub y_max: Option<f64>,
}

/// One threshold varied by one factor.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Variation {
    pub threshold: &'static str,
    pub scaling: Scaling,
    pub factor: f64,
    /// The threshold of the sweep's first relabelled job, and its varied value.
    pub from: f64,
    pub to: f64,
    /// Labels that differ from the baseline, and the transitions `"s -> f"` with their counts.
    pub labels_changed: usize,
    pub changes: BTreeMap<String, usize>,
    /// Every boundary that either map has.
    pub boundaries: Vec<Moved>,
}

/// The sensitivity of a sweep's boundaries to its thresholds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sensitivity {
    pub sweep: String,
    /// The map's axes: label and whether the plane reads it in decades.
    pub x_axis: Option<(String, bool)>,
    pub y_axis: Option<(String, bool)>,
    /// Results relabelled from their observables, and how many of the baseline labels differ
    /// from the stored ones (a database not relabelled since its thresholds or wetgran
    /// changed).
    pub relabelled: usize,
    pub differ_from_stored: usize,
    pub variations: Vec<Variation>,
}

/// A function from a job's own thresholds to those a relabelling uses.
type Variant = dyn Fn(&Thresholds) -> Thresholds;

/// The sensitivity of a sweep (module doc): `rows` its jobs with their results
/// (`Store::points`), `summaries` its `Store::point_summaries`, `how` the extraction of
/// `boundaries`.
pub fn sensitivity(
    sweep: &SweepRow,
    rows: &[PointRow],
    summaries: &[PointSummary],
    how: Extraction,
) -> Result<Sensitivity, String> {
    let mut variants: Vec<(&'static str, f64)> = Vec::new();
    for key in THRESHOLDS {
        for k in FACTORS {
            variants.push((key, k));
        }
    }
    let own = |th: &Thresholds| th.clone();
    let fns: Vec<Box<Variant>> = variants
        .iter()
        .map(|&(key, k)| Box::new(move |th: &Thresholds| varied(th, key, k)) as Box<_>)
        .collect();
    let mut all: Vec<&Variant> = vec![&own];
    all.extend(fns.iter().map(|f| f.as_ref()));
    let labels: Vec<HashMap<String, String>> = relabel_variants(rows, &all)
        .into_iter()
        .map(|v| {
            v.into_iter()
                .map(|r| (r.job_id, r.classification.phase.to_string()))
                .collect()
        })
        .collect();
    let base = &labels[0];
    let map_of = |phases: &HashMap<String, String>| map_with(sweep, summaries, phases, how);
    let base_map = map_of(base)?;
    let first = rows
        .iter()
        .find(|r| base.contains_key(&r.job_id))
        .map(|r| r.spec.scene.classify.clone())
        .unwrap_or_default();
    let differ = rows
        .iter()
        .filter(|r| {
            base.get(&r.job_id)
                .is_some_and(|p| r.phase.as_ref() != Some(p))
        })
        .count();
    let mut variations = Vec::new();
    for (k, &(key, factor)) in variants.iter().enumerate() {
        let phases = &labels[k + 1];
        let mut changes: BTreeMap<String, usize> = BTreeMap::new();
        for (job, p) in phases {
            if let Some(b) = base.get(job).filter(|b| *b != p) {
                *changes.entry(format!("{b} -> {p}")).or_default() += 1;
            }
        }
        variations.push(Variation {
            threshold: key,
            scaling: scaling(key),
            factor,
            from: value(&first, key),
            to: value(&varied(&first, key, factor), key),
            labels_changed: changes.values().sum(),
            changes,
            boundaries: compare(&base_map, &map_of(phases)?),
        });
    }
    let axis = |a: &Option<PlaneAxis>| a.as_ref().map(|a| (a.label.clone(), a.log));
    Ok(Sensitivity {
        sweep: sweep.name.clone(),
        x_axis: axis(&base_map.x),
        y_axis: axis(&base_map.y),
        relabelled: base.len(),
        differ_from_stored: differ,
        variations,
    })
}

/// The phase map of the sweep with the jobs' labels replaced by `phases` (a job not in it keeps
/// its stored label); trust is read for the new label (a trend keeps some labels only).
fn map_with(
    sweep: &SweepRow,
    summaries: &[PointSummary],
    phases: &HashMap<String, String>,
    how: Extraction,
) -> Result<PhaseMap, String> {
    let obs: Vec<Observation> = summaries
        .iter()
        .map(|s| {
            let mut s = s.clone();
            if let Some(p) = phases.get(&s.job_id) {
                s.phase = Some(p.clone());
            }
            Observation::of_summary(&s)
        })
        .collect();
    crate::boundary::phase_map_with(&sweep.axes, &obs, how)
        .map_err(|e| format!("sweep {}: {e}", sweep.name))
}

/// Every boundary of either map, slice by slice (matched by their fixed coordinates).
fn compare(base: &PhaseMap, other: &PhaseMap) -> Vec<Moved> {
    let Some(xa) = base.x.as_ref() else {
        return Vec::new();
    };
    let ya = base.y.as_ref();
    let mut out = Vec::new();
    for a in &base.slices {
        let empty = Slice {
            fixed: a.fixed.clone(),
            branch: a.branch.clone(),
            points: Vec::new(),
            boundaries: BTreeMap::new(),
        };
        let b = other
            .slices
            .iter()
            .find(|s| s.fixed == a.fixed)
            .unwrap_or(&empty);
        let span = |f: &dyn Fn(&crate::boundary::MapPoint) -> f64| {
            let (lo, hi) = a
                .points
                .iter()
                .map(f)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                    (l.min(v), h.max(v))
                });
            if hi > lo { hi - lo } else { 1.0 }
        };
        let plane = Plane {
            xa,
            ya,
            span: (
                span(&|p| xa.scale(p.x)),
                span(&|p| ya.map_or(0.0, |y| y.scale(p.y))),
            ),
        };
        let mut pairs: Vec<&String> = a.boundaries.keys().chain(b.boundaries.keys()).collect();
        pairs.sort();
        pairs.dedup();
        for pair in pairs {
            let none = Vec::new();
            let pa = a.boundaries.get(pair).unwrap_or(&none);
            let pb = b.boundaries.get(pair).unwrap_or(&none);
            out.push(plane.moved(pa, pb, pair, a));
        }
    }
    out
}

/// The plane a displacement is measured in: the map's axes and the span of the slice's points
/// along each (scaled: decades on a log axis).
struct Plane<'a> {
    xa: &'a PlaneAxis,
    ya: Option<&'a PlaneAxis>,
    span: (f64, f64),
}

impl Plane<'_> {
    fn at(&self, b: &BoundaryPoint) -> (f64, f64) {
        (self.xa.scale(b.x), self.ya.map_or(0.0, |y| y.scale(b.y)))
    }

    /// For each point of `from`, the offset `(|dx|, |dy|)` to the nearest point of `to`.
    fn nearest(&self, from: &[BoundaryPoint], to: &[BoundaryPoint]) -> Vec<(f64, f64)> {
        from.iter()
            .filter_map(|p| {
                let (px, py) = self.at(p);
                to.iter()
                    .map(|q| {
                        let (qx, qy) = self.at(q);
                        ((px - qx).abs(), (py - qy).abs())
                    })
                    .min_by(|a, b| {
                        let d = |o: &(f64, f64)| {
                            (o.0 / self.span.0).powi(2) + (o.1 / self.span.1).powi(2)
                        };
                        d(a).total_cmp(&d(b))
                    })
            })
            .collect()
    }

    /// The displacement of one boundary (module doc).
    fn moved(&self, a: &[BoundaryPoint], b: &[BoundaryPoint], pair: &str, s: &Slice) -> Moved {
        let mut offsets = self.nearest(a, b);
        offsets.extend(self.nearest(b, a));
        let status = match (a.is_empty(), b.is_empty()) {
            (true, _) => Status::Appears,
            (_, true) => Status::Vanishes,
            _ if offsets.iter().all(|o| *o == (0.0, 0.0)) => Status::Unchanged,
            _ => Status::Moved,
        };
        let stats = |k: usize| {
            let mut v: Vec<f64> = offsets
                .iter()
                .map(|o| if k == 0 { o.0 } else { o.1 })
                .collect();
            v.sort_by(f64::total_cmp);
            let n = v.len();
            (n > 0).then(|| {
                let median = if n % 2 == 1 {
                    v[n / 2]
                } else {
                    0.5 * (v[n / 2 - 1] + v[n / 2])
                };
                (median, v[n - 1])
            })
        };
        let (x, y) = (stats(0), stats(1));
        Moved {
            slice: super::boundaries_text::fixed_text(&s.fixed),
            branch: s.branch.clone(),
            pair: pair.to_string(),
            status,
            points: [a.len(), b.len()],
            x_median: x.map(|s| s.0),
            x_max: x.map(|s| s.1),
            y_median: y.filter(|_| self.ya.is_some()).map(|s| s.0),
            y_max: y.filter(|_| self.ya.is_some()).map(|s| s.1),
        }
    }
}

/// The text of a sensitivity: per threshold and factor the labels that changed and every
/// boundary that moved, then a summary table (the largest move per threshold).
pub fn sensitivity_text(s: &Sensitivity) -> String {
    let mut out = String::new();
    let unit = |a: &Option<(String, bool)>| match a {
        Some((l, true)) => (l.clone(), " dec"),
        Some((l, false)) => (l.clone(), ""),
        None => (String::new(), ""),
    };
    let ((xl, xu), (yl, yu)) = (unit(&s.x_axis), unit(&s.y_axis));
    let _ = writeln!(
        out,
        "sweep {}: how far each boundary moves when one threshold is varied (labels from the \
         stored observables as `reclassify` gives them; docs/classification.md)",
        s.sweep
    );
    let _ = writeln!(
        out,
        "  {} result(s) relabelled with each job's own [classify] (the baseline: {} differ from \
         the stored labels); moved: each boundary point's offset to the nearest one of the same \
         pair and slice in the other map, both ways, median and max",
        s.relabelled, s.differ_from_stored
    );
    for v in &s.variations {
        let changed = if v.labels_changed == 0 {
            "no label changed".to_string()
        } else {
            let parts: Vec<String> = v.changes.iter().map(|(t, n)| format!("{t} {n}")).collect();
            format!(
                "{} label(s) changed ({})",
                v.labels_changed,
                parts.join(", ")
            )
        };
        let _ = writeln!(
            out,
            "  {} {} -> {} (x{}{}): {changed}",
            v.threshold,
            short(v.from),
            short(v.to),
            v.factor,
            match v.scaling {
                Scaling::Value => "",
                Scaling::DistanceToOne => " of 1 - value",
                Scaling::DensityExcess => " of dense/dilute - 1",
            }
        );
        for m in v
            .boundaries
            .iter()
            .filter(|m| m.status != Status::Unchanged)
        {
            let place = match (&m.branch, m.slice.is_empty()) {
                (Some(b), _) => format!(" ({})", crate::boundary::branch_words(b)),
                (None, false) => format!(" ({})", m.slice),
                (None, true) => String::new(),
            };
            let what = match m.status {
                Status::Appears => format!("appears ({} point(s))", m.points[1]),
                Status::Vanishes => format!("vanishes ({} point(s))", m.points[0]),
                _ => {
                    let y = match (m.y_median, m.y_max) {
                        (Some(a), Some(b)) => {
                            format!(", {yl} median {} max {}{yu}", short(a), short(b))
                        }
                        _ => String::new(),
                    };
                    format!(
                        "{} -> {} points, {xl} median {} max {}{xu}{y}",
                        m.points[0],
                        m.points[1],
                        short(m.x_median.unwrap_or(0.0)),
                        short(m.x_max.unwrap_or(0.0))
                    )
                }
            };
            let _ = writeln!(out, "      {}{place}: {what}", m.pair);
        }
    }
    out.push_str(&summary_text(s, &xl, xu, &yl, yu));
    out
}

/// The summary table: per threshold and factor, labels changed, the largest move of any
/// boundary along each axis, boundaries that appear or vanish.
fn summary_text(s: &Sensitivity, xl: &str, xu: &str, yl: &str, yu: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "  summary (x{} | x{}): labels changed, largest move of a boundary, boundaries new/gone",
        FACTORS[0], FACTORS[1]
    );
    let _ = writeln!(
        out,
        "    {:<26} {:>13} {:>19} {:>19} {:>13}",
        "threshold",
        "labels",
        format!("{xl} max{xu}"),
        format!("{yl} max{yu}"),
        "new/gone"
    );
    for key in THRESHOLDS {
        let of: Vec<&Variation> = s.variations.iter().filter(|v| v.threshold == key).collect();
        let cell = |f: &dyn Fn(&Variation) -> String| {
            of.iter().map(|v| f(v)).collect::<Vec<_>>().join(" | ")
        };
        let max = |v: &Variation, y: bool| {
            let m = v
                .boundaries
                .iter()
                .filter_map(|m| if y { m.y_max } else { m.x_max })
                .fold(0.0, f64::max);
            short(m)
        };
        let count =
            |v: &Variation, st: Status| v.boundaries.iter().filter(|m| m.status == st).count();
        let _ = writeln!(
            out,
            "    {:<26} {:>13} {:>19} {:>19} {:>13}",
            key,
            cell(&|v| v.labels_changed.to_string()),
            cell(&|v| max(v, false)),
            cell(&|v| max(v, true)),
            cell(&|v| format!(
                "{}/{}",
                count(v, Status::Appears),
                count(v, Status::Vanishes)
            ))
        );
    }
    out
}

/// `boundaries --sensitivity --format csv`: one row per variation and boundary.
pub fn sensitivity_csv(all: &[Sensitivity]) -> String {
    let mut out = String::from(
        "sweep,threshold,scaling,factor,from,to,labels_changed,slice,branch,pair,status,\
         points_before,points_after,x_median,x_max,y_median,y_max\n",
    );
    let num = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
    let field = |t: &str| super::export::csv_field(t);
    for s in all {
        for v in &s.variations {
            let scaling = serde_json::to_value(v.scaling).expect("serializes");
            let head = format!(
                "{},{},{},{},{},{},{}",
                field(&s.sweep),
                v.threshold,
                scaling.as_str().unwrap_or_default(),
                v.factor,
                v.from,
                v.to,
                v.labels_changed
            );
            if v.boundaries.is_empty() {
                let _ = writeln!(out, "{head},,,,,,,,,,");
            }
            for m in &v.boundaries {
                let status = serde_json::to_value(m.status).expect("serializes");
                let _ = writeln!(
                    out,
                    "{head},{},{},{},{},{},{},{},{},{},{}",
                    field(&m.slice),
                    m.branch.as_deref().unwrap_or(""),
                    m.pair,
                    status.as_str().unwrap_or_default(),
                    m.points[0],
                    m.points[1],
                    num(m.x_median),
                    num(m.x_max),
                    num(m.y_median),
                    num(m.y_max)
                );
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The transformations of the module doc on the defaults.
    #[test]
    fn each_threshold_is_varied_by_its_transformation() {
        let th = Thresholds::default();
        let at = |key: &str, k: f64| value(&varied(&th, key, k), key);
        assert_eq!(at("solid_diffusion", 2.0), 2e-3);
        assert_eq!(at("gas_temperature", 0.5), 1.0);
        assert!((at("still_members", 0.5) - 0.9).abs() < 1e-15);
        assert!((at("still_members", 2.0) - 0.6).abs() < 1e-15);
        assert!((at("coexistence_level", 0.5) - 0.995).abs() < 1e-15);
        assert!((at("coexistence_level", 2.0) - 0.98).abs() < 1e-15);
        assert!((at("coexistence_contrast", 0.5) - 1.0 / 3.0).abs() < 1e-15);
        assert!((at("coexistence_contrast", 2.0) - 2.0 / 3.0).abs() < 1e-15);
        assert_eq!(at("diffusive_exponent", 2.0), 1.0);
        // Only the varied threshold changes.
        let v = varied(&th, "cluster_fraction", 2.0);
        assert_eq!(v.cluster_fraction, 0.4);
        assert_eq!(
            Thresholds {
                cluster_fraction: th.cluster_fraction,
                ..v
            },
            th
        );
    }

    /// Without the clamps a varied threshold leaves its valid range: each clamp is needed, and
    /// every varied set of thresholds passes the scene validation.
    #[test]
    fn varied_thresholds_stay_in_their_valid_range() {
        let edge = Thresholds {
            diffusive_exponent: 0.8,
            still_members: 0.3,
            cluster_fraction: 0.7,
            coexistence_level: 0.6,
            coexistence_contrast: 1.0,
            gas_temperature: 0.03,
            solid_temperature: 0.02,
            line_jump_ratio: 1.5,
            ..Thresholds::default()
        };
        edge.validate("edge").unwrap();
        for key in THRESHOLDS {
            for k in [0.25, 0.5, 2.0, 4.0] {
                let v = varied(&edge, key, k);
                v.validate("varied")
                    .unwrap_or_else(|e| panic!("{key} x{k}: {e}"));
            }
        }
        // The unclamped values would not validate: each clamp is needed.
        let raw = [
            ("diffusive_exponent", 0.8 * 2.0),
            ("still_members", 1.0 - (1.0 - 0.3) * 2.0),
            ("cluster_fraction", 0.7 * 2.0),
            ("coexistence_level", 1.0 - (1.0 - 0.6) * 2.0),
            ("line_jump_ratio", 1.5 * 0.5),
            ("gas_temperature", 0.03 * 0.5),
            ("solid_temperature", 0.02 * 2.0),
        ];
        for (key, x) in raw {
            let mut t = edge.clone();
            *slot(&mut t, key) = x;
            assert!(t.validate("raw").is_err(), "{key} = {x} validates");
        }
    }
}
