//! Scene validation: every value a simulation cannot use is rejected at load, with an error that
//! names the file, the key and the allowed range. This module holds the error type, the entry
//! point [`Scene::validate`] and the sections every scene has; [`drive`] checks the `[drive]`
//! section (sine and shear drives, the wall table) and [`time_engine`] the keys of each engine
//! kind and the time-driven engine's numbers.

mod drive;
mod time_engine;

use super::{Boundary, CapillaryModel, Scene, lattice};
use crate::physics::size::MAX_POLYDISPERSITY;
use std::fmt;

/// Largest neighbour grid the engine is allowed to allocate (2^28 cells, 1 GiB of list heads).
const MAX_CELLS: usize = 1 << 28;

/// Fewest neighbour cells a periodic axis may have (see the check in `validate`).
pub(crate) const MIN_PERIODIC_CELLS: i32 = 4;

/// Largest amplitude `A` of the shaken container, units of `d`: positions are computed next to
/// a floor displaced by up to `A`, so their round-off (`~ A 1e-16`) stays far below the overlap
/// tolerance. (Found by the input fuzzer: `e_star = 1e300` put the floor at 1e298.)
pub(super) const MAX_AMPLITUDE: f64 = 1e4;
/// Largest peak wall speed `A omega`, units of `sqrt(g d)` (20 times the hardest case of
/// `wetgran-bench stress`, 50).
pub(super) const MAX_WALL_SPEED: f64 = 1e3;
/// Largest peak acceleration `Gamma = A omega^2 / g` (100 times `wetgran-bench stress`'s 1000).
pub(super) const MAX_GAMMA: f64 = 1e5;
/// Smallest non-zero amplitude `A` of the shaken container, units of `d`. The wall solvers find
/// a hit to the gap tolerance `drive.root_tolerance` (1e-10 d by default) and take a tabulated
/// hit or a late one within a thousand times it (1e-7 d, `sim::event_driven::walls`): a stroke
/// `2 A` inside that window cannot be told from a floor touching the grain at every instant,
/// and a grain resting on the floor collides with it at every event (the run spends its events
/// without advancing, then fails on the guards). The floor keeps `A` ten times above the
/// window at the default tolerance; it also keeps the motion 4.5e3 times above the round-off
/// of positions in a box 1e3 d high (`2.2e-16 x 1e3 d`). (Found by the tests: `E* =
/// 1e-20` at `Gamma = 3` is `A = 1.9e-21 d`.) `A = 0` (a still container) stays allowed.
pub(super) const MIN_AMPLITUDE: f64 = 1e-6;
/// Largest angular frequency `omega` of the shaken container, units of `sqrt(g / d)`. Every
/// period costs at least one wall event per grain the floor touches (it launches or catches
/// each of them once a period) and the observers' samples of a period (20 by default), while
/// the bed's own times are in time units (a grain falls one diameter in 1.4 time units; a bed
/// settles and heats in tens to thousands): at `omega = 1e4` one time unit is 1.6e3 periods, so
/// a run of 100 time units is already 1.6e5 wall events per floor grain and 3.2e6 samples
/// before the bed has relaxed. It also keeps a period (6.3e-4 time units) 1e7 times above the
/// round-off of event times in a run of 2.8e5 time units (`2.2e-16 t`). The largest `omega`
/// of the shipped sweeps is 112, of the stress cases 3162 (`gamma_1000`).
pub(super) const MAX_OMEGA: f64 = 1e4;
/// Largest peak shear force `F_max`, units of `m g` (found by the input fuzzer: at `1e300` the
/// sheared pair quartics lose every digit and pairs pass through each other).
pub(super) const MAX_SHEAR_FORCE: f64 = 1e3;
/// Narrowest shear slab, in units of `d` (`drive.slab_width`).
const MIN_SLAB_WIDTH: f64 = 1e-3;
/// Most shear slabs along `L_x` (`drive.slab_width`).
const MAX_SHEAR_SLABS: f64 = 1e6;
/// Largest gravity, in the scene's units.
pub(super) const MAX_GRAVITY: f64 = 1e6;
/// Range of `particles.diameter` and `particles.mass`, in the scene's units.
pub(super) const MIN_UNIT_SCALE: f64 = 1e-6;
pub(super) const MAX_UNIT_SCALE: f64 = 1e6;
/// Smallest `engine.overlap_tolerance`, in units of the diameter.
pub(super) const MIN_OVERLAP_TOLERANCE: f64 = 1e-12;
/// Smallest non-zero gravity: below it the time unit sqrt(d/g) leaves event times no digits.
pub(super) const MIN_GRAVITY: f64 = 1e-6;

