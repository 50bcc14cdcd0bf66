//! Phase-boundary extraction (docs/model.md 7, last paragraph): the phase map of a sweep and the
//! boundary points between its phases.
//!
//! 1. Phase map: the replicas of a grid point vote; the point takes the majority phase. A tie
//!    goes to the tied phase of the lowest-numbered replica (deterministic; such a point sits on
//!    a boundary anyway). Replicas without a phase (not run, failed, unclassified) do not vote; a
//!    point with no vote is left out.
//! 2. The plane: for a shaking sweep with both a `Gamma` and an `E*` (or `E_d*`) axis, the
//!    `(log10 E*, Gamma)` plane of the thesis (x = log10 E*, y = Gamma). Otherwise the first two
//!    numeric axes (x = first, y = second), each scaled linearly, or by log10 where the axis was
//!    written as a `log` range. Further axes cut the map into slices, each handled on its own. A
//!    sweep with one axis is a line: boundary points lie halfway between neighbours.
//! 3. Boundary points: Delaunay-triangulate the map points of a slice in that plane (spade, exact
//!    predicates) and put a point at the midpoint of every edge whose two ends differ in phase.
//!    The midpoint is taken in the scaled plane (so on a log axis it is the geometric mean).
//!    Points are grouped by the pair of phases, sorted by name and joined with `|` (`f|fgc`).
//!    Each boundary point carries its uncertainty, half the straddling edge along each axis (in
//!    the plane's units: decades on a log axis) with the edge's interval in axis units, and a
//!    confidence: the fraction of the votes at the two ends that agree with their end's
//!    majority.
//! 4. Trust: a point with a voting replica whose label may still change (a run neither
//!    stationary nor on a trend that keeps its label: `observe::trend::trust`; for results stored
//!    before trend states, the run-length policy's verdict or the stationarity check) is kept on
//!    the map, marked `trusted = false` (hollow in `plot`, `?` in `boundaries`), but left out of
//!    the triangulation, so no boundary rests on it, unless [`Extraction::include_unconverged`]
//!    asks for it (`boundaries --include-unconverged`). Its untrusted neighbours are then joined
//!    to the trusted points around them. A heating gas, a cooling solid and a coarsening
//!    coexistence are trusted for their label (`~` in `boundaries`): more time only makes the
//!    gas hotter, the solid colder and the drops bigger.
//! 5. Branches: a sweep with an `initial.start` axis (`["hot", "continue"]` in the shipped
//!    elastic diagrams, or `["hot", "cold"]`: docs/observables.md "Cold start and hysteresis")
//!    has one slice per start mode, so each branch's boundaries are extracted from its own
//!    points alone; the slice and each of its boundary points name their branch (the start
//!    mode).
//! 6. Physical units: for shaking sweeps every map and boundary point also carries the container
//!    motion `(A, omega)` of docs/model.md 4.1, computed from its `(Gamma, E*)` and the scene's
//!    `E_cb`, `m`, `g` (Scene::drive_motion).

use crate::sweep::file::{Axis, AxisKind};
use serde::Serialize;
use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};
use std::collections::BTreeMap;
use std::sync::Arc;
use wetgran_core::observe::criterion::DecidedBy;
use wetgran_core::scene::{DriveKind, Scene};

/// One job's contribution to the map.
#[derive(Debug, Clone)]
pub struct Observation {
    /// The axis values of its grid point, in axis order.
    pub coords: Vec<serde_json::Value>,
    pub replica: i64,
    pub phase: Option<String>,
    /// Whether the label may carry a boundary (`false`: not stationary and on no trend that
    /// keeps the label; `true` also where the result carries no verdict).
    pub trusted: bool,
    /// Not stationary, but on a trend that cannot change the label (`~`).
    pub label_kept: bool,
    /// The job's scene (for physical units); shared between the jobs of a sweep where their
    /// scenes agree in what the map reads (`store::PointSummary`).
    pub scene: Arc<Scene>,
    /// The criterion that decided its label (`observe::criterion`; `None`: not known).
    pub decided_by: Option<DecidedBy>,
}

