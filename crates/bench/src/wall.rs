//! `wetgran-bench wall`: what accuracy costs for the shaken-wall collision solvers.
//!
//! A fixed random set of trajectories (seeded) in the 2D standard wet system's drive at a fluid
//! point (Gamma = 5, E* = 10): contact heights within three diameters above the wall's reach,
//! normal velocities in `[-3, 3]`, phases over a period; the lid problem (gravity pointing away)
//! for a quarter of them. The reference root of each is `exact_root` at gap tolerance 1e-15
//! (conservative advancement cannot skip a root; the test suite checks it against an
//! independent bisection reference). For each solver and knob: mean and largest collision-time
//! error, the fraction of wrong roots (a different root or a missed one), and nanoseconds per
//! prediction (median over repetitions); for the `table` solver also the build time, the memory,
//! and the fraction of queries the table hands to the exact solver.

use rand::{Rng, SeedableRng};
use std::fmt::Write as _;
use std::hint::black_box;
use std::sync::Arc;
use std::time::Instant;
use wetgran_core::physics::shaken_wall::{WallMotion, WallRoot, bracket_root, exact_root};
use wetgran_core::physics::wall_table::{self, TableHit, TableSpec, WallTable};

/// One solver setting and what it measured.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct WallRow {
    pub solver: &'static str,
    pub(crate) knob: String,
    pub(crate) mean_error: f64,
    pub(crate) max_error: f64,
    pub(crate) wrong_fraction: f64,
    pub(crate) ns_per_prediction: f64,
    /// `table` only: seconds to fill the floor and lid tables, their memory in bytes, and the
    /// fraction of queries answered by the exact solver (outside the table or failed cells).
    pub table: Option<TableCost>,
}

/// What a table costs besides its lookups.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TableCost {
    pub(crate) build_seconds: f64,
    /// CPU seconds of the whole process (every thread) during the builds; NaN without `/proc`.
    /// The cells are filled on the pool `sim::threads` chooses (`WETGRAN_THREADS` caps it).
    pub(crate) build_cpu_seconds: f64,
    pub bytes: usize,
    pub(crate) fallback_fraction: f64,
}

/// A collision time more than this fraction of a period off is a wrong root (another root, or
/// a missed one); the errors of the others are the mean and maximum reported.
pub(crate) const WRONG_ROOT_FRACTION_OF_PERIOD: f64 = 1e-2;