/// Why a scene was rejected.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// The file (or other origin) the scene came from.
    pub origin: String,
    /// The offending key in dotted form (`particles.polydispersity`), empty for syntax errors.
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
    /// The geometric or physical constraint of the scene that failed, when the error is one
    /// (each key on its own is in range, their combination is not); `None` for a key outside its
    /// own range. A sweep with `skip_invalid` leaves out only points failing a constraint.
    pub constraint: Option<Constraint>,
}

/// The constraints between scene keys that a grid point may fail although every key is in its
/// own range; `sweep.skip_invalid` leaves such points out (docs/model-choices.md, "Sweeps").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Constraint {
    /// The gap between the floor and lid (the box height) is not larger than the largest
    /// diameter `d_max`.
    GapBelowDiameter,
    /// More particles than fit on the initial lattice of the box.
    LatticeFull,
    /// A periodic axis shorter than the neighbour cells it must hold (event-driven: 4 cells of
    /// `d_max + s_crit`; time-driven: 3 cells of `d_max + s_crit + skin`).
    PeriodicAxisTooShort,
    /// The box would need more neighbour cells than the engine can allocate.
    TooManyCells,
}

impl Constraint {
    /// Every constraint, in the order of the docs.
    pub const ALL: [Constraint; 4] = [
        Constraint::GapBelowDiameter,
        Constraint::LatticeFull,
        Constraint::PeriodicAxisTooShort,
        Constraint::TooManyCells,
    ];

    /// One line saying why a point failing it is left out.
    pub fn reason(self) -> &'static str {
        match self {
            Constraint::GapBelowDiameter => "the floor-to-lid gap does not exceed d_max",
            Constraint::LatticeFull => "more particles than fit on the initial lattice",
            Constraint::PeriodicAxisTooShort => {
                "a periodic axis is shorter than the neighbour cells it must hold"
            }
            Constraint::TooManyCells => "the box needs more neighbour cells than allowed",
        }
    }
}

impl SceneError {
    pub(crate) fn new(origin: &str, key: &str, message: impl Into<String>) -> Self {
        Self {
            origin: origin.to_string(),
            key: key.to_string(),
            message: message.into(),
            constraint: None,
        }
    }

    /// The same error, marked as failing `constraint`.
    pub(crate) fn failing(mut self, constraint: Constraint) -> Self {
        self.constraint = Some(constraint);
        self
    }

    pub(crate) fn parse(origin: &str, err: toml::de::Error) -> Self {
        // The TOML error already says "unknown field `x`, expected one of ..." or
        // "invalid type: ..., expected ..." and points at the line; the dotted key is added.
        let mut message = err.to_string().trim_end().to_string();
        for (rust, words) in [
            ("expected usize", "expected an integer >= 0"),
            ("expected u64", "expected an integer >= 0"),
            ("expected f64", "expected a number"),
        ] {
            message = message.replace(rust, words);
        }
        Self::new(origin, &parse_error_key(&err), message)
    }

    pub(crate) fn io(origin: &str, err: std::io::Error) -> Self {
        Self::new(origin, "", format!("cannot read the scene file: {err}"))
    }

    /// `Ok` where `ok`, else `key = v is out of range: must be {must}`.
    pub(crate) fn unless(
        ok: bool,
        origin: &str,
        key: &str,
        v: impl fmt::Display,
        must: &str,
    ) -> Result<(), Self> {
        if ok {
            return Ok(());
        }
        Err(Self::new(
            origin,
            key,
            format!("= {v} is out of range: must be {must}"),
        ))
    }
}

