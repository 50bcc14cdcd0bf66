//! `wetgran-bench stress`: the hard cases of the engines run at length (10^7 events or time steps each
//! by default) with the invariant checks on.
//!
//! Each [`StressCase`] is one situation that has broken, or could break, an engine: a bed resting
//! on the shaken plate below Gamma = 1, inelastic collapse in a dense bonded cluster, grazing
//! wall hits, Gamma = 1000 with a tiny amplitude, a wall speed of 50 `sqrt(g d)`, a packing near
//! jamming, the shear drive's quartic pair predictions near double roots, and the time-driven
//! engine at the largest time step validation admits. [`run_case`] builds the case's scene (on
//! `wetgran_testkit::reference`), runs it in [`CHECKS`] chunks and after every chunk
//!
//! - runs the engine's own `sanity_check` (finite states, inside the box, no overlap beyond the
//!   tolerance, no over-stretched bond, no event in the past, ...): the first violation stops
//!   the case and is reported;
//! - counts the non-finite numbers in the state and in the energy ledger;
//! - records the largest pair overlap (event engine: from the configuration, all pairs under
//!   the minimum image; time engine: the engine's own running maximum of pair and wall overlaps).
//!
//! The energy-ledger error is `|A(end) - A(0)| / S`, `A` the accounted total
//! ([`EnergyLedger::total_accounted`]: kinetic + potential + dissipated - injected), `S =
//! |K(0)| + |P(0)| + ` every energy that went through the ledger (restitution, ruptures, collapse
//! remedies, wall placement, `|drive work|`): round-off for the event engine, the integrator's
//! error for the time engine (docs/accuracy.md).
//!
//! [`StressCase::PlantedOverlap`] is not a hard case but the harness's self-check: two disks
//! planted overlapping, moving together, so the first check must report the overlap. It runs
//! only when named.

use serde::Serialize;
use std::time::Instant;
use wetgran_core::scene::Boundary::{self, Periodic, Wall};
use wetgran_core::scene::{
    CapillaryModel, CapillarySpec, DriveKind, EngineKind, Scene, StartMode, WallSolverKind,
};
use wetgran_core::sim::EnergyLedger;
use wetgran_core::sim::event_driven::table_cache::{DEFAULT_TABLE_CACHE_MIB, TableCache};
use wetgran_core::sim::event_driven::{Engine, Vector};
use wetgran_core::sim::{EngineVisitor, Frame, Simulation, with_engine};
use wetgran_testkit::reference::{base_scene, shaken_standard};

/// Events (or time steps) per case by default.
pub const DEFAULT_EVENTS: u64 = 10_000_000;
/// Invariant checks per case: one after each of this many equal chunks of the run.
pub(crate) const CHECKS: u64 = 100;

/// One hard case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StressCase {
    /// The standard wet system (docs/model.md 1, 1200 disks) on the plate at Gamma = 0.5, E* = 0.1:
    /// the bed rides the plate, grains rest on it and on each other (rebound floor at work).
    RestingBed,
    /// A dense cluster of wet disks (no gravity, `E_cb` far above the kinetic energy) with
    /// restitution 0.3: every collision bonds, the cluster collapses inelastically.
    BondedCollapse,
    /// Disks sliding along a static floor under gravity at lateral speed 1: every floor hit
    /// comes in at the rebound floor's normal speed (1e-3), a grazing angle of 1e-3.
    GrazingWalls,
    /// Gamma = 1000 with amplitude A = 1e-4 (omega = 3162), wet, 100 disks.
    #[serde(rename = "gamma_1000")]
    StrongShaking,
    /// Wall speed A omega = 50 sqrt(g d) (A = 2, omega = 25, Gamma = 1250), wet, 100 disks.
    #[serde(rename = "wall_speed_50")]
    FastWall,
    /// 841 disks on a square lattice at spacing 1.0005 d in a periodic box: every disk nearly
    /// touches four neighbours (dense packing near jamming).
    Jammed,
    /// A dense sheared wet 3D packing (380 spheres, F_max = 1.5) with slabs of a quarter
    /// diameter: most pairs straddle slab faces, so their predictions are quartics, and bonded
    /// pairs graze the well wall (near-double roots).
    ShearDoubleRoots,
    /// The time-driven engine at the largest time step validation admits
    /// (`Scene::largest_time_step`: 3.36e-4 here at the default stiffness, with the bound on the
    /// damping of its restitution; 3.94e-4 without that bound), on a small shaken
    /// wet 2D system (20 disks, Gamma = 5, E* = 10, started hot).
    TimeLargestDt,
    /// Self-check of the harness (run only when named): two disks planted overlapping by 0.1 d,
    /// moving together; the first check must report the overlap.
    PlantedOverlap,
}

