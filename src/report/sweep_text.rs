//! The text of the sweep commands: `sweep status` per sweep (jobs, convergence, hysteresis, time
//! spent and left, trust, left-out and failed points), the grid points a sweep file leaves out,
//! durations, the lines of `sweep estimate`, of `sweep resume --extend` and of a refinement. Pure functions of the stored
//! rows and the figures measured.

use super::trust::{LABEL_KEPT, NOT_STATIONARY, mark};
use crate::run::runner::{point_label, short};
use crate::store::{LeftOut, PointSummary, RunningJob, Stale, StateCounts, SweepRow};
use crate::sweep::estimate::{MeasuredRuns, SweepCost};
use crate::terminal::escape;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use wetgran_core::observe::trend::TrendState;

/// A duration in seconds, minutes, hours or days, whichever reads best.
pub fn duration_text(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.1} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else if s < 3.0 * 86400.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.1} days", s / 86400.0)
    }
}

/// One line per left-out point: its coordinates and the constraint it fails.
pub fn left_out_text(axes: &[crate::sweep::Axis], left_out: &[LeftOut]) -> String {
    let labels: Vec<&str> = axes.iter().map(|a| a.label.as_str()).collect();
    let mut out = String::new();
    for k in left_out {
        let coords = coords_text(&labels, &k.coords);
        let _ = writeln!(out, "  left out {coords}: {}", escape(&k.constraint));
    }
    out
}

/// What `sweep status` reads of one sweep: `counts` its job counts, `points` its stored points
/// (`Store::point_summaries`), `spent` the wall time of its finished jobs (s), `cores` those the
/// time left is counted on, `running` its running jobs with their runners
/// (`Store::running_jobs`) and `now` the time they are judged at (stale or live).
#[derive(Debug)]
pub struct StatusInput<'a> {
    pub sweep: &'a SweepRow,
    pub counts: StateCounts,
    pub points: &'a [PointSummary],
    pub spent: f64,
    pub cores: usize,
    pub running: &'a [RunningJob],
    pub now: f64,
}

impl StatusInput<'_> {
    /// The running jobs whose runner is gone or silent, with why.
    pub fn stale(&self) -> Vec<(&RunningJob, Stale)> {
        self.running
            .iter()
            .filter_map(|j| j.stale(self.now).map(|s| (j, s)))
            .collect()
    }

    /// The mean wall seconds of the finished jobs (`None` before the first).
    fn mean_wall(&self) -> Option<f64> {
        let walls: Vec<f64> = self
            .points
            .iter()
            .filter(|p| p.status == "done")
            .filter_map(|p| p.wall_seconds)
            .collect();
        (!walls.is_empty()).then(|| walls.iter().sum::<f64>() / walls.len() as f64)
    }

    /// Seconds left on `cores` (`None`: unknown until a job finishes, or nothing left).
    pub fn time_left(&self) -> Option<f64> {
        let left = self.counts.pending + self.counts.running;
        (left > 0)
            .then(|| self.mean_wall())
            .flatten()
            .map(|m| m * left as f64 / self.cores as f64)
    }
}

/// The stale jobs of a sweep by runner: `(owner, jobs, why)` in order of first appearance.
fn stale_by_owner<'a>(stale: &[(&'a RunningJob, Stale)]) -> Vec<(&'a str, usize, Stale)> {
    let mut out: Vec<(&str, usize, Stale)> = Vec::new();
    for (j, why) in stale {
        let owner = j.owner.as_deref().unwrap_or("unknown runner");
        match out.iter_mut().find(|(o, _, _)| *o == owner) {
            Some(e) => e.1 += 1,
            None => out.push((owner, 1, *why)),
        }
    }
    out
}

/// The heartbeat age of a stale job in words.
fn heartbeat_text(why: &Stale) -> String {
    let age = match why.heartbeat_age {
        Some(a) => format!("last heartbeat {} ago", duration_text(a)),
        None => "no heartbeat".to_string(),
    };
    if why.process_gone {
        format!("its process is gone, {age}")
    } else {
        format!("silent, {age}")
    }
}