/// The dotted key a TOML error belongs to (empty for syntax errors): the table path the
/// deserializer recorded, plus the field of serde's "unknown field" and "missing field" errors.
pub fn parse_error_key(err: &toml::de::Error) -> String {
    // `toml` prints the recorded path ("in `a.b`") only for an error without source context.
    let mut bare = err.clone();
    bare.set_input(None);
    let bare = bare.to_string();
    let mut key = bare
        .trim_end()
        .lines()
        .last()
        .and_then(|l| l.strip_prefix("in `"))
        .and_then(|l| l.strip_suffix('`'))
        .unwrap_or("")
        .to_string();
    for prefix in ["unknown field `", "missing field `"] {
        if let Some((field, _)) = err
            .message()
            .strip_prefix(prefix)
            .and_then(|rest| rest.split_once('`'))
        {
            if !key.is_empty() {
                key.push('.');
            }
            key.push_str(field);
        }
    }
    key
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.origin, self.message)
        } else {
            write!(f, "{}: key `{}`: {}", self.origin, self.key, self.message)
        }
    }
}

impl std::error::Error for SceneError {}

/// Checks `lo <= value <= hi` (bounds may be open) and formats the range into the error.
struct Check<'a> {
    origin: &'a str,
}

/// A number as a person would write it in the scene file: plain for ordinary magnitudes,
/// scientific notation for very large or small ones (`1e300`, not 301 digits).
fn num(v: f64) -> String {
    if v != 0.0 && v.is_finite() && (v.abs() >= 1e6 || v.abs() < 1e-4) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

impl Check<'_> {
    fn err(&self, key: &str, msg: impl Into<String>) -> SceneError {
        SceneError::new(self.origin, key, msg)
    }

    /// `Ok` where `ok`, else `key = v is out of range: must be {must}` ([`SceneError::unless`]).
    fn require(
        &self,
        key: &str,
        v: impl fmt::Display,
        ok: bool,
        must: &str,
    ) -> Result<(), SceneError> {
        SceneError::unless(ok, self.origin, key, v, must)
    }

    /// `= v is out of range: must be <range>`, with "finite and" for `inf` (TOML allows it).
    fn out_of_range(&self, key: &str, v: f64, range: &str) -> SceneError {
        let finite = if v.is_finite() { "" } else { "finite and " };
        self.err(
            key,
            format!("= {} is out of range: must be {finite}{range}", num(v)),
        )
    }

    /// `Ok` where `ok`, else [`Check::out_of_range`].
    fn within(&self, key: &str, v: f64, ok: bool, range: &str) -> Result<(), SceneError> {
        if ok {
            Ok(())
        } else {
            Err(self.out_of_range(key, v, range))
        }
    }

    fn positive(&self, key: &str, v: f64) -> Result<(), SceneError> {
        self.within(key, v, v.is_finite() && v > 0.0, "> 0")
    }

    fn non_negative(&self, key: &str, v: f64) -> Result<(), SceneError> {
        self.within(key, v, v.is_finite() && v >= 0.0, ">= 0")
    }

    /// The first of `keys` that is set (`(key, set)`) is rejected with `why`.
    fn none_given<'k>(
        &self,
        keys: impl IntoIterator<Item = &'k (&'static str, bool)>,
        why: &str,
    ) -> Result<(), SceneError> {
        match keys.into_iter().find(|(_, given)| *given) {
            Some((key, _)) => Err(self.err(key, why.to_string())),
            None => Ok(()),
        }
    }

    /// `0 <= v <= hi`, the range written `[0, hi_text]`.
    fn closed(&self, key: &str, v: f64, hi: f64, hi_text: &str) -> Result<(), SceneError> {
        let range = format!("in [0, {hi_text}]");
        self.require(key, num(v), (0.0..=hi).contains(&v), &range)
    }
}