impl Observation {
    /// A report's summary of a stored job as one vote of the phase map.
    pub fn of_summary(row: &crate::store::PointSummary) -> Observation {
        let trust = row.trust();
        Observation {
            coords: row.coords.clone(),
            replica: row.replica,
            phase: row.phase.clone(),
            trusted: trust.label_trusted(),
            label_kept: trust == wetgran_core::observe::Verdict::LabelKept,
            scene: Arc::clone(&row.scene),
            decided_by: None,
        }
    }
}

/// How boundaries are extracted.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Extraction {
    /// Triangulate unconverged points too (default: only converged ones carry boundaries).
    pub include_unconverged: bool,
}

/// How an axis of the plane is scaled.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PlaneAxis {
    /// Index of the axis in the sweep's axis list.
    pub index: usize,
    pub key: String,
    pub label: String,
    /// Whether the plane uses `log10` of the axis value.
    pub log: bool,
}

impl PlaneAxis {
    /// The plane coordinate of an axis value (`log10` on a log axis).
    pub fn scale(&self, v: f64) -> f64 {
        if self.log { v.log10() } else { v }
    }
    /// The axis value of a plane coordinate.
    pub fn unscale(&self, s: f64) -> f64 {
        if self.log { 10f64.powf(s) } else { s }
    }
}

/// A grid point of the map with its majority phase.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct MapPoint {
    /// All axis values of the point.
    pub coords: Vec<serde_json::Value>,
    /// Values on the plane's axes (unscaled, in the sweep's units).
    pub x: f64,
    pub y: f64,
    pub phase: String,
    /// The replicas' phases, replica order (`None`: no result).
    pub votes: Vec<Option<String>>,
    /// Whether the majority was a tie.
    pub tie: bool,
    /// Whether every voting replica's label is trusted (module doc, 4).
    pub trusted: bool,
    /// Whether a voting replica is not stationary but on a trend that keeps its label.
    pub label_kept: bool,
    /// Container amplitude `A` and angular frequency `omega` (shaking sweeps).
    pub amplitude: Option<f64>,
    pub omega: Option<f64>,
    /// The criterion that decided the majority label: that of its lowest replica with the
    /// majority phase (`None`: not known).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decided_by: Option<DecidedBy>,
}

/// A boundary point: the midpoint of a Delaunay edge between two phases.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct BoundaryPoint {
    /// The phase pair, sorted and joined with `|` (`f|fgc`).
    pub pair: String,
    /// Position on the plane's axes (unscaled, in the sweep's units).
    pub x: f64,
    pub y: f64,
    /// The two map points of the edge (indices into [`Slice::points`]).
    pub between: [usize; 2],
    /// Uncertainty: half the straddling edge along each axis, in the plane's units (axis units;
    /// decades on a log axis, i.e. a factor `10^x_half` either side).
    pub x_half: f64,
    pub y_half: f64,
    /// The interval the boundary lies in along each axis: the edge's two ends, low to high.
    pub x_range: [f64; 2],
    pub y_range: [f64; 2],
    /// Fraction of the votes at the two ends that agree with their end's majority (1: every
    /// replica agrees).
    pub confidence: f64,
    pub amplitude: Option<f64>,
    pub omega: Option<f64>,
    /// The branch it bounds: the start mode of its slice (`hot`, `cold`, `continue`) when the
    /// sweep has an `initial.start` axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub branch: Option<String>,
}

/// The name of the start axis (`initial.start`), whose slices are the branches of a map.
pub const START_AXIS: &str = "initial.start";

/// A branch's name in words: `hot start`, `cold start`, `continuation` (another value: `X
/// start`).
pub fn branch_words(branch: &str) -> String {
    match branch {
        "continue" => "continuation".to_string(),
        b => format!("{b} start"),
    }
}

