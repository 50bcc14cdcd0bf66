//! The commands that turn a sweep's database into pictures and pages: `wetgran plot` (the phase
//! map, `report::plot_phase`), `wetgran lines` (the order
//! parameters along lines of constant Gamma, `report::lines`) and `wetgran report` (a static HTML
//! site of a sweep, `report::site`).

use super::common::{Failure, note, print_json, show, write_file};
use crate::boundary::Extraction;
use crate::output::folder::SiteFolder;
use crate::output::{Outputs, Protected};
use crate::report::boundaries_text::fixed_text;
use crate::report::figure::{FIGURE_EXTENSIONS, FigureFormat, figure_format, write_figure};
use crate::report::lines::{Lines, lines_csv, lines_of, lines_table};
use crate::report::lines_plot::{lines_svg, overlay_svg};
use crate::report::plot_phase::{self, DrawnMap, MapStyle};
use crate::report::point_text::series_title;
use crate::report::series_plot::series_svg;
use crate::report::site::{JobPictures, SiteInput, site};
use crate::report::{ColourBy, profiles_svg, snapshot_svg};
use crate::store::{Store, SweepRow};
use crate::terminal::escape;
use clap::{Args, ValueEnum};
use std::collections::HashMap;
use std::path::PathBuf;
use wetgran_core::observe::Observables;
use wetgran_core::scene::Scene;
use wetgran_core::sim::Frame;

/// The scale of a map's y axis (`Gamma` on a shaking map).
#[derive(Debug, Clone, Copy, ValueEnum)]
pub(super) enum Scale {
    /// Logarithmic where the sweep's axis is (`log = {...}` in the sweep file).
    Auto,
    Linear,
    Log,
}

impl Scale {
    /// `None` for auto, else whether the axis is logarithmic.
    pub(super) fn log(self) -> Option<bool> {
        match self {
            Scale::Auto => None,
            Scale::Linear => Some(false),
            Scale::Log => Some(true),
        }
    }
}

/// `--db` and `--sweep` of the commands that draw one sweep.
#[derive(Debug, Args)]
pub struct DbLatest {
    /// Database file; also from WETGRAN_DB (the flag wins).
    #[arg(long, env = "WETGRAN_DB", default_value = super::common::DEFAULT_DB)]
    pub db: PathBuf,
    #[arg(long, help = super::common::SWEEP_HELP)]
    sweep: Option<String>,
}

impl DbLatest {
    /// The database, read only, and its sweep by the rule of `common::latest_sweep`.
    fn open(&self) -> Result<(Store, SweepRow), Failure> {
        let store = Store::open_read_only(&self.db)?;
        let sweep = super::common::latest_sweep(&store, self.sweep.as_deref(), false)?;
        Ok((store, sweep))
    }
}

#[derive(Debug, Args)]
pub struct PlotArgs {
    #[command(flatten)]
    pub from: DbLatest,
    /// The figure to write: `.svg`, `.pdf` or `.png` by the extension.
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// Let unconverged points (drawn hollow) carry boundaries too.
    #[arg(long)]
    include_unconverged: bool,
    /// Scale of the y axis (Gamma): `auto` is logarithmic where the sweep's axis is.
    #[arg(long, value_enum, default_value = "auto")]
    y_scale: Scale,
}

#[derive(Debug, Args)]
pub struct ReportArgs {
    #[command(flatten)]
    pub from: DbLatest,
    /// The report folder: written whole beside its target and renamed into place. An existing
    /// folder is replaced only when it is a report (it holds the `.wetgran-report` marker
    /// file), else refused unless --force.
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// Replace an existing folder that is not a report (everything in it is deleted). Never a
    /// folder holding the database or the working folder, never a symbolic link.
    #[arg(long)]
    force: bool,
    /// Leave out the snapshots of the final configurations (each drawn from the job's stored
    /// final state).
    #[arg(long)]
    no_snapshots: bool,
    /// Let unconverged points carry boundaries too (as `boundaries` and `plot`).
    #[arg(long)]
    include_unconverged: bool,
    /// Scale of the map's y axis (Gamma).
    #[arg(long, value_enum, default_value = "auto")]
    y_scale: Scale,
}

#[derive(Debug, Args)]
pub struct LinesArgs {
    #[command(flatten)]
    pub from: DbLatest,
    /// The file to write: a figure (`.svg`, `.pdf` or `.png`: the panels) or `.csv` (one row
    /// per job).
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// Draw each quantity in one panel for all Gamma (one colour per Gamma) instead of one row
    /// of panels per Gamma.
    #[arg(long)]
    overlay: bool,
    /// Also write the CSV (one row per job) to this file.
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Print the table of lines (label changes, inflection) as JSON, points included.
    #[arg(long)]
    json: bool,
}