impl Scene {
    /// Validates every key, section by section; `origin` names the file in the error.
    pub fn validate(&self, origin: &str) -> Result<(), SceneError> {
        let c = Check { origin };
        let dim = self.dimension;
        if dim != 2 && dim != 3 {
            return Err(c.err(
                "dimension",
                format!("= {dim} is not allowed: must be 2 or 3"),
            ));
        }
        c.non_negative("gravity", self.gravity)?;
        // A tiny but non-zero g makes the time unit sqrt(d/g) astronomically long: event times
        // of 1e151 leave no digits for the motion between them (found by the input fuzzer: a
        // bond stretched past s_crit at g = 1e-300).
        let g = self.gravity;
        let ok = g <= MAX_GRAVITY && (g == 0.0 || g >= MIN_GRAVITY);
        c.within("gravity", g, ok, "0 or in [1e-6, 1e6]")?;

        self.validate_box(&c)?;
        self.validate_particles(&c)?;
        self.validate_contact(&c)?;
        self.validate_capillary(&c)?;
        self.validate_drive(&c)?;
        self.validate_initial(&c)?;
        self.validate_run(&c)?;
        self.validate_engine(&c)?;
        self.validate_cells(&c)?;
        // Observers and classification.
        self.observe.validate(self, origin)?;
        self.classify.validate(origin)?;
        if let Some(c) = &self.convergence {
            c.validate(self, origin)?;
        }
        Ok(())
    }

    /// `box.size` and `box.boundary`: one entry per axis, walls on the vertical axis with gravity.
    fn validate_box(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let dim = self.dimension;
        let size = &self.container.size;
        if size.len() != dim {
            return Err(c.err(
                "box.size",
                format!(
                    "has {} entries: a {dim}D scene needs exactly {dim} (lateral sizes, then height)",
                    size.len()
                ),
            ));
        }
        for (k, &l) in size.iter().enumerate() {
            c.positive(&format!("box.size[{k}]"), l)?;
        }
        if let Some(b) = &self.container.boundary
            && b.len() != dim
        {
            return Err(c.err(
                "box.boundary",
                format!(
                    "has {} entries: a {dim}D scene needs exactly {dim}",
                    b.len()
                ),
            ));
        }
        let boundaries = self.boundaries();
        if self.gravity > 0.0 && boundaries[dim - 1] != Boundary::Wall {
            return Err(c.err(
                &format!("box.boundary[{}]", dim - 1),
                "= \"periodic\" is not allowed with gravity: the vertical axis needs walls \
                 (\"wall\"), or set gravity = 0",
            ));
        }
        Ok(())
    }

    /// `[particles]`: count, diameter, mass, polydispersity.
    fn validate_particles(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let p = &self.particles;
        c.require("particles.count", p.count, p.count > 0, ">= 1")?;
        // The units are those of the scene (d = m = g = 1 in every shipped scene); a diameter or
        // mass many decades off makes speeds or times of 1e150 that leave the motion no digits
        // (found by the input fuzzer: grains overlapping at mass = 1e-300).
        for (key, v) in [
            ("particles.diameter", p.diameter),
            ("particles.mass", p.mass),
        ] {
            c.positive(key, v)?;
            let ok = (MIN_UNIT_SCALE..=MAX_UNIT_SCALE).contains(&v);
            c.within(key, v, ok, "in [1e-6, 1e6]")?;
        }
        let sigma = p.polydispersity;
        c.require(
            "particles.polydispersity",
            sigma,
            (0.0..MAX_POLYDISPERSITY).contains(&sigma),
            "in [0, 1/sqrt(3) = 0.5774) (the smallest diameter d (1 - sqrt(3) polydispersity) \
             must stay > 0)",
        )
    }

    /// `[contact]`: the restitution coefficients.
    fn validate_contact(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let ct = &self.contact;
        c.closed("contact.restitution", ct.restitution, 1.0, "1")?;
        c.closed("contact.wall_restitution", ct.wall_restitution, 1.0, "1")
    }

    /// `[capillary]`: the bridge keys belong to the thin-thread model; `e_cb` is needed
    /// without gravity.
    fn validate_capillary(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let cap = &self.capillary;
        match cap.model {
            CapillaryModel::None => c.none_given(
                &[
                    ("capillary.s_crit", cap.s_crit.is_some()),
                    ("capillary.e_cb", cap.e_cb.is_some()),
                    ("capillary.rupture_rule", cap.rupture_rule.is_some()),
                ],
                "is set but capillary.model = \"none\": choose model = \"thin_thread\" or \
                 remove the key",
            )?,
            CapillaryModel::ThinThread => {
                if let Some(s) = cap.s_crit {
                    c.positive("capillary.s_crit", s)?;
                }
                if let Some(e) = cap.e_cb {
                    c.non_negative("capillary.e_cb", e)?;
                }
                if cap.e_cb.is_none() && self.gravity == 0.0 {
                    return Err(c.err(
                        "capillary.e_cb",
                        "is required without gravity (its default 4 m g s_crit would be 0): \
                         give a value >= 0",
                    ));
                }
            }
        }
        Ok(())
    }

