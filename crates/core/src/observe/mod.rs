//! Observers, order parameters and the phase classification (docs/model.md 7).
//!
//! [`run_observed`] runs a scene and hands a [`Frame`] to every observer the scene's `[observe]`
//! section asks for, `samples_per_period` times per period (the driving period `2 pi / omega`,
//! or one time unit without a drive). Each observer keeps a time series over the whole run and
//! averages over the stationary window `[transient_periods * period, run.duration]`:
//!
//! | module | observable |
//! |---|---|
//! | [`temperature`] | `T_g / E_cb` of the whole system (Eq. 3.2) |
//! | [`profiles`] | lateral profiles of `n_cb` and of the packing fraction; `Delta n_cb` (Eq. 3.3), `Delta n_area` |
//! | [`clusters`] | bonded clusters: bonds older than `bond_time`, components of at least `cluster_min_size` grains, a cluster's rigid motion |
//! | [`lateral`] | per-bin block sums: packing, bridges, `T_g` of all grains and of cluster members, lateral mobility `D_lat` at two lags |
//! | [`noise`] | statistical error of the profiles and the noise baseline of `Delta n` |
//! | [`location_changes`] | `f_lc` (Delaunay in 2D, neighbour shells in 3D), only when asked for |
//! | [`diffusion`] | per-layer lateral MSD and diffusion coefficient |
//! | [`trend`](mod@trend) | the end of the transient and what the run did after it: stationary, heating, cooling, coarsening or undecided |
//! | [`settling`] | whether each region of a label has settled: the one verdict on a run |
//! | `run` | [`run_observed`] and the run-length policy that extends a run until its label settles |
//! | [`shear`](mod@shear) | shear drive: `E_par`, `E_perp`, their window means and extrema per cycle |
//! | [`classify`](mod@classify) | the phase from the observables and the `[classify]` thresholds |
//! | [`classify`]`::evidence` | a point's own evidence against the line rule; borderline decisions |
//! | [`line`](mod@line) | the fluid-gas inflection point along a line of constant Gamma |
//! | [`criterion`] | which criterion decided a label, from its decision record |
//!
//! Collision counts (pair, wall), bridge formations and ruptures over the window come from the
//! engine's event counters at the window's first and last sample. Observers only read copies of
//! the state: observing never changes a trajectory.

pub mod bins;
pub mod classify;
pub mod clusters;
pub mod convergence;
pub mod criterion;
pub(crate) mod diffusion;
pub(crate) mod lateral;
pub mod line;
pub mod location_changes;
pub mod noise;
pub mod profiles;
mod run;
pub mod settling;
pub mod shear;
pub mod temperature;
pub mod trend;

pub use crate::scene::{ConvergenceSpec, ObserveSpec};
pub use classify::{
    Classification, DecisionInputs, Mobility, Phase, RegionInputs, Thresholds, classify,
};
pub use diffusion::{Diffusion, LayerDiffusion};
pub use line::{Inflection, fluid_gas_inflection};
pub use run::{ObservedRun, run_observed, run_observed_from, run_observed_with_frame};
pub use settling::{Settling, Verdict};
pub use trend::Ending;

use crate::scene::Scene;
use crate::sim::Frame;
use lateral::{LateralObserver, field, field_sums};
use location_changes::{LocationChangeCounter, Method};
pub use profiles::CageCounts;
use profiles::ProfileObserver;
use serde::{Deserialize, Serialize};
use temperature::TemperatureObserver;

/// Tolerance floors of the trend tests (`observe::trend`): below these magnitudes a drift is
/// judged against the floor instead of the value itself. `T_g / E_cb`:
pub(crate) const FLOOR_TEMPERATURE: f64 = 0.05;
/// Bridges per particle.
pub(crate) const FLOOR_BRIDGES_PER_PARTICLE: f64 = 0.1;
/// `E_par` in units of `E_cb` (`m g d` dry): the default solid threshold.
pub(crate) const FLOOR_E_PAR: f64 = 0.1;

/// `f_lc` over the window.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LocationChanges {
    /// "delaunay" (2D) or "neighbour_shell" (3D).
    pub method: String,
    /// Location changes counted in the window.
    pub count: u64,
    /// `f_lc`: changes per particle per period.
    pub per_particle_per_period: f64,
    /// `f_lc` per particle per time unit (`None` in results stored before it existed).
    pub per_particle_per_time: Option<f64>,
    /// Interval between the samples the count was taken from.
    pub sample_interval: f64,
}

