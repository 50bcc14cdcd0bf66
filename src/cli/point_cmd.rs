//! Commands on stored results: `wetgran show` (one sweep point, found by its job id or nearest
//! to given coordinates: its phase and a summary of what decided it, its lateral profiles and
//! time series from the stored observables, and a snapshot of its stored final state, or of a
//! re-run of its job spec, which is deterministic, where none is stored) and `wetgran inflection` (the fluid-gas boundary of
//! inelastic systems along lines of constant Gamma, docs/model.md 7).

use super::common::{
    Failure, check_snapshot_names, latest_sweep, note, print_json, show as show_text,
};
use crate::boundary::START_AXIS;
use crate::output::{Outputs, Protected};
use crate::report::figure::{figure_format, write_figure};
use crate::report::point_text::{
    coordinates_text, decision_text, gamma_lines, inflection_json, inflection_text, job_json,
    job_text, series_title,
};
use crate::report::series_plot::series_svg;
use crate::report::{ColourBy, profiles_svg, write_snapshot};
use crate::store::{PointRow, Store, SweepRow};
use crate::sweep::file::{Axis, AxisKind};
use crate::terminal::escape;
use clap::Args;
use std::path::PathBuf;
use wetgran_core::observe::{Observables, run_observed_with_frame};
use wetgran_core::sim::Frame;

/// The stored job whose id starts with `prefix` (at least 6 characters), with its sweep:
/// of the sweeps that hold the job, the one `sweep` names, else the one registered or refined
/// last (the rule of `common::latest_sweep`), named on stderr when several hold it.
fn find_job(
    store: &Store,
    prefix: &str,
    sweep: Option<&str>,
) -> Result<(SweepRow, PointRow), Failure> {
    if prefix.len() < 6 || !prefix.chars().all(|c| c.is_ascii_hexdigit()) {
        return Err(Failure::BadInput(format!(
            "job `{prefix}`: give at least 6 hex digits of a job id (`wetgran export` lists \
             them), or find it by its coordinates with `--at gamma=2.19,e_star=1.19`"
        )));
    }
    let sweeps: std::collections::HashMap<i64, SweepRow> =
        store.sweeps()?.into_iter().map(|s| (s.id, s)).collect();
    let wanted = sweep.map(|n| store.sweep(n)).transpose()?;
    // Later is (updated_at, id) greater: the order of `common::latest_sweep`.
    let when = |id: &i64| sweeps.get(id).map(|s| (s.updated_at, s.id));
    let mut found: Vec<(i64, usize, PointRow)> = Vec::new();
    for (sweep_id, p) in store.points_with_job_prefix(prefix)? {
        if wanted.as_ref().is_some_and(|w| w.id != sweep_id) {
            continue;
        }
        match found.iter_mut().find(|(_, _, q)| q.job_id == p.job_id) {
            None => found.push((sweep_id, 1, p)),
            Some((id, holders, q)) => {
                *holders += 1;
                if when(&sweep_id) > when(id) {
                    (*id, *q) = (sweep_id, p);
                }
            }
        }
    }
    let name = |id: &i64| sweeps.get(id).map(|s| s.name.clone()).unwrap_or_default();
    if let [(id, holders @ 2.., _)] = found.as_slice() {
        note(&format!(
            "job in {holders} sweeps: shown under sweep {} (registered or refined last; \
             --sweep NAME takes another)",
            escape(&name(id))
        ));
    }
    let mut found: Vec<(SweepRow, PointRow)> = found
        .into_iter()
        .filter_map(|(id, _, p)| Some((sweeps.get(&id)?.clone(), p)))
        .collect();
    match found.len() {
        1 => Ok(found.remove(0)),
        0 => Err(Failure::BadInput(format!(
            "no job id starts with `{prefix}` in {}",
            store.path().display()
        ))),
        n => Err(Failure::BadInput(format!(
            "job `{prefix}` is ambiguous: {n} jobs start with it; give more digits"
        ))),
    }
}

/// One wanted coordinate of `--at`: the name as given and its value (a number, or a text such
/// as a branch).
type Wanted = (String, serde_json::Value);

