//! The run-length policy of a scene, section `[convergence]`: run at least a minimum, then
//! extend the same trajectory window by window until the window is stationary
//! (`observe::convergence` tests the windows, `observe::run_observed_from` runs them), up to a cap. Pure data plus its validation (errors
//! name the file, the key and the allowed range). Without the section a run has the fixed
//! length `run.duration`.
//!
//! Windows (docs/observables.md "Run to a settled label"): the first check is at
//! `t_1 = max(run.duration, min_periods T, min_time, transient + 2 lag)` (`T` the period of
//! [`Scene::driving_period`], `lag` the mobility lag: the window holds it, [`MIN_WINDOW_LAGS`])
//! and tests the window `[transient, t_1]`, `transient = observe.transient_periods T`. A failed
//! check extends the run by one window length `W = t_1 - transient`: the next window is
//! `[t_1, t_1 + W]`, and so on, so the reported window is always the last `W` of the run and
//! everything before it is transient. The run stops unconverged when the next window would end
//! after the cap `max(max_periods T, max_time, t_1)` (`max_periods T` defaults to
//! [`DEFAULT_CAP_FACTOR`] `t_1`): a cap below the first check means no extension. As with the
//! minimum, the cap has a floor in time units (`max_time`): at high Gamma 800 periods are only
//! about 100 time units, too short for the standard system to settle (docs/validation.md).

use super::{Scene, SceneError};
use serde::{Deserialize, Serialize};

/// Default cap, in units of the first check time.
pub(crate) const DEFAULT_CAP_FACTOR: f64 = 4.0;

/// Shortest window, in mobility lags (`observe.mobility_lag`): a window must hold the lag over
/// which the classifier measures mobility, with lags from several origins (one every quarter
/// lag: `observe::lateral`), or solid versus mobile falls back to the temperature.
pub(crate) const MIN_WINDOW_LAGS: f64 = 2.0;

/// Scene section `[convergence]` (every key optional).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ConvergenceSpec {
    /// Shortest run in periods (default 0: `run.duration` alone).
    pub min_periods: f64,
    /// Shortest run in time units (default 0). A high-Gamma period is short: this keeps the
    /// run long in physical time as well.
    pub min_time: f64,
    /// Longest run in periods (default `4 t_1 / T`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_periods: Option<f64>,
    /// Longest run in time units, where that is longer than `max_periods` periods (default
    /// none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_time: Option<f64>,
    /// Blocks the window is cut into for the tests (default 4, 3 ..= 64).
    pub blocks: usize,
    /// `k`: block means must agree within `k` standard errors (default 3, in (0, 10]).
    pub sigmas: f64,
    /// Relative allowance `tol / max(|mean|, floor)` (default 0.02, in [0, 1)).
    pub rel_tolerance: f64,
}

impl Default for ConvergenceSpec {
    fn default() -> Self {
        Self {
            min_periods: 0.0,
            min_time: 0.0,
            max_periods: None,
            max_time: None,
            blocks: 4,
            sigmas: 3.0,
            rel_tolerance: 0.02,
        }
    }
}

/// The policy in time units for one scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Schedule {
    /// First check `t_1`.
    pub first_check: f64,
    /// Window length `W = t_1 - transient`.
    pub window: f64,
    /// Longest run.
    pub cap: f64,
}

impl ConvergenceSpec {
    /// `t_1 = max(run.duration, min_periods T, min_time, transient + MIN_WINDOW_LAGS lag)`.
    pub fn first_check(&self, scene: &Scene) -> f64 {
        let holds_the_lag =
            scene.observe.window_start(scene) + MIN_WINDOW_LAGS * scene.observe.mobility_lag;
        scene
            .run
            .duration
            .max(self.min_periods * scene.driving_period())
            .max(self.min_time)
            .max(holds_the_lag)
    }

    /// The schedule of a validated scene.
    pub fn schedule(&self, scene: &Scene) -> Schedule {
        let t1 = self.first_check(scene);
        // Never below the first check: where `max_periods T` is shorter than `min_time` (high
        // Gamma, short periods), the run stops at its first check, converged or not.
        let cap = self
            .max_periods
            .map_or(DEFAULT_CAP_FACTOR * t1, |p| p * scene.driving_period())
            .max(self.max_time.unwrap_or(0.0))
            .max(t1);
        Schedule {
            first_check: t1,
            window: t1 - scene.observe.window_start(scene),
            cap,
        }
    }

