//! What a sweep costs, before or while it runs (`wetgran sweep estimate`).
//!
//! Each job's wall time is a rate times a run length. The rate (wall seconds per simulated
//! time unit) comes from the job's own stored result when the database has it, else from the
//! nearest rate known on the grid: sampled short runs or other stored results. The run length
//! is what the job's policy sets: its first check (the minimum run), that times the extension
//! factor measured on the stored results of the sweep, or its cap. The wall time of the whole
//! sweep on `w` workers is not `job time / w`: [`makespan`] replays the runner's claim order (a
//! continuation job only once its predecessor has ended; a chain's next link before grid
//! order, as `claim_next_job.sql`), so the tail of lone long jobs and the waits along chains
//! are counted.
//!
//! A sweep that runs its points from more than one start (an `initial.start` axis: the hot and
//! the cold branch of an elastic diagram) is sampled in every start mode ([`sample_picks`]), and
//! an unmeasured job takes the nearest rate of its own start mode ([`nearest_rate`]): a bonded
//! bed and a hot gas at the same grid point cost different event rates.

use super::{JobError, JobSpec, SweepFile, SweepJob, run_job};
use std::collections::HashMap;
use std::time::Instant;

/// One job as the estimate sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedJob {
    /// Its grid point's index along each axis, scaled to `[0, 1]` (an axis of one value: 0).
    pub position: Vec<f64>,
    /// Simulated time of its minimum run (the first check under a `[convergence]` policy, the
    /// run length without one).
    pub first_check: f64,
    /// The longest run its policy allows (`first_check` without a policy).
    pub cap: f64,
    /// Index (in the job list) of the job whose final state it starts from.
    pub predecessor: Option<usize>,
    /// Its stored result's cost, if the database has one.
    pub measured: Option<MeasuredCost>,
    /// Its start mode (`initial.start`: hot, cold, continue).
    pub start: String,
}

/// A finished job's measured cost (`Store::finished_job_costs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredCost {
    /// Wall seconds of the attempt that finished, plus any extensions.
    pub wall_seconds: f64,
    /// The simulated time its run ended at.
    pub simulated_time: f64,
    /// Whether its label settled (`observe::settling::Verdict`; `None` for a result stored
    /// before verdicts).
    pub settled: Option<bool>,
}

/// A measured rate at a grid position.
#[derive(Debug, Clone, PartialEq)]
pub struct RateSample {
    pub position: Vec<f64>,
    /// Wall seconds per simulated time unit.
    pub seconds_per_time: f64,
    /// The start mode of the job it was measured on.
    pub start: String,
}

/// The run length an unmeasured job is assumed to run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RunLength {
    /// Stationary at its first check.
    FirstCheck,
    /// Its first check times a factor (the stored runs' mean), at most its cap.
    Extended(f64),
    /// Run to its cap.
    Cap,
}

/// The cost of a sweep under one assumption on the run lengths.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepCost {
    /// Sum of the jobs' wall times ("job time": a job on `t` threads uses up to `t` times that in
    /// CPU, so it is not called CPU time).
    pub job_seconds: f64,
    /// Wall time on the workers in the runner's claim order.
    pub wall_seconds: f64,
    /// The dearest single job.
    pub longest_job: f64,
}

/// What the stored results of a sweep's jobs say about run lengths.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredRuns {
    pub jobs: usize,
    /// Mean of `simulated time / first check` over them.
    pub mean_length_factor: f64,
    /// How many ran beyond their first check.
    pub extended: usize,
    /// How many ended with a label that had not settled (at their cap).
    pub unconverged: usize,
    /// Their summed wall seconds.
    pub wall_seconds: f64,
}