/// How `Profiles::n_cb` is normalised.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NcbNormalisation {
    /// Bridges per lateral measure of the bin and per unit height, units `d^-D` (docs/model.md 7).
    PerAreaAveragedOverHeight,
    /// Results stored before the docs/model.md 7 normalisation: bridges per lateral measure summed
    /// over the height, units `d^-(D-1)`; divide by `H` to convert.
    #[default]
    PerLateralMeasureSummedOverHeight,
}

/// Lateral profiles, time-averaged over the window. Bins are slabs along `x` in 2D and, by
/// default, square cells over `(x, y)` in 3D (`bins::LateralBins`, numbered `ix + nx iy`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Profiles {
    pub bin_width: f64,
    /// 3D plane bins: width along `y` and the grid `(nx, ny)`.
    pub bin_width_y: Option<f64>,
    pub grid: Option<(usize, usize)>,
    /// Bin centres along `x` (one per bin).
    pub centres: Vec<f64>,
    /// Bin centres along `y` (3D plane bins).
    pub centres_y: Option<Vec<f64>>,
    /// Mean particle number per bin.
    pub particles: Vec<f64>,
    /// Packing fraction (areal in 2D, volume in 3D).
    pub packing: Vec<f64>,
    /// Bridge density `n_cb` per bin (see `n_cb_normalisation`).
    pub n_cb: Vec<f64>,
    #[serde(default)]
    pub n_cb_normalisation: NcbNormalisation,
    /// `T_g / E_cb` per bin, all grains in the bin at each sample (`None` where a bin never
    /// held two particles).
    pub temperature_reduced: Vec<Option<f64>>,
    /// `T_g / E_cb` per bin of the clustered grains only (`observe::lateral`).
    #[serde(default)]
    pub temperature_clustered: Vec<Option<f64>>,
    /// Mean number of clustered grains per bin.
    #[serde(default)]
    pub clustered: Vec<f64>,
    /// Lateral mobility `D_lat` per bin (grains booked to their bin at the lag's origin).
    #[serde(default)]
    pub diffusion: Vec<Option<f64>>,
    /// `D_lat` per bin of the grains that were cluster members at the lag's origin.
    #[serde(default)]
    pub diffusion_clustered: Vec<Option<f64>>,
    /// `D_lat` per bin over the short lag (`LateralMobility::short_lag`; empty in results
    /// stored before it was measured).
    #[serde(default)]
    pub diffusion_short: Vec<Option<f64>>,
    /// The same for the cluster members.
    #[serde(default)]
    pub diffusion_clustered_short: Vec<Option<f64>>,
    /// `f_lc` per bin, per particle per time unit (`None` without the location-change
    /// observer). Results stored before per-time normalisation hold per-period values.
    pub flc: Option<Vec<f64>>,
    /// `max n_cb - min n_cb` (Eq. 3.3), units as `n_cb`.
    pub delta_n_cb: f64,
    /// `max - min` of the packing fraction.
    pub delta_n_area: f64,
    /// Root mean square over the bins of the standard error of each bin's time-averaged
    /// `n_cb`, from block means (`observe::noise`); `None` with fewer than two blocks.
    pub n_cb_standard_error: Option<f64>,
    /// The same for the packing fraction.
    pub packing_standard_error: Option<f64>,
    /// Blocks the standard errors were taken from.
    #[serde(default)]
    pub noise_blocks: usize,
    /// Bootstrap null distribution of `Delta n_cb` (`noise::NullRanges`; `None` in results
    /// stored before it, or with too few blocks).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n_cb_null: Option<noise::NullRanges>,
    /// The same for the packing fraction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub packing_null: Option<noise::NullRanges>,
    /// The bonded-cluster definition `clustered` counts members of: `(bond_time,
    /// cluster_min_size)` (`None` in results stored before it, where `clustered` counted grains
    /// holding any bridge).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clusters: Option<(f64, usize)>,
    /// The members' cage-relative displacements over the long lag, counted per bin (`None` in
    /// results stored before they were measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub member_cages: Option<CageCounts>,
}

/// The lateral mobility of the whole system over the window (`observe::lateral`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LateralMobility {
    /// The lag `tau`, time units.
    pub lag: f64,
    /// `D_lat = <|Delta r_lat|^2> / (2 n_lat tau)`, all grains.
    pub diffusion: f64,
    /// The same over the grains that were cluster members at the lag's origin (`None` without
    /// any).
    pub diffusion_clustered: Option<f64>,
    /// The short lag, a quarter of `lag` (`None` in results stored before it was measured).
    pub short_lag: Option<f64>,
    /// `D_lat` over the short lag, all grains.
    pub diffusion_short: Option<f64>,
    /// `D_lat` over the short lag, cluster members.
    pub diffusion_clustered_short: Option<f64>,
    /// Lag windows that went into it (grain-lags / N).
    pub lags: f64,
}

