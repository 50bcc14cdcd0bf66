//! The `[classify]` section of a scene: the classifier's thresholds and choices
//! (`observe::classify` applies them). Pure data plus its validation (errors name the file, key
//! and range); defaults and their reasoning in docs/observables.md.

use serde::{Deserialize, Serialize};

/// Which observable separates solid from mobile.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mobility {
    /// The lateral mobility `D_lat` per unit time (falls back to temperature where it was not
    /// observed).
    #[default]
    Displacement,
    /// The location-change frequency `f_lc` per period (falls back to temperature where it was
    /// not observed). Depends on the sampling rate and the drive period (docs/observables.md).
    LocationChanges,
    /// `T_g / E_cb`.
    Temperature,
}

/// Which lateral profile decides coexistence.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CoexistenceBy {
    /// `n_cb` for wet scenes, the packing fraction for dry ones.
    #[default]
    Auto,
    /// The bridge density `n_cb` (Eq. 3.3).
    Bridges,
    /// The packing fraction (`Delta n_area`).
    Packing,
}

/// Thresholds of the classifier (scene section `[classify]`); defaults and their reasoning are
/// in docs/observables.md.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Thresholds {
    /// Observable for solid versus mobile.
    pub mobility: Mobility,
    /// Largest lateral mobility `D_lat` (units `d^2 / sqrt(d/g)`) of a solid.
    pub solid_diffusion: f64,
    /// Smallest growth exponent `alpha` of the lateral mean-square displacement between the
    /// short and the long mobility lag (`MSD ~ tau^alpha`) of a mobile region (default 0.5):
    /// caged grains give `alpha` near 0, diffusing ones near 1 (`observe::classify`, rule 1).
    pub diffusive_exponent: f64,
    /// Smallest fraction of the dense bins' grains that are members of bonded clusters for a
    /// coexistence (default 0.2): a density wave in a gas or fluid without a bonded cluster is
    /// homogeneous (rule 2).
    pub cluster_fraction: f64,
    /// Smallest fraction of a coexistence's dense-region members whose displacement over the
    /// long lag stays within `solid_diffusion` of their cage (the grains they were bonded to)
    /// for that region to be solid (default 0.8): nearly all its grains keep their neighbours,
    /// whatever a mobile surface layer or an eroding edge adds to the mean (rule 1). Not the
    /// median (0.5): the liquid drop of the fluid-gas coexistence at Gamma = 30 has 0.57 over a
    /// 300-unit run and more than half in many 25-unit windows (docs/observables.md).
    pub still_members: f64,
    /// Largest `f_lc` (location changes per particle per period) of a solid
    /// (`mobility = "location_changes"`).
    pub solid_flc: f64,
    /// Largest `T_g / E_cb` of a solid (used with `mobility = "temperature"` or without
    /// another mobility observable).
    pub solid_temperature: f64,
    /// `T_g / E_cb` above which a mobile region is a gas: the per-point fallback where no line
    /// of constant Gamma decides.
    pub gas_temperature: f64,
    /// Which profile decides coexistence.
    pub coexistence_by: CoexistenceBy,
    /// Quantile of the homogeneous-state spread a coexistence must exceed (default 0.99).
    pub coexistence_level: f64,
    /// Smallest relative difference `(dense - dilute) / dense` of the two classes' mean
    /// profile values of a coexistence (default 0.5).
    pub coexistence_contrast: f64,
    /// Optional absolute floor on `Delta` (units of the profile; default 0). For results
    /// stored without statistical errors it is the only test (2, in their old `n_cb` units,
    /// when 0).
    pub coexistence_delta_n_cb: f64,
    /// Along a line of constant Gamma of elastic grains: smallest ratio of `T_g / E_cb`
    /// between neighbouring points that counts as the fluid-gas jump (default 3).
    pub line_jump_ratio: f64,
    /// Sheared scenes: largest window mean of `E_par / E_cb` (`/ (m g d)` dry) of a solid.
    pub shear_e_par: f64,
    /// A homogeneous mobile wet point is a gas by its own evidence, whatever a line rule says,
    /// when its `T_g / E_cb` is at least this (default 10: fewer than 1 - exp(-1/10) = 9.5 %
    /// of collisions can leave a bridge bound, docs/observables.md)...
    pub gas_evidence_temperature: f64,
    /// ... and its bridges per grain at most this (default 0.2, a tenth of a bonded bed's 2).
    pub gas_evidence_bridges: f64,
    /// It is a fluid by its own evidence when its `T_g / E_cb` is at most this (default 1: most
    /// collisions bind, 1 - exp(-1) = 63 %)...
    pub fluid_evidence_temperature: f64,
    /// ... and its bridges per grain at least this (default 1, half a bonded bed's).
    pub fluid_evidence_bridges: f64,
}