/// The map for one combination of the axes outside the plane.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Slice {
    /// `(label, value)` of every axis outside the plane.
    pub fixed: Vec<(String, serde_json::Value)>,
    /// The start mode of its points when the sweep has an `initial.start` axis (module doc, 5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub branch: Option<String>,
    pub points: Vec<MapPoint>,
    /// Boundary points grouped by phase pair.
    pub boundaries: BTreeMap<String, Vec<BoundaryPoint>>,
}

/// The phase map of a sweep and its boundaries.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PhaseMap {
    pub x: Option<PlaneAxis>,
    pub y: Option<PlaneAxis>,
    /// Whether this is the `(E*, Gamma)` plane of a shaking sweep.
    pub shaking: bool,
    pub slices: Vec<Slice>,
}

/// Why a map cannot be made.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundaryError(pub String);

impl std::fmt::Display for BoundaryError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BoundaryError {}

/// Picks the plane's axes (see the module doc); `None` entries for sweeps with fewer axes.
pub fn plane_axes(axes: &[Axis]) -> (Option<PlaneAxis>, Option<PlaneAxis>, bool) {
    let make = |index: usize, log: bool| PlaneAxis {
        index,
        key: axes[index].key.clone(),
        label: axes[index].label.clone(),
        log,
    };
    let gamma = axes.iter().position(Axis::is_gamma);
    let e_star = axes.iter().position(Axis::is_e_star);
    if let (Some(g), Some(e)) = (gamma, e_star) {
        return (Some(make(e, true)), Some(make(g, false)), true);
    }
    let numeric: Vec<usize> = (0..axes.len())
        .filter(|&i| axes[i].values.iter().all(|v| v.as_f64().is_some()))
        .collect();
    let pick = |k: usize| {
        numeric
            .get(k)
            .map(|&i| make(i, axes[i].kind == AxisKind::Log))
    };
    (pick(0), pick(1), false)
}

/// The majority phase of a point's votes (see the module doc for ties).
pub fn majority(votes: &[Option<String>]) -> Option<(String, bool)> {
    let mut count: BTreeMap<&str, (usize, usize)> = BTreeMap::new(); // phase -> (votes, first replica)
    for (r, v) in votes.iter().enumerate() {
        if let Some(p) = v {
            let e = count.entry(p.as_str()).or_insert((0, r));
            e.0 += 1;
        }
    }
    let best = count.values().map(|c| c.0).max()?;
    let tied: Vec<(&str, usize)> = count
        .iter()
        .filter(|(_, c)| c.0 == best)
        .map(|(p, c)| (*p, c.1))
        .collect();
    let (phase, _) = tied.iter().min_by_key(|(_, first)| *first)?;
    Some((phase.to_string(), tied.len() > 1))
}

/// `(A, omega)` of docs/model.md 4.1 at `(Gamma, E*)` for the given scene's `E_cb`, `m`, `g`.
pub fn drive_at(scene: &Scene, gamma: f64, e_star: f64) -> Option<(f64, f64)> {
    let mut s = scene.clone();
    s.drive.kind = DriveKind::Sine;
    s.drive.amplitude = None;
    s.drive.omega = None;
    s.drive.gamma = Some(gamma);
    s.drive.e_star = Some(e_star);
    s.drive_motion()
}

struct Vertex {
    pos: Point2<f64>,
    index: usize,
}

