//! The command line: `wetgran simulate` and the sweep commands (`sweep`, `boundaries`, `plot`,
//! `export`; see `sweep_cmd`). `src/main.rs` only calls [`main`]. The benchmarks and the stress
//! cases are the binary of the crate `wetgran-bench`.

mod cluster_cmd;
mod common;
mod export_cmd;
mod extend_cmd;
mod interrupt;
pub mod point_cmd;
mod reclassify_cmd;
mod refine_cmd;
mod report_cmd;
mod simulate_cmd;
pub mod sweep_cmd;

use common::{Failure, available_cores, exit, workers_or_fail};
use sweep_cmd::SweepCommand;

use crate::boundary::Extraction;
use crate::report::ColourBy;
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Phase diagrams of wet granular matter.
#[derive(Debug, Parser)]
#[command(name = "wetgran", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run one scene file with its observers and print a summary (events by kind, energy,
    /// observables over the stationary window, and the phase).
    Simulate(simulate_cmd::SimulateArgs),
    /// Phase-diagram sweeps: run, resume, status, refine, submit to Slurm and collect (and
    /// expand, job for running elsewhere).
    Sweep {
        #[command(subcommand)]
        action: sweep_cmd::SweepCommand,
    },
    /// Single jobs, as a cluster task runs them.
    Job {
        #[command(subcommand)]
        action: JobCommand,
    },
    /// Print the phase map of each sweep and its boundary points.
    ///
    /// docs/model.md 7: the grid points (majority phase of their replicas) are Delaunay-triangulated
    /// in the (log E*, Gamma) plane and a boundary point is put at the midpoint of every edge
    /// between two phases; the points are grouped by phase pair (e.g. f|fgc) and given in the
    /// sweep's axes and as container motion (A, omega), with their uncertainty (half the
    /// straddling edge per axis, decades on a log axis) and confidence (the fraction of the
    /// replicas at both ends agreeing with their point's majority). Unconverged points are marked
    /// `?` and carry no boundary unless asked (`--include-unconverged`).
    Boundaries {
        /// Database file; also from WETGRAN_DB (the flag wins).
        #[arg(long, env = "WETGRAN_DB", default_value = sweep_cmd::DEFAULT_DB)]
        db: PathBuf,
        /// Only this sweep (default: all).
        #[arg(long)]
        sweep: Option<String>,
        /// Print JSON (every sweep's map: points, labels, boundaries) instead of the table.
        #[arg(long, conflicts_with = "format")]
        json: bool,
        /// `table`, or `csv` (one row per boundary point); `json` is `--json`.
        #[arg(long, value_enum, default_value = "table")]
        format: sweep_cmd::BoundaryFormat,
        /// Let unconverged points (marked `?`) carry boundaries too; by default a boundary
        /// rests only on converged points.
        #[arg(long)]
        include_unconverged: bool,
    },
    /// Draw a sweep's phase diagram as SVG.
    ///
    /// E* (log axis) against Gamma, points coloured by phase, the boundary points, and the lines
    /// A = s_crit, A = d and Eq. 4.15 (solid-fluid force balance) drawn over; grey error bars
    /// span each boundary point's straddling edge; unconverged points are drawn hollow and carry
    /// no boundary unless asked.
    Plot {
        /// Database file; also from WETGRAN_DB (the flag wins).
        #[arg(long, env = "WETGRAN_DB", default_value = sweep_cmd::DEFAULT_DB)]
        db: PathBuf,
        /// The sweep (default: the one registered or updated last).
        #[arg(long)]
        sweep: Option<String>,
        /// The SVG file to write.
        #[arg(short = 'o', long = "output")]
        output: PathBuf,
        /// Let unconverged points (drawn hollow) carry boundaries too.
        #[arg(long)]
        include_unconverged: bool,
        /// Scale of the y axis (Gamma): `auto` is logarithmic where the sweep's axis is.
        #[arg(long, value_enum, default_value = "auto")]
        y_scale: report_cmd::Scale,
    },
    /// Show one stored sweep point: phase, the numbers it was decided on, pictures.
    ///
    /// The lateral profiles come from the stored observables; a snapshot re-runs the job's
    /// stored spec (same spec and seed, same numbers: the event count is compared with the
    /// stored run's) and draws its final configuration.
    Show {
        /// Database file; also from WETGRAN_DB (the flag wins).
        #[arg(long, env = "WETGRAN_DB", default_value = sweep_cmd::DEFAULT_DB)]
        db: PathBuf,
        /// The job: at least 6 leading hex digits of its id (`wetgran export` lists ids).
        job: String,
        /// Write a snapshot of the final configuration (`.xyz` for OVITO, or `.svg`); repeatable.
        #[arg(long)]
        snapshot: Vec<PathBuf>,
        /// Colour of the SVG snapshot: `energy` (kinetic energy / E_cb) or `bridges`.
        #[arg(long, default_value = "energy")]
        colour_by: String,
        /// Write the lateral profiles (T_g, packing fraction, n_cb against x) as SVG.
        #[arg(long)]
        profiles: Option<PathBuf>,
        /// Print JSON (one object: the job, its phase and what it was decided on, the files
        /// written) instead of the text.
        #[arg(long)]
        json: bool,
    },
    /// The fluid-gas boundary of inelastic systems: the inflection point of T_g/E_cb against
    /// E* along each line of constant Gamma of a sweep (docs/model.md 7), where it stands out
    /// of the line's scatter, else why there is none.
    Inflection {
        /// Database file; also from WETGRAN_DB (the flag wins).
        #[arg(long, env = "WETGRAN_DB", default_value = sweep_cmd::DEFAULT_DB)]
        db: PathBuf,
        /// Only this sweep (default: all).
        #[arg(long)]
        sweep: Option<String>,
        /// Print JSON (an array, one object per sweep with its lines) instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Export all finished jobs in tidy form: one row per job, CSV or JSON with the same fields.
    ///
    /// For pandas, Julia and friends: the axis columns in the sweep's order, then
    /// sweep,point,replica,job_id, the container motion, phase, stationary, trend, trust and the
    /// run's cost, then the scalar observables (`obs.`) and decision inputs (`decided_on.`) that
    /// carry information: a column empty or the same in every row is left out unless --all. The
    /// series (time series, profiles) go to --series FILE in long format, numbers only; their
    /// text entries to --text FILE. docs/reports.md reads the database directly from pandas.
    Export {
        /// Database file; also from WETGRAN_DB (the flag wins).
        #[arg(long, env = "WETGRAN_DB", default_value = sweep_cmd::DEFAULT_DB)]
        db: PathBuf,
        /// Only this sweep (default: all).
        #[arg(long)]
        sweep: Option<String>,
        /// Write JSON (everything nested, the series included) instead of CSV.
        #[arg(long, conflicts_with = "format")]
        json: bool,
        /// `csv`; `json` is `--json`.
        #[arg(long, value_enum, default_value = "csv")]
        format: sweep_cmd::ExportFormat,
        /// Write to this file instead of standard output.
        #[arg(short = 'o', long = "output")]
        output: Option<PathBuf>,
        /// Write the series (every array of the observables: time series, profiles, MSD) to
        /// this file in long format, `job_id,series,index,value`, numbers only.
        #[arg(long, value_name = "FILE")]
        series: Option<PathBuf>,
        /// With --series: write the text and true/false entries of the series (the names of the
        /// monitored quantities, the checks' verdicts) to this file, same columns.
        #[arg(long, value_name = "FILE")]
        text: Option<PathBuf>,
        /// Keep every scalar column, also those empty or the same in every row.
        #[arg(long)]
        all: bool,
    },
    /// Plot the order parameters along each line of constant Gamma of a shaking sweep.
    ///
    /// T_g/E_cb, bridges per grain and Delta n_cb (Delta n_area for dry scenes) against E*, one
    /// row of panels per Gamma: markers coloured by label, shaped by run state (trend), hollow
    /// where the label may change, bars of one standard error, each branch's label changes
    /// dashed. Prints the lines' label changes and T_g inflections (--json: as JSON). -o FILE
    /// writes SVG (.svg) or CSV (.csv).
    Lines(report_cmd::LinesArgs),
    /// Write a sweep's report: a static HTML site (no script, works offline).
    ///
    /// index.html: the phase map with every point a link to its page, the table of points, the
    /// boundaries, the order parameters along lines of constant Gamma, the sweep file and the
    /// command lines that reproduce it; one page per grid position with each job's label, run
    /// state and the numbers it was decided on, its snapshot (from the stored final state), its
    /// lateral profiles and its line's curves.
    Report(report_cmd::ReportArgs),
    /// Re-label stored results from their stored observables, without simulating.
    ///
    /// Calls the phase classifier on each result's observables with each job's own `[classify]`
    /// thresholds (those of the sweep that last registered it), or with the thresholds of
    /// --classify FILE (a `[classify]` table or top-level keys); updates the phase and the
    /// numbers it was decided on, and prints how many labels changed (from -> to).
    Reclassify {
        /// Only this sweep's results (default: every sweep's).
        #[arg(long)]
        sweep: Option<String>,
        /// Thresholds file (TOML).
        #[arg(long, value_name = "FILE")]
        classify: Option<PathBuf>,
        /// Database file; also from WETGRAN_DB (the flag wins).
        #[arg(long, env = "WETGRAN_DB", default_value = sweep_cmd::DEFAULT_DB)]
        db: PathBuf,
    },
}

