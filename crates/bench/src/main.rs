//! The `wetgran-bench` binary: the benchmark figures (`wetgran-bench engine`, `wall`, `shake`,
//! ...) and the engines' hard cases (`wetgran-bench stress`).

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use wetgran_bench::stress::{DEFAULT_EVENTS, StressCase, run_case};
use wetgran_bench::{orchestrator, orchestrator_scale};

/// Benchmarks and stress cases of wetgran's engines.
#[derive(Debug, Parser)]
#[command(
    name = "wetgran-bench",
    version,
    about,
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    figures: Figures,
}

/// Measure the engine's speed on the reference systems and print the figures.
#[derive(Debug, Args)]
struct Figures {
    /// Which benchmark: `engine` (collisions/s for the reference systems of the
    /// performance doc), `wall` (error and cost of the shaken-wall solvers), `shake` (the
    /// shaken standard wet system with each wall solver), `tdmd` (the time-driven engine on
    /// the dry shaken 2D system of issue 6; `scale` = simulated time units timed), `slab`
    /// (E_par and cost of the shear drive against the slab width), `memory` (peak resident
    /// memory of the event engine per particle at N = 125 000 and 10^6; `scale` scales N),
    /// `engines` (event- vs time-driven engine on the 2D standard wet system, seconds per time
    /// unit), `observer` (cost of the location-change observer as a share of an observed
    /// run; `observer:POINTS` for some of gas, fluid, coexistence), `barrier` (what two threads meeting twice per step, with
    /// and without a hand-over of data, can gain on this machine), `jobs` (representative jobs
    /// of the shipped 2D elastic diagram at fixed length: events/s and where the CPU time goes,
    /// beside `--baseline`'s; `scale` scales their length).
    #[arg(default_value = "engine")]
    which: String,
    /// Repetitions per system (the median is reported).
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Scale the run lengths (events per repetition) by this factor (finite, > 0).
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// `wall` only: also write the error-against-cost plot as SVG to this file.
    #[arg(long)]
    svg: Option<PathBuf>,
    /// `tdmd` only: thread counts to run on, comma-separated (e.g. `1,2`; the speed-up is
    /// against the first).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    threads: Vec<usize>,
    /// `tdmd` only: `K` times the particles in a box `K` times as wide (same density).
    #[arg(long, default_value_t = 1)]
    n_factor: usize,
    /// `jobs` only: another build's `wetgran` binary (e.g. main's, kept aside) to run the same
    /// jobs with, alternated with this build's.
    #[arg(long, value_name = "PATH")]
    baseline: Option<PathBuf>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The sweep orchestrator alone: register and run sweeps of N stand-in jobs (results of
    /// the real shape, returned at once) with the real runner and store on a file database, and
    /// print claims per second, overhead per job, database size per result and the time of
    /// `sweep status`, `boundaries`, `plot`, `export` and `reclassify` (docs/performance.md,
    /// "Orchestrator"). Needs the `wetgran` binary beside this one.
    Orchestrator(orchestrator::Options),
    /// One runner of `orchestrator --two-runners` (internal).
    #[command(hide = true)]
    OrchestratorRunner {
        #[arg(long)]
        db: PathBuf,
        #[arg(long)]
        dir: PathBuf,
        #[arg(long)]
        log: PathBuf,
    },
    /// Run the engines' hard cases at length with the invariant checks on, and print per case
    /// the events (or time steps), simulated time, largest overlap, energy-ledger error, NaN
    /// count and wall time. Exit status 3 if any case broke an invariant.
    ///
    /// Cases: resting_bed, bonded_collapse, grazing_walls, gamma_1000, wall_speed_50, jammed,
    /// shear_double_roots, time_largest_dt (all by default); planted_overlap (the harness's
    /// self-check, must fail) only when named.
    Stress {
        /// One case (default: every hard case).
        case: Option<String>,
        /// Events (time engine: steps) per case.
        #[arg(long, default_value_t = DEFAULT_EVENTS)]
        events: u64,
        /// Print the rows as JSON instead of the table.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Some(Command::Stress { case, events, json }) => stress(case.as_deref(), events, json),
        Some(Command::Orchestrator(o)) => {
            report(if o.collect || o.submit_dry_run || o.two_runners {
                orchestrator_scale::run(&o).map(|()| String::new())
            } else {
                orchestrator::run(&o)
            })
        }
        Some(Command::OrchestratorRunner { db, dir, log }) => {
            match orchestrator_scale::runner(&db, &dir, &log) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(1)
                }
            }
        }
        None => {
            let f = &cli.figures;
            report(wetgran_bench::run(
                &f.which,
                f.repeat.max(1),
                f.scale,
                f.svg.as_deref(),
                &f.threads,
                f.n_factor.max(1),
                f.baseline.as_deref(),
            ))
        }
    }
}

/// Prints a benchmark's table, or its error (exit status 2).
fn report(r: Result<String, String>) -> ExitCode {
    match r {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// `wetgran-bench stress [CASE] [--events N] [--json]`; exit status 3 if a case broke an
/// invariant.
fn stress(case: Option<&str>, events: u64, json: bool) -> ExitCode {
    let cases: Vec<StressCase> = match case {
        None => StressCase::ALL.to_vec(),
        Some(name) => match StressCase::from_name(name) {
            Some(c) => vec![c],
            None => {
                let names: Vec<&str> = StressCase::ALL.iter().map(|c| c.name()).collect();
                eprintln!(
                    "error: unknown stress case `{name}`: use one of {}, or planted_overlap",
                    names.join(", ")
                );
                return ExitCode::from(2);
            }
        },
    };
    let mut rows = Vec::new();
    for c in cases {
        let row = run_case(c, events);
        if !json {
            eprintln!("{}: {:.1} s", c.name(), row.wall_seconds);
        }
        rows.push(row);
    }
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&rows).expect("stress rows serialize")
        );
    } else {
        print!("{}", wetgran_bench::stress_text::stress_text(&rows, events));
    }
    if rows.iter().all(|r| r.passed()) {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(3)
    }
}
