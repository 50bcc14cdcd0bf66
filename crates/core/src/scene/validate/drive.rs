//! Validation of the `[drive]` section: no drive keys without a drive, the sine drive's pair of
//! keys, its motion limits, wall solver and table keys and the floor-to-lid gap, and the shear
//! drive's box, force and slabs.

use super::{
    Check, Constraint, MAX_AMPLITUDE, MAX_GAMMA, MAX_OMEGA, MAX_SHEAR_FORCE, MAX_WALL_SPEED,
    MIN_AMPLITUDE, SceneError, num,
};
use super::{MAX_SHEAR_SLABS, MIN_SLAB_WIDTH};
use crate::scene::{Boundary, DriveKind, DriveSpec, Scene, WallSolverKind};

impl Scene {
    /// `[drive]`: no drive keys without a drive, and the keys of each kind.
    pub(super) fn validate_drive(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let drive = &self.drive;
        match drive.kind {
            DriveKind::None => c.none_given(
                shaking_keys_given(drive)
                    .iter()
                    .chain(&table_keys_given(drive))
                    .chain(&shear_keys_given(drive)),
                "is set but drive.kind = \"none\": set kind = \"sine\" (or \"shear\" for \
                 f_max, slab_width) or remove the key",
            )?,
            DriveKind::Shear => self.validate_shear(c)?,
            DriveKind::Sine => self.validate_sine(c)?,
        }
        Ok(())
    }

    /// A sine drive: exactly one pair (amplitude and omega, or gamma and e_star), its solver
    /// keys, the wall table and the gap between floor and lid.
    fn validate_sine(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let drive = &self.drive;
        c.none_given(
            &shear_keys_given(drive),
            "is set but drive.kind = \"sine\": it belongs to kind = \"shear\"",
        )?;
        if self.gravity <= 0.0 {
            return Err(c.err(
                "drive.kind",
                "= \"sine\" needs gravity > 0 (Gamma and E* are defined through g)",
            ));
        }
        let physical = drive.amplitude.is_some() || drive.omega.is_some();
        let reduced = drive.gamma.is_some() || drive.e_star.is_some();
        if physical == reduced {
            return Err(c.err(
                "drive",
                "a sine drive needs exactly one pair: amplitude and omega, or gamma and \
                     e_star",
            ));
        }
        let pairs = if physical {
            [
                ("drive.amplitude", drive.amplitude),
                ("drive.omega", drive.omega),
            ]
        } else {
            [("drive.gamma", drive.gamma), ("drive.e_star", drive.e_star)]
        };
        for (key, value) in pairs {
            match value {
                None => {
                    return Err(c.err(key, "is missing: it comes in a pair"));
                }
                Some(v) if key == "drive.amplitude" => c.non_negative(key, v)?,
                Some(v) => c.positive(key, v)?,
            }
        }
        self.validate_drive_motion(c, physical)?;
        if let Some(tol) = drive.root_tolerance {
            c.positive("drive.root_tolerance", tol)?;
        }
        if let Some(t_min) = drive.t_min {
            c.positive("drive.t_min", t_min)?;
        }
        self.validate_wall_table(c)?;
        self.validate_shaken_gap(c)?;
        Ok(())
    }