/// Events inside the window.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WindowCounts {
    pub pair_collisions: u64,
    pub wall_collisions: u64,
    pub bridge_formations: u64,
    pub bridge_ruptures: u64,
    /// Pair collisions per wall collision (`None` without wall collisions).
    pub pair_per_wall: Option<f64>,
}

/// The time series sampled over the whole run (observer samples).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TimeSeries {
    pub time: Vec<f64>,
    /// `T_g / E_cb`.
    pub temperature_reduced: Vec<f64>,
    pub bridges_per_particle: Vec<f64>,
    /// `(t, f_lc)` over each sample interval ending at `t` (empty without the observer).
    pub location_changes: Vec<(f64, f64)>,
}

/// Stationary averages, the trend of the history and the counts of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Observables {
    pub dimension: usize,
    pub particles: usize,
    /// The period time is counted in (driving period, or 1 without a drive).
    pub period: f64,
    pub window_start: f64,
    pub window_end: f64,
    /// Observer samples inside the window.
    pub window_samples: usize,
    pub sample_interval: f64,
    /// The energy unit of the reduced temperatures: `E_cb`, or `m g d` for dry scenes.
    pub temperature_unit: f64,
    /// "E_cb" or "m g d".
    pub temperature_unit_name: String,
    /// Window mean of `T_g / temperature_unit` (`T_g / E_cb` for wet scenes).
    pub granular_temperature_reduced: f64,
    /// Window mean of the number of bridges per particle.
    pub bridges_per_particle: f64,
    pub location_changes: Option<LocationChanges>,
    /// Lateral mobility (`None` in results stored before it existed, or when the window is
    /// shorter than the lag).
    pub mobility: Option<LateralMobility>,
    pub profiles: Profiles,
    pub diffusion: Option<Diffusion>,
    pub counts: WindowCounts,
    pub series: Option<TimeSeries>,
    /// Shear drive only: `E_par`, `E_perp` and their cycles ([`shear`](mod@shear)).
    pub shear: Option<shear::ShearObservables>,
    /// What the history did ([`trend`](mod@trend)): the tests of the sampled and the regions'
    /// quantities, and how the run policy ended the run. Every run stores one; observables
    /// built by hand (tests) may have none, and their label's verdict is then not settled.
    pub trend: Option<trend::Trend>,
}

/// The lateral observer of a validated scene: its bins, bonds and mobility lags
/// (`observe::lateral`), its blocks `block_time` long at first.
fn lateral_observer(scene: &Scene, block_time: f64) -> LateralObserver {
    let spec = &scene.observe;
    let dt = spec.sample_interval(scene);
    LateralObserver::new(
        spec.lateral_bins(scene),
        lateral::LateralSettings {
            wet: scene.is_wet(),
            unit: temperature_unit(scene).0,
            sample_interval: dt,
            block_time,
            lag: spec.mobility_lag,
            bond_time: spec.bond_time,
            cluster_min_size: spec.cluster_min_size,
        },
    )
}

/// The energy unit of a scene's reduced temperatures and its name: `E_cb` for a wet scene,
/// `m g d` for a dry one under gravity, else 1.
fn temperature_unit(scene: &Scene) -> (f64, &'static str) {
    let e_cb = scene.e_cb();
    if e_cb > 0.0 {
        (e_cb, "E_cb")
    } else {
        let u = scene.particles.mass * scene.gravity.max(0.0) * scene.particles.diameter;
        if u > 0.0 { (u, "m g d") } else { (1.0, "1") }
    }
}

/// Every observer a scene's `[observe]` section asks for, fed frame by frame
/// ([`ObserverSet::observe`]) and summed up into [`Observables`] ([`ObserverSet::finish`]).
/// [`run_observed`] feeds it from an engine; tests feed it prescribed configurations.
#[derive(Debug)]
pub struct ObserverSet {
    period: f64,
    dt: f64,
    t_start: f64,
    eps: f64,
    unit: f64,
    unit_name: &'static str,
    temperature: TemperatureObserver,
    profiles: ProfileObserver,
    lateral: LateralObserver,
    lc: Option<LocationChangeCounter>,
    diffusion: Option<diffusion::DiffusionObserver>,
    shear: Option<shear::ShearObserver>,
    first_counts: Option<crate::sim::EventCounts>,
    window_samples: usize,
    /// The last frame seen.
    pub last: Option<Frame>,
}