/// Summary of the measured jobs; `None` if there are none.
pub fn measured_runs(jobs: &[PlannedJob]) -> Option<MeasuredRuns> {
    let measured: Vec<(&PlannedJob, &MeasuredCost)> = jobs
        .iter()
        .filter_map(|j| j.measured.as_ref().map(|m| (j, m)))
        .collect();
    if measured.is_empty() {
        return None;
    }
    let n = measured.len();
    let factor = measured
        .iter()
        .map(|(j, m)| m.simulated_time / j.first_check)
        .sum::<f64>()
        / n as f64;
    Some(MeasuredRuns {
        jobs: n,
        mean_length_factor: factor,
        // A run that ended more than a part in 10^6 past its first check was extended.
        extended: measured
            .iter()
            .filter(|(j, m)| m.simulated_time > j.first_check * (1.0 + 1e-6))
            .count(),
        unconverged: measured
            .iter()
            .filter(|(_, m)| m.settled == Some(false))
            .count(),
        wall_seconds: measured.iter().map(|(_, m)| m.wall_seconds).sum(),
    })
}

/// The rate known nearest to `position` (Euclidean distance in the scaled grid; ties: the
/// first sample) among the samples of start mode `start`; from all samples when none has that
/// start. `None` without samples.
pub fn nearest_rate(samples: &[RateSample], position: &[f64], start: &str) -> Option<f64> {
    let dist = |s: &RateSample| -> f64 {
        s.position
            .iter()
            .zip(position)
            .map(|(a, b)| (a - b) * (a - b))
            .sum()
    };
    let same: Vec<&RateSample> = samples.iter().filter(|s| s.start == start).collect();
    let pool: Vec<&RateSample> = if same.is_empty() {
        samples.iter().collect()
    } else {
        same
    };
    // `min_by` keeps the first of equal distances.
    let nearest = pool.into_iter().min_by(|a, b| dist(a).total_cmp(&dist(b)));
    nearest.map(|s| s.seconds_per_time)
}

/// Which jobs `sweep estimate` samples (indices into `starts`, the start mode of each job in
/// grid order): `samples` spread evenly over the job list (one: the middle job). With more than
/// one start mode the samples are shared out among the modes (the first modes in order of
/// appearance get the remainder, every mode at least one), each mode's spread evenly over its
/// own jobs, so each branch's rate is measured. Sorted, without repeats.
pub fn sample_picks(starts: &[String], samples: usize) -> Vec<usize> {
    let spread = |n: usize, k: usize| -> Vec<usize> {
        if k >= n {
            (0..n).collect()
        } else if k == 1 {
            vec![n / 2]
        } else {
            (0..k)
                .map(|i| (i as f64 * (n - 1) as f64 / (k - 1) as f64).round() as usize)
                .collect()
        }
    };
    let mut modes: Vec<&str> = Vec::new();
    for s in starts {
        if !modes.contains(&s.as_str()) {
            modes.push(s);
        }
    }
    if modes.len() <= 1 || samples == 0 {
        return spread(starts.len(), samples.min(starts.len()));
    }
    let mut picks = Vec::new();
    for (m, mode) in modes.iter().enumerate() {
        let own: Vec<usize> = (0..starts.len()).filter(|&k| starts[k] == *mode).collect();
        let share = (samples / modes.len() + usize::from(m < samples % modes.len())).max(1);
        picks.extend(spread(own.len(), share).into_iter().map(|i| own[i]));
    }
    picks.sort_unstable();
    picks.dedup();
    picks
}

/// Each job's wall seconds under `length`: a measured job costs what it cost; another one its
/// nearest rate (`samples`, plus the rates of the measured jobs) times its run length.
/// `left_only`: measured jobs cost nothing (what is left to run).
pub fn job_seconds(
    jobs: &[PlannedJob],
    samples: &[RateSample],
    length: RunLength,
    left_only: bool,
) -> Vec<f64> {
    let mut rates: Vec<RateSample> = samples.to_vec();
    rates.extend(jobs.iter().filter_map(|j| {
        let m = j.measured?;
        (m.simulated_time > 0.0).then(|| RateSample {
            position: j.position.clone(),
            seconds_per_time: m.wall_seconds / m.simulated_time,
            start: j.start.clone(),
        })
    }));
    jobs.iter()
        .map(|j| match (j.measured, left_only) {
            (Some(_), true) => 0.0,
            (Some(m), false) => m.wall_seconds,
            (None, _) => {
                let run = match length {
                    RunLength::FirstCheck => j.first_check,
                    RunLength::Extended(f) => (j.first_check * f).min(j.cap),
                    RunLength::Cap => j.cap,
                };
                nearest_rate(&rates, &j.position, &j.start).unwrap_or(0.0) * run
            }
        })
        .collect()
}

