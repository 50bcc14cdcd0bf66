//! The `[observe]` section of a scene: which observers run, when they sample, and the
//! stationary window. Pure data plus its validation (errors name the file, key and range).

use super::thresholds::Mobility;
use super::{Scene, SceneError, Thresholds};
use serde::{Deserialize, Serialize};

/// How a 3D box is cut into lateral bins (`observe.bins_3d`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Bins3d {
    /// Square cells over `(x, y)`.
    #[default]
    Plane,
    /// Slabs along `x` spanning all of `L_y`.
    XSlabs,
}

/// What to observe and when (scene section `[observe]`; every key optional).
///
/// Time is counted in *periods*: the driving period `2 pi / omega` of a shaken scene, or one
/// time unit `sqrt(d/g)` (the scene's own time unit without gravity) when nothing drives it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ObserveSpec {
    /// Length of the transient, in periods: the stationary window is
    /// `[max(transient_periods * period, transient_time), run.duration]`. Default 0 (the whole
    /// run).
    pub transient_periods: f64,
    /// Shortest transient in time units (default 0): a high-frequency period is short, and a hot
    /// start cools on its own clock, not the drive's. With a `[convergence]` policy this is the
    /// floor; the run's trend decides where its transient really ended (docs/observables.md).
    #[serde(skip_serializing_if = "is_zero")]
    pub transient_time: f64,
    /// Width of the lateral bins of the profiles, in units of length (`d = 1`); rounded so that
    /// a whole number of bins tiles `L_x` (one bin if it exceeds `L_x`). Default 4 d.
    pub bin_width: f64,
    /// Observer samples per period (default 20). The location-change counter needs it fine
    /// enough (docs/observables.md). A run takes `run.duration / period * samples_per_period`
    /// samples, each costing a Delaunay triangulation in 2D where location changes are counted;
    /// like `run.duration`, that is the user's choice and not capped (a scene run without
    /// observers never samples).
    pub samples_per_period: f64,
    /// Shortest interval between two observer samples, in time units (default 0: none). At
    /// high frequency `period / samples_per_period` is far shorter than anything the observers
    /// resolve (at omega = 850, 20 samples per period are 3.7e-4 time units apart), and a run
    /// long in time would cost millions of samples. The interval is then the smallest whole
    /// multiple of `period / samples_per_period` at least this long, so samples stay on the
    /// drive's phase grid.
    #[serde(skip_serializing_if = "is_zero")]
    pub min_sample_interval: f64,
    /// Count location changes (`f_lc`; Delaunay in 2D, neighbour shells in 3D). Left out, it
    /// is on only where the classifier reads `f_lc` (`classify.mobility =
    /// "location_changes"`): [`ObserveSpec::counts_location_changes`]. A scene read from text
    /// has it resolved to `Some` ([`Scene::resolve_observers`]), so a job spec names it.
    pub location_changes: Option<bool>,
    /// Per-layer lateral mean-square displacement and diffusion coefficient. Default on.
    pub diffusion: bool,
    /// Number of layers with equal particle numbers for the diffusion observer (default 3; at
    /// most one per particle is used).
    pub layers: usize,
    /// Keep the sampled time series in the result (default on).
    pub time_series: bool,
    /// 2D: a new Delaunay edge counts as a location change only if it is at most this long
    /// (units of `d`; default 2). Longer edges span the empty space above a bed or a gas and
    /// change with every rattle of a surface grain without any neighbour exchange.
    pub lc_max_edge: f64,
    /// 2D: hysteresis of the Delaunay flips, in radians (default 0.2): a flip counts once the
    /// replaced edge violates the in-circle condition by more than this angle
    /// (`angle_a + angle_b - pi` of its quadrilateral).
    pub lc_flip_margin: f64,
    /// 3D: two grains become neighbours when their centres come closer than this multiple of
    /// `r_i + r_j` (default 1.2), and stop being neighbours beyond `lc_leave_factor` times it.
    pub(crate) lc_enter_factor: f64,
    /// 3D: leaving factor of the neighbour shell (default 1.5; > `lc_enter_factor`).
    pub(crate) lc_leave_factor: f64,
    /// Lag of the mobility measure, in time units `sqrt(d/g)` (default 10): the lateral
    /// mean-square displacement over this lag gives `D_lat` (`observe::lateral`).
    pub mobility_lag: f64,
    /// How long, in time units `sqrt(d/g)`, a grain must have held a bond (a capillary bridge;
    /// dry: a gap below 0.1 d) at every sample before it counts as bound into a cluster
    /// (default 0.2): longer than a bounce, so a gas grain that touches a drop and flies off is
    /// not counted with it (`observe::clusters`).
    /// Left out of the serialized spec at its default, so that job ids (hashes of the spec) of
    /// sweeps that do not set it are those they had before it existed.
    #[serde(skip_serializing_if = "is_default_bond_time")]
    pub bond_time: f64,
    /// Smallest bonded cluster, in grains, whose grains make up a dense region (default 3).
    /// Left out of the serialized spec at its default (job ids as before it existed).
    #[serde(skip_serializing_if = "is_default_cluster_min_size")]
    pub cluster_min_size: usize,
    /// 3D: lateral bins as square cells over `(x, y)` (`"plane"`, default) or slabs along `x`
    /// across the whole depth (`"x_slabs"`).
    pub bins_3d: Bins3d,
    /// `stationarity_tolerance`, a key of the run policy the settling verdict replaced: read
    /// from the stored specs of older results and ignored (never written, so it is no part of
    /// a job id); a scene file that sets it is refused (`Scene::from_toml_str`).
    #[serde(default, skip_serializing, rename = "stationarity_tolerance")]
    pub(crate) removed_stationarity_tolerance: Option<f64>,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl Default for ObserveSpec {
    fn default() -> Self {
        Self {
            transient_periods: 0.0,
            transient_time: 0.0,
            bin_width: 4.0,
            samples_per_period: 20.0,
            min_sample_interval: 0.0,
            location_changes: None,
            diffusion: true,
            layers: 3,
            time_series: true,
            lc_max_edge: 2.0,
            lc_flip_margin: 0.2,
            lc_enter_factor: 1.2,
            lc_leave_factor: 1.5,
            mobility_lag: 10.0,
            bond_time: DEFAULT_BOND_TIME,
            cluster_min_size: DEFAULT_CLUSTER_MIN_SIZE,
            bins_3d: Bins3d::default(),
            removed_stationarity_tolerance: None,
        }
    }
}