impl ObserverSet {
    /// The observers of a validated scene, its window starting after `transient_periods`.
    pub fn new(scene: &Scene) -> Self {
        Self::with_window_start(scene, scene.observe.window_start(scene))
    }

    /// The observers of a validated scene with the window starting at `t_start` (a run
    /// continued from a checkpoint, or a new window of the run-length policy).
    pub fn with_window_start(scene: &Scene, t_start: f64) -> Self {
        let spec = &scene.observe;
        let period = scene.driving_period();
        let dt = spec.sample_interval(scene);
        let bins = spec.lateral_bins(scene);
        let (unit, unit_name) = temperature_unit(scene);
        let lc = spec.counts_location_changes(&scene.classify).then(|| {
            let method = if scene.dimension == 2 {
                Method::Delaunay {
                    max_edge: spec.lc_max_edge * scene.particles.diameter,
                    margin: spec.lc_flip_margin,
                }
            } else {
                Method::NeighbourShell {
                    enter: spec.lc_enter_factor,
                    leave: spec.lc_leave_factor,
                }
            };
            LocationChangeCounter::new(method, bins, period)
        });
        Self {
            period,
            dt,
            t_start,
            eps: 1e-9 * scene.run.duration.max(t_start).max(1.0),
            unit,
            unit_name,
            temperature: TemperatureObserver::new(unit),
            profiles: ProfileObserver::default(),
            lateral: lateral_observer(scene, scene.driving_period()),
            lc,
            diffusion: spec
                .diffusion
                .then(|| diffusion::DiffusionObserver::new(spec.layers.min(scene.particles.count))),
            shear: scene
                .shear_slabs()
                .is_some()
                .then(|| shear::ShearObserver::new(unit)),
            first_counts: None,
            window_samples: 0,
            last: None,
        }
    }

    /// Interval between two samples.
    pub fn sample_interval(&self) -> f64 {
        self.dt
    }

    /// Start of the window.
    pub fn window_start(&self) -> f64 {
        self.t_start
    }

    /// Hands one sampled frame to every observer. The location-change counter (a triangulation
    /// per frame, by far the dearest) runs beside the others (`rayon::join`) when called on a
    /// rayon pool of more than one thread (the run's `Threads`); the observers share no state,
    /// so the results are the same either way.
    pub fn observe(&mut self, frame: &Frame) {
        let in_window = frame.time >= self.t_start - self.eps;
        let Self {
            temperature,
            profiles,
            lateral,
            lc,
            diffusion,
            shear,
            ..
        } = self;
        let mut others = || {
            temperature.observe(frame, in_window);
            profiles.observe(frame);
            if in_window {
                lateral.observe(frame);
            }
            if let Some(o) = diffusion.as_mut() {
                o.observe(frame, in_window);
            }
            if let Some(o) = shear.as_mut() {
                o.observe(frame, in_window);
            }
        };
        match lc.as_mut() {
            Some(lc) => {
                if rayon::current_thread_index().is_some() && rayon::current_num_threads() > 1 {
                    rayon::join(|| lc.observe(frame, in_window), others);
                } else {
                    lc.observe(frame, in_window);
                    others();
                }
            }
            None => others(),
        }
        if in_window {
            self.window_samples += 1;
            if self.first_counts.is_none() {
                self.first_counts = Some(frame.counts.clone());
            }
        }
        self.last = Some(frame.clone());
    }