impl StressCase {
    /// The hard cases `wetgran-bench stress` runs without a case name, in order.
    pub const ALL: [StressCase; 8] = [
        StressCase::RestingBed,
        StressCase::BondedCollapse,
        StressCase::GrazingWalls,
        StressCase::StrongShaking,
        StressCase::FastWall,
        StressCase::Jammed,
        StressCase::ShearDoubleRoots,
        StressCase::TimeLargestDt,
    ];

    /// The name on the command line and in the report.
    pub fn name(self) -> &'static str {
        match self {
            StressCase::RestingBed => "resting_bed",
            StressCase::BondedCollapse => "bonded_collapse",
            StressCase::GrazingWalls => "grazing_walls",
            StressCase::StrongShaking => "gamma_1000",
            StressCase::FastWall => "wall_speed_50",
            StressCase::Jammed => "jammed",
            StressCase::ShearDoubleRoots => "shear_double_roots",
            StressCase::TimeLargestDt => "time_largest_dt",
            StressCase::PlantedOverlap => "planted_overlap",
        }
    }

    /// The case of a name (the hard cases and `planted_overlap`).
    pub fn from_name(name: &str) -> Option<StressCase> {
        Self::ALL
            .iter()
            .chain([StressCase::PlantedOverlap].iter())
            .copied()
            .find(|c| c.name() == name)
    }

    /// The case's scene (validated).
    pub fn scene(self) -> Scene {
        let s = match self {
            StressCase::RestingBed => shaken_standard(0.5, 0.1, WallSolverKind::Exact),
            StressCase::BondedCollapse => {
                let mut s = small_scene(0.0, vec![14.0, 30.0], vec![Periodic; 2], 130, 7);
                s.particles.polydispersity = 0.06;
                s.contact.restitution = 0.3;
                s.capillary = thin_thread(0.0711, 100.0);
                s.initial.temperature = Some(0.5);
                s
            }
            StressCase::GrazingWalls => {
                let mut s = small_scene(1.0, vec![60.0, 6.0], vec![Periodic, Wall], 30, 1);
                s.initial.temperature = Some(0.0);
                s
            }
            StressCase::StrongShaking => shaken_motion(1e-4, (1000.0f64 / 1e-4).sqrt()),
            StressCase::FastWall => shaken_motion(2.0, 25.0),
            StressCase::Jammed => {
                let mut s = small_scene(0.0, vec![29.02; 2], vec![Periodic; 2], 841, 3);
                s.initial.lattice_spacing = 1.0005;
                s
            }
            StressCase::ShearDoubleRoots => {
                let (size, walls) = (vec![10.0, 10.0, 6.0], vec![Periodic, Periodic, Wall]);
                let mut s = small_scene(1.0, size, walls, 380, 4);
                s.contact.restitution = 0.9;
                s.capillary = thin_thread(0.0625, 0.375);
                s.engine.min_rebound_speed = 0.03;
                s.drive.kind = DriveKind::Shear;
                s.drive.f_max = Some(1.5);
                s.drive.slab_width = Some(0.25);
                s.initial.temperature = None;
                s.initial.temperature_over_ecb = Some(5.0);
                s
            }
            StressCase::TimeLargestDt => {
                let mut s = shaken_standard(5.0, 10.0, WallSolverKind::Exact);
                s.container.size = vec![10.0, 9.0];
                s.particles.count = 20;
                s.engine.kind = EngineKind::Time;
                s.capillary.rupture_rule = None;
                s.engine.dt = Some(s.largest_time_step());
                s.initial.seed = 5;
                s.run.duration = 1.0;
                s
            }
            StressCase::PlantedOverlap => {
                let mut s = small_scene(0.0, vec![20.0; 2], vec![Periodic; 2], 2, 0);
                s.initial.temperature = Some(0.0);
                s
            }
        };
        s.validate(self.name())
            .unwrap_or_else(|e| panic!("stress case scene: {e}"));
        s
    }
}