impl HasPosition for Vertex {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

/// Builds the phase map and its boundary points from a sweep's axes and jobs; only converged
/// points carry boundaries (module doc, 4).
pub fn phase_map(axes: &[Axis], jobs: &[Observation]) -> Result<PhaseMap, BoundaryError> {
    phase_map_with(axes, jobs, Extraction::default())
}

/// [`phase_map`] with the extraction options.
pub fn phase_map_with(
    axes: &[Axis],
    jobs: &[Observation],
    how: Extraction,
) -> Result<PhaseMap, BoundaryError> {
    let (x, y, shaking) = plane_axes(axes);
    let plane = Plane {
        x: &x,
        y: &y,
        shaking,
    };
    let start_axis = axes.iter().position(|a| a.key == START_AXIS);
    let mut slices = Vec::new();
    for group in group_by_slice(axes, jobs, &plane)? {
        let (points, scenes) = plane.map_points(&group.points)?;
        let edges = plane.carrier_edges(&points, how)?;
        // The branch: the start axis's value, the same for every job of the slice.
        let branch = start_axis.and_then(|i| {
            group.points.first()?.first()?.coords[i]
                .as_str()
                .map(String::from)
        });
        let mut boundaries = plane.boundaries(&points, &scenes, &edges);
        for b in boundaries.values_mut().flatten() {
            b.branch = branch.clone();
        }
        slices.push(Slice {
            fixed: group.fixed,
            branch,
            points,
            boundaries,
        });
    }
    Ok(PhaseMap {
        x,
        y,
        shaking,
        slices,
    })
}

/// The jobs of one slice (fixed values of the axes outside the plane), grouped by grid point
/// in the order of first appearance; each point's replicas in job order.
struct SliceJobs<'a> {
    fixed: Vec<(String, serde_json::Value)>,
    points: Vec<Vec<&'a Observation>>,
}

/// Groups the jobs by slice, then by grid point, both in the order of first appearance.
fn group_by_slice<'a>(
    axes: &[Axis],
    jobs: &'a [Observation],
    plane: &Plane,
) -> Result<Vec<SliceJobs<'a>>, BoundaryError> {
    let mut slices: Vec<SliceJobs> = Vec::new();
    let mut slice_of: BTreeMap<String, usize> = BTreeMap::new();
    let mut point_of: BTreeMap<(usize, String), usize> = BTreeMap::new();
    for job in jobs {
        if job.coords.len() != axes.len() {
            return Err(BoundaryError(format!(
                "a job has {} coordinates for {} axes",
                job.coords.len(),
                axes.len()
            )));
        }
        let fixed: Vec<(String, serde_json::Value)> = (0..axes.len())
            .filter(|&i| !plane.holds_axis(i))
            .map(|i| (axes[i].label.clone(), job.coords[i].clone()))
            .collect();
        let skey = serde_json::to_string(&fixed).expect("serializes");
        let s = *slice_of.entry(skey).or_insert_with(|| {
            slices.push(SliceJobs {
                fixed,
                points: Vec::new(),
            });
            slices.len() - 1
        });
        let pkey = serde_json::to_string(&job.coords).expect("serializes");
        let points = &mut slices[s].points;
        let p = *point_of.entry((s, pkey)).or_insert_with(|| {
            points.push(Vec::new());
            points.len() - 1
        });
        points[p].push(job);
    }
    Ok(slices)
}

/// The plane of the map: its axes, and whether points carry the container motion.
struct Plane<'a> {
    x: &'a Option<PlaneAxis>,
    y: &'a Option<PlaneAxis>,
    shaking: bool,
}

