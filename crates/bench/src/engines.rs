//! `wetgran-bench engines`: the event-driven and the time-driven engine on the same scene, the
//! 2D standard wet system (docs/model.md 1: N = 1200, 400 x 9, `sigma_p` 0.06, thin thread, elastic
//! walls, eps 0.96, hot start `T_g / E_cb = 20`; the scene of crates/core/tests/engines_like.rs), whose
//! time-driven twin differs only in `engine.kind = "time"` (restitution converted by the
//! default calibration, `contact.restitution_speed = "auto"`).
//!
//! At each of three points (gas Gamma 2 E* 3, fluid Gamma 30 E* 0.7, coexistence Gamma 30
//! E* 2.6), `repeat` times, alternately event then time engine: a fresh engine (same seed) runs
//! [`WARM_UP`] time units untimed (the hot start cools), then `MEASURED * scale` time units
//! timed on one core (a one-thread pool), wall clock and the thread's CPU time. Reported per point and engine: the medians of
//! wall and CPU seconds per simulated time unit, and the ratio time / event (CPU where known).
//! The engines run in one process, one after the other, so both see the same machine load.

use super::median;
use super::observer::{POINTS, standard_shaken};
use super::tdmd::thread_cpu_seconds;
use std::fmt::Write as _;
use std::time::Instant;
use wetgran_core::scene::{EngineKind, Scene};
use wetgran_core::sim::{Frame, RunSettings, run_scene_observed};

/// Untimed time units before the timed part.
pub(crate) const WARM_UP: f64 = 10.0;
/// Timed time units at `scale = 1`.
pub(crate) const MEASURED: f64 = 5.0;
/// Restitution of crates/core/tests/engines_like.rs (`sweeps/shaken_2d_eps096.toml`).
pub(crate) const EPS: f64 = 0.96;

/// One point and engine: seconds per simulated time unit, one value per repetition.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct EngineRow {
    pub label: &'static str,
    pub gamma: f64,
    pub e_star: f64,
    pub engine: &'static str,
    pub(crate) wall_per_time: Vec<f64>,
    pub(crate) cpu_per_time: Vec<f64>,
}

/// Wall and CPU seconds of the timed part of one run, on one core: the run happens inside an
/// installed one-thread rayon pool, so the time-driven engine steps on the thread whose CPU time
/// is read (without it the engine ran on a pool thread of its own and the calling thread's CPU
/// time was about zero).
fn time_one(scene: &Scene, measured: f64) -> (f64, Option<f64>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("one-thread pool");
    pool.install(|| {
        let mut start: Option<(Instant, Option<f64>)> = None;
        let mut end = None;
        run_scene_observed(
            scene,
            &RunSettings::default(),
            measured,
            &mut |f: &Frame| {
                if start.is_none() && f.time >= WARM_UP - 1e-9 {
                    start = Some((Instant::now(), thread_cpu_seconds()));
                } else if start.is_some() {
                    end = Some((Instant::now(), thread_cpu_seconds()));
                }
            },
            &mut |_| {},
        );
        let ((w0, c0), (w1, c1)) = (start.expect("warm-up ends"), end.expect("timed part ends"));
        ((w1 - w0).as_secs_f64(), c0.zip(c1).map(|(a, b)| b - a))
    })
}

/// Measures every point with both engines, interleaved.
pub(crate) fn measure(repeat: usize, scale: f64) -> Vec<EngineRow> {
    let measured = (MEASURED * scale).max(0.5);
    // The warm-up must end on a sample time: samples every `measured` time units.
    let warm = (WARM_UP / measured).ceil() * measured;
    let mut rows = Vec::new();
    for &(label, gamma, e_star) in &POINTS {
        let mut pair = ["event", "time"].map(|engine| EngineRow {
            label,
            gamma,
            e_star,
            engine,
            ..EngineRow::default()
        });
        for _ in 0..repeat {
            for (k, kind) in [EngineKind::Event, EngineKind::Time]
                .into_iter()
                .enumerate()
            {
                let mut s = standard_shaken(gamma, e_star, EPS, None, warm + measured);
                s.engine.kind = kind;
                s.validate("bench engines").expect("bench scene is valid");
                let (wall, cpu) = time_one(&s, measured);
                pair[k].wall_per_time.push(wall / measured);
                if let Some(c) = cpu {
                    pair[k].cpu_per_time.push(c / measured);
                }
            }
        }
        rows.extend(pair);
    }
    rows
}

/// The table: one line per point and engine, the ratio on the time engine's line.
pub(crate) fn report(rows: &[EngineRow], repeat: usize, scale: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "event- vs time-driven engine, 2D standard wet system (N 1200, 400x9, eps {EPS}, restitution_speed auto); \
         {WARM_UP} time units warm-up, {} timed, median of {repeat}, engines alternating",
        (MEASURED * scale).max(0.5)
    );
    s.push_str(
        "point        Gamma    E* engine     wall s/t      cpu s/t   wall ratio    cpu ratio\n",
    );
    for pair in rows.chunks(2) {
        let (e, t) = (&pair[0], &pair[1]);
        for r in [e, t] {
            let (w, c) = (median(&r.wall_per_time), median(&r.cpu_per_time));
            let (wr, cr) = if r.engine == "time" {
                (
                    format!("{:.1}x", w / median(&e.wall_per_time)),
                    format!("{:.1}x", c / median(&e.cpu_per_time)),
                )
            } else {
                (String::new(), String::new())
            };
            let _ = writeln!(
                s,
                "{:<12} {:>5} {:>5} {:>6} {:>12.4} {:>12.4} {:>12} {:>12}",
                r.label, r.gamma, r.e_star, r.engine, w, c, wr, cr
            );
        }
    }
    s
}
