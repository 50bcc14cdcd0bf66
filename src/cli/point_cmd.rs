//! Commands on stored results: `wetgran show` (one sweep point: its phase and the numbers it
//! was decided on, its lateral profiles from the stored observables, and a snapshot by re-running
//! its job spec, which is deterministic) and `wetgran inflection` (the fluid-gas boundary of
//! inelastic systems along lines of constant Gamma, MODEL.md 7).

use super::sweep_cmd::{Failure, exit, select};
use crate::observe::{Observables, fluid_gas_inflection, run_observed_with_frame};
use crate::report::{ColourBy, profiles_svg, write_snapshot};
use crate::store::{PointRow, Store};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The stored job whose id starts with `prefix` (at least 6 characters), with its sweep's name.
fn find_job(store: &Store, prefix: &str) -> Result<(String, PointRow), Failure> {
    if prefix.len() < 6 || !prefix.chars().all(|c| c.is_ascii_hexdigit()) {
        return Err(Failure::BadInput(format!(
            "job `{prefix}`: give at least 6 hex digits of a job id (`wetgran export` lists them)"
        )));
    }
    let mut found: Vec<(String, PointRow)> = Vec::new();
    for s in store.sweeps()? {
        for p in store.points(s.id)? {
            if p.job_id.starts_with(prefix) && !found.iter().any(|(_, q)| q.job_id == p.job_id) {
                found.push((s.name.clone(), p));
            }
        }
    }
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

/// `wetgran show`.
pub fn show(
    db: &Path,
    job: &str,
    snapshot: &[PathBuf],
    colour_by: ColourBy,
    profiles: Option<&Path>,
) -> ExitCode {
    exit((|| {
        for path in snapshot {
            if !matches!(
                path.extension().and_then(|e| e.to_str()),
                Some("xyz" | "svg")
            ) {
                return Err(Failure::BadInput(format!(
                    "--snapshot {}: the file name must end in .xyz or .svg",
                    path.display()
                )));
            }
        }
        let store = Store::open_existing(db)?;
        let (sweep, p) = find_job(&store, job)?;
        println!(
            "job {} (sweep {sweep}, point {}, replica {})",
            p.job_id, p.point, p.replica
        );
        println!("coordinates {}", serde_json::Value::from(p.coords.clone()));
        println!("status      {}", p.status);
        if let Some(e) = &p.last_error {
            println!("last error  {e}");
        }
        let observables: Option<Observables> = match &p.observables {
            Some(v) => Some(serde_json::from_value(v.clone()).map_err(|e| {
                Failure::BadInput(format!(
                    "job {}: stored observables unreadable: {e}",
                    p.job_id
                ))
            })?),
            None => None,
        };
        if let Some(phase) = &p.phase {
            println!("phase       {phase}");
        }
        if let Some(o) = &p.observables {
            match crate::report::trust::stationary(o) {
                Some(true) => println!("stationary  yes"),
                Some(false) => {
                    println!(
                        "stationary  NO ({} in `boundaries`): the averages may still drift",
                        crate::report::trust::NOT_STATIONARY
                    );
                    for c in crate::report::trust::failed_checks(o) {
                        println!("            {c}");
                    }
                }
                None => println!("stationary  unknown (no check stored)"),
            }
        }
        if let Some(d) = &p.decided_on {
            println!(
                "decided on  {}",
                serde_json::to_string_pretty(d).expect("JSON prints")
            );
        }
        if let Some(path) = profiles {
            let Some(o) = &observables else {
                return Err(Failure::BadInput(format!(
                    "--profiles: job {} has no stored observables (status {})",
                    p.job_id, p.status
                )));
            };
            std::fs::write(path, profiles_svg(o))
                .map_err(|e| Failure::Other(format!("{}: cannot write: {e}", path.display())))?;
            println!(
                "profiles    {} (from the stored observables)",
                path.display()
            );
        }
        if !snapshot.is_empty() {
            // The stored spec runs the job again; same spec and seed, same numbers, so the
            // re-run is the stored run, which the event count confirms.
            let (run, frame) = run_observed_with_frame(&p.spec.scene, &mut |_| {});
            match p.events {
                Some(stored) if stored as u64 == run.report.events_total => {
                    println!("re-run      reproduces the stored run ({stored} events)")
                }
                Some(stored) => println!(
                    "re-run      WARNING: {} events, the stored run had {stored} (another \
                     build or platform?)",
                    run.report.events_total
                ),
                None => println!("re-run      {} events", run.report.events_total),
            }
            for path in snapshot {
                write_snapshot(path, &frame, colour_by, run.observables.temperature_unit)
                    .map_err(Failure::Other)?;
                println!("snapshot    {} (final configuration)", path.display());
            }
        }
        Ok(())
    })())
}

/// `(Gamma, E*)` of a shaken scene (MODEL.md 4.1), from the drive as the scene gives it.
fn gamma_e_star(scene: &crate::scene::Scene) -> Option<(f64, f64)> {
    let (a, omega) = scene.drive_motion()?;
    let unit = if scene.is_wet() && scene.e_cb() > 0.0 {
        scene.e_cb()
    } else {
        scene.particles.mass * scene.gravity * scene.particles.diameter
    };
    let gamma = a * omega * omega / scene.gravity;
    let e_star = 0.5 * scene.particles.mass * (a * omega).powi(2) / unit;
    Some((gamma, e_star))
}

/// `wetgran inflection`.
pub fn inflection(db: &Path, name: Option<&str>) -> ExitCode {
    exit((|| {
        let store = Store::open_existing(db)?;
        for s in select(&store, name)? {
            // Lines of constant Gamma: (E*, T_g / E_cb) of every finished job.
            let mut lines: Vec<(f64, Vec<(f64, f64)>)> = Vec::new();
            for p in store.points(s.id)? {
                let (Some(obs), Some((gamma, e_star))) =
                    (&p.observables, gamma_e_star(&p.spec.scene))
                else {
                    continue;
                };
                let Some(t) = obs["granular_temperature_reduced"].as_f64() else {
                    continue;
                };
                match lines
                    .iter_mut()
                    .find(|(g, _)| (g - gamma).abs() <= 1e-9 * gamma.abs())
                {
                    Some((_, pts)) => pts.push((e_star, t)),
                    None => lines.push((gamma, vec![(e_star, t)])),
                }
            }
            lines.sort_by(|a, b| a.0.total_cmp(&b.0));
            println!(
                "sweep {}: fluid-gas inflection of T_g/E_cb(E*) along constant Gamma",
                s.name
            );
            println!(
                "{:>10} {:>7} {:>12} {:>10} {:>22}",
                "Gamma", "points", "E* inflect.", "max slope", "between E*"
            );
            for (gamma, pts) in &lines {
                match fluid_gas_inflection(pts) {
                    Some(i) => println!(
                        "{:>10.4} {:>7} {:>12.4} {:>10.3} {:>10.4} .. {:<10.4}",
                        gamma,
                        pts.len(),
                        i.e_star,
                        i.max_slope,
                        i.bracket.0,
                        i.bracket.1
                    ),
                    None => println!(
                        "{:>10.4} {:>7} {:>12}",
                        gamma,
                        pts.len(),
                        "none (fewer than 4 points, or steepest at an end)"
                    ),
                }
            }
        }
        Ok(())
    })())
}