pub(super) fn plot(a: PlotArgs) -> Result<(), Failure> {
    let how = Extraction {
        include_unconverged: a.include_unconverged,
    };
    let mut outputs = Outputs::new(Protected::database(&a.from.db));
    // The database's protection first (its refusal names the database), then the extension.
    outputs.claim("-o", &a.output)?;
    figure_format("-o", &a.output)?;
    let (store, sweep) = a.from.open()?;
    let map = draw_map(&store, &sweep, how, a.y_scale.log())?;
    write_figure(&a.output, &map.svg, outputs.protected())?;
    note(&format!("wrote {}", a.output.display()));
    Ok(())
}

pub(super) fn lines(args: LinesArgs) -> Result<(), Failure> {
    let ext = |p: &PathBuf| p.extension().and_then(|e| e.to_str()).map(String::from);
    let figure = |p: &PathBuf| FigureFormat::of(p).is_some();
    if let Some(p) = &args.output
        && !figure(p)
        && ext(p).as_deref() != Some("csv")
    {
        return Err(Failure::BadInput(format!(
            "-o {}: the file name must end in {FIGURE_EXTENSIONS} (a figure) or .csv",
            p.display()
        )));
    }
    let mut outputs = Outputs::new(Protected::database(&args.from.db));
    for (flag, path) in [("-o", &args.output), ("--csv", &args.csv)] {
        if let Some(p) = path {
            outputs.claim(flag, p)?;
        }
    }
    let (store, sweep) = args.from.open()?;
    let lines = lines_of(&sweep, &store.points(sweep.id)?);
    if lines.lines.is_empty() {
        return Err(Failure::BadInput(format!(
            "sweep {}: no finished job of a shaken scene: lines of constant Gamma need the \
             drive's Gamma and E* (and at least one finished job)",
            escape(&sweep.name)
        )));
    }
    if args.json {
        print_json(&lines);
    } else {
        show(&lines_table(&lines));
    }
    for (path, csv) in [(&args.output, false), (&args.csv, true)] {
        let Some(path) = path else { continue };
        if !csv && figure(path) {
            let svg = if args.overlay {
                overlay_svg(&lines)
            } else {
                lines_svg(&lines)
            }
            .map_err(Failure::BadInput)?;
            write_figure(path, &svg, outputs.protected())?;
        } else {
            write_file(path, lines_csv(&lines), outputs.protected())?;
        }
        note(&format!("wrote {}", path.display()));
    }
    Ok(())
}

/// The phase map of a sweep as `wetgran plot` draws it: the first slice of its map with its
/// branches (slices that differ only in `initial.start`), the landmark lines of a shaking sweep
/// and the chain model of a shear sweep; `y_log`: the y axis's scale (`None`: `Scale::Auto`).
pub(super) fn draw_map(
    store: &Store,
    sweep: &SweepRow,
    how: Extraction,
    y_log: Option<bool>,
) -> Result<DrawnMap, Failure> {
    let points = store.point_summaries(sweep)?;
    let map = super::sweep_cmd::sweep_map(store, sweep, &points, how)?;
    let landmarks = points
        .first()
        .and_then(|p| plot_phase::Landmarks::of(&p.scene));
    let Some(slice) = map.slices.first() else {
        return Err(Failure::BadInput(format!(
            "sweep {}: no classified point to plot yet",
            escape(&sweep.name)
        )));
    };
    // The branches (slices differing only in `initial.start`) draw as one map: the slices
    // whose other fixed coordinates are those of the first slice.
    let start_label = sweep
        .axes
        .iter()
        .find(|a| a.key == crate::boundary::START_AXIS)
        .map(|a| a.label.clone());
    let others = |sl: &crate::boundary::Slice| -> Vec<(String, serde_json::Value)> {
        sl.fixed
            .iter()
            .filter(|(l, _)| Some(l) != start_label.as_ref())
            .cloned()
            .collect()
    };
    let drawn: Vec<&crate::boundary::Slice> = map
        .slices
        .iter()
        .filter(|sl| others(sl) == others(slice))
        .collect();
    if drawn.len() < map.slices.len() {
        note(&format!(
            "sweep {} has {} slices (axes beyond the plane); plotting {}{}",
            escape(&sweep.name),
            map.slices.len(),
            if drawn.len() > 1 {
                "the branches of the first: "
            } else {
                "the first: "
            },
            if others(slice).is_empty() {
                fixed_text(&slice.fixed)
            } else {
                fixed_text(&others(slice))
            }
        ));
    }
    // A log axis where the sweep's axis is logarithmic, unless `y_log` chose.
    let log_kind = |a: &Option<crate::boundary::PlaneAxis>| {
        a.as_ref()
            .map(|a| a.log || sweep.axes[a.index].kind == crate::sweep::AxisKind::Log)
    };
    let style = MapStyle {
        x_log: log_kind(&map.x),
        y_log: y_log.or(log_kind(&map.y)),
    };
    let title = format!("wetgran phase diagram: {}", escape(&sweep.name));
    // The scene of each grid point's first job, by its coordinates (what `find` over the
    // points gave, without a search per point).
    let mut scene_at: HashMap<String, &Scene> = HashMap::new();
    for p in &points {
        scene_at
            .entry(serde_json::Value::from(p.coords.clone()).to_string())
            .or_insert(p.scene.as_ref());
    }
    let chain = plot_phase::chain_model_line(&map, slice, |coords| {
        scene_at
            .get(&serde_json::Value::from(coords.to_vec()).to_string())
            .map(|s| (*s).clone())
    });
    plot_phase::branches_map(&map, &drawn, landmarks, chain, &title, style)
        .map_err(|e| Failure::BadInput(format!("sweep {}: {e}", escape(&sweep.name))))
}