const DEFAULT_BOND_TIME: f64 = 0.2;
const DEFAULT_CLUSTER_MIN_SIZE: usize = 3;
fn is_default_bond_time(v: &f64) -> bool {
    *v == DEFAULT_BOND_TIME
}
fn is_default_cluster_min_size(v: &usize) -> bool {
    *v == DEFAULT_CLUSTER_MIN_SIZE
}

impl ObserveSpec {
    /// Whether the location-change counter runs: as set, else only where `classify` decides
    /// mobility by `f_lc`. The counter triangulates every sample (2D) and can cost as much as
    /// the engine, so nothing pays for it unless asked (docs/observables.md).
    pub(crate) fn counts_location_changes(&self, classify: &Thresholds) -> bool {
        self.location_changes
            .unwrap_or(classify.mobility == Mobility::LocationChanges)
    }

    /// Interval between two observer samples: `period / samples_per_period`, or the smallest
    /// whole multiple of it that is at least `min_sample_interval`.
    pub fn sample_interval(&self, scene: &Scene) -> f64 {
        let base = scene.driving_period() / self.samples_per_period;
        if self.min_sample_interval > base {
            base * (self.min_sample_interval / base * (1.0 - 1e-12)).ceil()
        } else {
            base
        }
    }

    /// Start of the stationary window: `max(transient_periods T, transient_time)`.
    pub fn window_start(&self, scene: &Scene) -> f64 {
        (self.transient_periods * scene.driving_period()).max(self.transient_time)
    }

    /// Checks every key of `[observe]` against the rest of the scene.
    pub fn validate(&self, scene: &Scene, origin: &str) -> Result<(), SceneError> {
        self.validate_sampling(scene, origin)?;
        self.validate_observers(scene, origin)
    }