/// Job time (summed wall times) and wall time of jobs costing `seconds` each on `workers` workers.
pub fn sweep_cost(jobs: &[PlannedJob], seconds: &[f64], workers: usize) -> SweepCost {
    let predecessors: Vec<Option<usize>> = jobs.iter().map(|j| j.predecessor).collect();
    SweepCost {
        job_seconds: seconds.iter().sum(),
        wall_seconds: makespan(seconds, &predecessors, workers),
        longest_job: seconds.iter().cloned().fold(0.0, f64::max),
    }
}

/// Wall time of running jobs of the given durations on `workers` workers, each free worker
/// claiming as the runner does (`claim_next_job.sql`): among the jobs whose predecessor has
/// ended (or that have none), first those a pending job waits for, then the lowest index. A
/// worker that finds nothing ready waits for the next job to end.
pub fn makespan(seconds: &[f64], predecessor: &[Option<usize>], workers: usize) -> f64 {
    let n = seconds.len();
    let workers = workers.max(1);
    let mut has_successor = vec![false; n];
    for p in predecessor.iter().flatten() {
        has_successor[*p] = true;
    }
    // End time of each claimed job; `None` while pending.
    let mut ends: Vec<Option<f64>> = vec![None; n];
    // Time at which each worker is free.
    let mut free = vec![0.0_f64; workers];
    let mut claimed = 0;
    while claimed < n {
        // The worker free first claims next.
        let w = (0..workers)
            .min_by(|&a, &b| free[a].total_cmp(&free[b]))
            .expect("at least one worker");
        let now = free[w];
        let ready = |k: usize| -> bool {
            ends[k].is_none() && predecessor[k].is_none_or(|p| ends[p].is_some_and(|e| e <= now))
        };
        let pick = (0..n)
            .filter(|&k| ready(k))
            .min_by_key(|&k| (!has_successor[k], k));
        match pick {
            Some(k) => {
                ends[k] = Some(now + seconds[k]);
                free[w] = now + seconds[k];
                claimed += 1;
            }
            None => {
                // Nothing ready: wait for the next end after `now` (a pending job's
                // predecessor is claimed, since chains are claimed in order).
                let next = ends
                    .iter()
                    .flatten()
                    .copied()
                    .filter(|&e| e > now)
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    next.is_finite(),
                    "a job waits for a predecessor never claimed"
                );
                free[w] = next;
            }
        }
    }
    ends.iter().flatten().copied().fold(0.0, f64::max)
}

/// The jobs of a sweep as the estimate sees them: grid position, run lengths, predecessor, and
/// the cost of those in `stored` (finished runs, by job id). `jobs` holds one job per id.
pub fn planned_jobs(
    sweep: &SweepFile,
    jobs: &[SweepJob],
    stored: &HashMap<String, MeasuredCost>,
) -> Vec<PlannedJob> {
    let lens: Vec<usize> = sweep.axes.iter().map(|a| a.values.len().max(1)).collect();
    let index: HashMap<&str, usize> = jobs
        .iter()
        .enumerate()
        .map(|(k, j)| (j.id.as_str(), k))
        .collect();
    jobs.iter()
        .map(|j| {
            let scene = &j.spec.scene;
            let (first_check, cap) = match &scene.convergence {
                Some(c) => {
                    let s = c.schedule(scene);
                    (s.first_check, s.cap)
                }
                None => (scene.run.duration, scene.run.duration),
            };
            PlannedJob {
                position: grid_position(j.point, &lens),
                first_check,
                cap,
                predecessor: j
                    .spec
                    .start_from
                    .as_deref()
                    .and_then(|p| index.get(p).copied()),
                measured: stored.get(&j.id).copied(),
                start: scene.initial.start.to_string(),
            }
        })
        .collect()
}