/// `count` equal elastic particles at `T = 1` ([`base_scene`]) in the given box, seed `seed`,
/// run length 1.
fn small_scene(
    gravity: f64,
    size: Vec<f64>,
    boundary: Vec<Boundary>,
    count: usize,
    seed: u64,
) -> Scene {
    let mut s = base_scene(size.len(), gravity, size, boundary);
    s.particles.count = count;
    s.initial.seed = seed;
    s.run.duration = 1.0;
    s
}

/// Thin-thread bridges of rupture distance `s_crit` and rupture energy `e_cb`.
fn thin_thread(s_crit: f64, e_cb: f64) -> CapillarySpec {
    CapillarySpec {
        model: CapillaryModel::ThinThread,
        s_crit: Some(s_crit),
        e_cb: Some(e_cb),
        rupture_rule: None,
    }
}

/// The standard wet system's material in a 30 x 9 box, 100 disks, shaken at `(A, omega)`
/// (the geometry of crates/core/tests/shaken_container.rs, `strong_shaking_with_a_tiny_amplitude_stays_inside`).
fn shaken_motion(amplitude: f64, omega: f64) -> Scene {
    let mut s = shaken_standard(1.0, 1.0, WallSolverKind::Exact);
    s.container.size = vec![30.0, 9.0];
    s.particles.count = 100;
    s.drive.gamma = None;
    s.drive.e_star = None;
    s.drive.amplitude = Some(amplitude);
    s.drive.omega = Some(omega);
    s.initial.seed = 3;
    s
}

/// What one case measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StressRow {
    pub case: StressCase,
    /// `"events"` (event engine) or `"steps"` (time engine).
    pub unit: &'static str,
    #[serde(flatten)]
    pub measured: Measured,
    pub wall_seconds: f64,
}

impl StressRow {
    /// No broken invariant and no non-finite number.
    pub fn passed(&self) -> bool {
        self.measured.violation.is_none() && self.measured.nan_count == 0
    }
}

/// What a checked run measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Measured {
    /// Events or time steps done.
    pub work: u64,
    pub simulated_time: f64,
    /// Largest pair overlap seen at the checks (time engine: pair or wall, at every step), in
    /// units of the mean diameter.
    pub max_overlap: f64,
    /// `|A(end) - A(0)| / S` (module header).
    pub ledger_error: f64,
    /// Non-finite numbers in the state and the ledger, summed over the checks.
    pub nan_count: u64,
    /// Invariant checks run.
    pub checks: u64,
    /// The first broken invariant; the case stopped there.
    pub violation: Option<String>,
    /// The engine ran out of events before the work asked (nothing moves).
    #[serde(skip)]
    pub(crate) exhausted: bool,
}