/// Parses `--at` (`gamma=2.19,e_star=1.19`).
fn parse_at(at: &str) -> Result<Vec<Wanted>, Failure> {
    let bad = |why: String| Failure::BadInput(format!("--at `{}`: {why}", escape(at)));
    let mut out: Vec<Wanted> = Vec::new();
    for part in at.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let Some((k, v)) = part.split_once('=') else {
            return Err(bad(format!("`{}` is not AXIS=VALUE", escape(part))));
        };
        let (k, v) = (k.trim(), v.trim());
        if out.iter().any(|(n, _)| n.eq_ignore_ascii_case(k)) {
            return Err(bad(format!("axis `{}` given twice", escape(k))));
        }
        let value = match v.parse::<f64>() {
            Ok(x) if x.is_finite() => serde_json::Value::from(x),
            Ok(_) => return Err(bad(format!("`{}` is not a finite number", escape(v)))),
            Err(_) => serde_json::Value::from(v),
        };
        out.push((k.to_string(), value));
    }
    if out.is_empty() {
        return Err(bad("give AXIS=VALUE pairs, comma-separated".to_string()));
    }
    Ok(out)
}

/// The index of the axis a name of `--at` means: its name in the sweep file (`gamma`), its
/// scene key (`drive.gamma`) or its label (`Gamma`, `E*`), in any case.
fn axis_index(axes: &[Axis], name: &str) -> Option<usize> {
    axes.iter().position(|a| {
        [&a.name, &a.key, &a.label]
            .iter()
            .any(|n| n.eq_ignore_ascii_case(name))
    })
}

/// Whether `--at` compares an axis on a log scale: a log axis, and `E*` (drawn log).
fn log_axis(a: &Axis) -> bool {
    a.kind == AxisKind::Log || a.is_e_star()
}