impl Plane<'_> {
    /// Whether axis `i` is one of the plane's.
    fn holds_axis(&self, i: usize) -> bool {
        [self.x, self.y]
            .iter()
            .any(|a| a.as_ref().is_some_and(|a| a.index == i))
    }

    /// The value of a job's coordinate on a plane axis (0 without one).
    fn value(job: &Observation, a: &Option<PlaneAxis>) -> Result<f64, BoundaryError> {
        let Some(a) = a else {
            return Ok(0.0);
        };
        let v = job.coords[a.index]
            .as_f64()
            .ok_or_else(|| BoundaryError(format!("axis {} has a non-numeric value", a.label)))?;
        if a.log && v <= 0.0 {
            return Err(BoundaryError(format!(
                "axis {} is on a log scale but has the value {v}",
                a.label
            )));
        }
        Ok(v)
    }

    /// The container motion `(A, omega)` at a point of a shaking plane (docs/model.md 4.1).
    fn motion(&self, scene: &Scene, xv: f64, yv: f64) -> (Option<f64>, Option<f64>) {
        match self.shaking.then(|| drive_at(scene, yv, xv)).flatten() {
            Some((a, w)) => (Some(a), Some(w)),
            None => (None, None),
        }
    }

    /// The map points of a slice: each grid point's majority phase (step 1; a point without a
    /// vote is left out), with the scene of its first replica.
    fn map_points<'a>(
        &self,
        grid: &[Vec<&'a Observation>],
    ) -> Result<(Vec<MapPoint>, Vec<&'a Scene>), BoundaryError> {
        let (mut points, mut scenes) = (Vec::new(), Vec::new());
        for replicas in grid {
            let mut votes = replicas.clone();
            votes.sort_by_key(|job| job.replica);
            let phases: Vec<Option<String>> = votes.iter().map(|job| job.phase.clone()).collect();
            let Some((phase, tie)) = majority(&phases) else {
                continue;
            };
            let job = votes[0];
            let trusted = votes.iter().all(|v| v.phase.is_none() || v.trusted);
            let label_kept = votes.iter().any(|v| v.phase.is_some() && v.label_kept);
            let (xv, yv) = (Self::value(job, self.x)?, Self::value(job, self.y)?);
            let (amplitude, omega) = self.motion(&job.scene, xv, yv);
            let decided_by = votes
                .iter()
                .find(|v| v.phase.as_deref() == Some(phase.as_str()))
                .and_then(|v| v.decided_by.clone());
            points.push(MapPoint {
                coords: job.coords.clone(),
                x: xv,
                y: yv,
                phase,
                votes: phases,
                tie,
                trusted,
                label_kept,
                amplitude,
                omega,
                decided_by,
            });
            scenes.push(job.scene.as_ref());
        }
        Ok((points, scenes))
    }

    /// The edges between the points that carry boundaries (step 4: the converged ones, unless
    /// asked otherwise), as indices into `points`: Delaunay edges in the plane, neighbours on a
    /// line (step 3).
    fn carrier_edges(
        &self,
        points: &[MapPoint],
        how: Extraction,
    ) -> Result<Vec<(usize, usize)>, BoundaryError> {
        let carriers: Vec<usize> = (0..points.len())
            .filter(|&i| how.include_unconverged || points[i].trusted)
            .collect();
        let subset: Vec<MapPoint> = carriers.iter().map(|&i| points[i].clone()).collect();
        let edges = match (self.x, self.y) {
            (Some(xa), Some(ya)) => delaunay_edges(&subset, xa, ya)?,
            (Some(xa), None) => line_edges(&subset, xa),
            _ => Vec::new(),
        };
        Ok(edges
            .into_iter()
            .map(|(i, j)| (carriers[i], carriers[j]))
            .collect())
    }

    /// A boundary point at the midpoint (in the scaled plane) of every edge whose ends differ in
    /// phase, grouped by the pair of phases and sorted along x, then y (step 3).
    fn boundaries(
        &self,
        points: &[MapPoint],
        scenes: &[&Scene],
        edges: &[(usize, usize)],
    ) -> BTreeMap<String, Vec<BoundaryPoint>> {
        let mut boundaries: BTreeMap<String, Vec<BoundaryPoint>> = BTreeMap::new();
        for &(i, j) in edges {
            let (a, b) = (&points[i], &points[j]);
            if a.phase == b.phase {
                continue;
            }
            let mut pair = [a.phase.as_str(), b.phase.as_str()];
            pair.sort();
            let pair = pair.join("|");
            let mid = |ax: &Option<PlaneAxis>, u: f64, v: f64| {
                ax.as_ref()
                    .map_or(0.0, |ax| ax.unscale(0.5 * (ax.scale(u) + ax.scale(v))))
            };
            let half = |ax: &Option<PlaneAxis>, u: f64, v: f64| {
                ax.as_ref()
                    .map_or(0.0, |ax| 0.5 * (ax.scale(u) - ax.scale(v)).abs())
            };
            let (xv, yv) = (mid(self.x, a.x, b.x), mid(self.y, a.y, b.y));
            let (amplitude, omega) = self.motion(scenes[i], xv, yv);
            boundaries
                .entry(pair.clone())
                .or_default()
                .push(BoundaryPoint {
                    pair,
                    x: xv,
                    y: yv,
                    between: [i.min(j), i.max(j)],
                    x_half: half(self.x, a.x, b.x),
                    y_half: half(self.y, a.y, b.y),
                    x_range: [a.x.min(b.x), a.x.max(b.x)],
                    y_range: [a.y.min(b.y), a.y.max(b.y)],
                    confidence: edge_confidence(a, b),
                    amplitude,
                    omega,
                    branch: None,
                });
        }
        for list in boundaries.values_mut() {
            list.sort_by(|p, q| p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y)));
        }
        boundaries
    }
}