/// A grid point's index along each axis ([`super::spec::grid_index`]), scaled to `[0, 1]`.
fn grid_position(point: usize, lens: &[usize]) -> Vec<f64> {
    let index = super::spec::grid_index(point, lens);
    index
        .iter()
        .zip(lens)
        .map(|(&i, &len)| match len {
            1 => 0.0,
            _ => i as f64 / (len - 1) as f64,
        })
        .collect()
}

/// The spec a sampled job runs: `settle` time units, then `periods` driving periods, with no
/// convergence policy and no transient. A continuation job is sampled from the start of its
/// chain's first job.
pub fn sample_spec(sweep: &SweepFile, job: &SweepJob, settle: f64, periods: f64) -> JobSpec {
    let mut spec = job.spec.clone();
    if spec.start_from.take().is_some()
        && let Some(c) = &sweep.continuation
    {
        spec.scene.initial.start = c.first;
    }
    let period = spec.period();
    spec.scene.convergence = None;
    spec.scene.run.duration = settle + periods * period;
    spec.scene.observe.transient_periods = 0.0;
    spec.scene.observe.transient_time = 0.0;
    // A timed stretch shorter than the job's sample spacing still gets a few samples.
    let o = &mut spec.scene.observe;
    o.min_sample_interval = o.min_sample_interval.min(0.25 * spec.scene.run.duration);
    spec
}

/// One sampled job's measured rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledRate {
    /// Wall seconds per simulated time unit past the settling time.
    pub seconds_per_time: f64,
    /// Events the whole sampled run processed.
    pub events: u64,
}

/// Runs a sample spec (from [`sample_spec`]) and times it from the first progress report past
/// `settle` time units to its end, with `settings` (the threads it runs on).
pub fn time_sample(
    spec: &JobSpec,
    settle: f64,
    settings: &wetgran_core::sim::RunSettings,
) -> Result<SampledRate, JobError> {
    let settled = settle / spec.scene.run.duration;
    let mut mark: Option<(Instant, f64)> = None;
    let t0 = Instant::now();
    let outcome = run_job(spec, settings, &mut |f| {
        if mark.is_none() && f >= settled {
            mark = Some((Instant::now(), f));
        }
    });
    let (start, from) = mark.unwrap_or((t0, 0.0));
    let wall = start.elapsed().as_secs_f64();
    let r = outcome?;
    let timed = (1.0 - from) * r.simulated_time;
    Ok(SampledRate {
        seconds_per_time: wall / timed,
        events: r.events,
    })
}

/// One assumption on the run lengths: its label, the whole sweep's cost, the cost of what is
/// left to run.
pub type CostLine = (String, SweepCost, SweepCost);

/// Job seconds per start mode, in order of appearance: (start mode, jobs, job seconds).
pub type StartSplit = Vec<(String, usize, f64)>;

/// The cost of the sweep under each assumption on the run lengths that applies: with a
/// convergence policy (`policy`) the minimum, the stored runs' mean extension (when `measured`
/// has one) and the cap; without one, the sweep's run length. Each line comes with its job
/// time per start mode.
pub fn cost_lines(
    planned: &[PlannedJob],
    rates: &[RateSample],
    measured: Option<&MeasuredRuns>,
    policy: bool,
    cores: usize,
) -> (Vec<CostLine>, Vec<StartSplit>) {
    let mut lengths: Vec<(String, RunLength)> = Vec::new();
    if policy {
        lengths.push((
            "minimum (every job stationary at its first check)".to_string(),
            RunLength::FirstCheck,
        ));
        if let Some(m) = measured {
            lengths.push((
                format!(
                    "likely (the stored runs' {:.2} x their first check)",
                    m.mean_length_factor
                ),
                RunLength::Extended(m.mean_length_factor),
            ));
        }
        lengths.push(("cap (every job run to its cap)".to_string(), RunLength::Cap));
    } else {
        lengths.push(("the sweep's run length".to_string(), RunLength::FirstCheck));
    }
    let mut lines = Vec::new();
    let mut by_start = Vec::new();
    for (label, length) in lengths {
        let seconds = job_seconds(planned, rates, length, false);
        by_start.push(start_split(planned, &seconds));
        let whole = sweep_cost(planned, &seconds, cores);
        let left = sweep_cost(planned, &job_seconds(planned, rates, length, true), cores);
        lines.push((label, whole, left));
    }
    (lines, by_start)
}

