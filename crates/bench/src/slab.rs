//! `wetgran-bench slab`: what the slab width of the shear drive costs and buys (docs/model.md 4.2).
//!
//! The event-driven engine replaces `F_max cos(2 pi x / L_x)` by its value at the centre of
//! each slab; narrower slabs approach the continuous force and cost more slab-crossing events
//! and more quartic pair predictions. This benchmark runs the small fluidised shear scene
//! (`scenes/shear_small_3d.toml`, 360 wet spheres, `F_max = 1 m g`, above the chain model's
//! 0.46) for `10 * scale` time units at several slab widths and `repeat` seeds each, and prints
//! per width: the mean of `E_par / E_cb` over the second half of the run (sampled every 0.5)
//! with its standard error over the seeds, the events and slab crossings per particle per time
//! unit, and the median wall time.

use std::fmt::Write as _;
use std::time::Instant;
use wetgran_core::observe::shear::shear_energies;
use wetgran_core::scene::Scene;
use wetgran_core::sim::Frame;
use wetgran_core::sim::event_driven::Engine;

/// Slab widths measured (units of `d`); 12 / w slabs tile `L_x = 12`.
pub(crate) const WIDTHS: [f64; 5] = [3.0, 2.0, 1.0, 0.5, 0.25];

/// One slab width.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SlabRow {
    pub width: f64,
    pub slabs: usize,
    /// Mean over seeds of the second-half mean of `E_par / E_cb`, and its standard error.
    pub e_par: f64,
    pub(crate) e_par_error: f64,
    pub(crate) events_per_particle_time: f64,
    pub(crate) slab_crossings_per_particle_time: f64,
    pub(crate) median_seconds: f64,
}

/// The scene of the benchmark at slab width `w`, seed `seed`, run length `duration`.
pub(crate) fn scene(w: f64, seed: u64, duration: f64) -> Scene {
    let mut s = Scene::from_toml_str(
        include_str!("../../../scenes/shear_small_3d.toml"),
        "scenes/shear_small_3d.toml",
    )
    .expect("the shipped scene is valid");
    s.drive.f_max = Some(1.0);
    s.drive.slab_width = Some(w);
    s.initial.seed = seed;
    s.run.duration = duration;
    s
}

/// Runs every width with `repeat` seeds for `10 * scale` time units (at least 2).
pub(crate) fn measure(repeat: usize, scale: f64) -> Vec<SlabRow> {
    let duration = (10.0 * scale).max(2.0);
    let repeat = repeat.max(1);
    let mut rows = Vec::new();
    for &w in &WIDTHS {
        let (mut e_par, mut secs, mut events, mut slabs_crossed) = (vec![], vec![], 0.0, 0.0);
        let mut slabs = 0;
        for seed in 1..=repeat as u64 {
            let s = scene(w, seed, duration);
            slabs = s.shear_slabs().expect("sheared").count;
            let e_cb = s.e_cb();
            let n = s.particles.count as f64;
            let mut e = Engine::<3, true, true, true>::new(&s);
            let start = Instant::now();
            let (mut sum, mut k) = (0.0, 0.0);
            let mut t = 0.0;
            while t < duration - 1e-9 {
                t += 0.5;
                e.run_until(t, None);
                if t > 0.5 * duration {
                    let (par, _) = shear_energies(&Frame::of_engine(&e, &s));
                    sum += par / e_cb;
                    k += 1.0;
                }
            }
            secs.push(start.elapsed().as_secs_f64());
            e_par.push(sum / k);
            events += e.counts().total() as f64 / (n * duration);
            slabs_crossed += e.counts().slab_crossings as f64 / (n * duration);
        }
        let r = repeat as f64;
        let mean = e_par.iter().sum::<f64>() / r;
        let var = if repeat > 1 {
            e_par.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (r - 1.0)
        } else {
            0.0
        };
        rows.push(SlabRow {
            width: w,
            slabs,
            e_par: mean,
            e_par_error: (var / r).sqrt(),
            events_per_particle_time: events / r,
            slab_crossings_per_particle_time: slabs_crossed / r,
            median_seconds: crate::quantile(&secs, 0.5),
        });
    }
    rows
}

/// The table.
pub(crate) fn report(rows: &[SlabRow], repeat: usize, scale: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "bench slab: scenes/shear_small_3d.toml at F_max = 1, {} time units, {} seed(s) per width",
        (10.0 * scale).max(2.0),
        repeat.max(1)
    );
    s.push_str(
        "  width  slabs   E_par/E_cb        +-   events/(N t)   slab x/(N t)     wall s   vs w=1\n",
    );
    let base = rows
        .iter()
        .find(|r| r.width == 1.0)
        .map_or(f64::NAN, |r| r.median_seconds);
    for r in rows {
        let _ = writeln!(
            s,
            "{:>7} {:>6} {:>12.4} {:>9.4} {:>14.1} {:>14.2} {:>10.3} {:>8.2}",
            r.width,
            r.slabs,
            r.e_par,
            r.e_par_error,
            r.events_per_particle_time,
            r.slab_crossings_per_particle_time,
            r.median_seconds,
            r.median_seconds / base
        );
    }
    s
}