/// The fraction of the votes at the two ends of an edge that agree with their end's majority.
fn edge_confidence(a: &MapPoint, b: &MapPoint) -> f64 {
    let agree = |p: &MapPoint| p.votes.iter().flatten().filter(|v| **v == p.phase).count();
    let votes = |p: &MapPoint| p.votes.iter().flatten().count();
    (agree(a) + agree(b)) as f64 / (votes(a) + votes(b)) as f64
}

/// Undirected Delaunay edges `(i, j)`, `i < j`, of the map points in the scaled plane.
fn delaunay_edges(
    points: &[MapPoint],
    xa: &PlaneAxis,
    ya: &PlaneAxis,
) -> Result<Vec<(usize, usize)>, BoundaryError> {
    let pos: Vec<(f64, f64)> = points
        .iter()
        .map(|p| (xa.scale(p.x), ya.scale(p.y)))
        .collect();
    delaunay_pairs(&pos).map_err(|k| {
        BoundaryError(format!(
            "point ({}, {}) cannot be triangulated",
            points[k].x, points[k].y
        ))
    })
}

/// Undirected Delaunay edges `(i, j)`, `i < j`, sorted, of points in a plane (spade, exact
/// predicates). Error: the index of a point that cannot be inserted (not finite).
pub fn delaunay_pairs(pos: &[(f64, f64)]) -> Result<Vec<(usize, usize)>, usize> {
    let mut tri: DelaunayTriangulation<Vertex> = DelaunayTriangulation::new();
    for (index, &(x, y)) in pos.iter().enumerate() {
        tri.insert(Vertex {
            pos: Point2::new(x, y),
            index,
        })
        .map_err(|_| index)?;
    }
    let mut edges: Vec<(usize, usize)> = tri
        .undirected_edges()
        .map(|e| {
            let [a, b] = e.vertices();
            let (i, j) = (a.data().index, b.data().index);
            (i.min(j), i.max(j))
        })
        .collect();
    edges.sort();
    Ok(edges)
}