    /// The container motion `(A, omega)` of a sine drive (each key already in its own range):
    /// amplitude, wall speed and peak acceleration within [`MAX_AMPLITUDE`],
    /// [`MAX_WALL_SPEED`] and [`MAX_GAMMA`], then the amplitude at least [`MIN_AMPLITUDE`]
    /// (or 0) and `omega` at most [`MAX_OMEGA`] (what the engine can integrate). The error
    /// names the key that sets the excess: `amplitude` / `omega` as given, or `e_star` (wall
    /// speed, and the smallness of `A` and largeness of `omega` at a given Gamma) / `gamma`
    /// (amplitude, Gamma).
    fn validate_drive_motion(&self, c: &Check<'_>, physical: bool) -> Result<(), SceneError> {
        let Some((a, omega)) = self.drive_motion() else {
            return Ok(());
        };
        let unit = (self.gravity * self.particles.diameter).sqrt();
        let speed = a * omega / unit;
        let gamma = a * omega * omega / self.gravity;
        let (amp_key, speed_key, gamma_key) = if physical {
            ("drive.amplitude", "drive.omega", "drive.omega")
        } else {
            ("drive.gamma", "drive.e_star", "drive.gamma")
        };
        let (small_key, fast_key) = if physical {
            ("drive.amplitude", "drive.omega")
        } else {
            ("drive.e_star", "drive.e_star")
        };
        let a_d = a / self.particles.diameter;
        let omega_unit = omega / (self.gravity / self.particles.diameter).sqrt();
        let value = |key: &str| match key {
            "drive.amplitude" => a,
            "drive.omega" => omega,
            "drive.gamma" => self.drive.gamma.unwrap_or(gamma),
            _ => self.drive.e_star.unwrap_or(f64::NAN),
        };
        for (key, excess, what) in [
            (
                speed_key,
                speed.is_nan() || speed > MAX_WALL_SPEED,
                format!(
                    "the wall speed A omega = {} sqrt(g d) must be <= {}",
                    num(speed),
                    num(MAX_WALL_SPEED)
                ),
            ),
            (
                gamma_key,
                gamma.is_nan() || gamma > MAX_GAMMA,
                format!(
                    "Gamma = A omega^2 / g = {} must be <= {}",
                    num(gamma),
                    num(MAX_GAMMA)
                ),
            ),
            (
                amp_key,
                (a / self.particles.diameter).is_nan()
                    || a / self.particles.diameter > MAX_AMPLITUDE,
                format!(
                    "the amplitude A = {} d must be <= {} d",
                    num(a / self.particles.diameter),
                    num(MAX_AMPLITUDE)
                ),
            ),
            (
                small_key,
                a_d != 0.0 && a_d < MIN_AMPLITUDE,
                format!(
                    "the amplitude A = {} d must be 0 or >= {} d (a smaller stroke is inside the \
                     wall solvers' tolerance: docs/scene-reference.md, [drive])",
                    num(a_d),
                    num(MIN_AMPLITUDE)
                ),
            ),
            (
                fast_key,
                omega_unit > MAX_OMEGA,
                format!(
                    "omega = {} sqrt(g/d) must be <= {} sqrt(g/d) (every period costs wall events \
                     and samples: docs/scene-reference.md, [drive])",
                    num(omega_unit),
                    num(MAX_OMEGA)
                ),
            ),
        ] {
            if excess {
                return Err(c.err(
                    key,
                    format!("= {} is out of range: {what}", num(value(key))),
                ));
            }
        }
        Ok(())
    }

    /// The `table` wall solver's keys: only with `wall_solver = "table"`, and in range.
    fn validate_wall_table(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let drive = &self.drive;
        if drive.wall_solver != WallSolverKind::Table {
            c.none_given(
                &table_keys_given(drive),
                "is set but drive.wall_solver is not \"table\": set wall_solver = \"table\" or \
                 remove the key",
            )?;
        }
        if let Some(cells) = drive.table_cells {
            for (k, n) in cells.iter().enumerate() {
                let key = format!("drive.table_cells[{k}]");
                c.require(&key, n, (4..=4096).contains(n), "in [4, 4096]")?;
            }
        }
        if let Some(v) = drive.table_v_min {
            c.positive("drive.table_v_min", v)?;
        }
        if let Some(v) = drive.table_v_max {
            c.positive("drive.table_v_max", v)?;
            let v_min = drive
                .table_v_min
                .unwrap_or(crate::physics::wall_table::DEFAULT_V_MIN_OVER_WALL_SPEED);
            let must = format!("greater than table_v_min = {v_min}");
            c.require("drive.table_v_max", v, v > v_min, &must)?;
        }
        if let Some(tol) = drive.table_corner_tolerance {
            let ok = tol > 0.0 && tol <= 1.0;
            c.require(
                "drive.table_corner_tolerance",
                tol,
                ok,
                "in (0, 1] (periods)",
            )?;
            if drive.table_corner_check == Some(false) {
                return Err(c.err(
                    "drive.table_corner_tolerance",
                    "is set but drive.table_corner_check = false",
                ));
            }
        }
        Ok(())
    }

    /// The shaken floor and lid must leave room for the largest particle.
    fn validate_shaken_gap(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let dim = self.dimension;
        let size = &self.container.size;
        // Floor and lid move together (`z_w(t) = A sin(omega t)`), so the gap between
        // them is the box height at every phase, whatever the stroke `2 A`: the
        // geometry only needs the largest particle to fit between them.
        if self.drive_motion().is_some() {
            let h = size[dim - 1];
            let (_, d_max) = self.diameter_range();
            if h <= d_max {
                return Err(c
                    .err(
                        &format!("box.size[{}]", dim - 1),
                        format!(
                            "= {h} is out of range: the gap between the shaken floor and lid \
                             must exceed the largest diameter d_max = {d_max:.4}"
                        ),
                    )
                    .failing(Constraint::GapBelowDiameter));
            }
        }
        Ok(())
    }