/// `wetgran job ...`.
#[derive(Debug, Subcommand)]
pub enum JobCommand {
    /// Run one job spec and write its result record (what a Slurm array task runs).
    ///
    /// The spec is JSON as `sweep submit` writes it (or a line of `sweep expand --specs`). The
    /// record (JSON: the result, or the error of a failed job) is written atomically to --out
    /// (temporary file + rename), else printed. Never opens a database. Exit status 0: done;
    /// 1: the job failed (record written); 2: the spec cannot be read (record written).
    Run {
        /// The job spec file.
        spec: PathBuf,
        /// Where to write the result record.
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

impl Command {
    /// The `--db` paths of the command, each with whether the command may create it.
    fn databases(&self) -> Vec<(&Path, bool)> {
        use SweepCommand as S;
        match self {
            Command::Boundaries { db, .. }
            | Command::Plot { db, .. }
            | Command::Show { db, .. }
            | Command::Inflection { db, .. }
            | Command::Export { db, .. }
            | Command::Reclassify { db, .. } => vec![(db.as_path(), false)],
            Command::Lines(args) => vec![(args.db(), false)],
            Command::Report(args) => vec![(args.db(), false)],
            Command::Sweep { action } => match action {
                S::Run { db, .. } | S::Submit { db, .. } => vec![(db.as_path(), true)],
                S::Resume { db, .. }
                | S::Status { db, .. }
                | S::Refine { db, .. }
                | S::Collect { db, .. } => vec![(db.as_path(), false)],
                S::Estimate { db, .. } => db.iter().map(|d| (d.as_path(), false)).collect(),
                S::Expand { .. } | S::Job { .. } => Vec::new(),
            },
            Command::Simulate(_) | Command::Job { .. } => Vec::new(),
        }
    }
}

/// Entry point of the binary.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    for (db, creates) in cli.command.databases() {
        if let Err(f) = common::folder_of_database(db, creates) {
            return exit(Err(f));
        }
    }
    match cli.command {
        Command::Simulate(args) => simulate_cmd::simulate(args),
        Command::Sweep { action } => sweep(action),
        Command::Job {
            action: JobCommand::Run { spec, out },
        } => cluster_cmd::job_run(&spec, out.as_deref()),
        Command::Boundaries {
            db,
            sweep,
            json,
            format,
            include_unconverged,
        } => sweep_cmd::boundaries(
            &db,
            sweep.as_deref(),
            if json {
                sweep_cmd::BoundaryFormat::Json
            } else {
                format
            },
            Extraction {
                include_unconverged,
            },
        ),
        Command::Plot {
            db,
            sweep,
            output,
            include_unconverged,
            y_scale,
        } => report_cmd::plot(
            &db,
            sweep.as_deref(),
            &output,
            Extraction {
                include_unconverged,
            },
            crate::report::plot_phase::MapStyle {
                x_log: None,
                y_log: y_scale.log(),
            },
        ),
        Command::Export {
            db,
            sweep,
            json,
            format,
            output,
            series,
            text,
            all,
        } => export_cmd::export(
            &db,
            sweep.as_deref(),
            export_cmd::ExportTo {
                format: if json {
                    sweep_cmd::ExportFormat::Json
                } else {
                    format
                },
                output: output.as_deref(),
                series: series.as_deref(),
                text: text.as_deref(),
                all,
            },
        ),
        Command::Show {
            db,
            job,
            snapshot,
            colour_by,
            profiles,
            json,
        } => match colour_by.parse::<ColourBy>() {
            Ok(c) => point_cmd::show(&db, &job, &snapshot, c, profiles.as_deref(), json),
            Err(e) => {
                eprintln!("error: --colour-by: {e}");
                ExitCode::from(2)
            }
        },
        Command::Lines(args) => report_cmd::lines(args),
        Command::Report(args) => report_cmd::report(args),
        Command::Inflection { db, sweep, json } => {
            point_cmd::inflection(&db, sweep.as_deref(), json)
        }
        Command::Reclassify {
            sweep,
            classify,
            db,
        } => reclassify_cmd::reclassify(&db, sweep.as_deref(), classify.as_deref()),
    }
}

