//! Construction and state I/O of the time-driven engine: the engine from a scene or from a
//! saved state (`sim::state`) and the overwriting of one particle's state. Nothing here steps.

use super::stepping::Then;
use super::*;
use crate::scene::{Boundary, DEFAULT_SKIN, DEFAULT_STIFFNESS, Scene};
use crate::sim::initial::{FlatInitialState, initial_state_flat};
use crate::sim::time_driven::integrator::{GEAR5, GEAR5_C0_VELOCITY_DEPENDENT};

impl<const D: usize, const GRAV: bool, const WET: bool> TimeEngine<D, GRAV, WET, NoBodyForce> {
    /// Builds the engine for a validated scene with `engine.kind = "time"`.
    pub fn new(scene: &Scene) -> Self {
        Self::start(scene, None, NoBodyForce)
    }

    /// [`Self::start`] without a body force.
    pub(crate) fn from_state(scene: &Scene, state: Option<&crate::sim::EngineState>) -> Self {
        Self::start(scene, state, NoBodyForce)
    }
}

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>>
    TimeEngine<D, GRAV, WET, B>
{
    /// Builds the engine with a body force.
    pub fn with_body_force(scene: &Scene, body: B) -> Self {
        Self::start(scene, None, body)
    }

    /// The engine of the scene's initial state or, with `Some(state)`, rebuilt from a saved
    /// state (`sim::state`): positions, velocities, radii and the bridges (flagged bonded in
    /// the neighbour list) at the state's time, rounded to a whole number of steps; event
    /// counts and energy ledger continued. The Gear derivatives beyond the velocity are
    /// re-initialised as at a start (`r_2` from the forces, higher ones zero), so the
    /// continuation is physically continuous (same positions, velocities, bridges and energy)
    /// but not identical to an uninterrupted run; contacts overlapping at the state count as
    /// new contact onsets.
    pub(crate) fn start(scene: &Scene, start: Option<&crate::sim::EngineState>, body: B) -> Self {
        assert_eq!(
            (scene.dimension, scene.gravity > 0.0, scene.is_wet()),
            (D, GRAV, WET),
            "the scene's dimension, gravity and capillary flags do not match the engine"
        );
        let init = start.map_or_else(|| initial_state_flat(scene), FlatInitialState::of_state);
        let n = init.radius.len();
        let p = Params::of_scene(scene, &init.radius);
        let list = neighbour_list(scene, &p, n);
        let mut r: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; D * n]);
        for i in 0..n {
            for k in 0..D {
                r[0][k * n + i] = init.position[i * D + k];
                r[1][k * n + i] = init.velocity[i * D + k];
            }
        }
        let wall_kr = init
            .radius
            .iter()
            .map(|&ri| p.stiffness * ri.sqrt())
            .collect();
        let s = State {
            p,
            n,
            steps: 0,
            r,
            predicted: false,
            acc: vec![0.0; D * n],
            acc_is_start: false,
            radius: init.radius,
            wall_kr,
            wall_contact: vec![0; D * n],
            list,
            moved_bound: 0.0,
            since_check: 0,
            counts: EventCounts::default(),
            dissipated_damping: 0.0,
            dissipated_bridges: 0.0,
            work_by_drive: 0.0,
            max_overlap: 0.0,
            body,
        };
        let mut engine = Self {
            s,
            domains_from: DOMAIN_MIN_PARTICLES,
            serial: Serial::default(),
            domains: Domains::default(),
        };
        engine.s.list.build(&engine.s.r[0], &engine.s.radius);
        if let Some(st) = start {
            engine.s.continue_from(st);
        }
        // The velocities are scaled for Gear after this evaluation.
        engine.initial_forces(1.0);
        if engine.s.p.integrator == IntegratorKind::Gear5 {
            let dt = engine.s.p.dt;
            engine.s.r[1].iter_mut().for_each(|v| *v *= dt);
        }
        engine
    }

    /// The accelerations of the current state (velocity array times `vs`), booked as no step
    /// (`dt = 0`), and Gear's `r_2` from them.
    fn initial_forces(&mut self, vs: f64) {
        let t = self.time();
        self.forces_then(t, vs, 0.0, Then::Nothing);
        if self.s.p.integrator == IntegratorKind::Gear5 {
            let (dt, s) = (self.s.p.dt, &mut self.s);
            for e in 0..D * s.n {
                s.r[2][e] = 0.5 * dt * dt * s.acc[e];
            }
        }
    }

    /// Overwrites position and velocity of particle `i` (tests and set-ups); the higher Gear
    /// derivatives are reset to zero and the neighbour list rebuilt.
    pub fn set_state(&mut self, i: usize, x: [f64; D], v: [f64; D]) {
        let n = self.s.n;
        let dt = self.s.p.dt;
        if self.s.predicted {
            // Back to the corrected state of the current step: the inverse of the predictor.
            for e in 0..D * n {
                let (x, _) = self.now_at(e);
                let a = gear_unpredict(std::array::from_fn(|k| self.s.r[k][e]));
                for (k, ak) in a.into_iter().enumerate() {
                    self.s.r[k][e] = ak;
                }
                self.s.r[0][e] = x;
            }
            self.s.predicted = false;
        }
        let s = &mut self.s;
        for k in 0..D {
            s.r[0][k * n + i] = x[k];
            s.r[1][k * n + i] = match s.p.integrator {
                IntegratorKind::Gear5 => v[k] * dt,
                IntegratorKind::Verlet => v[k],
            };
            for r in &mut s.r[2..] {
                r[k * n + i] = 0.0;
            }
        }
        s.list.build(&s.r[0], &s.radius);
        s.moved_bound = 0.0;
        self.domains.forget();
        self.initial_forces(self.s.velocity_scale());
    }
}