/// Runs one case for `events` events (or time steps), checking after each of [`CHECKS`] chunks.
pub fn run_case(case: StressCase, events: u64) -> StressRow {
    let scene = case.scene();
    let start = Instant::now();
    // A panic is a failed case, reported like a broken invariant.
    let mut m = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        measure(case, &scene, events)
    }))
    .unwrap_or_else(|payload| Measured {
        work: 0,
        simulated_time: f64::NAN,
        max_overlap: f64::NAN,
        ledger_error: f64::NAN,
        nan_count: 0,
        checks: 0,
        violation: Some(format!(
            "panicked: {}",
            wetgran::sweep::job::panic_message(payload.as_ref())
        )),
        exhausted: false,
    });
    // A hard case that runs out of events tests nothing: a failure.
    if m.exhausted && m.violation.is_none() {
        m.violation = Some(format!("no event left to process after {} events", m.work));
    }
    StressRow {
        case,
        // The time-driven case counts its work in time steps.
        unit: match case {
            StressCase::TimeLargestDt => "steps",
            _ => "events",
        },
        measured: m,
        wall_seconds: start.elapsed().as_secs_f64(),
    }
}

/// Builds the case's engine from `scene`, sets it up and runs it checked.
fn measure(case: StressCase, scene: &Scene, events: u64) -> Measured {
    match case {
        StressCase::GrazingWalls => {
            let mut e = Engine::<2, true, false>::new(scene);
            slide_along_the_floor(&mut e);
            checked_run(e, scene, events, CHECKS)
        }
        StressCase::PlantedOverlap => {
            let mut e = Engine::<2, false, false>::new(scene);
            e.set_position(0, Vector::<2>::new(5.0, 5.0));
            e.set_position(1, Vector::<2>::new(5.9, 5.0));
            for i in 0..2 {
                e.set_velocity(i, Vector::<2>::new(1.0, 0.3));
            }
            checked_run(e, scene, events, CHECKS)
        }
        _ => first_events(scene, events, CHECKS).expect("the hard cases start hot"),
    }
}

/// Runs the first `work` events (time steps) of a validated scene from its initial state (hot,
/// or the cold bonded bed), checking the invariants `checks` times on the way: what the input
/// fuzzing asks of every scene it got accepted (crates/bench/tests/fuzz_inputs.rs). A continuation scene
/// (`initial.start = "continue"`) has no state of its own: an error.
pub fn first_events(scene: &Scene, work: u64, checks: u64) -> Result<Measured, String> {
    let cold = match scene.initial.start {
        StartMode::Hot => None,
        StartMode::Cold => Some(wetgran_core::sim::initial::cold_state(scene)),
        StartMode::Continue => {
            return Err("initial.start = \"continue\" has no state of its own".into());
        }
    };
    let tables = TableCache::with_cap_mib(DEFAULT_TABLE_CACHE_MIB);
    Ok(with_engine(
        scene,
        cold.as_ref(),
        &tables,
        CheckedRun {
            scene,
            events: work,
            checks,
        },
    ))
}

/// Grazing set-up: every disk on the floor (`z = r`), evenly spaced along `x`, sliding at
/// lateral speed 1 (alternating directions, so neighbours meet head-on), no vertical speed.
fn slide_along_the_floor(e: &mut Engine<2, true, false>) {
    let n = e.len();
    let radii = e.radii();
    let l_x = 60.0;
    for i in 0..n {
        let x = (i as f64 + 0.5) * l_x / n as f64;
        e.set_position(i, Vector::<2>::new(x, radii[i]));
        let vx = if i % 2 == 0 { 1.0 } else { -1.0 };
        e.set_velocity(i, Vector::<2>::new(vx, 0.0));
    }
}

/// [`checked_run`] as an [`EngineVisitor`], for the cases built by [`with_engine`].
struct CheckedRun<'a> {
    scene: &'a Scene,
    events: u64,
    checks: u64,
}

impl EngineVisitor for CheckedRun<'_> {
    type Output = Measured;
    fn visit<S: Simulation>(self, engine: S) -> Measured {
        checked_run(engine, self.scene, self.events, self.checks)
    }
}

/// The engine's units of work done so far: time steps (time engine) or events.
fn work_done<S: Simulation>(e: &S) -> u64 {
    match S::KIND {
        "time" => e.steps(),
        _ => e.counts().total(),
    }
}