/// Jobs and job seconds per start mode, in order of appearance.
fn start_split(planned: &[PlannedJob], seconds: &[f64]) -> StartSplit {
    let mut split: StartSplit = Vec::new();
    for (j, s) in planned.iter().zip(seconds) {
        match split.iter_mut().find(|(m, _, _)| *m == j.start) {
            Some(e) => {
                e.1 += 1;
                e.2 += s;
            }
            None => split.push((j.start.clone(), 1, *s)),
        }
    }
    split
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(position: f64, first_check: f64, cap: f64) -> PlannedJob {
        PlannedJob {
            position: vec![position],
            first_check,
            cap,
            predecessor: None,
            measured: None,
            start: "hot".into(),
        }
    }

    fn sample(position: f64, seconds_per_time: f64, start: &str) -> RateSample {
        RateSample {
            position: vec![position],
            seconds_per_time,
            start: start.into(),
        }
    }

    #[test]
    fn jobs_fill_the_workers_in_claim_order_and_chains_run_in_order() {
        // Two workers, grid order 3, 3, 2, 2, 2: w0 runs 3 then 2 (ends 5) then 2 (ends 7),
        // w1 runs 3 then 2 (ends 5): 7.
        assert_eq!(makespan(&[3.0, 3.0, 2.0, 2.0, 2.0], &[None; 5], 2), 7.0);
        // One worker: the sum.
        assert_eq!(makespan(&[3.0, 3.0, 2.0, 2.0, 2.0], &[None; 5], 1), 12.0);
        // More workers than jobs: the longest.
        assert_eq!(makespan(&[3.0, 1.0], &[None; 2], 8), 3.0);
        // A long job last is a tail: 1 + 1 then 10 alone.
        assert_eq!(makespan(&[1.0, 1.0, 1.0, 10.0], &[None; 4], 2), 11.0);
        assert_eq!(makespan(&[], &[], 2), 0.0);
        // One chain 0 -> 1 -> 2 of 2 s each and one lone job of 1 s on two workers: the chain
        // takes 6 s whatever the workers; the lone job runs beside it.
        let pred = [None, Some(0), Some(1), None];
        assert_eq!(makespan(&[2.0, 2.0, 2.0, 1.0], &pred, 2), 6.0);
        // Two chains of two jobs on two workers: 2 + 2.
        let pred = [None, Some(0), None, Some(2)];
        assert_eq!(makespan(&[2.0, 2.0, 2.0, 2.0], &pred, 2), 4.0);
        // A chain's next link goes before grid order: chain 0 -> 3 and lone jobs 1, 2 on one
        // worker run 0, 3, 1, 2 (the sum either way, but the order shows in two workers):
        // w0: 0 (0-1), then 3 is ready at 1 and beats 2: w0 3 (1-5); w1: 1 (0-1), 2 (1-2).
        let pred = [None, None, None, Some(0)];
        assert_eq!(makespan(&[1.0, 1.0, 1.0, 4.0], &pred, 2), 5.0);
    }

    #[test]
    fn unmeasured_jobs_take_the_nearest_rate_and_their_run_length() {
        let mut jobs = vec![
            job(0.0, 10.0, 40.0),
            job(0.4, 20.0, 80.0),
            job(1.0, 30.0, 120.0),
        ];
        // No sample, no rate; no measured job, no measured runs.
        assert_eq!(nearest_rate(&[], &[0.5], "hot"), None);
        assert!(measured_runs(&jobs).is_none());
        let samples = [sample(0.0, 1.0, "hot"), sample(1.0, 3.0, "hot")];
        assert_eq!(
            job_seconds(&jobs, &samples, RunLength::FirstCheck, false),
            vec![10.0, 20.0, 90.0]
        );
        assert_eq!(
            job_seconds(&jobs, &samples, RunLength::Cap, false),
            vec![40.0, 80.0, 360.0]
        );
        // The factor is capped per job: 1.5 x 10, 1.5 x 20, 1.5 x 30.
        assert_eq!(
            job_seconds(&jobs, &samples, RunLength::Extended(1.5), false),
            vec![15.0, 30.0, 135.0]
        );
        assert_eq!(
            job_seconds(&jobs, &samples, RunLength::Extended(100.0), false),
            vec![40.0, 80.0, 360.0]
        );
        // A measured job costs what it cost, lends its rate (8 / 40 = 0.2) to its nearest
        // neighbour (0.4 is nearer 0.5 than 0.0), and nothing when only what is left counts.
        jobs.push(job(0.5, 20.0, 80.0));
        jobs[3].measured = Some(MeasuredCost {
            wall_seconds: 8.0,
            simulated_time: 40.0,
            settled: Some(true),
        });
        assert_eq!(
            job_seconds(&jobs, &samples, RunLength::FirstCheck, false),
            vec![10.0, 4.0, 90.0, 8.0]
        );
        assert_eq!(
            job_seconds(&jobs, &samples, RunLength::FirstCheck, true),
            vec![10.0, 4.0, 90.0, 0.0]
        );
        let runs = measured_runs(&jobs).unwrap();
        assert_eq!((runs.jobs, runs.extended, runs.unconverged), (1, 1, 0));
        assert_eq!(runs.mean_length_factor, 2.0);
        assert_eq!(runs.wall_seconds, 8.0);
        let cost = sweep_cost(&jobs, &[10.0, 4.0, 90.0, 8.0], 2);
        assert_eq!(cost.job_seconds, 112.0);
        assert_eq!(cost.longest_job, 90.0);
        // w0: 10 (0-10), then 8 (10-18); w1: 4 (0-4), then 90 (4-94).
        assert_eq!(cost.wall_seconds, 94.0);
    }

    #[test]
    fn each_start_mode_is_sampled_and_lends_its_rate_to_its_own_jobs() {
        // A (3 points) x (hot, cold) grid, the start axis fastest: hot, cold, hot, cold, ...
        let starts: Vec<String> = (0..6)
            .map(|k| if k % 2 == 0 { "hot" } else { "cold" }.to_string())
            .collect();
        // Two samples spread over the list would be jobs 0 and 5; shared out, one per mode: the
        // middle hot job (2) and the middle cold job (3).
        assert_eq!(sample_picks(&starts, 2), vec![2, 3]);
        // Four: both ends of each mode.
        assert_eq!(sample_picks(&starts, 4), vec![0, 1, 4, 5]);
        // One sample still measures every mode.
        assert_eq!(sample_picks(&starts, 1), vec![2, 3]);
        // Three: the first mode takes the remainder.
        assert_eq!(sample_picks(&starts, 3), vec![0, 3, 4]);
        // More samples than jobs: every job once.
        assert_eq!(sample_picks(&starts, 20), (0..6).collect::<Vec<_>>());
        // One start mode: spread over the whole list, as before.
        let hot = vec!["hot".to_string(); 5];
        assert_eq!(sample_picks(&hot, 3), vec![0, 2, 4]);
        assert_eq!(sample_picks(&hot, 1), vec![2]);
        // A cold job takes the cold sample's rate even where a hot sample is nearer.
        let samples = [sample(0.0, 1.0, "hot"), sample(1.0, 5.0, "cold")];
        assert_eq!(nearest_rate(&samples, &[0.1], "hot"), Some(1.0));
        assert_eq!(nearest_rate(&samples, &[0.1], "cold"), Some(5.0));
        // A mode with no sample falls back to the nearest of any mode.
        assert_eq!(nearest_rate(&samples, &[0.1], "continue"), Some(1.0));
        let mut jobs = vec![job(0.1, 10.0, 10.0), job(0.1, 10.0, 10.0)];
        jobs[1].start = "cold".into();
        assert_eq!(
            job_seconds(&jobs, &samples, RunLength::FirstCheck, false),
            vec![10.0, 50.0]
        );
    }
}
