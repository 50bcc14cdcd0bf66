//! `wetgran simulate`: one scene file run with its observers, reported as a table or JSON, with
//! optional snapshots and profile pictures.

use super::common::{Failure, check_snapshot_names, exit, print_json, show};
use crate::output::{Outputs, Protected};
use crate::report::run_text::{observed_text, summary_text};
use crate::report::{ColourBy, profiles_svg, write_snapshot};
use clap::Args;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use wetgran_core::observe::run_observed_with_frame;
use wetgran_core::scene::{Scene, StartMode};

/// The arguments of `wetgran simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// The scene file (TOML); see scenes/ for examples.
    pub scene: PathBuf,
    /// Print the full result as JSON (run report, observables with time series and profiles,
    /// classification with the numbers it was decided on) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write the final configuration: extended XYZ (`.xyz`, opens in OVITO) or an SVG picture
    /// (`.svg`). May be given more than once.
    #[arg(long, value_name = "FILE")]
    pub snapshot: Vec<PathBuf>,
    /// Colour of the SVG snapshot: `energy` (kinetic energy / E_cb) or `bridges`.
    #[arg(long, default_value = "energy", value_name = "BY")]
    pub colour_by: String,
    /// Write the lateral profiles (T_g / E_cb, packing fraction, n_cb, f_lc against x): a
    /// figure, `.svg`, `.pdf` or `.png` by the extension.
    #[arg(long, value_name = "FILE")]
    pub profiles: Option<PathBuf>,
}

/// Runs the scene; exit status 2 on bad input, 3 when the run stopped on a broken invariant.
pub(super) fn simulate(args: SimulateArgs) -> ExitCode {
    match run(&args) {
        Ok(None) => ExitCode::SUCCESS,
        Ok(Some(violation)) => {
            eprintln!("error: the run stopped on a broken invariant: {violation}");
            ExitCode::from(3)
        }
        Err(e) => exit(Err(e)),
    }
}

/// The run and its outputs; the broken invariant it stopped on, if any.
fn run(args: &SimulateArgs) -> Result<Option<String>, Failure> {
    let colour_by: ColourBy = args
        .colour_by
        .parse()
        .map_err(|e| Failure::BadInput(format!("--colour-by: {e}")))?;
    check_snapshot_names(&args.snapshot)?;
    let mut outputs = Outputs::new(Protected::none().and("the scene file", &args.scene));
    for path in &args.snapshot {
        outputs.claim("--snapshot", path)?;
    }
    if let Some(p) = &args.profiles {
        outputs.claim("--profiles", p)?;
        crate::report::figure::figure_format("--profiles", p)?;
    }
    let scene = load_scene(&args.scene)?;
    let ctx = super::common::all_cores();
    let (run, frame) = if std::io::stderr().is_terminal() {
        let duration = scene.run.duration;
        let out = run_observed_with_frame(&scene, &ctx, &mut |f| {
            eprint!(
                "\r  t = {:.3} / {duration}  ({:.0}%)   ",
                f * duration,
                100.0 * f
            );
        });
        eprintln!();
        out
    } else {
        run_observed_with_frame(&scene, &ctx, &mut |_| {})
    };
    if args.json {
        print_json(&run);
    } else {
        show(&summary_text(&run.report));
        show(&observed_text(&run));
    }
    let unit = run.observables.temperature_unit;
    for path in &args.snapshot {
        write_snapshot(path, &frame, colour_by, unit, outputs.protected())?;
    }
    if let Some(path) = &args.profiles {
        let svg = profiles_svg(&run.observables);
        crate::report::figure::write_figure(path, &svg, outputs.protected())?;
    }
    Ok(run.report.invariant_violation.clone())
}

/// Loads the scene; a continued start needs a sweep's neighbouring point, so it is refused here.
fn load_scene(path: &std::path::Path) -> Result<Scene, Failure> {
    let scene = Scene::load(path).map_err(|e| Failure::BadInput(e.to_string()))?;
    if scene.initial.start == StartMode::Continue {
        return Err(Failure::BadInput(format!(
            "{}: initial.start = \"continue\" needs the final state of a neighbouring sweep point \
             ([sweep.continuation] in a sweep file); a scene run on its own starts \"hot\" or \
             \"cold\"",
            path.display()
        )));
    }
    Ok(scene)
}