/// Does `n` more units of work, whatever simulated time they take (`dt`: the time engine's
/// step); false when the engine has nothing left to do (an event engine with no event pending).
fn advance_work<S: Simulation>(e: &mut S, n: u64, dt: f64) -> bool {
    let before = work_done(e);
    match S::KIND {
        "time" => e.run_until((before + n) as f64 * dt, None),
        _ => e.run_until(f64::INFINITY, Some(before.saturating_add(n))),
    };
    work_done(e) > before || n == 0
}

/// Runs `events` units of work in `checks` chunks, checking the invariants after each.
fn checked_run<S: Simulation>(
    mut e: S,
    scene: &Scene,
    events: u64,
    checks_wanted: u64,
) -> Measured {
    let chunk = events.div_ceil(checks_wanted.max(1)).max(1);
    let dt = scene.time_step();
    let a0 = e.energy();
    let w0 = work_done(&e);
    let (mut max_overlap, mut nan_count, mut checks) = (0.0f64, 0u64, 0u64);
    let (mut violation, mut exhausted) = (None, false);
    while work_done(&e) - w0 < events {
        let n = chunk.min(events - (work_done(&e) - w0));
        let moved = advance_work(&mut e, n, dt);
        checks += 1;
        let frame = e.frame(scene);
        nan_count += non_finite(&frame, &e.energy());
        let overlap = e
            .max_overlap()
            .unwrap_or_else(|| largest_pair_overlap(&frame));
        max_overlap = max_overlap.max(overlap / scene.particles.diameter);
        if let Err(m) = e.sanity_check() {
            violation = Some(m);
            break;
        }
        if !moved {
            exhausted = true;
            break;
        }
    }
    Measured {
        work: work_done(&e) - w0,
        simulated_time: e.time(),
        max_overlap,
        ledger_error: ledger_error(&a0, &e.energy()),
        nan_count,
        checks,
        violation,
        exhausted,
    }
}

/// `|A1 - A0| / S` (module header).
pub fn ledger_error(a0: &EnergyLedger, a1: &EnergyLedger) -> f64 {
    let through = a1.dissipated_restitution.abs()
        + a1.dissipated_ruptures.abs()
        + a1.added_by_collapse_remedies.abs()
        + a1.added_by_wall_placement.abs()
        + a1.work_by_drive.abs();
    let scale = a0.kinetic.abs() + a0.potential.abs() + through;
    let diff = (a1.total_accounted() - a0.total_accounted()).abs();
    if scale > 0.0 { diff / scale } else { diff }
}

/// Non-finite numbers in a frame's positions and velocities and in a ledger.
fn non_finite(frame: &Frame, ledger: &EnergyLedger) -> u64 {
    let books = [
        ledger.kinetic,
        ledger.potential,
        ledger.dissipated_restitution,
        ledger.dissipated_ruptures,
        ledger.added_by_collapse_remedies,
        ledger.added_by_wall_placement,
        ledger.work_by_drive,
    ];
    frame
        .positions
        .iter()
        .chain(&frame.velocities)
        .chain(&books)
        .filter(|x| !x.is_finite())
        .count() as u64
}

/// Largest `r_i + r_j - |x_i - x_j|` over all pairs (minimum image along periodic axes), 0 if
/// no pair overlaps. All pairs: the cases are small enough.
pub(crate) fn largest_pair_overlap(f: &Frame) -> f64 {
    let d = f.dimension;
    let n = f.radii.len();
    let mut worst = 0.0f64;
    for i in 0..n {
        for j in i + 1..n {
            let mut r2 = 0.0;
            for k in 0..d {
                let mut dx = f.positions[i * d + k] - f.positions[j * d + k];
                if f.periodic[k] {
                    let l = f.box_size[k];
                    dx -= l * (dx / l).round();
                }
                r2 += dx * dx;
            }
            let overlap = f.radii[i] + f.radii[j] - r2.sqrt();
            // `max` keeps a NaN out; the NaN count reports it.
            worst = worst.max(overlap);
        }
    }
    worst
}