    /// The transient, the lateral bins and the sample spacing, against the run's first window.
    fn validate_sampling(&self, scene: &Scene, origin: &str) -> Result<(), SceneError> {
        let check = |key: &str, v: f64, ok: bool, must: &str| {
            SceneError::unless(ok, origin, &format!("observe.{key}"), v, must)
        };
        let period = scene.driving_period();
        // With a run-length policy the first window ends at its first check.
        let (duration, run_name) = scene
            .convergence
            .as_ref()
            .map_or((scene.run.duration, "run.duration"), |c| {
                (c.first_check(scene), "the [convergence] first check")
            });
        let first_window =
            format!(">= 0 and shorter than the first window, i.e. < {run_name} = {duration}");
        let t = self.transient_time;
        let ok = t.is_finite() && t >= 0.0 && t < duration;
        check("transient_time", t, ok, &first_window)?;
        let t = self.transient_periods;
        let must = format!(
            ">= 0 and shorter than the run, i.e. < {run_name} / period = {duration} / \
             {period:.6} = {:.6} (one period is {})",
            duration / period,
            if scene.drive_motion().is_some() {
                "the driving period 2 pi / omega"
            } else {
                "one time unit without a drive"
            }
        );
        check(
            "transient_periods",
            t,
            t.is_finite() && t >= 0.0 && t * period < duration,
            &must,
        )?;
        let w = self.bin_width;
        let must = "> 0 (a width above L_x gives one bin)";
        check("bin_width", w, w.is_finite() && w > 0.0, must)?;
        let s = self.samples_per_period;
        check("samples_per_period", s, s.is_finite() && s > 0.0, "> 0")?;
        let t = self.min_sample_interval;
        let ok = t.is_finite() && t >= 0.0 && t < duration;
        check("min_sample_interval", t, ok, &first_window)
    }

    /// The observers' own settings: layers, the line rule, mobility, bonds, clusters,
    /// stationarity.
    fn validate_observers(&self, scene: &Scene, origin: &str) -> Result<(), SceneError> {
        let check = |key: &str, v: &dyn std::fmt::Display, ok: bool, must: &str| {
            SceneError::unless(ok, origin, &format!("observe.{key}"), v, must)
        };
        let must = ">= 1 (more layers than particles give one particle per layer)";
        check("layers", &self.layers, self.layers > 0, must)?;
        let e = self.lc_max_edge;
        let must = ">= 1 (units of d; neighbours touch at 1)";
        check("lc_max_edge", &e, e.is_finite() && e >= 1.0, must)?;
        let m = self.lc_flip_margin;
        let ok = m.is_finite() && (0.0..std::f64::consts::FRAC_PI_2).contains(&m);
        check("lc_flip_margin", &m, ok, "in [0, pi/2) (radians)")?;
        let (enter, leave) = (self.lc_enter_factor, self.lc_leave_factor);
        let must = ">= 1 (touching grains are at 1)";
        check(
            "lc_enter_factor",
            &enter,
            enter.is_finite() && enter >= 1.0,
            must,
        )?;
        let must = format!("finite and > lc_enter_factor = {enter}");
        check(
            "lc_leave_factor",
            &leave,
            leave.is_finite() && leave > enter,
            &must,
        )?;
        let lag = self.mobility_lag;
        let must = "finite and > 0 (time units)";
        check("mobility_lag", &lag, lag.is_finite() && lag > 0.0, must)?;
        let b = self.bond_time;
        let must = "finite and >= 0 (time units)";
        check("bond_time", &b, b.is_finite() && b >= 0.0, must)?;
        let size = self.cluster_min_size;
        check("cluster_min_size", &size, size >= 2, ">= 2 (grains)")?;
        if self.location_changes == Some(false)
            && scene.classify.mobility == Mobility::LocationChanges
        {
            return Err(SceneError::new(
                origin,
                "observe.location_changes",
                "= false, but classify.mobility = \"location_changes\" decides solid versus \
                 mobile by f_lc, which only this observer measures: set it true or leave it out",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sweep and the observers count the periods of an undriven scene with one definition
    /// (`Scene::driving_period`), in the scene's time unit; two definitions (`sqrt(d/g)` and 1)
    /// would disagree.
    #[test]
    fn an_undriven_scene_counts_periods_in_its_time_unit() {
        let s = Scene::from_toml_str(
            "dimension = 2\ngravity = 4.0\n[box]\nsize = [20.0, 9.0]\n[particles]\ncount = 10\n\
             [initial]\ntemperature = 1.0\n[run]\nduration = 10.0\n\
             [observe]\ntransient_periods = 6.0\nsamples_per_period = 10.0\n",
            "test",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.driving_period(), 0.5);
        assert_eq!(s.observe.window_start(&s), 3.0);
        assert_eq!(s.observe.sample_interval(&s), 0.05);
    }
}