/// The snapshot (from the stored final state), profiles and time series of each finished job.
fn pictures(
    store: &Store,
    sweep: &crate::store::SweepRow,
    rows: &[crate::store::PointRow],
    snapshots: bool,
) -> Result<HashMap<String, JobPictures>, Failure> {
    let mut out = HashMap::new();
    for r in rows.iter().filter(|r| r.status == "done") {
        let mut pics = JobPictures::default();
        let observables: Option<Observables> = r
            .observables
            .as_ref()
            .and_then(|o| serde_json::from_value(o.clone()).ok());
        match &observables {
            Some(o) => {
                pics.profiles = Some(profiles_svg(o));
                let title = series_title(&sweep.name, &sweep.axes, r);
                pics.series = Some(series_svg(o, &title, r.phase.as_deref()));
            }
            None => pics
                .notes
                .push("No profiles: the stored observables are not readable.".to_string()),
        }
        if snapshots {
            match store.checkpoint(&r.job_id)? {
                Some(state) => {
                    let frame = Frame::of_saved_state(&state, &r.spec.scene);
                    let unit = observables.as_ref().map_or(1.0, |o| o.temperature_unit);
                    pics.snapshot = Some(snapshot_svg(&frame, ColourBy::KineticEnergy, unit));
                }
                None => pics.notes.push(
                    "No snapshot: the database holds no final state of this job (`wetgran \
                     show --snapshot` runs it again)."
                        .to_string(),
                ),
            }
        }
        out.insert(r.job_id.clone(), pics);
    }
    Ok(out)
}

pub(super) fn report(args: ReportArgs) -> Result<(), Failure> {
    let protected = Protected::database(&args.from.db);
    // The folder is checked (and its temporary twin made) before the work.
    let folder = SiteFolder::create(&args.output, args.force, &protected)?;
    let (store, sweep) = args.from.open()?;
    let how = Extraction {
        include_unconverged: args.include_unconverged,
    };
    let rows = store.points(sweep.id)?;
    let summaries = store.point_summaries(&sweep)?;
    let map = super::sweep_cmd::sweep_map(&store, &sweep, &summaries, how)?;
    let plane = map
        .x
        .as_ref()
        .zip(map.y.as_ref())
        .map(|(x, y)| (x.index, y.index));
    // A sweep without a map (one numeric axis, nothing classified yet) still gets its
    // report, with the reason in place of the map.
    let drawn = match draw_map(&store, &sweep, how, args.y_scale.log()) {
        Ok(d) => Ok(d),
        Err(Failure::BadInput(m)) => Err(m),
        Err(e) => return Err(e),
    };
    let sensitivity = crate::report::sensitivity::sensitivity(&sweep, &rows, &summaries, how)
        .map(|s| crate::report::sensitivity::sensitivity_text(&s));
    let lines = lines_of(&sweep, &rows);
    let line_pictures = if lines.lines.is_empty() {
        None
    } else {
        let all = lines_svg(&lines).map_err(Failure::Other)?;
        let per_gamma = lines
            .gammas()
            .into_iter()
            .map(|g| {
                let one = Lines {
                    lines: lines.at_gamma(g).into_iter().cloned().collect(),
                    ..lines.clone()
                };
                lines_svg(&one).map_err(Failure::Other)
            })
            .collect::<Result<Vec<String>, Failure>>()?;
        Some((all, per_gamma))
    };
    let pictures = pictures(&store, &sweep, &rows, !args.no_snapshots)?;
    let source = store.sweep_source(sweep.id)?;
    let input = SiteInput {
        sweep: &sweep,
        source: &source,
        db: &args.from.db.display().to_string(),
        out: &args.output.display().to_string(),
        rows: &rows,
        map: drawn.as_ref().map_err(Clone::clone),
        plane,
        phase_map: &map,
        summaries: &summaries,
        how,
        sensitivity: sensitivity.as_deref().map_err(Clone::clone),
        lines: line_pictures
            .as_ref()
            .map(|(all, per)| (&lines, all.as_str(), per.as_slice())),
        pictures: &pictures,
    };
    let files = site(&input);
    for (path, text) in &files {
        folder.write(path, text)?;
    }
    folder.commit()?;
    note(&format!(
        "wrote {} ({} files; open it in a browser)",
        args.output.join("index.html").display(),
        files.len()
    ));
    Ok(())
}