/// The coexistence threshold of results stored before block statistics, in their `n_cb` units
/// (bridges per lateral measure summed over the height).
pub const LEGACY_DELTA_N_CB: f64 = 2.0;

impl Default for Thresholds {
    fn default() -> Self {
        Self {
            mobility: Mobility::default(),
            // docs/observables.md gives the calibration.
            solid_diffusion: 1e-3,
            diffusive_exponent: 0.5,
            cluster_fraction: 0.2,
            still_members: 0.8,
            solid_flc: 0.02,
            solid_temperature: 0.02,
            gas_temperature: 2.0,
            coexistence_by: CoexistenceBy::default(),
            coexistence_level: 0.99,
            coexistence_contrast: 0.5,
            coexistence_delta_n_cb: 0.0,
            line_jump_ratio: 3.0,
            shear_e_par: 0.1,
            gas_evidence_temperature: 10.0,
            gas_evidence_bridges: 0.2,
            fluid_evidence_temperature: 1.0,
            fluid_evidence_bridges: 1.0,
        }
    }
}

impl Thresholds {
    /// Checks every key of `[classify]`.
    pub fn validate(&self, origin: &str) -> Result<(), crate::scene::SceneError> {
        let check = |key: &str, v: f64, ok: bool, must: &str| {
            crate::scene::SceneError::unless(ok, origin, &format!("classify.{key}"), v, must)
        };
        let checks = [
            ("solid_diffusion", self.solid_diffusion),
            ("solid_flc", self.solid_flc),
            ("solid_temperature", self.solid_temperature),
            ("gas_temperature", self.gas_temperature),
            ("coexistence_delta_n_cb", self.coexistence_delta_n_cb),
            ("shear_e_par", self.shear_e_par),
            ("gas_evidence_bridges", self.gas_evidence_bridges),
            (
                "fluid_evidence_temperature",
                self.fluid_evidence_temperature,
            ),
            ("fluid_evidence_bridges", self.fluid_evidence_bridges),
        ];
        for (key, v) in checks {
            check(key, v, v.is_finite() && v >= 0.0, "finite and >= 0")?;
        }
        let q = self.coexistence_level;
        let quantile = "in (0.5, 1) (a quantile, e.g. 0.99)";
        check(
            "coexistence_level",
            q,
            q.is_finite() && q > 0.5 && q < 1.0,
            quantile,
        )?;
        let a = self.diffusive_exponent;
        let exponent = "in (0, 1] (1: diffusion, 0: caged)";
        check(
            "diffusive_exponent",
            a,
            a.is_finite() && a > 0.0 && a <= 1.0,
            exponent,
        )?;
        for (key, f) in [
            ("cluster_fraction", self.cluster_fraction),
            ("still_members", self.still_members),
            ("coexistence_contrast", self.coexistence_contrast),
        ] {
            check(
                key,
                f,
                f.is_finite() && (0.0..=1.0).contains(&f),
                "in [0, 1]",
            )?;
        }
        let j = self.line_jump_ratio;
        check(
            "line_jump_ratio",
            j,
            j.is_finite() && j > 1.0,
            "finite and > 1",
        )?;
        check(
            "gas_temperature",
            self.gas_temperature,
            self.gas_temperature >= self.solid_temperature,
            &format!(
                ">= classify.solid_temperature = {} (a gas is hotter than a solid)",
                self.solid_temperature
            ),
        )?;
        let g = self.gas_evidence_temperature;
        check(
            "gas_evidence_temperature",
            g,
            g.is_finite() && g > self.fluid_evidence_temperature,
            &format!(
                "finite and > classify.fluid_evidence_temperature = {} (a gas's own evidence is \
                 hotter than a fluid's)",
                self.fluid_evidence_temperature
            ),
        )
    }
}