impl<const D: usize, const GRAV: bool, const WET: bool, B> State<D, GRAV, WET, B> {
    /// Continues the clock, the bridges and the books of a saved state.
    fn continue_from(&mut self, st: &crate::sim::EngineState) {
        self.steps = (st.time / self.p.dt).round() as u64;
        if WET {
            for &(i, j) in &st.bridges {
                assert!(
                    self.list.set_flag(i, j, BOND),
                    "saved bridge {i}-{j} is beyond the interaction range"
                );
            }
        }
        self.counts = st.counts.clone();
        self.dissipated_damping = st.ledger.dissipated_restitution;
        self.dissipated_bridges = st.ledger.dissipated_ruptures;
        self.work_by_drive = st.ledger.work_by_drive;
    }
}

impl<const D: usize> Params<D> {
    /// The parameters of a validated scene whose particles have radii `radius`.
    fn of_scene(scene: &Scene, radius: &[f64]) -> Self {
        let boundaries = scene.boundaries();
        let size = std::array::from_fn(|k| scene.container.size[k]);
        let periodic = std::array::from_fn(|k| boundaries[k] == Boundary::Periodic);
        let (damping, wall_damping) = crate::sim::time_driven::damping::contact_damping(scene);
        let mut gear = GEAR5;
        if damping > 0.0 || wall_damping > 0.0 {
            gear[0] = GEAR5_C0_VELOCITY_DEPENDENT;
        }
        let s_crit = scene.s_crit();
        Self {
            size,
            periodic,
            gravity: scene.gravity,
            mass: scene.particles.mass,
            dt: scene.time_step(),
            integrator: scene.engine.integrator.unwrap_or_default(),
            gear,
            stiffness: scene.contact.stiffness.unwrap_or(DEFAULT_STIFFNESS),
            damping,
            wall_damping,
            s_crit,
            bridge_force: if scene.is_wet() {
                hertz::bridge_force(scene.e_cb(), s_crit)
            } else {
                0.0
            },
            drive: scene.drive_motion(),
            diameter: scene.particles.diameter,
            max_radius: radius.iter().fold(0.0, |a: f64, &r| a.max(r)),
        }
    }
}

/// The empty Verlet list of the scene for `n` particles: reach `s_crit` plus the skin, cells
/// spanning the box and, on the walled axes, the walls' travel and one diameter beyond.
fn neighbour_list<const D: usize>(scene: &Scene, p: &Params<D>, n: usize) -> NeighbourList<D> {
    let skin = scene.engine.skin.unwrap_or(DEFAULT_SKIN) * scene.particles.diameter;
    let (_, d_max) = scene.diameter_range();
    let amp = p.drive.map_or(0.0, |(a, _)| a.abs());
    let mut lower = [0.0; D];
    let mut upper = p.size;
    for k in 0..D {
        if !p.periodic[k] {
            lower[k] = -amp - d_max;
            upper[k] = p.size[k] + amp + d_max;
        }
    }
    NeighbourList::new(
        n,
        p.size,
        p.periodic,
        lower,
        upper,
        p.s_crit + skin,
        skin,
        d_max + p.s_crit + skin,
    )
}