/// The `hysteresis` lines of `sweep status`: how many points' start modes disagree, and each
/// such point with the labels of its start modes.
fn hysteresis_text(out: &mut String, s: &SweepRow, points: &[PointSummary]) {
    let starts = crate::store::hysteresis::by_start(&s.axes, points);
    let compared = starts.iter().filter(|g| g.compared()).count();
    if compared > 0 {
        let _ = writeln!(
            out,
            "  hysteresis  {} of {compared} point(s) hysteretic (their start modes disagree)",
            starts.iter().filter(|g| g.hysteretic).count()
        );
        for g in starts.iter().filter(|g| g.hysteretic) {
            let labels: Vec<String> = g
                .by_start
                .iter()
                .map(|(mode, l)| format!("{mode} {}", l.join("/")))
                .collect();
            let at: Vec<String> = s
                .axes
                .iter()
                .filter(|a| a.key != "initial.start")
                .zip(&g.coords)
                .map(|(a, v)| format!("{} = {v}", a.label))
                .collect();
            let at = if at.is_empty() {
                "the base scene".to_string()
            } else {
                at.join(", ")
            };
            let _ = writeln!(out, "    {at}: {}", labels.join(", "));
        }
    }
}

/// The trend states of the finished results, counted.
fn trend_counts(points: &[PointSummary]) -> BTreeMap<TrendState, usize> {
    let mut trends = BTreeMap::new();
    for t in points
        .iter()
        .filter(|p| p.status == "done")
        .filter_map(|p| p.trend)
    {
        *trends.entry(t).or_insert(0) += 1;
    }
    trends
}

/// The `trend` and `trust` lines of `sweep status`: the trends of the finished results, and how
/// many of the `done` results are not stationary.
fn trust_text(out: &mut String, points: &[PointSummary], done: u64) {
    let trends = trend_counts(points);
    if !trends.is_empty() {
        let counts: Vec<String> = trends.iter().map(|(t, n)| format!("{n} {t}")).collect();
        let _ = writeln!(out, "  trend  {}", counts.join(", "));
    }
    let marked = |m: char| {
        points
            .iter()
            .filter(|p| p.status == "done")
            .filter(|p| mark(p.trust()) == Some(m))
            .count()
    };
    let (may_change, kept) = (marked(NOT_STATIONARY), marked(LABEL_KEPT));
    if may_change + kept > 0 {
        let _ = writeln!(
            out,
            "  trust  {} of {} result(s) not stationary: {may_change} not settled, the label may \
             change ({} in `boundaries`, left out of them), {kept} label kept ({}: every region \
             the label names settled, some numbers still drift); see `show JOB`",
            may_change + kept,
            done,
            NOT_STATIONARY,
            LABEL_KEPT
        );
    }
}

/// The `sweep status` lines of one sweep (see [`StatusInput`]).
pub fn sweep_status_text(input: &StatusInput) -> String {
    let (s, c, points, spent, cores) = (
        input.sweep,
        &input.counts,
        input.points,
        input.spent,
        input.cores,
    );
    let stale = input.stale();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "sweep {}  ({}; {} point(s) x {} replica(s))",
        escape(&s.name),
        escape(&s.file),
        points.len() as u64 / s.replicas.max(1) as u64,
        s.replicas
    );
    if let Some(d) = &s.description {
        let _ = writeln!(out, "  {}", escape(d));
    }
    if let Some(cost) = &s.cost {
        let _ = writeln!(out, "  cost: {}", escape(cost));
    }
    let live = (c.running as usize).saturating_sub(stale.len());
    let running = if stale.is_empty() {
        format!("{} running", c.running)
    } else {
        format!("{live} running, {} stale", stale.len())
    };
    let _ = writeln!(
        out,
        "  jobs   {} total: {} done, {running}, {} pending, {} failed",
        c.total(),
        c.done,
        c.pending,
        c.failed
    );
    for (owner, n, why) in stale_by_owner(&stale) {
        let _ = writeln!(
            out,
            "  stale  {n} job(s) of runner {} ({}): not running; `sweep resume` runs them \
             again",
            escape(owner),
            heartbeat_text(&why)
        );
    }
    let (unconverged, checked) = crate::store::unconverged_summaries(points);
    if checked > 0 {
        // The hint to extend only where a run stopped at its cap (issue 45).
        let hint = if unconverged > 0 {
            " (`sweep resume --extend` runs those further; the trend and trust lines say whether \
             a label may still change)"
        } else {
            ""
        };
        let _ = writeln!(
            out,
            "  run end  {} of {checked} result(s) passed the run policy's convergence test, \
             {unconverged} stopped at its cap{hint}",
            checked - unconverged
        );
    }
    hysteresis_text(&mut out, s, points);
    let left = c.pending + c.running;
    let estimate = match (left, input.mean_wall(), input.time_left()) {
        (0, _, _) => "nothing left".to_string(),
        (_, None, _) | (_, _, None) => "time left unknown until a job finishes".to_string(),
        (_, Some(mean), Some(t)) if live == 0 && !stale.is_empty() => format!(
            "no runner is working on it: {left} job(s) left, about {} on {cores} core(s) once \
             resumed ({} mean)",
            duration_text(t),
            duration_text(mean)
        ),
        (_, Some(mean), Some(t)) => format!(
            "about {} left on {cores} core(s) ({left} job(s) x {} mean)",
            duration_text(t),
            duration_text(mean)
        ),
    };
    let _ = writeln!(
        out,
        "  time   {} spent in finished jobs; {estimate}",
        duration_text(spent)
    );
    trust_text(&mut out, points, c.done);
    if !s.left_out.is_empty() {
        let _ = writeln!(
            out,
            "  left out {} grid point(s) (sweep.skip_invalid):",
            s.left_out.len()
        );
        out.push_str(&left_out_text(&s.axes, &s.left_out));
    }
    for p in points.iter().filter(|p| p.status == "failed") {
        let _ = writeln!(
            out,
            "  failed {} (job {}, {} attempt(s)): {}",
            point_label(s, &p.coords, p.replica),
            p.job_id.get(..12).unwrap_or(&p.job_id),
            p.attempts,
            escape(p.last_error.as_deref().unwrap_or("no message"))
        );
    }
    out
}