    /// The observables over the window, from every frame seen so far.
    pub fn finish(&self, scene: &Scene) -> Observables {
        let spec = &scene.observe;
        let (t_start, eps, dt) = (self.t_start, self.eps, self.dt);
        let last = self.last.as_ref().expect("at least one frame observed");
        let window_end = last.time;
        let lc = self.lc.as_ref();
        let (profile, mobility) = lateral_profiles(&self.lateral, scene, t_start, lc);
        let location_changes = lc.map(|o| LocationChanges {
            method: o.method().name().to_string(),
            count: o.window_count,
            per_particle_per_period: o.per_particle_per_period(),
            per_particle_per_time: Some(o.per_particle_per_time()),
            sample_interval: dt,
        });
        let c0 = self
            .first_counts
            .clone()
            .unwrap_or_else(|| last.counts.clone());
        let c1 = &last.counts;
        let walls = c1.wall_collisions - c0.wall_collisions;
        let pairs = c1.pair_collisions - c0.pair_collisions;
        let counts = WindowCounts {
            pair_collisions: pairs,
            wall_collisions: walls,
            bridge_formations: c1.bridge_formations - c0.bridge_formations,
            bridge_ruptures: c1.bridge_ruptures - c0.bridge_ruptures,
            pair_per_wall: (walls > 0).then(|| pairs as f64 / walls as f64),
        };
        let in_window = |s: &[(f64, f64)]| -> Vec<f64> {
            s.iter()
                .filter(|(t, _)| *t >= t_start - eps)
                .map(|&(_, x)| x)
                .collect()
        };
        let mean = |v: Vec<f64>| v.iter().sum::<f64>() / v.len().max(1) as f64;
        let temperature = &self.temperature;
        let series = spec.time_series.then(|| TimeSeries {
            time: temperature.series.iter().map(|&(t, _)| t).collect(),
            temperature_reduced: temperature.series.iter().map(|&(_, x)| x).collect(),
            bridges_per_particle: self.profiles.series.iter().map(|&(_, x)| x).collect(),
            location_changes: lc.map_or_else(Vec::new, |o| o.series.clone()),
        });
        Observables {
            dimension: scene.dimension,
            particles: scene.particles.count,
            period: self.period,
            window_start: t_start,
            window_end,
            window_samples: self.window_samples,
            sample_interval: dt,
            temperature_unit: self.unit,
            temperature_unit_name: self.unit_name.to_string(),
            granular_temperature_reduced: temperature.mean_reduced(),
            bridges_per_particle: mean(in_window(&self.profiles.series)),
            location_changes,
            mobility,
            profiles: profile,
            diffusion: self
                .diffusion
                .as_ref()
                .and_then(|o| o.finish(scene.dimension)),
            counts,
            series,
            shear: self.shear.as_ref().map(|o| o.finish(spec.time_series)),
            trend: None,
        }
    }
}

