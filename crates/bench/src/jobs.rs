//! `wetgran-bench jobs`: representative jobs of the shipped 2D elastic diagram
//! (`sweeps/shaken_2d_elastic.toml`: the 2D standard system, N = 1200, 400 d x 9 d, its
//! `[scene]`, `[observe]` and `[classify]` settings) at fixed length, run by this build's
//! `wetgran` and, with `--baseline PATH`, by another build's `wetgran` in the same minutes
//! (alternated job by job), as `wetgran sweep job SPEC`: the command both builds share.
//!
//! Per job and binary: events, events per CPU second and per wall second of the job, and,
//! where `perf` runs (`perf record -e cpu-clock`, one sample per CPU millisecond), where the
//! CPU time went, by the symbols sampled: the engine (`sim::event_driven`), wall prediction
//! (the shaken-wall solvers and the sines and cosines they call), the invariant checks, the
//! report samples, the observers (`observe`, frames), and the rest (start-up, allocation, the
//! kernel). Inlined code counts where it was inlined. The bulk system (a) of `engine` is timed
//! in this process for the rate the jobs are held against (goal: none below half of it).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;
use wetgran::sweep::{JobSpec, SweepFile};
use wetgran_core::sim::event_driven::Engine;
use wetgran_testkit::reference::system_a;

/// The representative jobs: label, Gamma, E*.
pub(crate) const JOBS: [(&str, f64, f64); 5] = [
    ("solid, high frequency", 30.0, 0.0022),
    ("dense fluid", 3.0, 0.7),
    ("fluid", 30.0, 0.7),
    ("coexistence", 30.0, 2.6),
    ("gas", 2.0, 3.0),
];

/// Simulated time units of every job at `--scale 1` (half of it the transient).
const BASE_LENGTH: f64 = 30.0;

/// The shipped sweep and its base scene, as built into this binary.
const ELASTIC_SWEEP: &str = include_str!("../../../sweeps/shaken_2d_elastic.toml");
const BASE_SCENE: &str = include_str!("../../../scenes/shaken_wet_2d.toml");

/// Where the CPU time of one run went, in CPU seconds (from `perf`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Shares {
    pub engine: f64,
    pub wall: f64,
    pub checks: f64,
    pub samples: f64,
    pub observers: f64,
    pub other: f64,
}

impl Shares {
    fn total(&self) -> f64 {
        self.engine + self.wall + self.checks + self.samples + self.observers + self.other
    }
}

/// One run of one job by one binary.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct JobRun {
    pub events: u64,
    pub simulated_time: f64,
    /// The job's own wall time (`wall_seconds` of its result).
    pub wall_seconds: f64,
    /// CPU time and its shares, where `perf` ran.
    pub shares: Option<Shares>,
}

impl JobRun {
    fn cpu(&self) -> Option<f64> {
        self.shares.map(|s| s.total())
    }
}

/// The figures of one job: its runs by this build and by the baseline.
#[derive(Debug, Clone)]
pub(crate) struct JobRow {
    pub label: &'static str,
    pub gamma: f64,
    pub e_star: f64,
    pub ours: Vec<JobRun>,
    pub baseline: Vec<JobRun>,
}

/// The spec of a representative job: the shipped elastic sweep at `(gamma, e_star)`, hot
/// start, run for `length` time units (no run policy: every build does the same work), the
/// window the second half.
pub(crate) fn job_spec(
    dir: &Path,
    gamma: f64,
    e_star: f64,
    length: f64,
) -> Result<JobSpec, String> {
    let e = |m: &dyn std::fmt::Display| m.to_string();
    std::fs::write(dir.join("shaken_wet_2d.toml"), BASE_SCENE).map_err(|m| e(&m))?;
    let head = ELASTIC_SWEEP
        .split("[[axis]]")
        .next()
        .expect("split yields a first part");
    let continuation = "[sweep.continuation]\naxis = \"e_star\"\ndirection = \"descending\"\n";
    let text = format!(
        "{}\n[[axis]]\nkey = \"gamma\"\nvalues = [{gamma:?}]\n\n[[axis]]\nkey = \"e_star\"\n\
         values = [{e_star:?}]\n",
        head.replace(continuation, "")
            .replace("../scenes/shaken_wet_2d.toml", "shaken_wet_2d.toml")
    );
    let path = dir.join("job.toml");
    std::fs::write(&path, text).map_err(|m| e(&m))?;
    let file = SweepFile::load(&path).map_err(|m| e(&m))?;
    let mut jobs = file.expand().map_err(|m| e(&m))?;
    if jobs.len() != 1 {
        return Err(format!("expected one job, got {}", jobs.len()));
    }
    let mut spec = jobs.remove(0).spec;
    spec.scene.convergence = None;
    spec.scene.run.duration = length;
    spec.scene.observe.transient_periods = 0.0;
    spec.scene.observe.transient_time = 0.5 * length;
    Ok(spec)
}

