//! Progress display of a sweep run: on a terminal an indicatif overall bar (with ETA) and one
//! line per worker (its grid point and progress); otherwise nothing but the lines.
//! Results go to standard output, progress to standard error (issue 45): the line of each
//! finished job (`[ 3/30] done ...`, and the jobs that fail before they start) is a result, so
//! `sweep run > log` keeps them in `log`; the bars and the status notes stay on stderr. Where
//! standard output is the bars' terminal too, a job line is printed above the bars (through
//! indicatif) so that it does not tear them.
//! Every line passes through `terminal` (a job's error text may hold anything).

use crate::terminal::{escape, escape_lines};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::Write;
use std::time::Duration;

/// Where progress goes.
#[derive(Debug)]
pub enum Progress {
    /// indicatif bars on stderr; job lines above them when stdout is the same terminal
    /// (`stdout_tty`), else on stdout.
    Bars {
        multi: MultiProgress,
        overall: ProgressBar,
        workers: Vec<ProgressBar>,
        stdout_tty: bool,
    },
    /// Job lines on stdout, notes on stderr (stderr not a terminal).
    Plain { total: u64, done: u64 },
    /// Nothing (library use).
    Quiet,
}

/// Writes a result line on standard output (a closed pipe is not the run's failure: the
/// results are in the database).
fn print_out(line: &str) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{line}");
    let _ = out.flush();
}

impl Progress {
    /// Nothing unless `show`; then bars when stderr is a terminal, plain lines otherwise.
    pub fn auto(show: bool, total: u64, done: u64, workers: usize) -> Progress {
        use std::io::IsTerminal;
        if !show {
            Progress::Quiet
        } else if std::io::stderr().is_terminal() {
            Self::bars(total, done, workers)
        } else {
            Progress::Plain { total, done }
        }
    }

    fn bars(total: u64, done: u64, workers: usize) -> Progress {
        let multi = MultiProgress::with_draw_target(ProgressDrawTarget::stderr_with_hz(4));
        let overall = multi.add(ProgressBar::new(total));
        overall.set_style(
            ProgressStyle::with_template(
                "{prefix:>8} [{bar:40}] {pos}/{len} jobs  {elapsed_precise}  ETA {eta_precise}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        overall.set_prefix("sweep");
        overall.set_position(done);
        overall.reset_eta();
        let style = ProgressStyle::with_template("{prefix:>8} {bar:20} {percent:>3}%  {msg}")
            .expect("valid template")
            .progress_chars("## ");
        let workers = (0..workers)
            .map(|w| {
                let b = multi.add(ProgressBar::new(1000));
                b.set_style(style.clone());
                b.set_prefix(format!("worker {}", w + 1));
                b.set_message("idle");
                b
            })
            .collect();
        overall.enable_steady_tick(Duration::from_millis(500));
        use std::io::IsTerminal;
        Progress::Bars {
            multi,
            overall,
            workers,
            stdout_tty: std::io::stdout().is_terminal(),
        }
    }

    /// A worker started a job at `label`.
    pub fn start(&mut self, worker: usize, label: &str) {
        if let Progress::Bars { workers, .. } = self {
            workers[worker].set_position(0);
            workers[worker].set_message(escape(label).into_owned());
        }
    }

    /// A worker's job is `fraction` done.
    pub fn update(&mut self, worker: usize, fraction: f64) {
        if let Progress::Bars { workers, .. } = self {
            workers[worker].set_position((fraction.clamp(0.0, 1.0) * 1000.0) as u64);
        }
    }

    /// A worker's job ended; `line` describes the outcome (a result: module doc).
    pub fn finish(&mut self, worker: usize, line: &str) {
        match self {
            Progress::Bars {
                overall, workers, ..
            } => {
                overall.inc(1);
                workers[worker].set_position(0);
                workers[worker].set_message("idle");
                self.outcome(line);
            }
            Progress::Plain { total, done } => {
                *done += 1;
                let width = total.to_string().len();
                print_out(&format!(
                    "[{:>width$}/{total}] {}",
                    *done,
                    escape_lines(line)
                ));
            }
            Progress::Quiet => {}
        }
    }

    /// A result line outside the count of finished jobs (a job that failed before it started):
    /// on stdout, above the bars where stdout is their terminal.
    pub fn outcome(&mut self, line: &str) {
        match self {
            Progress::Bars {
                multi,
                stdout_tty: true,
                ..
            } => {
                let _ = multi.println(escape_lines(line));
            }
            Progress::Bars { .. } | Progress::Plain { .. } => print_out(&escape_lines(line)),
            Progress::Quiet => {}
        }
    }

    /// A status message outside the job lines (stderr).
    pub fn note(&mut self, line: &str) {
        match self {
            Progress::Bars { multi, .. } => {
                let _ = multi.println(escape_lines(line));
            }
            Progress::Plain { .. } => eprintln!("{}", escape_lines(line)),
            Progress::Quiet => {}
        }
    }

    /// Removes the bars.
    pub fn close(&mut self) {
        if let Progress::Bars {
            overall, workers, ..
        } = self
        {
            for w in workers.iter() {
                w.finish_and_clear();
            }
            overall.finish();
        }
    }
}

/// Progress of one long step before any job runs (expanding a large grid, registering it):
/// a bar on a terminal, else a line at every tenth; nothing for fewer than [`STEPS_SHOWN_FROM`]
/// items (small sweeps print what they printed before).
#[derive(Debug)]
pub struct Steps {
    what: &'static str,
    total: usize,
    shown_tenths: usize,
    bar: Option<ProgressBar>,
    plain: bool,
}

/// Steps of fewer items than this show no progress.
pub const STEPS_SHOWN_FROM: usize = 10_000;

impl Steps {
    /// `total` items of `what` (`"expanding grid points"`); quiet unless `show` and `total`
    /// reaches [`STEPS_SHOWN_FROM`].
    pub fn new(what: &'static str, total: usize, show: bool) -> Steps {
        use std::io::IsTerminal;
        let show = show && total >= STEPS_SHOWN_FROM;
        let bar = (show && std::io::stderr().is_terminal()).then(|| {
            let b = ProgressBar::with_draw_target(
                Some(total as u64),
                ProgressDrawTarget::stderr_with_hz(4),
            );
            b.set_style(
                ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len}  ETA {eta_precise}")
                    .expect("valid template")
                    .progress_chars("=> "),
            );
            b.set_message(what);
            b
        });
        Steps {
            what,
            total,
            shown_tenths: 0,
            plain: show && bar.is_none(),
            bar,
        }
    }

    /// `done` of the items are through.
    pub fn set(&mut self, done: usize) {
        if let Some(b) = &self.bar {
            b.set_position(done as u64);
        } else if self.plain && self.total > 0 {
            let tenths = done * 10 / self.total;
            if tenths > self.shown_tenths {
                self.shown_tenths = tenths;
                eprintln!("{}: {done} of {}", self.what, self.total);
            }
        }
    }

    /// Removes the bar.
    pub fn finish(&mut self) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
    }
}