/// Runs a `sweep` subcommand.
fn sweep(cmd: SweepCommand) -> ExitCode {
    exit(match cmd {
        SweepCommand::Run {
            file,
            db,
            jobs,
            oversubscribe,
            retry_failed,
            replace,
            table_cache_mib,
        } => workers_or_fail(jobs, oversubscribe).and_then(|n| {
            sweep_cmd::sweep_run(&file, &db, n, retry_failed, replace, table_cache_mib)
        }),
        SweepCommand::Resume {
            name,
            db,
            jobs,
            oversubscribe,
            retry_failed,
            extend,
            extend_time,
            table_cache_mib,
        } => workers_or_fail(jobs, oversubscribe).and_then(|n| {
            use crate::sweep::job::ExtendTo;
            let extend = extend
                .map(ExtendTo::Periods)
                .or(extend_time.map(ExtendTo::Time));
            sweep_cmd::sweep_resume(
                name.as_deref(),
                &db,
                n,
                retry_failed,
                extend,
                table_cache_mib,
            )
        }),
        SweepCommand::Status { db, json } => sweep_cmd::sweep_status(&db, json),
        SweepCommand::Expand { file, specs } => sweep_cmd::sweep_expand(&file, specs),
        SweepCommand::Job { spec } => sweep_cmd::sweep_job(&spec),
        SweepCommand::Submit {
            file,
            slurm,
            partition,
            time,
            cpus_per_task,
            array_limit,
            dry_run,
            db,
            dir,
            replace,
        } => {
            if slurm {
                cluster_cmd::submit(
                    &file,
                    &db,
                    &cluster_cmd::Submit {
                        options: crate::cluster::slurm::SbatchOptions {
                            partition,
                            time,
                            cpus_per_task,
                        },
                        array_limit,
                        dry_run,
                        dir,
                        replace,
                    },
                )
            } else {
                Err(Failure::BadInput(
                    "sweep submit: give --slurm (the only cluster backend so far)".to_string(),
                ))
            }
        }
        SweepCommand::Collect { db, sweep } => cluster_cmd::collect_cmd(&db, sweep.as_deref()),
        SweepCommand::Refine {
            sweep,
            db,
            budget,
            rounds,
            resolution,
            max_replicas,
            jobs,
            oversubscribe,
            table_cache_mib,
        } => workers_or_fail(jobs, oversubscribe).and_then(|n| {
            refine_cmd::refine(
                &db,
                sweep.as_deref(),
                refine_cmd::Overrides {
                    budget,
                    rounds,
                    resolution,
                    max_replicas,
                },
                n,
                table_cache_mib,
            )
        }),
        SweepCommand::Estimate {
            file,
            periods,
            settle,
            samples,
            cores,
            db,
        } => match cores {
            Some(0) => Err(Failure::BadInput(
                "--cores 0 is out of range: must be >= 1".to_string(),
            )),
            c => sweep_cmd::sweep_estimate(
                &file,
                periods,
                settle,
                samples,
                c.unwrap_or_else(available_cores),
                &db,
            ),
        },
    })
}