/// Time-averaged lateral profiles over the blocks of the window starting at `t_start`, their
/// statistical errors, and the system's lateral mobility.
fn lateral_profiles(
    lateral: &LateralObserver,
    scene: &Scene,
    t_start: f64,
    lc: Option<&LocationChangeCounter>,
) -> (Profiles, Option<LateralMobility>) {
    let bins = lateral.bins();
    let nb = bins.n;
    let blocks = lateral.blocks_from(t_start);
    let samples: u64 = blocks.iter().map(|b| b.samples).sum();
    let per_sample = |f: usize| -> Vec<f64> {
        field_sums(blocks, nb, f)
            .into_iter()
            .map(|x| x / samples.max(1) as f64)
            .collect()
    };
    let ratio = |num: usize, den: usize, scale: f64| -> Vec<Option<f64>> {
        field_sums(blocks, nb, num)
            .into_iter()
            .zip(field_sums(blocks, nb, den))
            .map(|(a, w)| (w > 0.0).then(|| scale * a / w))
            .collect()
    };
    let d = scene.particles.diameter;
    let dim = scene.dimension;
    let n_lat = (dim - 1) as f64;
    let bin_volume = bins.bin_volume(&scene.container.size);
    // n_cb: bridges per lateral measure per unit height, units d^-D (docs/model.md 7, Eq. 3.3).
    let ncb_scale = d.powi(dim as i32) / bin_volume;
    let n_cb: Vec<f64> = per_sample(field::BRIDGES)
        .into_iter()
        .map(|x| x * ncb_scale)
        .collect();
    let packing: Vec<f64> = per_sample(field::VOLUME)
        .into_iter()
        .map(|x| x / bin_volume)
        .collect();
    let particles = per_sample(field::PARTICLES);
    // Block means (blocks x bins) and weights: per-bin standard errors and the bootstrap null
    // distribution of the spread (observe::noise).
    let weights: Vec<f64> = blocks.iter().map(|k| k.samples as f64).collect();
    let block_means = |f: usize, scale: f64| -> Vec<Vec<f64>> {
        blocks
            .iter()
            .map(|k| {
                (0..nb)
                    .map(|b| scale * k.get(b, f) / k.samples.max(1) as f64)
                    .collect()
            })
            .collect()
    };
    let block_se = |f: usize, scale: f64| -> Option<f64> {
        let means = block_means(f, scale);
        let mut sq = 0.0;
        for b in 0..nb {
            let column: Vec<f64> = means.iter().map(|row| row[b]).collect();
            let se = noise::block_standard_error(&column, &weights, NOISE_BLOCKS)?;
            sq += se * se;
        }
        Some((sq / nb as f64).sqrt())
    };
    let null = |f: usize, scale: f64| -> Option<noise::NullRanges> {
        let (means, weights) =
            noise::merge_to(block_means(f, scale), weights.clone(), BOOTSTRAP_MAX_BLOCKS);
        noise::null_ranges(means, weights)
    };
    let lag = lateral.lag();
    let diff_scale = 1.0 / (2.0 * n_lat * lag);
    let short_lag = lateral.short_lag();
    let short_scale = 1.0 / (2.0 * n_lat * short_lag);
    let flc = lc.map(|o| o.per_bin(&particles));
    let sum = |f: usize| -> f64 { field_sums(blocks, nb, f).iter().sum() };
    // `D_lat` of the displacement sums at `f` (their count at `f + 1`), `None` without any.
    let d_lat = |f: usize, scale: f64| (sum(f + 1) > 0.0).then(|| scale * sum(f) / sum(f + 1));
    let mobility = d_lat(field::MSD_ALL, diff_scale).map(|diffusion| LateralMobility {
        lag,
        diffusion,
        diffusion_clustered: d_lat(field::MSD_CL, diff_scale),
        short_lag: Some(short_lag),
        diffusion_short: d_lat(field::MSD_SHORT_ALL, short_scale),
        diffusion_clustered_short: d_lat(field::MSD_SHORT_CL, short_scale),
        lags: sum(field::MSD_ALL_N) / scene.particles.count.max(1) as f64,
    });
    let profile = Profiles {
        bin_width: bins.width,
        bin_width_y: bins.is_plane().then_some(bins.width_y),
        grid: bins.is_plane().then_some((bins.nx, bins.ny)),
        centres: bins.centres(),
        centres_y: bins.centres_y(),
        delta_n_cb: profiles::spread(&n_cb),
        delta_n_area: profiles::spread(&packing),
        n_cb_standard_error: block_se(field::BRIDGES, ncb_scale),
        packing_standard_error: block_se(field::VOLUME, 1.0 / bin_volume),
        noise_blocks: blocks.len().min(NOISE_BLOCKS),
        n_cb_null: null(field::BRIDGES, ncb_scale),
        packing_null: null(field::VOLUME, 1.0 / bin_volume),
        clusters: Some((scene.observe.bond_time, scene.observe.cluster_min_size)),
        member_cages: Some(member_cages(blocks, nb)),
        particles,
        packing,
        n_cb,
        n_cb_normalisation: NcbNormalisation::PerAreaAveragedOverHeight,
        temperature_reduced: ratio(field::T_ALL, field::T_ALL_W, 1.0),
        temperature_clustered: ratio(field::T_CL, field::T_CL_W, 1.0),
        clustered: per_sample(field::CLUSTERED),
        diffusion: ratio(field::MSD_ALL, field::MSD_ALL_N, diff_scale),
        diffusion_clustered: ratio(field::MSD_CL, field::MSD_CL_N, diff_scale),
        diffusion_short: ratio(field::MSD_SHORT_ALL, field::MSD_SHORT_ALL_N, short_scale),
        diffusion_clustered_short: ratio(field::MSD_SHORT_CL, field::MSD_SHORT_CL_N, short_scale),
        flc,
    };
    (profile, mobility)
}

/// The members' cage-relative displacement counts of the blocks `blocks`, per bin.
fn member_cages(blocks: &[lateral::Block], nb: usize) -> CageCounts {
    let per_edge: Vec<Vec<f64>> = (0..lateral::CAGE_EDGES.len())
        .map(|k| field_sums(blocks, nb, field::CAGE_WITHIN + k))
        .collect();
    CageCounts {
        edges: lateral::CAGE_EDGES.to_vec(),
        measured: field_sums(blocks, nb, field::CAGE_N),
        within: (0..nb)
            .map(|b| per_edge.iter().map(|e| e[b]).collect())
            .collect(),
    }
}

/// At most this many blocks enter the bootstrap of the profile's spread (neighbours merged
/// first; the bootstrap merges further while they are correlated).
pub(crate) const BOOTSTRAP_MAX_BLOCKS: usize = 64;

/// Blocks the standard error of a profile is taken from (`noise::block_standard_error`
/// merges the window's blocks down to at most this many).
pub(crate) const NOISE_BLOCKS: usize = 32;