/// The jobs nearest to the coordinates of `at` (see [`ShowArgs::at`]): the first by point and
/// replica, its sweep, and the other jobs at the same position (other branches, replicas).
/// Each numeric axis counts in its own scale, as a fraction of its grid's span.
fn find_at(
    store: &Store,
    sweep: Option<&str>,
    at: &str,
) -> Result<(SweepRow, PointRow, Vec<PointRow>), Failure> {
    let wanted = parse_at(at)?;
    // The one rule of every command: the sweep named, else the one registered or refined last.
    let sweeps = vec![latest_sweep(store, sweep, false)?];
    let mut best: Option<(f64, SweepRow, Vec<PointRow>)> = None;
    let mut matching_sweeps = 0;
    for s in &sweeps {
        let Some(idx) = wanted
            .iter()
            .map(|(n, _)| axis_index(&s.axes, n))
            .collect::<Option<Vec<usize>>>()
        else {
            continue;
        };
        matching_sweeps += 1;
        // Per wanted axis: the scale and the span of its grid in that scale.
        let mut scale: Vec<(bool, f64)> = Vec::new();
        for (&k, (n, v)) in idx.iter().zip(&wanted) {
            let a = &s.axes[k];
            let log = log_axis(a) && a.values.iter().all(|x| x.as_f64().is_some_and(|x| x > 0.0));
            if v.is_number() && !a.values.iter().any(|x| x.is_number()) {
                return Err(Failure::BadInput(format!(
                    "--at: axis `{}` of sweep {} is not numeric (its values: {})",
                    escape(n),
                    escape(&s.name),
                    serde_json::Value::from(a.values.clone())
                )));
            }
            if log && v.as_f64().is_some_and(|x| x <= 0.0) {
                return Err(Failure::BadInput(format!(
                    "--at: {} = {v} on a log axis: give a positive value",
                    escape(n)
                )));
            }
            let f = |x: f64| if log { x.log10() } else { x };
            let grid: Vec<f64> = a.values.iter().filter_map(|x| x.as_f64()).map(f).collect();
            let lo = grid.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = grid.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let span = if hi > lo { hi - lo } else { 1.0 };
            scale.push((log, span));
        }
        for r in store.points(s.id)? {
            let mut d2 = 0.0;
            let mut fits = true;
            for ((&k, (_, v)), &(log, span)) in idx.iter().zip(&wanted).zip(&scale) {
                let c = r.coords.get(k);
                match (v.as_f64(), c.and_then(|c| c.as_f64())) {
                    (Some(w), Some(x)) => {
                        let f = |x: f64| {
                            if log {
                                x.max(f64::MIN_POSITIVE).log10()
                            } else {
                                x
                            }
                        };
                        d2 += ((f(x) - f(w)) / span).powi(2);
                    }
                    _ => {
                        // A text value (a branch) matches exactly, or by its words.
                        let text = v.as_str().unwrap_or_default();
                        let stored = c.and_then(|c| c.as_str()).unwrap_or_default();
                        fits &= stored.eq_ignore_ascii_case(text)
                            || crate::boundary::branch_words(stored).eq_ignore_ascii_case(text);
                    }
                }
            }
            if !fits {
                continue;
            }
            let near = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300);
            match &mut best {
                Some((d, bs, jobs)) if near(d2, *d) && bs.id == s.id => {
                    if !jobs.iter().any(|j| j.job_id == r.job_id) {
                        jobs.push(r);
                    }
                }
                Some((d, _, _)) if d2 >= *d => {}
                _ => best = Some((d2, s.clone(), vec![r])),
            }
        }
    }
    if matching_sweeps == 0 {
        let known: Vec<String> = sweeps
            .iter()
            .map(|s| {
                let names: Vec<String> = s
                    .axes
                    .iter()
                    .map(|a| format!("{} ({})", a.name, a.label))
                    .collect();
                format!("{}: {}", escape(&s.name), names.join(", "))
            })
            .collect();
        let unknown: Vec<String> = wanted
            .iter()
            .filter(|(n, _)| sweeps.iter().all(|s| axis_index(&s.axes, n).is_none()))
            .map(|(n, _)| format!("`{}`", escape(n)))
            .collect();
        let what = if unknown.is_empty() {
            "no sweep has all of these axes".to_string()
        } else {
            format!("unknown axis {}", unknown.join(", "))
        };
        return Err(Failure::BadInput(format!(
            "--at `{}`: {what}; the axes are {}",
            escape(at),
            if known.is_empty() {
                "none (no sweep stored)".to_string()
            } else {
                known.join("; ")
            }
        )));
    }
    let Some((_, s, mut jobs)) = best else {
        return Err(Failure::BadInput(format!(
            "--at `{}`: no job matches (a branch or text value not in the sweep?)",
            escape(at)
        )));
    };
    jobs.sort_by_key(|j| (j.point, j.replica));
    let first = jobs.remove(0);
    Ok((s, first, jobs))
}

/// The `also near` line of `show --at`: the other jobs as near as the one shown.
fn also_near(axes: &[Axis], others: &[PointRow]) -> String {
    let list: Vec<String> = others
        .iter()
        .map(|o| {
            format!(
                "{} ({}; {})",
                &o.job_id[..12.min(o.job_id.len())],
                escape(&coordinates_text(axes, o)),
                branch_text(axes, o)
            )
        })
        .collect();
    format!("also near   {}", list.join(", "))
}

/// The branch and replica of a job, in words (`cold start, replica 0`).
fn branch_text(axes: &[Axis], p: &PointRow) -> String {
    let branch = axes
        .iter()
        .position(|a| a.key == START_AXIS)
        .and_then(|k| p.coords.get(k)?.as_str().map(crate::boundary::branch_words));
    match branch {
        Some(b) => format!("{b}, replica {}", p.replica),
        None => format!("replica {}", p.replica),
    }
}