    /// `[initial]`: one temperature, the lattice spacing, and room on the lattice for every
    /// particle.
    fn validate_initial(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let size = &self.container.size;
        let p = &self.particles;
        let init = &self.initial;
        match (init.temperature, init.temperature_over_ecb) {
            (Some(_), Some(_)) => {
                return Err(c.err(
                    "initial.temperature_over_ecb",
                    "and initial.temperature are both set: give exactly one",
                ));
            }
            (None, None) => {
                return Err(c.err(
                    "initial.temperature",
                    "is missing: give initial.temperature (>= 0) or, for wet scenes, \
                     initial.temperature_over_ecb (>= 0)",
                ));
            }
            (Some(t), None) => {
                c.closed("initial.temperature", t, 1e8, "1e8")?;
            }
            (None, Some(r)) => {
                c.closed("initial.temperature_over_ecb", r, 1e8, "1e8")?;
                let t = self.initial_temperature();
                if t > 1e8 {
                    return Err(c.err(
                        "initial.temperature_over_ecb",
                        format!(
                            "= {} is out of range: with E_cb = {} the temperature {} m g d \
                             exceeds 1e8",
                            num(r),
                            num(self.e_cb()),
                            num(t)
                        ),
                    ));
                }
                if !self.is_wet() || self.e_cb() <= 0.0 {
                    return Err(c.err(
                        "initial.temperature_over_ecb",
                        "needs capillary bridges with E_cb > 0: use initial.temperature for dry \
                         scenes",
                    ));
                }
            }
        }
        let a = init.lattice_spacing;
        let must = ">= 1 (units of the largest diameter)";
        c.within(
            "initial.lattice_spacing",
            a,
            a.is_finite() && a >= 1.0,
            must,
        )?;
        let (_, d_max) = self.diameter_range();
        let spacing = init.lattice_spacing * d_max;
        // `lattice::capacity` without its overflow: a huge box holds "very many" sites.
        let fit = lattice::sites_per_axis(size, spacing)
            .iter()
            .try_fold(1usize, |acc, &n| acc.checked_mul(n))
            .unwrap_or(usize::MAX);
        if p.count > fit {
            return Err(c.err(
                "particles.count",
                format!(
                    "= {} is out of range: at most {fit} particles fit on the initial lattice of \
                     spacing {spacing:.4} in this box",
                    p.count
                ),
            )
            .failing(Constraint::LatticeFull));
        }
        Ok(())
    }

    /// `[run]`: duration, sample interval, event cap.
    fn validate_run(&self, c: &Check<'_>) -> Result<(), SceneError> {
        c.positive("run.duration", self.run.duration)?;
        c.non_negative("run.sample_interval", self.run.sample_interval)?;
        if self.run.sample_interval > 0.0 && self.run.duration / self.run.sample_interval > 1e7 {
            return Err(c.err(
                "run.sample_interval",
                format!(
                    "= {} is out of range: at most 1e7 samples per run, so >= run.duration / 1e7 \
                     = {:e}",
                    self.run.sample_interval,
                    self.run.duration / 1e7
                ),
            ));
        }
        c.require("run.max_events", 0, self.run.max_events != Some(0), ">= 1")?;
        Ok(())
    }

