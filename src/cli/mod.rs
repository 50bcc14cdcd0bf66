//! The command line: `wetgran simulate` and the sweep commands (`sweep`, `boundaries`, `plot`,
//! `export`; see `sweep_cmd`). `src/main.rs` only calls [`main`]; [`main_with`] is the same
//! command line with [`Hooks`] of the caller's (a program that embeds it: the crash tests stop
//! their child process at the hooks' points). The benchmarks and the stress cases are the
//! binary of the crate `wetgran-bench`.

mod cluster_cmd;
mod common;
mod export_cmd;
mod interrupt;
pub mod point_cmd;
mod reclassify_cmd;
mod refine_cmd;
mod report_cmd;
mod simulate_cmd;
pub mod sweep_cmd;

use common::exit;
use sweep_cmd::SweepCommand;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use wetgran_core::sim::ExtendHook;

/// Functions the command line calls at points of `sweep run` and `sweep resume`: `write` inside
/// the store's write transactions (`store::WritePoint`), `extend` each time a job's run-length
/// policy extends its run by a window.
#[derive(Debug, Clone, Default)]
pub struct Hooks {
    pub write: Option<crate::store::WriteHook>,
    pub extend: Option<ExtendHook>,
}

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
    /// Print the phase map of a sweep and its boundary points (--all-sweeps: of each sweep).
    ///
    /// docs/model.md 7: the grid points (majority phase of their replicas) are Delaunay-triangulated
    /// in the (log E*, Gamma) plane and a boundary point is put at the midpoint of every edge
    /// between two phases; the points are grouped by phase pair (e.g. f|fgc) and given in the
    /// sweep's axes and as container motion (A, omega), with their uncertainty (half the
    /// straddling edge per axis, decades on a log axis) and confidence (the fraction of the
    /// replicas at both ends agreeing with their point's majority). Unconverged points are marked
    /// `?` and carry no boundary unless asked (`--include-unconverged`).
    Boundaries(sweep_cmd::BoundariesArgs),
    /// Draw a sweep's phase diagram as SVG.
    ///
    /// E* (log axis) against Gamma, points coloured by phase, the boundary points, and the lines
    /// A = s_crit, A = d and Eq. 4.15 (solid-fluid force balance) drawn over; grey error bars
    /// span each boundary point's straddling edge; unconverged points are drawn hollow and carry
    /// no boundary unless asked.
    Plot(report_cmd::PlotArgs),
    /// Show one stored sweep point: phase, the numbers it was decided on, pictures.
    ///
    /// The lateral profiles come from the stored observables; a snapshot re-runs the job's
    /// stored spec (same spec and seed, same numbers: the event count is compared with the
    /// stored run's) and draws its final configuration.
    Show(point_cmd::ShowArgs),
    /// The fluid-gas boundary of inelastic systems: the inflection point of T_g/E_cb against
    /// E* along each line of constant Gamma of a sweep (docs/model.md 7), where it stands out
    /// of the line's scatter, else why there is none.
    Inflection(point_cmd::InflectionArgs),
    /// Export a sweep's finished jobs in tidy form: one row per job, CSV or JSON with the same
    /// fields (--all-sweeps: every sweep's).
    ///
    /// For pandas, Julia and friends: the axis columns in the sweep's order, then
    /// sweep,point,replica,job_id, the container motion, phase, stationary, trend, trust and the
    /// run's cost, then the scalar observables (`obs.`, each averaged one with its standard
    /// error `obs.NAME_se` beside it), decision inputs (`decided_on.`) and the system's
    /// constants (`sys.`) that carry information: a column empty or the same in every row is
    /// left out unless --all, and written with its value to the sidecar FILE.meta.json beside
    /// -o FILE (--meta elsewhere). The series (time series, profiles) go to --series FILE in
    /// long format, numbers only; their text entries to --text FILE. docs/reports.md reads the
    /// export and its sidecar from pandas.
    Export(export_cmd::ExportArgs),
    /// Plot the order parameters along each line of constant Gamma of a shaking sweep.
    ///
    /// T_g/E_cb, bridges per grain and Delta n_cb (Delta n_area for dry scenes) against E*, one
    /// row of panels per Gamma: markers coloured by label, shaped by run state (trend), hollow
    /// where the label may change, bars of one standard error, each branch's label changes
    /// dashed. Prints the lines' label changes and T_g inflections (--json: as JSON). -o FILE
    /// writes SVG (.svg) or CSV (.csv).
    Lines(report_cmd::LinesArgs),
    /// Write a sweep's report: a static HTML site (works offline; one small script sorts its
    /// points table).
    ///
    /// index.html: the phase map with every point a link to its page, the sortable table of
    /// points, the boundaries as tables, the order parameters along lines of constant Gamma, the
    /// physical parameters, the sweep file and the command lines that reproduce it; one page
    /// per grid position with each job's label, run
    /// state and the numbers it was decided on, its snapshot (from the stored final state), its
    /// lateral profiles and its line's curves.
    Report(report_cmd::ReportArgs),
    /// Re-label stored results from their stored observables, without simulating.
    ///
    /// Calls the phase classifier on each result's observables with each job's own `[classify]`
    /// thresholds (those of the sweep that last registered it), or with the thresholds of
    /// --classify FILE (a `[classify]` table or top-level keys); updates the phase and the
    /// numbers it was decided on, and prints how many labels changed (from -> to).
    Reclassify(reclassify_cmd::ReclassifyArgs),
    /// Upgrade a database written by an older wetgran in place: apply this wetgran's migrations
    /// and job-id rule (the commands that only read refuse such a database and never change
    /// it). Copy the file first to keep the old one. Prints what was upgraded.
    Upgrade {
        /// Database file; also from WETGRAN_DB (the flag wins).
        #[arg(long, env = "WETGRAN_DB", default_value = common::DEFAULT_DB)]
        db: PathBuf,
    },
}

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

