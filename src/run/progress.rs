//! Progress display of a sweep run: on a terminal an indicatif overall bar (with ETA) and one
//! line per worker (its grid point and progress); otherwise one plain line per finished job.
//! Every line passes through `terminal` (a job's error text may hold anything).

use crate::terminal::{escape, escape_lines};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::Write;
use std::time::Duration;

/// Where progress goes.
#[derive(Debug)]
pub enum Progress {
    /// indicatif bars on stderr.
    Bars {
        multi: MultiProgress,
        overall: ProgressBar,
        workers: Vec<ProgressBar>,
    },
    /// Plain lines on stderr (not a terminal).
    Plain { total: u64, done: u64 },
    /// Nothing (library use).
    Quiet,
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
        Progress::Bars {
            multi,
            overall,
            workers,
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

    /// A worker's job ended; `line` describes the outcome.
    pub fn finish(&mut self, worker: usize, line: &str) {
        match self {
            Progress::Bars {
                multi,
                overall,
                workers,
            } => {
                overall.inc(1);
                workers[worker].set_position(0);
                workers[worker].set_message("idle");
                let _ = multi.println(escape_lines(line));
            }
            Progress::Plain { total, done } => {
                *done += 1;
                let width = total.to_string().len();
                let mut err = std::io::stderr().lock();
                let _ = writeln!(err, "[{:>width$}/{total}] {}", *done, escape_lines(line));
            }
            Progress::Quiet => {}
        }
    }

    /// A message outside the job lines.
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