    /// `[engine]`: the keys of the engine kind, the collapse remedies, the overlap tolerance.
    fn validate_engine(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let p = &self.particles;
        self.validate_engine_kind(c)?;
        let e = &self.engine;
        c.non_negative("engine.tc", e.tc)?;
        c.non_negative("engine.min_rebound_speed", e.min_rebound_speed)?;
        c.require(
            "engine.min_rebound_speed",
            e.min_rebound_speed,
            e.min_rebound_speed < 0.1,
            "< 0.1 (a collapse remedy, far below thermal speeds)",
        )?;
        if self.is_wet() && e.min_rebound_speed <= 0.0 {
            return Err(c.err(
                "engine.min_rebound_speed",
                "= 0 is out of range: must be > 0 with bridges (a bonded pair grazing the well \
                 wall would bounce ever faster)",
            ));
        }
        if self.gravity > 0.0 && e.min_rebound_speed <= 0.0 {
            return Err(c.err(
                "engine.min_rebound_speed",
                format!(
                    "= {} is out of range: must be > 0 with gravity (a grain at rest on the \
                     floor would bounce in zero time forever)",
                    e.min_rebound_speed
                ),
            ));
        }
        let inelastic = self.contact.restitution < 1.0 || self.contact.wall_restitution < 1.0;
        if inelastic && e.min_rebound_speed <= 0.0 && e.tc <= 0.0 {
            return Err(c.err(
                "engine.min_rebound_speed",
                "= 0 together with engine.tc = 0 leaves inelastic collisions without a collapse \
                 remedy: set min_rebound_speed > 0 or tc > 0",
            ));
        }
        c.positive("engine.overlap_tolerance", e.overlap_tolerance)?;
        // Below the round-off of a position the check fails on exact arithmetic's last digit
        // (found by the input fuzzer: a grain 3e-16 below the floor at a tolerance of 1e-300).
        if e.overlap_tolerance < MIN_OVERLAP_TOLERANCE * p.diameter {
            return Err(c.err(
                "engine.overlap_tolerance",
                format!(
                    "= {} is out of range: must be >= 1e-12 d = {} (below it the invariant \
                     check trips over the round-off of positions)",
                    num(e.overlap_tolerance),
                    num(MIN_OVERLAP_TOLERANCE * p.diameter)
                ),
            ));
        }
        c.require(
            "engine.overlap_tolerance",
            e.overlap_tolerance,
            e.overlap_tolerance <= 0.01 * p.diameter,
            &format!(
                "<= 0.01 d = {} (it is what the invariant check forgives)",
                0.01 * p.diameter
            ),
        )
    }

    /// `engine.cell_size` and the neighbour grid it gives the box: enough cells on a periodic
    /// axis, not too many in all.
    fn validate_cells(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let dim = self.dimension;
        let size = &self.container.size;
        let boundaries = self.boundaries();
        let (_, d_max) = self.diameter_range();
        let e = &self.engine;
        c.non_negative("engine.cell_size", e.cell_size)?;
        let range = d_max + self.s_crit();
        c.require(
            "engine.cell_size",
            e.cell_size,
            e.cell_size <= 0.0 || e.cell_size >= range,
            &format!("0 (automatic) or >= d_max + s_crit = {range:.4}"),
        )?;
        let cell = e.cell_size.max(range);
        for k in 0..dim {
            // Counted exactly as the engine's cell grid counts them. Four cells, not three: with
            // three, two particles in the outer cells can swap nearest image without crossing a
            // cell face, and their collision through the seam would be missed.
            let n_cells = (size[k] / cell).floor();
            if boundaries[k] == Boundary::Periodic && n_cells < MIN_PERIODIC_CELLS as f64 {
                return Err(c.err(
                    &format!("box.size[{k}]"),
                    format!(
                        "= {} is out of range: a periodic axis must hold >= {MIN_PERIODIC_CELLS} \
                         cells, i.e. be >= {:.4} (cell edge >= d_max + s_crit = {cell:.4})",
                        size[k],
                        MIN_PERIODIC_CELLS as f64 * cell
                    ),
                )
            .failing(Constraint::PeriodicAxisTooShort));
            }
        }
        // A finite but huge box would make the engine allocate a neighbour grid it cannot hold.
        let cells: f64 = size.iter().map(|&l| (l / cell).floor().max(1.0)).product();
        if cells > MAX_CELLS as f64 {
            let cells = if cells.is_finite() {
                format!("{cells:.3e}")
            } else {
                "over 1e308".to_string()
            };
            return Err(c.err(
                "box.size",
                format!(
                    "= {size:?} is out of range: the neighbour grid of cell edge {cell:.4} would \
                     have {cells} cells, must be at most {MAX_CELLS} cells: use a smaller box or \
                     a larger engine.cell_size"
                ),
            )
            .failing(Constraint::TooManyCells));
        }
        Ok(())
    }
}