    /// Checks every key against the rest of the scene.
    pub fn validate(&self, scene: &Scene, origin: &str) -> Result<(), SceneError> {
        let check = |key: &str, v: &dyn std::fmt::Display, ok: bool, must: &str| {
            SceneError::unless(ok, origin, &format!("convergence.{key}"), v, must)
        };
        let nonneg = |v: f64| v.is_finite() && v >= 0.0;
        check(
            "min_periods",
            &self.min_periods,
            nonneg(self.min_periods),
            "finite and >= 0",
        )?;
        check(
            "min_time",
            &self.min_time,
            nonneg(self.min_time),
            "finite and >= 0",
        )?;
        let b = self.blocks;
        check("blocks", &b, (3..=64).contains(&b), "in 3 ..= 64")?;
        let k = self.sigmas;
        check(
            "sigmas",
            &k,
            k.is_finite() && k > 0.0 && k <= 10.0,
            "in (0, 10]",
        )?;
        let tol = self.rel_tolerance;
        let ok = tol.is_finite() && (0.0..1.0).contains(&tol);
        check("rel_tolerance", &tol, ok, "in [0, 1)")?;
        if let Some(t) = self.max_time {
            check("max_time", &t, t.is_finite() && t > 0.0, "finite and > 0")?;
        }
        let period = scene.driving_period();
        let t1 = self.first_check(scene);
        if let Some(p) = self.max_periods {
            let must = format!(
                "finite and > 0 (a cap below the first check max(run.duration, min_periods T, \
                 min_time) = {:.6} periods, T = {period:.6}, means no extension)",
                t1 / period
            );
            check("max_periods", &p, p.is_finite() && p > 0.0, &must)?;
        }
        let samples =
            (t1 - scene.observe.window_start(scene)) / scene.observe.sample_interval(scene);
        if samples < (2 * self.blocks) as f64 {
            return Err(SceneError::new(
                origin,
                "convergence.blocks",
                format!(
                    "= {} is out of range: the window holds about {samples:.0} observer samples, \
                     at least 2 per block are needed (lengthen the run or raise \
                     observe.samples_per_period)",
                    self.blocks
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A shaken scene at Gamma = 30, E* = 1 (period 0.157 time units).
    fn scene(convergence: &str) -> Scene {
        Scene::from_toml_str(
            &format!(
                "dimension = 2\n[box]\nsize = [20.0, 9.0]\n[particles]\ncount = 10\n\
                 [capillary]\nmodel = \"thin_thread\"\n[drive]\nkind = \"sine\"\ngamma = 30.0\n\
                 e_star = 1.0\n[initial]\ntemperature = 1.0\n[run]\nduration = 10.0\n\
                 [observe]\ntransient_periods = 10.0\n[convergence]\n{convergence}\n"
            ),
            "test",
        )
        .unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn the_cap_has_a_floor_in_time_units() {
        let s = scene("min_time = 50.0\nmax_periods = 800.0");
        let t = s.driving_period();
        let c = s.convergence.clone().unwrap();
        // 800 periods are about 126 time units here.
        assert!((c.schedule(&s).cap - 800.0 * t).abs() < 1e-9);
        let s = scene("min_time = 50.0\nmax_periods = 800.0\nmax_time = 400.0");
        let c = s.convergence.clone().unwrap();
        let sch = c.schedule(&s);
        assert_eq!(sch.cap, 400.0);
        assert_eq!(sch.first_check, 50.0);
        // Where max_periods T is longer, it wins.
        let s = scene("min_time = 50.0\nmax_periods = 8000.0\nmax_time = 400.0");
        let c = s.convergence.clone().unwrap();
        assert!((c.schedule(&s).cap - 8000.0 * t).abs() < 1e-9);
    }

    #[test]
    fn a_bad_max_time_names_the_key() {
        let e = Scene::from_toml_str(
            "dimension = 2\n[box]\nsize = [20.0, 9.0]\n[particles]\ncount = 10\n\
             [initial]\ntemperature = 1.0\n[run]\nduration = 10.0\n[convergence]\nmax_time = -1.0\n",
            "bad.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("convergence.max_time") && e.contains("> 0"),
            "{e}"
        );
    }
}