    /// The shear drive (docs/model.md 4.2): 3D, `x` and `y` periodic, floor and lid, `f_max >= 0`,
    /// `0 < slab_width <= L_x`, none of the shaking keys.
    fn validate_shear(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let drive = &self.drive;
        if self.dimension != 3 {
            return Err(c.err(
                "drive.kind",
                "= \"shear\" needs dimension = 3: the force acts along y and varies along x \
                 (Kolmogorov flow, docs/model.md 4.2); a 2D box (axes x, z) has no y axis",
            ));
        }
        let b = self.boundaries();
        for (k, want) in [Boundary::Periodic, Boundary::Periodic, Boundary::Wall]
            .iter()
            .enumerate()
        {
            if b[k] != *want {
                return Err(c.err(
                    &format!("box.boundary[{k}]"),
                    "is not allowed with drive.kind = \"shear\": the box must be [\"periodic\", \
                     \"periodic\", \"wall\"] (periodic in x and y, floor and lid)",
                ));
            }
        }
        let fixed = "is set but drive.kind = \"shear\": floor and lid are static; remove the key";
        c.none_given(
            shaking_keys_given(drive)
                .iter()
                .chain(&table_keys_given(drive)),
            fixed,
        )?;
        if drive.wall_solver != WallSolverKind::Exact {
            return Err(c.err("drive.wall_solver", fixed));
        }
        match drive.f_max {
            None => {
                return Err(c.err(
                    "drive.f_max",
                    "is missing: drive.kind = \"shear\" needs the peak force f_max (>= 0)",
                ));
            }
            Some(f) => {
                c.non_negative("drive.f_max", f)?;
                c.within("drive.f_max", f, f <= MAX_SHEAR_FORCE, "in [0, 1e3]")?;
            }
        }
        // At least 4 slabs: with 2 the slab centres sit on the zeros of the cosine (no force at
        // all), with 1 the force is uniform (no shear).
        // At most MAX_SHEAR_SLABS slabs, each at least MIN_SLAB_WIDTH d wide: the engine keeps one
        // acceleration per slab (found by the job-spec fuzzer: `slab_width = 1e-300` asked for
        // 5e300 slabs and the allocation panicked).
        let l_x = self.container.size[0];
        let d = self.particles.diameter;
        let w = drive.slab_width.unwrap_or(d);
        if !(w.is_finite()
            && w >= MIN_SLAB_WIDTH * d
            && (l_x / w).round() >= 4.0
            && (l_x / w).round() <= MAX_SHEAR_SLABS)
        {
            return Err(c.out_of_range(
                "drive.slab_width",
                w,
                &format!(
                    "in [{}, L_x / 3.5 = {:.4}] (at least {MIN_SLAB_WIDTH} d and at most \
                     {MAX_SHEAR_SLABS:e} slabs; at least 4 slabs along L_x = {l_x}: with 2 the \
                     slab centres sit on the zeros of the cosine)",
                    num((MIN_SLAB_WIDTH * d).max(l_x / MAX_SHEAR_SLABS)),
                    l_x / 3.5
                ),
            ));
        }
        Ok(())
    }
}

/// The shaking drive's keys (other than the table's) and whether each is set.
fn shaking_keys_given(drive: &DriveSpec) -> [(&'static str, bool); 6] {
    [
        ("drive.amplitude", drive.amplitude.is_some()),
        ("drive.omega", drive.omega.is_some()),
        ("drive.gamma", drive.gamma.is_some()),
        ("drive.e_star", drive.e_star.is_some()),
        ("drive.root_tolerance", drive.root_tolerance.is_some()),
        ("drive.t_min", drive.t_min.is_some()),
    ]
}

/// The shear drive's keys and whether each is set.
fn shear_keys_given(drive: &DriveSpec) -> [(&'static str, bool); 2] {
    [
        ("drive.f_max", drive.f_max.is_some()),
        ("drive.slab_width", drive.slab_width.is_some()),
    ]
}

/// The `table` solver's keys and whether each is set.
pub(super) fn table_keys_given(drive: &DriveSpec) -> [(&'static str, bool); 5] {
    [
        ("drive.table_cells", drive.table_cells.is_some()),
        ("drive.table_v_min", drive.table_v_min.is_some()),
        ("drive.table_v_max", drive.table_v_max.is_some()),
        (
            "drive.table_corner_check",
            drive.table_corner_check.is_some(),
        ),
        (
            "drive.table_corner_tolerance",
            drive.table_corner_tolerance.is_some(),
        ),
    ]
}