/// Entry point of the binary.
pub fn main() -> ExitCode {
    main_with(&Hooks::default())
}

/// The command line with `hooks` (module doc).
pub fn main_with(hooks: &Hooks) -> ExitCode {
    let matches = Cli::command().get_matches();
    // Every `--db` of the command is checked before anything else (`folder_of_database`);
    // `sweep run` and `sweep submit` may create theirs (`job run` has no `--db`).
    let (mut name, mut args) = ("", &matches);
    while let Some(sub) = args.subcommand() {
        (name, args) = sub;
    }
    for db in args
        .try_get_many::<PathBuf>("db")
        .ok()
        .flatten()
        .into_iter()
        .flatten()
    {
        if let Err(f) = common::folder_of_database(db, matches!(name, "run" | "submit")) {
            return exit(Err(f));
        }
    }
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    exit(match cli.command {
        Command::Simulate(args) => return simulate_cmd::simulate(args),
        Command::Job {
            action: JobCommand::Run { spec, out },
        } => return cluster_cmd::job_run(&spec, out.as_deref()),
        Command::Sweep { action } => match action {
            SweepCommand::Run(a) => sweep_cmd::sweep_run(a, hooks),
            SweepCommand::Resume(a) => sweep_cmd::sweep_resume(a, hooks),
            SweepCommand::Status { db, json } => sweep_cmd::sweep_status(&db, json),
            SweepCommand::Expand { file, specs } => sweep_cmd::sweep_expand(&file, specs),
            SweepCommand::Job { spec } => sweep_cmd::sweep_job(&spec),
            SweepCommand::Submit(a) => cluster_cmd::submit(a),
            SweepCommand::Collect(a) => cluster_cmd::collect_cmd(a),
            SweepCommand::Refine(a) => refine_cmd::refine(a),
            SweepCommand::Estimate(a) => sweep_cmd::sweep_estimate(a),
        },
        Command::Boundaries(a) => sweep_cmd::boundaries(a),
        Command::Plot(a) => report_cmd::plot(a),
        Command::Export(a) => export_cmd::export(a),
        Command::Show(a) => point_cmd::show(a),
        Command::Lines(a) => report_cmd::lines(a),
        Command::Report(a) => report_cmd::report(a),
        Command::Inflection(a) => point_cmd::inflection(a),
        Command::Reclassify(a) => reclassify_cmd::reclassify(a),
        Command::Upgrade { db } => sweep_cmd::upgrade(&db),
    })
}