/// The line reporting a refinement of sweep `sweep`: jobs added, rounds, whether every boundary
/// edge is resolved.
pub fn refinement_text(sweep: &str, added: usize, rounds: usize, resolved: bool) -> String {
    format!(
        "sweep {sweep}: refinement added {added} job(s) in {rounds} round(s){}",
        if resolved {
            "; every boundary edge is resolved"
        } else {
            ""
        }
    )
}

/// `label = value, ...` of a grid point (numbers in short form).
pub fn coords_text(labels: &[&str], coords: &[serde_json::Value]) -> String {
    let coords: Vec<String> = labels
        .iter()
        .zip(coords)
        .map(|(l, v)| match v.as_f64() {
            Some(x) => format!("{l} = {}", short(x)),
            None => format!("{l} = {v}"),
        })
        .collect();
    coords.join(", ")
}

/// The first line of `sweep estimate`.
pub fn estimate_head_text(
    file: &str,
    jobs: usize,
    sampled: usize,
    periods: f64,
    settle: f64,
) -> String {
    let after = if settle > 0.0 {
        format!(" after {} settling time unit(s)", short(settle))
    } else {
        " from the initial state".to_string()
    };
    format!(
        "{file}: {jobs} job(s); sampling {sampled} for {} driving period(s) each{after}, one at \
         a time\n",
        short(periods)
    )
}

/// The line of one job `sweep estimate` sampled.
pub fn estimate_sample_text(
    coords: &str,
    seconds_per_period: f64,
    seconds_per_time: f64,
    events: u64,
) -> String {
    format!(
        "  {coords:<40} {seconds_per_period:>9.3} s per period, {seconds_per_time:>9.5} s per \
         time unit  ({events} events run)\n"
    )
}

/// The line of a sampled job whose result the database holds.
pub fn estimate_stored_text(coords: &str, seconds_per_time: f64) -> String {
    format!("  {coords:<40} stored: {seconds_per_time:>9.5} s per time unit over its whole run\n")
}

/// The line of a sampled job that failed.
pub fn estimate_failed_text(coords: &str, error: &str) -> String {
    format!("  {coords:<40} failed: {error}\n")
}

