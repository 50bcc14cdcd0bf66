//! The reference systems: scenes built in code that the benchmarks, the stress cases and the
//! engine tests share, so that each is defined once.
//!
//! - (a) 3D bulk: 32000 elastic monodisperse spheres, number density 0.5 (periodic cube of side
//!   40), no gravity, `T = 1` ([`system_a`]);
//! - (b) 3D gravity: 32000 elastic spheres, `g = 1`, box 80 x 80 x 40 periodic laterally with
//!   floor and lid, `T = 1` ([`system_b`]);
//! - (c) the 2D standard wet system (scenes/standard_wet_2d.toml, docs/model.md 1): 1200 disks, box
//!   400 x 9, `sigma_p = 0.06`, thin-thread bridges, particle restitution 0.9, wall restitution
//!   1, `T_g / E_cb = 20` ([`system_c`]), shaken by [`shaken_standard`];
//! - (c') the same system dry at the same absolute temperature ([`system_c_dry`]);
//! - the dry shaken 2D system of the time-driven engine ([`dry_shaken_time_driven`]): N = 1200
//!   disks, `sigma_p = 0.06`, box 400 x 9 periodic in x, Hertz floor and lid shaken with
//!   `A = 0.05` at `Gamma = 15`, `dt = 1e-4`, default stiffness, the damping `A_d` that gives
//!   restitution 0.9 at impact speed 1, elastic walls, initial `T = 1 m g d`.

use wetgran_core::physics::hertz;
use wetgran_core::scene::{
    Boundary, CapillarySpec, DEFAULT_STIFFNESS, DriveKind, Scene, WallSolverKind,
};

/// A scene of `32 000` equal elastic particles at `T = 1` in the given box; the reference
/// systems below change what differs from it. Everything else is at its default; the run length
/// is not used by the benchmarks (they drive the engine themselves) but must be valid.
pub fn base_scene(
    dimension: usize,
    gravity: f64,
    size: Vec<f64>,
    boundary: Vec<Boundary>,
) -> Scene {
    let text = format!(
        "dimension = {dimension}\ngravity = {gravity:?}\n[box]\nsize = {size:?}\n\
         [particles]\ncount = 32000\n[initial]\ntemperature = 1.0\nseed = 1\n\
         [run]\nduration = 1.0e9\n"
    );
    let mut s: Scene = toml::from_str(&text).expect("the base scene parses");
    s.container.boundary = Some(boundary);
    s
}

/// (a): 32000 elastic spheres at number density 0.5 in a periodic cube, no gravity, `T = 1`.
///
/// The default lattice (spacing 1.01, 39 sites per axis) would fit too, but it is filled layer by
/// layer from `z = 0` and would start as a dense slab (21 of 39 layers) that takes long to melt.
/// Spacing 1.25 gives exactly 32 sites per axis, so the 32000 spheres fill 31.25 of 32 layers:
/// an almost uniform start at the target density.
pub fn system_a() -> Scene {
    let side = (32_000.0f64 / 0.5).cbrt();
    let mut s = base_scene(3, 0.0, vec![side; 3], vec![Boundary::Periodic; 3]);
    s.initial.lattice_spacing = 1.25;
    s
}

/// (b): 32000 elastic spheres, `g = 1`, box 80 x 80 x 40, periodic laterally, floor and lid,
/// 7 lattice layers near the floor (spacing 1.17: 68 x 68 sites per layer), `T = 1`.
pub fn system_b() -> Scene {
    let mut s = base_scene(
        3,
        1.0,
        vec![80.0, 80.0, 40.0],
        vec![Boundary::Periodic, Boundary::Periodic, Boundary::Wall],
    );
    s.initial.lattice_spacing = 1.17;
    s
}

/// (c): the 2D standard wet system (as scenes/standard_wet_2d.toml, without a drive), the run
/// length as in [`base_scene`].
pub fn system_c() -> Scene {
    let text = "dimension = 2\n[box]\nsize = [400.0, 9.0]\nboundary = [\"periodic\", \"wall\"]\n\
        [particles]\ncount = 1200\npolydispersity = 0.06\n[contact]\nrestitution = 0.9\n\
        [capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\ne_cb = 0.2844\n\
        rupture_rule = \"reduced_mass\"\n[initial]\ntemperature_over_ecb = 20.0\nseed = 1\n\
        [run]\nduration = 1.0e9\n";
    toml::from_str(text).expect("the standard system parses")
}

/// (c'): (c) without bridges, at the same absolute initial temperature `20 * 0.2844`.
pub fn system_c_dry() -> Scene {
    let mut s = system_c();
    s.capillary = CapillarySpec::default();
    s.initial.temperature = Some(20.0 * 0.2844);
    s.initial.temperature_over_ecb = None;
    s
}

/// (c) in the shaken container at `(Gamma, E*)`, its floor and lid moved by `solver`.
pub fn shaken_standard(gamma: f64, e_star: f64, solver: WallSolverKind) -> Scene {
    let mut s = system_c();
    s.drive.kind = DriveKind::Sine;
    s.drive.gamma = Some(gamma);
    s.drive.e_star = Some(e_star);
    s.drive.wall_solver = solver;
    s
}

/// The dry shaken 2D system of the time-driven engine's benchmark for one integrator (`"gear5"` or `"verlet"`).
pub fn dry_shaken_time_driven(integrator: &str) -> Scene {
    dry_shaken_time_driven_widened(integrator, 1)
}

/// The benchmark scene with `k` times the particles in a box `k` times as wide (same density;
/// `--n-factor`).
pub fn dry_shaken_time_driven_widened(integrator: &str, k: usize) -> Scene {
    let kr = DEFAULT_STIFFNESS * 0.25f64.sqrt();
    let a_d = hertz::damping_for_restitution(kr, 0.5, 1.0, 0.9);
    let text = format!(
        r#"
dimension = 2
gravity = 1.0
[box]
size = [{width:?}, 9.0]
boundary = ["periodic", "wall"]
[particles]
count = {count}
polydispersity = 0.06
[contact]
damping = {a_d}
[drive]
kind = "sine"
amplitude = 0.05
omega = {omega}
[initial]
temperature = 1.0
seed = 1
[run]
duration = 1.0
[engine]
kind = "time"
dt = 1e-4
integrator = "{integrator}"
"#,
        omega = (15.0f64 / 0.05).sqrt(),
        width = 400.0 * k as f64,
        count = 1200 * k,
    );
    Scene::from_toml_str(&text, "reference dry_shaken_time_driven")
        .expect("the reference scene is valid")
}