#[derive(Debug, Args)]
pub struct ShowArgs {
    /// Database file; also from WETGRAN_DB (the flag wins).
    #[arg(long, env = "WETGRAN_DB", default_value = super::common::DEFAULT_DB)]
    pub db: PathBuf,
    /// The job: at least 6 leading hex digits of its id (`wetgran export` lists ids); or
    /// `--at`.
    #[arg(required_unless_present = "at", conflicts_with = "at")]
    job: Option<String>,
    /// The job nearest to these coordinates, `AXIS=VALUE,...` by the sweep's axis names or
    /// labels (`gamma=2.19,e_star=1.19`; `initial.start=cold` picks a branch), in each axis's
    /// own scale (log where it is log).
    #[arg(long)]
    at: Option<String>,
    /// Of the sweeps that hold the job (or, with `--at`, the sweep searched), this one
    /// [default: the one registered (`sweep run`) or refined last; named on standard error when
    /// several hold it].
    #[arg(long)]
    sweep: Option<String>,
    /// Write a snapshot of the stored final configuration (`.xyz` for OVITO, or `.svg`);
    /// repeatable.
    #[arg(long)]
    snapshot: Vec<PathBuf>,
    /// Colour of the SVG snapshot: `energy` (kinetic energy / E_cb) or `bridges`.
    #[arg(long, default_value = "energy")]
    colour_by: String,
    /// Write the lateral profiles (T_g / E_cb, packing fraction, n_cb, D_lat against x): a
    /// figure, `.svg`, `.pdf` or `.png` by the extension.
    #[arg(long)]
    profiles: Option<PathBuf>,
    /// Write the run's time series (T_g/E_cb, bridges per grain, Delta n_cb against time, the
    /// transient, the window and the run's end marked): a figure, `.svg`, `.pdf` or `.png` by
    /// the extension.
    #[arg(long)]
    series: Option<PathBuf>,
    /// Print JSON (one object: the job, its phase and what it was decided on, the files
    /// written) instead of the text.
    #[arg(long)]
    json: bool,
}

/// The final configuration of a job: its stored final state (the checkpoint, which the report
/// draws too), else the final state of a re-run of its spec (same spec and seed, same numbers,
/// which the event count confirms), with a line saying which.
fn final_frame(store: &Store, p: &PointRow) -> Result<(Frame, serde_json::Value, String), Failure> {
    if let Some(state) = store.checkpoint(&p.job_id)? {
        let line = format!(
            "final state the stored one, t = {} (the report draws the same)",
            crate::report::point_text::time_label(state.time)
        );
        return Ok((
            Frame::of_saved_state(&state, &p.spec.scene),
            "stored".into(),
            line,
        ));
    }
    let (run, last) =
        run_observed_with_frame(&p.spec.scene, &super::common::all_cores(), &mut |_| {});
    let events = run.report.events_total;
    let line = match p.events {
        Some(stored) if stored as u64 == events => {
            format!(
                "final state no stored one: re-run, reproduces the stored run ({stored} events)"
            )
        }
        Some(stored) => format!(
            "final state no stored one: re-run, WARNING: {events} events, the stored run had \
             {stored} (another build or platform?)"
        ),
        None => format!("final state no stored one: re-run, {events} events"),
    };
    let frame = run
        .report
        .final_state
        .as_ref()
        .map_or(last, |s| Frame::of_saved_state(s, &p.spec.scene));
    Ok((frame, serde_json::json!({ "rerun_events": events }), line))
}