/// Neighbours along a single axis.
fn line_edges(points: &[MapPoint], xa: &PlaneAxis) -> Vec<(usize, usize)> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&i, &j| xa.scale(points[i].x).total_cmp(&xa.scale(points[j].x)));
    order
        .windows(2)
        .map(|w| (w[0].min(w[1]), w[0].max(w[1])))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shaken_scene() -> Scene {
        Scene::from_toml_str(
            "dimension = 2\n[box]\nsize = [20.0, 9.0]\n[particles]\ncount = 10\n\
             [drive]\nkind = \"sine\"\ngamma = 3.0\ne_star = 2.0\n[initial]\nseed = 1\n\
             temperature = 1.0\n[run]\nduration = 1.0\n",
            "test",
        )
        .unwrap()
    }

    fn axis(key: &str, label: &str) -> Axis {
        Axis {
            name: key.to_string(),
            key: key.to_string(),
            label: label.to_string(),
            kind: AxisKind::Values,
            values: vec![],
            line: 0,
        }
    }

    /// One vote at `coords` of the shaken scene.
    fn obs(coords: &[f64], replica: i64, phase: &str, trusted: bool) -> Observation {
        Observation {
            coords: coords.iter().map(|&c| serde_json::json!(c)).collect(),
            replica,
            phase: Some(phase.to_string()),
            trusted,
            label_kept: false,
            scene: Arc::new(shaken_scene()),
            decided_by: None,
        }
    }

    fn v(s: &[Option<&str>]) -> Vec<Option<String>> {
        s.iter().map(|x| x.map(str::to_string)).collect()
    }

    #[test]
    fn majority_counts_votes_and_breaks_ties_by_the_first_replica() {
        assert_eq!(
            majority(&v(&[Some("g"), Some("f"), Some("g")])),
            Some(("g".into(), false))
        );
        assert_eq!(
            majority(&v(&[Some("g"), Some("f")])),
            Some(("g".into(), true))
        );
        assert_eq!(
            majority(&v(&[None, Some("sfc"), Some("f")])),
            Some(("sfc".into(), true))
        );
        assert_eq!(majority(&v(&[None, None])), None);
    }

    #[test]
    fn boundary_points_carry_half_the_edge_and_the_replicas_agreement() {
        let axes = vec![axis("drive.gamma", "Gamma"), axis("drive.e_star", "E*")];
        // (Gamma 2, E* 1): f, f, g; (Gamma 2, E* 4): g, g, g.
        let jobs: Vec<Observation> = ["f", "f", "g", "g", "g", "g"]
            .iter()
            .enumerate()
            .map(|(k, p)| obs(&[2.0, if k < 3 { 1.0 } else { 4.0 }], k as i64 % 3, p, true))
            .collect();
        let map = phase_map(&axes, &jobs).unwrap();
        let b = &map.slices[0].boundaries["f|g"][0];
        // Midpoint in log10 E*: E* = 2 (geometric mean), half the edge = log10(2) decades.
        assert!((b.x - 2.0).abs() < 1e-12);
        assert!((b.x_half - 2f64.log10()).abs() < 1e-12);
        assert_eq!(
            (b.x_range, b.y_range, b.y_half),
            ([1.0, 4.0], [2.0, 2.0], 0.0)
        );
        // 5 of the 6 votes agree with their point's majority.
        assert!((b.confidence - 5.0 / 6.0).abs() < 1e-12);
    }

    #[test]
    fn unconverged_points_carry_no_boundary_unless_asked() {
        let axes = vec![axis("drive.e_star", "E*")];
        // A line f (E* 1), g unconverged (E* 2), g (E* 4).
        let jobs = vec![
            obs(&[1.0], 0, "f", true),
            obs(&[2.0], 0, "g", false),
            obs(&[4.0], 0, "g", true),
        ];
        let map = phase_map(&axes, &jobs).unwrap();
        let slice = &map.slices[0];
        // The unconverged point stays on the map, marked ...
        assert_eq!(slice.points.len(), 3);
        assert_eq!(
            slice.points.iter().map(|p| p.trusted).collect::<Vec<_>>(),
            [true, false, true]
        );
        // ... but the boundary is drawn between the converged neighbours, E* 1 and 4.
        let b = &slice.boundaries["f|g"];
        assert_eq!(b.len(), 1);
        assert_eq!(b[0].x_range, [1.0, 4.0]);
        assert_eq!(b[0].between, [0, 2]);
        // Asked to, the extraction uses it: the boundary lies between E* 1 and 2.
        let all = phase_map_with(
            &axes,
            &jobs,
            Extraction {
                include_unconverged: true,
            },
        )
        .unwrap();
        let b = &all.slices[0].boundaries["f|g"];
        assert_eq!(b.len(), 1);
        assert_eq!(b[0].x_range, [1.0, 2.0]);
        assert_eq!(b[0].between, [0, 1]);
    }
}