/// The closing lines of `sweep estimate`: what the stored results say, then per assumption on
/// the run lengths the job time (the jobs' wall times summed: a job on several threads uses
/// more CPU) and the wall time on the cores, of the whole sweep and of what
/// is left to run.
pub fn estimate_text(
    jobs: usize,
    cores: usize,
    measured: Option<&MeasuredRuns>,
    lines: &[(String, SweepCost, SweepCost)],
    by_start: &[Vec<(String, usize, f64)>],
    settle: f64,
    periods: f64,
) -> String {
    let mut out = String::new();
    if let Some(m) = measured {
        let _ = writeln!(
            out,
            "stored: {} of the {jobs} jobs finished in the database ({} of job time); their runs \
             were {:.2} x their first check on average, {} ran past it, {} unconverged at the cap",
            m.jobs,
            duration_text(m.wall_seconds),
            m.mean_length_factor,
            m.extended,
            m.unconverged
        );
    }
    let _ = writeln!(
        out,
        "estimate on {cores} worker(s), the runner's claim order (wall time of the whole sweep; \
         of what is left to run):"
    );
    for (k, (label, whole, left)) in lines.iter().enumerate() {
        let _ = write!(
            out,
            "  {label}:\n    {} of job time (the jobs' wall times summed), {} wall (longest \
             job {})",
            duration_text(whole.job_seconds),
            duration_text(whole.wall_seconds),
            duration_text(whole.longest_job)
        );
        if measured.is_some() {
            let _ = write!(out, "; left: {} wall", duration_text(left.wall_seconds));
        }
        out.push('\n');
        // A sweep of several starts (hot and cold branch): the job time of each.
        if let Some(split) = by_start.get(k).filter(|s| s.len() > 1) {
            let parts: Vec<String> = split
                .iter()
                .map(|(mode, n, seconds)| {
                    format!(
                        "{} {n} job(s) {} of job time",
                        crate::boundary::branch_words(mode),
                        duration_text(*seconds)
                    )
                })
                .collect();
            let _ = writeln!(out, "    by start: {}", parts.join(", "));
        }
    }
    let _ = writeln!(
        out,
        "  (unstored jobs: the rate of the nearest sampled or stored job on the grid, from {} \
         period(s){}; a stored job counts what it cost)",
        short(periods),
        if settle > 0.0 {
            format!(" after {} settling time unit(s)", short(settle))
        } else {
            " from the initial state: a settled run can cost more or less per period, use \
             --settle"
                .to_string()
        }
    );
    out
}

/// What `sweep resume --extend` did: jobs extended, now converged, left as they were under the
/// cap of `max_periods`, and the failures (one line each).
pub fn extended_text(
    extended: usize,
    converged: usize,
    skipped: usize,
    cap: &str,
    failed: &[String],
) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "extended {extended} unconverged job(s) from their checkpoints, {converged} now \
         converged; {skipped} left as they were (no checkpoint, or the cap of {cap} leaves \
         no room); {} failed",
        failed.len()
    );
    for f in failed {
        let _ = writeln!(out, "  {f}");
    }
    out
}

/// `sweep status --json` of one sweep: the figures of [`sweep_status_text`] as one object.
pub fn sweep_status_json(input: &StatusInput) -> serde_json::Value {
    use serde_json::json;
    let (s, c, points) = (input.sweep, &input.counts, input.points);
    let stale = input.stale();
    let live = (c.running as usize).saturating_sub(stale.len());
    let (unconverged, checked) = crate::store::unconverged_summaries(points);
    let starts = crate::store::hysteresis::by_start(&s.axes, points);
    let trends: BTreeMap<String, usize> = trend_counts(points)
        .into_iter()
        .map(|(t, n)| (t.to_string(), n))
        .collect();
    let stale_runners: Vec<_> = stale_by_owner(&stale)
        .into_iter()
        .map(|(owner, n, why)| {
            json!({
                "owner": owner, "jobs": n, "process_gone": why.process_gone,
                "heartbeat_age_s": why.heartbeat_age,
            })
        })
        .collect();
    let failed: Vec<_> = points
        .iter()
        .filter(|p| p.status == "failed")
        .map(|p| {
            json!({
                "point": p.point, "replica": p.replica, "coords": p.coords,
                "job_id": p.job_id, "attempts": p.attempts, "error": p.last_error,
            })
        })
        .collect();
    json!({
        "sweep": s.name,
        "file": s.file,
        "description": s.description,
        "points": points.len() as u64 / s.replicas.max(1) as u64,
        "replicas": s.replicas,
        "jobs": {
            "total": c.total(), "done": c.done, "running": live, "stale": stale.len(),
            "pending": c.pending, "failed": c.failed,
        },
        "stale_runners": stale_runners,
        "results_with_verdict": checked,
        "unconverged": unconverged,
        "hysteretic_points": starts.iter().filter(|g| g.hysteretic).count(),
        "compared_points": starts.iter().filter(|g| g.compared()).count(),
        "trends": trends,
        "time_spent_s": input.spent,
        "time_left_s": input.time_left(),
        "cores": input.cores,
        "runner_working": live > 0,
        "left_out": s.left_out,
        "failed": failed,
    })
}