pub(super) fn show(a: ShowArgs) -> Result<(), Failure> {
    let colour_by: ColourBy = a
        .colour_by
        .parse()
        .map_err(|e| Failure::BadInput(format!("--colour-by: {e}")))?;
    let (snapshot, json) = (&a.snapshot, a.json);
    check_snapshot_names(snapshot)?;
    let mut outputs = Outputs::new(Protected::database(&a.db));
    for path in snapshot {
        outputs.claim("--snapshot", path)?;
    }
    if let Some(p) = &a.profiles {
        outputs.claim("--profiles", p)?;
        figure_format("--profiles", p)?;
    }
    if let Some(p) = &a.series {
        outputs.claim("--series", p)?;
        figure_format("--series", p)?;
    }
    let store = Store::open_read_only(&a.db)?;
    let (sweep, p, others) = match (&a.job, &a.at) {
        (Some(job), _) => {
            let (sweep, p) = find_job(&store, job, a.sweep.as_deref())?;
            (sweep, p, Vec::new())
        }
        (None, Some(at)) => find_at(&store, a.sweep.as_deref(), at)?,
        (None, None) => unreachable!("clap requires JOB or --at"),
    };
    let axes = sweep.axes.clone();
    // With --json the lines below go to the object, printed at the end.
    let mut doc = json.then(|| job_json(&sweep.name, &axes, &p));
    let mut say = |key: &str, value: serde_json::Value, line: String| match doc.as_mut() {
        Some(d) => match (&mut d[key], value) {
            (serde_json::Value::Array(a), serde_json::Value::Array(b)) => a.extend(b),
            (slot, v) => *slot = v,
        },
        None => show_text(&format!("{line}\n")),
    };
    if !json {
        show_text(&job_text(&escape(&sweep.name), &axes, &p));
    }
    if !others.is_empty() {
        let ids = others.iter().map(|o| o.job_id.clone()).collect::<Vec<_>>();
        say("also_near", ids.into(), also_near(&axes, &others));
    }
    // Read when a picture needs them: the summary comes from the stored decision alone.
    let observables: Result<Option<Observables>, String> = p
        .observables
        .as_ref()
        .map(|v| serde_json::from_value(v.clone()))
        .transpose()
        .map_err(|e| format!("job {}: stored observables unreadable: {e}", p.job_id));
    if !json {
        show_text(&decision_text(&p));
    }
    let need = |flag: &str| -> Result<&Observables, Failure> {
        match &observables {
            Ok(Some(o)) => Ok(o),
            Ok(None) => Err(Failure::BadInput(format!(
                "{flag}: job {} has no stored observables (status {})",
                p.job_id, p.status
            ))),
            Err(e) => Err(Failure::BadInput(format!("{flag}: {e}"))),
        }
    };
    if let Some(path) = &a.profiles {
        let o = need("--profiles")?;
        write_figure(path, &profiles_svg(o), outputs.protected())?;
        say(
            "profiles",
            path.display().to_string().into(),
            format!(
                "profiles    {} (from the stored observables)",
                path.display()
            ),
        );
    }
    if let Some(path) = &a.series {
        let o = need("--series")?;
        let svg = series_svg(o, &series_title(&sweep.name, &axes, &p), p.phase.as_deref());
        write_figure(path, &svg, outputs.protected())?;
        say(
            "series",
            path.display().to_string().into(),
            format!(
                "series      {} (time series, from the stored observables)",
                path.display()
            ),
        );
    }
    if !snapshot.is_empty() {
        let (frame, source, line) = final_frame(&store, &p)?;
        say("final_state", source, line);
        // As the report colours it (1 where the observables are unreadable).
        let unit = match &observables {
            Ok(Some(o)) => o.temperature_unit,
            _ => 1.0,
        };
        for path in snapshot {
            write_snapshot(path, &frame, colour_by, unit, outputs.protected())?;
            say(
                "snapshots",
                serde_json::json!([path.display().to_string()]),
                format!(
                    "snapshot    {} (final configuration, t = {}, {} bridges)",
                    path.display(),
                    crate::report::point_text::time_label(frame.time),
                    frame.bridges.len()
                ),
            );
        }
    }
    if let Some(d) = doc {
        print_json(&d);
    }
    Ok(())
}

pub(super) fn inflection(a: InflectionArgs) -> Result<(), Failure> {
    let store = Store::open_read_only(&a.from.db)?;
    let mut all = Vec::new();
    for s in a.from.select(&store)? {
        let lines = gamma_lines(&store.points(s.id)?);
        if a.json {
            all.push(inflection_json(&s.name, &lines));
        } else {
            show_text(&inflection_text(&escape(&s.name), &lines));
        }
    }
    if a.json {
        print_json(&all);
    }
    Ok(())
}

#[derive(Debug, Args)]
pub struct InflectionArgs {
    #[command(flatten)]
    pub from: super::common::DbPick,
    /// Print JSON (an array, one object per sweep with its lines) instead of the table.
    #[arg(long)]
    json: bool,
}
