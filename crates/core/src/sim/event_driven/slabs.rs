//! Event source of the shear drive (docs/model.md 4.2): the slabs of constant force along `x` and
//! each particle's next slab-face crossing. Empty (no field, no per-particle state) unless the
//! engine's `SHEAR` flag is set.
//!
//! The `x` motion is force-free, so a crossing time is linear. Firing moves the particle into
//! the neighbouring slab and changes its acceleration: a course change, after which the
//! scheduler re-predicts every event of the particle.

use super::bodies::{Bodies, permute_in_place, vec_bytes};
use super::event::{Event, EventKind, EventSource, PlaneEvent};
use super::shear::ShearField;
use crate::physics::flight::linear_time_to_plane;

/// The slabs and each particle's slab and next crossing.
#[derive(Debug, Clone)]
pub struct SlabSource {
    pub field: Option<ShearField>,
    pub slab: Vec<u32>,
    /// Next crossing of a slab face.
    pub ev: Vec<PlaneEvent>,
}

impl SlabSource {
    /// The source for particles at `positions_x` (their `x` coordinates); `None`: no shear.
    pub fn new(field: Option<ShearField>, positions_x: impl Iterator<Item = f64>) -> Self {
        let slab: Vec<u32> = match &field {
            Some(f) => positions_x.map(|x| f.slab_of(x) as u32).collect(),
            None => Vec::new(),
        };
        let ev = vec![PlaneEvent::NEVER; slab.len()];
        Self { field, slab, ev }
    }

    /// Heap bytes of the per-particle arrays (`wetgran-bench memory`).
    pub fn memory(&self) -> Vec<(&'static str, usize)> {
        vec![
            ("slabs.slab", vec_bytes(&self.slab)),
            ("slabs.ev", vec_bytes(&self.ev)),
        ]
    }

    /// The acceleration of every particle in its slab (empty without shear).
    pub(crate) fn accelerations(&self) -> Vec<f64> {
        match &self.field {
            Some(f) => self.slab.iter().map(|&k| f.accel(k as usize)).collect(),
            None => Vec::new(),
        }
    }

    /// Predicts the next slab-face crossing of `i` (at time `now`).
    pub fn predict<const D: usize, const G: bool, const S: bool>(
        &mut self,
        i: usize,
        bodies: &Bodies<D, G, S>,
        now: f64,
    ) {
        let Some(f) = &self.field else {
            return;
        };
        let mut best = PlaneEvent::NEVER;
        if f.count() > 1 {
            let (x, v) = (bodies.body[i].x[0], bodies.body[i].v[0]);
            let (lo, hi) = f.faces(self.slab[i] as usize, x);
            best.keep_earlier(linear_time_to_plane(x, v, hi, true), 0, true);
            best.keep_earlier(linear_time_to_plane(x, v, lo, false), 0, false);
        }
        best.time += now;
        self.ev[i] = best;
    }

    /// Moves `i` (at the current time) into the neighbouring slab and sets its new
    /// acceleration; the caller counts the course change and re-predicts.
    pub(crate) fn fire<const D: usize, const G: bool, const S: bool>(
        &mut self,
        i: usize,
        up: bool,
        bodies: &mut Bodies<D, G, S>,
    ) {
        let f = self.field.as_ref().expect("shear engine has slabs");
        let k = f.next(self.slab[i] as usize, up);
        self.slab[i] = k as u32;
        bodies.accel[i] = f.accel(k);
    }

    /// Puts `i` in the slab of position `x` (set-ups and tests).
    pub(crate) fn relocate<const D: usize, const G: bool, const S: bool>(
        &mut self,
        i: usize,
        x: f64,
        bodies: &mut Bodies<D, G, S>,
    ) {
        if let Some(f) = &self.field {
            let k = f.slab_of(x);
            self.slab[i] = k as u32;
            bodies.accel[i] = f.accel(k);
        }
    }

    /// Invariant: particle `i` at `x` lies in its slab.
    pub fn check(&self, i: usize, x: f64, tol: f64) -> Result<(), String> {
        if let Some(f) = &self.field {
            let (lo, hi) = f.faces(self.slab[i] as usize, x);
            if x < lo - tol || x > hi + tol {
                return Err(format!(
                    "is not in its slab {} [{lo}, {hi}] (x = {x})",
                    self.slab[i]
                ));
            }
        }
        Ok(())
    }
}

impl EventSource for SlabSource {
    #[inline]
    fn candidate(&self, i: usize) -> Event {
        self.ev[i].event(|_, up| EventKind::Slab { up })
    }

    fn permute(&mut self, order: &[u32], _new_of_old: &[u32]) {
        if self.field.is_some() {
            permute_in_place(&mut self.slab, order);
            permute_in_place(&mut self.ev, order);
        }
    }
}
