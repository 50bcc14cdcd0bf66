//! The 2D standard wet system of docs/model.md 1, built in one place for every test (and the
//! `engines_like_scan` example) that runs it: N grains in `l_x d x 9 d` (N = 1200 in 400 x 9 is
//! the standard), polydispersity 0.06, thin-thread bridges with the standard `s_crit = 0.0711`
//! and `E_cb = 0.2844`, elastic walls, periodic along x, a sinusoidally shaken floor and lid at
//! (Gamma, E*), a hot start at `T_g / E_cb = 20`.
//!
//! The standard values other than these are the scene defaults (gravity 1, periodic x and walls
//! in y, elastic walls, `s_crit` and `E_cb` of the thin thread), so the text leaves them out;
//! `standard_defaults_are_the_standard_system` in `crates/core/tests/standard_invariance.rs` pins that.

use wetgran_core::scene::{EngineKind, RestitutionSpeed, Scene};

/// Seed of the initial state used by every documented figure unless the test says otherwise.
pub const STANDARD_SEED: u64 = 1;
/// The second seed of the seed-invariance checks.
pub const OTHER_SEED: u64 = 2;
/// `E_cb` of the standard system (docs/model.md 1), units of m g d.
pub const E_CB: f64 = 0.2844;

/// The driving period `T = 2 pi v_w / (Gamma g)` with `v_w = sqrt(2 E* E_cb / m)` (docs/model.md
/// 4.1; m = g = 1).
pub fn driving_period(gamma: f64, e_star: f64) -> f64 {
    std::f64::consts::TAU * (2.0 * e_star * E_CB).sqrt() / gamma
}

/// How long the observers skip at the start of a run.
#[derive(Debug, Clone, Copy)]
pub enum Transient {
    /// In driving periods, as the scene counts it.
    Periods(f64),
    /// In time units, converted with [`driving_period`].
    Time(f64),
}

/// One run of the standard system; [`StandardWet::new`] gives the standard values and the
/// fields say what a test changes.
#[derive(Debug, Clone)]
pub struct StandardWet {
    pub gamma: f64,
    pub e_star: f64,
    /// Normal restitution between grains (walls stay elastic).
    pub restitution: f64,
    pub count: usize,
    /// Length of the box along the periodic axis, units of d.
    pub l_x: f64,
    pub seed: u64,
    /// `run.duration`, time units.
    pub duration: f64,
    pub transient: Transient,
    /// `observe.samples_per_period` (the scene's default where `None`).
    pub samples_per_period: Option<f64>,
    /// `run.sample_interval` (the scene's default where `None`).
    pub sample_interval: Option<f64>,
    pub location_changes: bool,
    pub diffusion: bool,
    /// `engine.min_rebound_speed` (the scene's default where `None`).
    pub min_rebound_speed: Option<f64>,
}

impl StandardWet {
    /// The standard system (N = 1200 in 400 x 9, seed [`STANDARD_SEED`]) at (Gamma, E*) with
    /// restitution `eps`, run for `duration` time units after skipping `transient`.
    pub fn new(gamma: f64, e_star: f64, eps: f64, duration: f64, transient: Transient) -> Self {
        StandardWet {
            gamma,
            e_star,
            restitution: eps,
            count: 1200,
            l_x: 400.0,
            seed: STANDARD_SEED,
            duration,
            transient,
            samples_per_period: None,
            sample_interval: None,
            location_changes: true,
            diffusion: true,
            min_rebound_speed: None,
        }
    }

    /// `count` grains in `l_x x 9` instead of 1200 in 400 x 9.
    pub fn sized(mut self, count: usize, l_x: f64) -> Self {
        self.count = count;
        self.l_x = l_x;
        self
    }

    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Without the Delaunay and diffusion observers (what the engine comparisons skip).
    pub fn without_mobility(mut self) -> Self {
        self.location_changes = false;
        self.diffusion = false;
        self
    }

    /// The transient in driving periods.
    pub fn transient_periods(&self) -> f64 {
        match self.transient {
            Transient::Periods(p) => p,
            Transient::Time(t) => t / driving_period(self.gamma, self.e_star),
        }
    }

    /// The scene file's text.
    pub fn toml(&self) -> String {
        let mut text = format!(
            "dimension = 2\n\
             [box]\nsize = [{:?}, 9.0]\n\
             [particles]\ncount = {}\npolydispersity = 0.06\n\
             [contact]\nrestitution = {:?}\n\
             [capillary]\nmodel = \"thin_thread\"\n\
             [drive]\nkind = \"sine\"\ngamma = {:?}\ne_star = {:?}\n\
             [initial]\ntemperature_over_ecb = 20.0\nseed = {}\n",
            self.l_x, self.count, self.restitution, self.gamma, self.e_star, self.seed
        );
        if let Some(v) = self.min_rebound_speed {
            text += &format!("[engine]\nmin_rebound_speed = {v:?}\n");
        }
        text += &format!("[run]\nduration = {:?}\n", self.duration);
        if let Some(dt) = self.sample_interval {
            text += &format!("sample_interval = {dt:?}\n");
        }
        text += &format!(
            "[observe]\ntransient_periods = {:?}\nlocation_changes = {}\ndiffusion = {}\n",
            self.transient_periods(),
            self.location_changes,
            self.diffusion
        );
        if let Some(spp) = self.samples_per_period {
            text += &format!("samples_per_period = {spp:?}\n");
        }
        text
    }

    /// The validated scene, run by the event-driven engine.
    pub fn scene(&self) -> Scene {
        Scene::from_toml_str(&self.toml(), "standard wet system").unwrap_or_else(|e| panic!("{e}"))
    }
}

/// The same scene run by the time-driven engine: `engine.kind` is the only change, and
/// `contact.restitution_speed` where a single-speed calibration is wanted instead of `"auto"`.
pub fn time_twin(s: &Scene, speed: Option<f64>) -> Scene {
    let mut t = s.clone();
    t.engine.kind = EngineKind::Time;
    t.contact.restitution_speed = speed.map(RestitutionSpeed::Speed);
    t.validate("time twin").unwrap_or_else(|e| panic!("{e}"));
    t
}
