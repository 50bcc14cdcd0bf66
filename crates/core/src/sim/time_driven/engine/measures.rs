//! What the time-driven engine reports about its state: the energy ledger, momentum,
//! granular temperature, flat copies of positions and velocities, and the invariant checks.

use super::*;

impl<const D: usize, const GRAV: bool, const WET: bool, B: BodyForce<D>>
    TimeEngine<D, GRAV, WET, B>
{
    /// Energy bookkeeping at the current time (see the module doc for the fields).
    pub fn energy(&self) -> EnergyLedger {
        let n = self.s.n;
        let p = &self.s.p;
        let vs = self.s.velocity_scale();
        let x = self.now(0);
        let v = self.now(1);
        let mut kinetic = 0.0;
        for e in 0..D * n {
            let ve = v[e] * vs;
            kinetic += 0.5 * p.mass * ve * ve;
        }
        let mut potential = 0.0;
        if GRAV {
            potential += x[(D - 1) * n..]
                .iter()
                .map(|z| p.mass * p.gravity * z)
                .sum::<f64>();
        }
        for i in 0..n {
            for q in self.s.list.start[i] as usize..self.s.list.start[i + 1] as usize {
                let j = self.s.list.partner[q] as usize;
                let r = self.distance(i, j);
                let sig = self.s.radius[i] + self.s.radius[j];
                if r < sig {
                    let kr = p.stiffness * (self.s.radius[i] * self.s.radius[j] / sig).sqrt();
                    potential += hertz::elastic_energy(kr, sig - r);
                }
                if WET && self.s.list.flags[q] & BOND != 0 {
                    potential += p.bridge_force * (r - sig);
                }
            }
        }
        let t = self.time();
        let zw = p.drive.map_or(0.0, |(a, w)| a * (w * t).sin());
        for k in 0..D {
            if p.periodic[k] {
                continue;
            }
            let shift = if k == D - 1 { zw } else { 0.0 };
            for i in 0..n {
                let xk = x[k * n + i];
                let ri = self.s.radius[i];
                for ov in [ri - (xk - shift), xk + ri - (p.size[k] + shift)] {
                    if ov > 0.0 {
                        potential += hertz::elastic_energy(self.s.wall_kr[i], ov);
                    }
                }
            }
        }
        EnergyLedger {
            kinetic,
            potential,
            dissipated_restitution: self.s.dissipated_damping,
            dissipated_ruptures: self.s.dissipated_bridges,
            added_by_collapse_remedies: 0.0,
            added_by_wall_placement: 0.0,
            work_by_drive: self.s.work_by_drive,
        }
    }

    /// Centre distance of `i` and `j` (nearest image).
    fn distance(&self, i: usize, j: usize) -> f64 {
        let n = self.s.n;
        let mut r2 = 0.0;
        for k in 0..D {
            let mut d = self.now_at(k * n + i).0 - self.now_at(k * n + j).0;
            if self.s.p.periodic[k] {
                let l = self.s.p.size[k];
                d -= l * (d / l).round();
            }
            r2 += d * d;
        }
        r2.sqrt()
    }

    pub fn momentum(&self) -> [f64; D] {
        let vs = self.s.velocity_scale();
        let v = self.now(1);
        std::array::from_fn(|k| {
            v[k * self.s.n..(k + 1) * self.s.n].iter().sum::<f64>() * vs * self.s.p.mass
        })
    }

    /// Granular temperature `T_g = m (<v^2> - <v>^2) / f_d` (Eq. 3.2, `f_d = D`).
    pub fn granular_temperature(&self) -> f64 {
        let n = self.s.n as f64;
        let vs = self.s.velocity_scale();
        let mut mean_sq = 0.0;
        let mut mean2 = 0.0;
        let v = self.now(1);
        for k in 0..D {
            let col = &v[k * self.s.n..(k + 1) * self.s.n];
            let m = col.iter().sum::<f64>() * vs / n;
            mean_sq += col.iter().map(|v| v * v).sum::<f64>() * vs * vs / n;
            mean2 += m * m;
        }
        self.s.p.mass * (mean_sq - mean2) / D as f64
    }

    /// Positions flat with stride `D`, scene order.
    pub fn positions_flat(&self) -> Vec<f64> {
        (0..self.s.n).flat_map(|i| self.position(i)).collect()
    }

    /// Velocities flat with stride `D`, scene order.
    pub fn velocities_flat(&self) -> Vec<f64> {
        (0..self.s.n).flat_map(|i| self.velocity(i)).collect()
    }

    /// `O(N^2)`: the first pair that overlaps (or is within `s_crit` of contact in a wet scene)
    /// but is missing from the Verlet list, which would make its force vanish (the test below).
    #[cfg(test)]
    fn pair_missing_from_list(&self) -> Option<(usize, usize)> {
        let reach = if WET { self.s.p.s_crit } else { 0.0 };
        for i in 0..self.s.n {
            let row = &self.s.list.partner
                [self.s.list.start[i] as usize..self.s.list.start[i + 1] as usize];
            for j in i + 1..self.s.n {
                let r = self.distance(i, j);
                if r < self.s.radius[i] + self.s.radius[j] + reach
                    && row.binary_search(&(j as u32)).is_err()
                {
                    return Some((i, j));
                }
            }
        }
        None
    }

    /// Checks the invariants: finite numbers; every centre inside the box (between the walls at
    /// their current position); no pair or wall overlap beyond [`SANITY_OVERLAP`] `d`; no
    /// bridge stretched beyond `s_crit` by more than the same amount; no pair in contact or
    /// bonded lost from the neighbour list. Returns the first violation.
    pub fn sanity_check(&self) -> Result<(), String> {
        self.quick_check()?;
        self.pair_check()
    }

    /// The invariants of each particle on its own, `O(N)`: no pair lost from the neighbour
    /// list (flagged as it happens), finite numbers, every centre inside the box.
    pub fn quick_check(&self) -> Result<(), String> {
        let n = self.s.n;
        let t = self.time();
        let tol = SANITY_OVERLAP * self.s.p.diameter;
        let zw = self.s.p.drive.map_or(0.0, |(a, w)| a * (w * t).sin());
        if let Some((i, j)) = self.s.list.lost_pair {
            return Err(format!(
                "flagged pair {i}-{j} (in contact or bonded) left the neighbour list: it moved \
                 apart by more than the skin between two list builds, a blown-up run (engine.dt \
                 too large for the speeds reached); at t = {t}"
            ));
        }
        for i in 0..n {
            let x = self.position(i);
            let v = self.velocity(i);
            if !x.iter().chain(v.iter()).all(|a| a.is_finite()) {
                return Err(format!("particle {i} has a non-finite state at t = {t}"));
            }
            for k in 0..D {
                let (lo, hi) = if self.s.p.periodic[k] {
                    (0.0, self.s.p.size[k])
                } else {
                    let s = if k == D - 1 { zw } else { 0.0 };
                    (
                        s + self.s.radius[i] - tol,
                        self.s.p.size[k] + s - self.s.radius[i] + tol,
                    )
                };
                if x[k] < lo || x[k] > hi {
                    return Err(format!(
                        "particle {i} is outside the box along axis {k}: x = {} not in [{lo}, {hi}] at t = {t}",
                        x[k]
                    ));
                }
            }
        }
        Ok(())
    }

    /// The pair part of [`Self::sanity_check`]: no overlap and no over-stretched bond among
    /// the pairs of the neighbour list.
    fn pair_check(&self) -> Result<(), String> {
        let n = self.s.n;
        let t = self.time();
        let tol = SANITY_OVERLAP * self.s.p.diameter;
        for i in 0..n {
            for q in self.s.list.start[i] as usize..self.s.list.start[i + 1] as usize {
                let j = self.s.list.partner[q] as usize;
                let r = self.distance(i, j);
                let sig = self.s.radius[i] + self.s.radius[j];
                if sig - r > tol {
                    return Err(format!(
                        "particles {i} and {j} overlap by {} at t = {t}",
                        sig - r
                    ));
                }
                if WET && self.s.list.flags[q] & BOND != 0 && r - sig > self.s.p.s_crit + tol {
                    return Err(format!(
                        "bonded pair {i}-{j} stretched beyond s_crit by {} at t = {t}",
                        r - sig - self.s.p.s_crit
                    ));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Safeguard of the Verlet list: with the rebuild criterion (some particle moved by more
    /// than skin / 2), no interacting pair is ever missing from the list, even with a thin skin
    /// in a hot shaken wet system (120 disks, standard `s_crit` and `E_cb`); checked by brute
    /// force every 50 steps.
    #[test]
    fn verlet_list_never_misses_an_interacting_pair() {
        let kr = crate::scene::DEFAULT_STIFFNESS * 0.25f64.sqrt();
        let a_d = hertz::damping_for_restitution(kr, 0.5, 1.0, 0.9);
        let text = format!(
            "dimension = 2\ngravity = 1.0\n[box]\nsize = [40.0, 9.0]\nboundary = [\"periodic\", \"wall\"]\n\
             [particles]\ncount = 120\npolydispersity = 0.06\n[contact]\ndamping = {a_d}\n\
             [capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\ne_cb = 0.2844\n\
             [drive]\nkind = \"sine\"\ngamma = 5.0\ne_star = 10.0\n\
             [initial]\ntemperature_over_ecb = 20.0\nseed = 5\n[run]\nduration = 1.0\n\
             [engine]\nkind = \"time\"\nskin = 0.02\n"
        );
        let s = crate::scene::Scene::from_toml_str(&text, "<test scene>").expect("a valid scene");
        let mut e = TimeEngine::<2, true, true>::new(&s);
        for step in 0..10_000 {
            e.step();
            if step % 50 == 0 {
                assert_eq!(e.pair_missing_from_list(), None, "at step {step}");
            }
        }
        assert!(
            e.list_builds() > 20,
            "the list was hardly rebuilt: {}",
            e.list_builds()
        );
    }
}
