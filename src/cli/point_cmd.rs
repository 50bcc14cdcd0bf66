//! Commands on stored results: `wetgran show` (one sweep point: its phase and the numbers it
//! was decided on, its lateral profiles from the stored observables, and a snapshot by re-running
//! its job spec, which is deterministic) and `wetgran inflection` (the fluid-gas boundary of
//! inelastic systems along lines of constant Gamma, docs/model.md 7).

use super::common::{
    Failure, check_snapshot_names, note, print_json, show as show_text, write_file,
};
use crate::output::{Outputs, Protected};
use crate::report::point_text::{
    decision_text, gamma_lines, inflection_json, inflection_text, job_json, job_text,
};
use crate::report::{ColourBy, profiles_svg, write_snapshot};
use crate::store::{PointRow, Store};
use crate::terminal::escape;
use clap::Args;
use std::path::PathBuf;
use wetgran_core::observe::{Observables, run_observed_with_frame};

/// The stored job whose id starts with `prefix` (at least 6 characters), with its sweep's name:
/// of the sweeps that hold the job, the one `sweep` names, else the one registered or refined
/// last (the rule of `common::latest_sweep`), named on stderr when several hold it.
fn find_job(
    store: &Store,
    prefix: &str,
    sweep: Option<&str>,
) -> Result<(String, PointRow), Failure> {
    if prefix.len() < 6 || !prefix.chars().all(|c| c.is_ascii_hexdigit()) {
        return Err(Failure::BadInput(format!(
            "job `{prefix}`: give at least 6 hex digits of a job id (`wetgran export` lists them)"
        )));
    }
    let sweeps: std::collections::HashMap<i64, crate::store::SweepRow> =
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
    let mut found: Vec<(String, PointRow)> =
        found.into_iter().map(|(id, _, p)| (name(&id), p)).collect();
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

#[derive(Debug, Args)]
pub struct ShowArgs {
    /// Database file; also from WETGRAN_DB (the flag wins).
    #[arg(long, env = "WETGRAN_DB", default_value = super::common::DEFAULT_DB)]
    pub db: PathBuf,
    /// The job: at least 6 leading hex digits of its id (`wetgran export` lists ids).
    job: String,
    /// Of the sweeps that hold the job, this one [default: the one registered (`sweep run`)
    /// or refined last; named on standard error when several hold it].
    #[arg(long)]
    sweep: Option<String>,
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
    }
    let store = Store::open_read_only(&a.db)?;
    let (sweep, p) = find_job(&store, &a.job, a.sweep.as_deref())?;
    // With --json the lines below go to the object, printed at the end.
    let mut doc = json.then(|| job_json(&sweep, &p));
    let mut say = |key: &str, value: serde_json::Value, line: String| match doc.as_mut() {
        Some(d) => match (&mut d[key], value) {
            (serde_json::Value::Array(a), serde_json::Value::Array(b)) => a.extend(b),
            (slot, v) => *slot = v,
        },
        None => show_text(&format!("{line}\n")),
    };
    if !json {
        show_text(&job_text(&escape(&sweep), &p));
    }
    let observables: Option<Observables> = p
        .observables
        .as_ref()
        .map(|v| serde_json::from_value(v.clone()))
        .transpose()
        .map_err(|e| {
            Failure::BadInput(format!(
                "job {}: stored observables unreadable: {e}",
                p.job_id
            ))
        })?;
    if !json {
        show_text(&decision_text(&p));
    }
    if let Some(path) = &a.profiles {
        let Some(o) = &observables else {
            return Err(Failure::BadInput(format!(
                "--profiles: job {} has no stored observables (status {})",
                p.job_id, p.status
            )));
        };
        write_file(path, profiles_svg(o), outputs.protected())?;
        say(
            "profiles",
            path.display().to_string().into(),
            format!(
                "profiles    {} (from the stored observables)",
                path.display()
            ),
        );
    }
    if !snapshot.is_empty() {
        // The stored spec runs the job again; same spec and seed, same numbers, so the
        // re-run is the stored run, which the event count confirms.
        let (run, frame) =
            run_observed_with_frame(&p.spec.scene, &super::common::all_cores(), &mut |_| {});
        let events = run.report.events_total;
        let line = match p.events {
            Some(stored) if stored as u64 == events => {
                format!("re-run      reproduces the stored run ({stored} events)")
            }
            Some(stored) => format!(
                "re-run      WARNING: {events} events, the stored run had {stored} (another \
                 build or platform?)"
            ),
            None => format!("re-run      {events} events"),
        };
        say("rerun_events", events.into(), line);
        for path in snapshot {
            write_snapshot(
                path,
                &frame,
                colour_by,
                run.observables.temperature_unit,
                outputs.protected(),
            )?;
            say(
                "snapshots",
                serde_json::json!([path.display().to_string()]),
                format!("snapshot    {} (final configuration)", path.display()),
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