/// The `table` solver as the engine uses it: the tabulated answer, or the exact solver (gap
/// tolerance 1e-10) where the table does not answer. Returns the root and whether it fell back.
pub(crate) fn table_root(
    table: &WallTable,
    h: f64,
    v: f64,
    t0: f64,
    horizon: f64,
) -> (WallRoot, bool) {
    match table.next_hit(h, v, t0, horizon) {
        TableHit::Hit { dt, .. } => (WallRoot::Hit(dt), false),
        TableHit::Now if h - table.motion().position(t0) <= 1e-7 => (WallRoot::Hit(0.0), false),
        TableHit::None => (WallRoot::None, false),
        TableHit::Now | TableHit::OutOfRange => {
            (exact_root(table.motion(), h, v, t0, 1e-10, horizon), true)
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct Shot {
    motion: WallMotion,
    h: f64,
    v: f64,
    t0: f64,
}

fn shots(n: usize) -> (WallMotion, Vec<Shot>) {
    let e_cb = 0.2844;
    let (gamma, e_star) = (5.0, 10.0);
    let v_w = (2.0f64 * e_star * e_cb).sqrt();
    let omega = gamma / v_w;
    let floor = WallMotion {
        amplitude: v_w * v_w / gamma,
        omega,
        g: 1.0,
    };
    let lid = WallMotion { g: -1.0, ..floor };
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(2010);
    let shots = (0..n)
        .map(|k| {
            let motion = if k % 4 == 3 { lid } else { floor };
            let t0 = rng.gen_range(0.0..floor.period());
            let h = rng
                .gen_range(0.0..floor.amplitude + 3.0)
                .max(motion.position(t0) + 1e-6);
            let v = rng.gen_range(-3.0..3.0);
            Shot { motion, h, v, t0 }
        })
        .collect();
    (floor, shots)
}

/// Compares roots with the reference ones: (summed error, largest error, wrong roots, roots
/// compared). A root off by more than `WRONG_ROOT_FRACTION_OF_PERIOD` of the period, or a hit
/// where the reference has none (or the reverse), is wrong.
fn root_errors(
    reference: &[WallRoot],
    roots: &[WallRoot],
    period: f64,
) -> (f64, f64, usize, usize) {
    let (mut sum, mut max, mut wrong, mut hits) = (0.0, 0.0f64, 0usize, 0usize);
    for (r, o) in reference.iter().zip(roots) {
        match (r, o) {
            (WallRoot::Hit(a), WallRoot::Hit(b)) => {
                let err = (a - b).abs();
                if err > WRONG_ROOT_FRACTION_OF_PERIOD * period {
                    wrong += 1;
                } else {
                    sum += err;
                    max = max.max(err);
                    hits += 1;
                }
            }
            (WallRoot::None, WallRoot::None) => {}
            _ => wrong += 1,
        }
    }
    (sum, max, wrong, hits)
}

/// Runs every solver setting on `4000 * scale` trajectories, `repeat` timing repetitions.
pub(crate) fn measure(repeat: usize, scale: f64) -> Vec<WallRow> {
    let n = ((4000.0 * scale) as usize).max(200);
    let (floor, shots) = shots(n);
    let horizon = 2.0 * floor.period();
    let reference: Vec<WallRoot> = shots
        .iter()
        .map(|s| exact_root(&s.motion, s.h, s.v, s.t0, 1e-15, horizon))
        .collect();
    type Solver = Box<dyn Fn(&Shot) -> WallRoot>;
    let mut settings: Vec<(&'static str, String, Solver)> = Vec::new();
    for tol in [1e-6, 1e-8, 1e-10, 1e-12] {
        settings.push((
            "exact",
            format!("tol {tol:.0e}"),
            Box::new(move |s: &Shot| exact_root(&s.motion, s.h, s.v, s.t0, tol, horizon)),
        ));
    }
    for per_period in [30.0, 100.0, 1000.0, 10000.0] {
        let t_min = floor.period() / per_period;
        settings.push((
            "bracket",
            format!("t_min T/{per_period}"),
            Box::new(move |s: &Shot| {
                bracket_root(&s.motion, s.h, s.v, s.t0, t_min, 1e-12, horizon)
            }),
        ));
    }
    let mut costs: Vec<Option<TableCost>> = vec![None; settings.len()];
    let vw = floor.amplitude * floor.omega;
    for (cells, check) in [
        (32, true),
        (64, true),
        (128, true),
        (256, true),
        (512, true),
        (128, false),
        (256, false),
    ] {
        let spec = TableSpec {
            phase_cells: cells,
            velocity_cells: cells,
            v_min: wall_table::DEFAULT_V_MIN_OVER_WALL_SPEED * vw,
            v_max: wall_table::DEFAULT_V_MAX_OVER_WALL_SPEED * vw,
            corner_tolerance: check.then_some(wall_table::DEFAULT_CORNER_TOLERANCE),
        };
        let lid_motion = WallMotion {
            g: -floor.g,
            ..floor
        };
        let cpu = crate::tdmd::process_cpu_seconds;
        let cpu0 = cpu();
        let tables = Arc::new([
            WallTable::build(floor, spec),
            WallTable::build(lid_motion, spec),
        ]);
        let build_cpu_seconds = match (cpu0, cpu()) {
            (Some(a), Some(b)) => b - a,
            _ => f64::NAN,
        };
        let fallbacks = shots
            .iter()
            .filter(|s| {
                let t = &tables[usize::from(s.motion.g < 0.0)];
                table_root(t, s.h, s.v, s.t0, horizon).1
            })
            .count();
        costs.push(Some(TableCost {
            build_seconds: tables[0].build_seconds + tables[1].build_seconds,
            build_cpu_seconds,
            bytes: tables[0].bytes() + tables[1].bytes(),
            fallback_fraction: fallbacks as f64 / shots.len() as f64,
        }));
        settings.push((
            "table",
            format!("{cells}x{cells}{}", if check { "" } else { " no check" }),
            Box::new(move |s: &Shot| {
                let t = &tables[usize::from(s.motion.g < 0.0)];
                table_root(t, s.h, s.v, s.t0, horizon).0
            }),
        ));
    }
    settings
        .into_iter()
        .zip(costs)
        .map(|((solver, knob, f), table)| {
            let roots: Vec<WallRoot> = shots.iter().map(&f).collect();
            let (sum, max, wrong, hits) = root_errors(&reference, &roots, floor.period());
            let times: Vec<f64> = (0..repeat.max(1))
                .map(|_| {
                    let start = Instant::now();
                    for s in &shots {
                        black_box(f(black_box(s)));
                    }
                    start.elapsed().as_secs_f64() * 1e9 / shots.len() as f64
                })
                .collect();
            WallRow {
                solver,
                knob,
                mean_error: if hits > 0 { sum / hits as f64 } else { 0.0 },
                max_error: max,
                wrong_fraction: wrong as f64 / shots.len() as f64,
                ns_per_prediction: crate::quantile(&times, 0.5),
                table,
            }
        })
        .collect()
}

/// The table `wetgran-bench wall` prints.
pub(crate) fn report(rows: &[WallRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "wetgran-bench wall: shaken-wall root solvers against exact_root at tol 1e-15\n\
         drive: Gamma 5, E* 10 (2D standard wet system), 3/4 floor shots, 1/4 lid shots\n\
         time errors in units of sqrt(d/g); wrong = other root or missed (> 1e-2 T off)\n\
         table: build s (wall, CPU of every thread) and MiB for floor + lid tables; exact % = queries the exact solver answers\n\
         the tables are built on {} thread(s) (WETGRAN_THREADS caps them)\n",
        wetgran_core::sim::threads::available_cores()
    );
    s.push_str("solver   knob                mean |dt|     max |dt|   wrong %   ns/predict   build s     cpu s       MiB  exact %\n");
    for r in rows {
        let _ = write!(
            s,
            "{:<8} {:<16} {:>12.3e} {:>12.3e} {:>9.3} {:>12.0}",
            r.solver,
            r.knob,
            r.mean_error,
            r.max_error,
            100.0 * r.wrong_fraction,
            r.ns_per_prediction
        );
        if let Some(c) = r.table {
            let _ = write!(
                s,
                " {:>9.3} {:>9.3} {:>9.1} {:>8.2}",
                c.build_seconds,
                c.build_cpu_seconds,
                c.bytes as f64 / (1024.0 * 1024.0),
                100.0 * c.fallback_fraction
            );
        }
        let _ = writeln!(s);
    }
    s
}

/// A log-log SVG of the largest time error against the cost per prediction, one marker per
/// solver setting (exact: circles, bracket: squares, table: diamonds), labelled with the knob; settings with
/// wrong roots are drawn in red. Hand-written SVG: no plotting dependency.
pub(crate) fn svg(rows: &[WallRow]) -> String {
    let (w, h, margin, right) = (820.0, 440.0, 70.0, 230.0);
    let xs: Vec<f64> = rows
        .iter()
        .map(|r| r.ns_per_prediction.max(1.0).log10())
        .collect();
    let ys: Vec<f64> = rows
        .iter()
        .map(|r| r.max_error.max(1e-16).log10())
        .collect();
    // The axes span whole decades.
    let decades = |v: &[f64]| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (lo.floor(), hi.ceil())
    };
    let ((x0, x1), (y0, y1)) = (decades(&xs), decades(&ys));
    let px = |x: f64| margin + (x - x0) / (x1 - x0).max(1.0) * (w - margin - right);
    let py = |y: f64| h - margin - (y - y0) / (y1 - y0).max(1.0) * (h - 2.0 * margin);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"11\">"
    );
    let _ = writeln!(s, "<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>");
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"20\" text-anchor=\"middle\" font-size=\"13\">Shaken-wall solvers: largest collision-time error against cost</text>",
        w / 2.0
    );
    for k in x0 as i32..=x1 as i32 {
        let x = px(k as f64);
        let _ = writeln!(
            s,
            "<line x1=\"{x}\" y1=\"{}\" x2=\"{x}\" y2=\"{}\" stroke=\"#ddd\"/><text x=\"{x}\" y=\"{}\" text-anchor=\"middle\">1e{k}</text>",
            margin,
            h - margin,
            h - margin + 16.0
        );
    }
    for k in y0 as i32..=y1 as i32 {
        let y = py(k as f64);
        let _ = writeln!(
            s,
            "<line x1=\"{margin}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\" stroke=\"#ddd\"/><text x=\"{}\" y=\"{}\" text-anchor=\"end\">1e{k}</text>",
            w - right,
            margin - 6.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">nanoseconds per wall-event prediction</text>",
        (w - right + margin) / 2.0,
        h - 20.0
    );
    let _ = writeln!(
        s,
        "<text x=\"18\" y=\"{}\" transform=\"rotate(-90 18 {})\" text-anchor=\"middle\">largest |dt| error (sqrt(d/g))</text>",
        h / 2.0,
        h / 2.0
    );
    for (k, (r, (&x, &y))) in rows.iter().zip(xs.iter().zip(&ys)).enumerate() {
        let (cx, cy) = (px(x), py(y));
        // Alternate labels above and below so neighbouring markers stay readable.
        let label_dy = if k % 2 == 0 { -7.0 } else { 15.0 };
        let colour = if r.wrong_fraction > 0.0 {
            "#c0392b"
        } else {
            "#2c3e50"
        };
        let marker = match r.solver {
            "exact" => format!("<circle cx=\"{cx}\" cy=\"{cy}\" r=\"5\""),
            "table" => format!(
                "<polygon points=\"{},{cy} {cx},{} {},{cy} {cx},{}\"",
                cx - 6.0,
                cy - 6.0,
                cx + 6.0,
                cy + 6.0
            ),
            _ => format!(
                "<rect x=\"{}\" y=\"{}\" width=\"10\" height=\"10\"",
                cx - 5.0,
                cy - 5.0
            ),
        };
        let _ = writeln!(s, "{marker} fill=\"{colour}\"/>");
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\">{} {} ({:.2}% wrong)</text>",
            cx + 8.0,
            cy + label_dy,
            r.solver,
            r.knob,
            100.0 * r.wrong_fraction
        );
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_solver_has_no_wrong_roots_and_errors_shrink_with_tolerance() {
        let rows = measure(1, 0.05);
        let exact: Vec<&WallRow> = rows.iter().filter(|r| r.solver == "exact").collect();
        // A loose gap tolerance can land far from a grazing root in time (counted as wrong);
        // from 1e-8 on, every root is the reference's.
        assert!(
            exact[1..].iter().all(|r| r.wrong_fraction == 0.0),
            "{exact:?}"
        );
        assert!(exact.last().unwrap().max_error < exact.first().unwrap().max_error);
        // A coarse bracket misses grazing roots that the fine one catches.
        let bracket: Vec<&WallRow> = rows.iter().filter(|r| r.solver == "bracket").collect();
        assert!(bracket.first().unwrap().wrong_fraction >= bracket.last().unwrap().wrong_fraction);
        // The checked table finds the reference's root on every shot; finer tables err less.
        let table: Vec<&WallRow> = rows
            .iter()
            .filter(|r| r.solver == "table" && !r.knob.contains("no check"))
            .collect();
        assert!(table.iter().all(|r| r.wrong_fraction == 0.0), "{table:?}");
        assert!(table.last().unwrap().max_error < table.first().unwrap().max_error);
        // The plot has one marker per setting.
        let plot = svg(&rows);
        let markers = plot.matches("<circle").count()
            + plot.matches("<rect x=").count()
            + plot.matches("<polygon").count();
        assert_eq!(markers, rows.len());
    }
}