/// Whether `perf record` works here.
fn perf_works() -> bool {
    Command::new("perf")
        .args([
            "record",
            "-q",
            "-e",
            "cpu-clock",
            "-o",
            "/dev/null",
            "--",
            "true",
        ])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Runs `wetgran sweep job SPEC` of the binary `bin` (under `perf` if `perf`).
fn run_job(bin: &Path, spec: &Path, dir: &Path, perf: bool) -> Result<JobRun, String> {
    let data = dir.join("perf.data");
    let mut cmd = if perf {
        let mut c = Command::new("perf");
        c.args(["record", "-q", "-e", "cpu-clock", "-c", "1000000", "-o"])
            .arg(&data)
            .arg("--")
            .arg(bin);
        c
    } else {
        Command::new(bin)
    };
    let out = cmd
        .args(["sweep", "job"])
        .arg(spec)
        .output()
        .map_err(|e| format!("cannot run {}: {e}", bin.display()))?;
    if !out.status.success() {
        return Err(format!(
            "{} sweep job failed: {}",
            bin.display(),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)
        .map_err(|e| format!("{}: unreadable job result: {e}", bin.display()))?;
    let r = &v["result"];
    let number = |k: &str| r[k].as_f64().ok_or(format!("no `{k}` in the job result"));
    Ok(JobRun {
        events: number("events")? as u64,
        simulated_time: number("simulated_time")?,
        wall_seconds: number("wall_seconds")?,
        shares: if perf {
            Some(perf_shares(&data)?)
        } else {
            None
        },
    })
}

/// The CPU seconds of a `perf record -c 1000000` profile by part (see the module doc).
fn perf_shares(data: &Path) -> Result<Shares, String> {
    let out = Command::new("perf")
        .args([
            "report",
            "--stdio",
            "--no-children",
            "--sort",
            "sym",
            "-F",
            "sample,sym",
            "-i",
        ])
        .arg(data)
        .output()
        .map_err(|e| format!("cannot run perf report: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    let mut s = Shares::default();
    for line in text.lines() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let Some((count, symbol)) = line.split_once(char::is_whitespace) else {
            continue;
        };
        let Ok(n) = count.parse::<f64>() else {
            continue;
        };
        let seconds = n * 1e-3;
        *part(&mut s, symbol) += seconds;
    }
    Ok(s)
}

/// The part of [`Shares`] a sampled symbol belongs to.
fn part<'a>(s: &'a mut Shares, symbol: &str) -> &'a mut f64 {
    let any = |names: &[&str]| names.iter().any(|n| symbol.contains(n));
    if any(&[
        "sanity_check",
        "quick_check",
        "pair_check",
        "neighbour_check",
        "CellSource<_>::check",
        "for_each_near",
        "FnMut<A> for &mut F>::call_mut",
    ]) {
        &mut s.checks
    } else if any(&[
        "shaken_wall::",
        "WallSource::predict",
        "WallSource::search",
        "WallSource::resume",
        "shaken_wall_times",
        "wall_table",
        "sincos",
        "__sin_fma",
        "__cos_fma",
    ]) {
        &mut s.wall
    } else if any(&[
        "Simulation>::energy",
        "granular_temperature",
        "Simulation>::sample",
    ]) {
        &mut s.samples
    } else if any(&[
        "observe::",
        "Simulation>::frame",
        "Frame::",
        "spade::",
        ">::bridges",
    ]) {
        &mut s.observers
    } else if any(&["sim::event_driven", "with_engine"]) {
        &mut s.engine
    } else {
        &mut s.other
    }
}

/// Events per CPU second of the bulk system (a) in this process: 500 000 events after a
/// warm-up of 50 000 (times `scale`), the median of `repeat`.
pub(crate) fn bulk_rate(repeat: usize, scale: f64) -> Result<f64, String> {
    let scene = system_a();
    let events = ((500_000.0 * scale) as u64).max(5_000);
    let rates: Vec<f64> = (0..repeat.max(1))
        .map(|_| {
            let mut e = Engine::<3, false, false>::new(&scene);
            e.run_until(f64::INFINITY, Some(events / 10));
            let (n0, c0) = (e.counts().total(), crate::tdmd::thread_cpu_seconds());
            let t0 = Instant::now();
            e.run_until(f64::INFINITY, Some(n0 + events));
            let cpu = crate::tdmd::thread_cpu_seconds()
                .zip(c0)
                .map_or(t0.elapsed().as_secs_f64(), |(b, a)| b - a);
            (e.counts().total() - n0) as f64 / cpu.max(1e-9)
        })
        .collect();
    Ok(crate::median(&rates))
}

/// Runs every job `repeat` times with this build's `wetgran` (beside this binary) and, if
/// given, the baseline's, alternated job by job.
pub(crate) fn measure(
    repeat: usize,
    scale: f64,
    baseline: Option<&Path>,
) -> Result<(Vec<JobRow>, bool), String> {
    let ours = sibling("wetgran")?;
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let perf = perf_works();
    let mut rows = Vec::new();
    for (label, gamma, e_star) in JOBS {
        let spec = job_spec(dir.path(), gamma, e_star, BASE_LENGTH * scale)?;
        let path = dir.path().join("spec.json");
        std::fs::write(
            &path,
            serde_json::to_string(&spec).map_err(|e| e.to_string())?,
        )
        .map_err(|e| e.to_string())?;
        let mut row = JobRow {
            label,
            gamma,
            e_star,
            ours: vec![],
            baseline: vec![],
        };
        for _ in 0..repeat.max(1) {
            if let Some(b) = baseline {
                row.baseline.push(run_job(b, &path, dir.path(), perf)?);
            }
            row.ours.push(run_job(&ours, &path, dir.path(), perf)?);
        }
        rows.push(row);
    }
    Ok((rows, perf))
}

/// The binary `name` beside this one.
fn sibling(name: &str) -> Result<PathBuf, String> {
    let me = std::env::current_exe().map_err(|e| e.to_string())?;
    let path = me.with_file_name(name);
    path.exists()
        .then_some(path)
        .ok_or(format!("no `{name}` beside {}", me.display()))
}

/// The table: per job and binary the medians over the repetitions.
pub(crate) fn report(rows: &[JobRow], perf: bool, bulk: f64) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "representative jobs of sweeps/shaken_2d_elastic.toml (N = 1200, 400 x 9, hot start, fixed \
         length); bulk system (a): {:.3} M events per CPU second",
        bulk * 1e-6
    );
    let _ = writeln!(
        out,
        "{:<22} {:>6} {:>7} {:<5} {:>9} {:>8} {:>8} {:>9} {:>8} {:>7} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6}",
        "job",
        "Gamma",
        "E*",
        "bin",
        "events",
        "wall s",
        "CPU s",
        "Mev/CPUs",
        "Mev/wall",
        "/bulk",
        "engine",
        "walls",
        "checks",
        "sampl",
        "observ",
        "other"
    );
    for r in rows {
        for (name, runs) in [("main", &r.baseline), ("ours", &r.ours)] {
            if runs.is_empty() {
                continue;
            }
            let events = runs[0].events as f64;
            let wall = crate::median(&runs.iter().map(|x| x.wall_seconds).collect::<Vec<_>>());
            let cpu = perf
                .then(|| crate::median(&runs.iter().filter_map(JobRun::cpu).collect::<Vec<_>>()));
            let share = |f: fn(&Shares) -> f64| {
                let v: Vec<f64> = runs
                    .iter()
                    .filter_map(|x| x.shares.map(|s| 100.0 * f(&s) / s.total().max(1e-12)))
                    .collect();
                if v.is_empty() {
                    f64::NAN
                } else {
                    crate::median(&v)
                }
            };
            let per_cpu = cpu.map_or(f64::NAN, |c| events / c);
            let _ = writeln!(
                out,
                "{:<22} {:>6} {:>7} {:<5} {:>9} {:>8.2} {:>8.2} {:>9.3} {:>8.3} {:>7.2} {:>5.1}% {:>5.1}% {:>5.1}% {:>5.1}% {:>5.1}% {:>5.1}%",
                r.label,
                r.gamma,
                r.e_star,
                name,
                runs[0].events,
                wall,
                cpu.unwrap_or(f64::NAN),
                per_cpu * 1e-6,
                events / wall * 1e-6,
                per_cpu / bulk,
                share(|s| s.engine),
                share(|s| s.wall),
                share(|s| s.checks),
                share(|s| s.samples),
                share(|s| s.observers),
                share(|s| s.other),
            );
        }
        if let (Some(a), Some(b)) = (r.baseline.first(), r.ours.first())
            && a.events != b.events
        {
            let _ = writeln!(
                out,
                "  note: the two builds processed different event counts"
            );
        }
        let ratio = |runs: &[JobRun]| {
            crate::median(&runs.iter().filter_map(JobRun::cpu).collect::<Vec<_>>())
        };
        if perf && !r.baseline.is_empty() {
            let _ = writeln!(
                out,
                "  ours against main: {:.2}x per CPU second, {:.2}x per wall second of the job",
                ratio(&r.baseline) / ratio(&r.ours),
                crate::median(
                    &r.baseline
                        .iter()
                        .map(|x| x.wall_seconds)
                        .collect::<Vec<_>>()
                ) / crate::median(&r.ours.iter().map(|x| x.wall_seconds).collect::<Vec<_>>())
            );
        }
    }
    if !perf {
        out.push_str("perf is not available here: no CPU seconds or shares (install linux-perf)\n");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_job_is_the_shipped_sweep_at_its_point_for_a_fixed_length() {
        let dir = tempfile::tempdir().unwrap();
        let spec = job_spec(dir.path(), 30.0, 0.0022, 12.0).unwrap();
        let s = &spec.scene;
        assert_eq!(s.particles.count, 1200);
        assert_eq!(s.container.size, vec![400.0, 9.0]);
        assert_eq!(s.contact.restitution, 1.0);
        assert_eq!(s.engine.min_rebound_speed, 0.03);
        assert_eq!(s.drive.gamma, Some(30.0));
        assert_eq!(s.drive.e_star, Some(0.0022));
        assert_eq!(s.observe.min_sample_interval, 0.05);
        assert!(s.convergence.is_none(), "fixed length: no run policy");
        assert_eq!((s.run.duration, s.observe.transient_time), (12.0, 6.0));
    }

    #[test]
    fn sampled_symbols_go_to_their_part() {
        let mut s = Shares::default();
        for (symbol, n) in [
            (
                "wetgran_core::sim::event_driven::pairs::PairSource<_,_>::scan",
                1.0,
            ),
            ("wetgran_core::physics::shaken_wall::exact_root_until", 2.0),
            ("__sincos_fma", 4.0),
            ("<Engine<_,_,_,_,Q> as Simulation>::sanity_check", 8.0),
            (
                "wetgran_core::observe::lateral::LateralObserver::observe",
                16.0,
            ),
            ("<Engine<_,_,_,_,Q> as Simulation>::sample", 32.0),
            ("_int_malloc", 64.0),
        ] {
            *part(&mut s, symbol) += n;
        }
        assert_eq!(
            s,
            Shares {
                engine: 1.0,
                wall: 6.0,
                checks: 8.0,
                samples: 32.0,
                observers: 16.0,
                other: 64.0,
            }
        );
    }
}
