//! The parameters table of the report's index (`report::site`): the physical constants of the
//! sweep's scene (grains, box, restitution, the bridge's `s_crit` and `E_cb`, the drive, the
//! start, the engine), read from the scenes its jobs ran (each job's scene is the sweep's base
//! scene with its axis values written in). A parameter the jobs do not share (a swept one, or
//! one an axis changes, such as the container's amplitude) shows its range over the jobs.

use super::esc;
use crate::run::runner::short;
use wetgran_core::scene::{Boundary, CapillaryModel, DriveKind, EngineKind, Scene};

/// One parameter's value in one scene.
#[derive(Debug, Clone, PartialEq)]
enum Value {
    Num(f64),
    Text(String),
}

/// A row of the table: name, symbol, unit, scene key (or how it is derived) and its value.
struct Parameter {
    name: &'static str,
    symbol: &'static str,
    unit: &'static str,
    key: &'static str,
    value: fn(&Scene) -> Option<Value>,
}

fn num(x: f64) -> Option<Value> {
    Some(Value::Num(x))
}

fn text(s: impl Into<String>) -> Option<Value> {
    Some(Value::Text(s.into()))
}

/// The mean of `d^k` over the scene's size distribution (uniform on `d (1 +- sqrt(3) sigma_p)`,
/// docs/model.md Eq. 2.22): `d^2 (1 + sigma_p^2)` for `k = 2`, `d^3 (1 + 3 sigma_p^2)` for 3.
fn mean_diameter_power(s: &Scene, k: i32) -> f64 {
    let (d, sigma) = (s.particles.diameter, s.particles.polydispersity);
    match k {
        2 => d * d * (1.0 + sigma * sigma),
        _ => d * d * d * (1.0 + 3.0 * sigma * sigma),
    }
}

/// The share of the box the grains fill: `N pi <d^2> / 4` over the area (2D), `N pi <d^3> / 6`
/// over the volume (3D).
fn filling_fraction(s: &Scene) -> Option<f64> {
    let size: f64 = s.container.size.iter().product();
    let n = s.particles.count as f64;
    let grains = match s.dimension {
        2 => n * std::f64::consts::PI * mean_diameter_power(s, 2) / 4.0,
        3 => n * std::f64::consts::PI * mean_diameter_power(s, 3) / 6.0,
        _ => return None,
    };
    (size > 0.0).then(|| grains / size)
}

/// The rows, in reading order (wet-only rows give nothing for a dry scene and are left out).
const PARAMETERS: &[Parameter] = &[
    Parameter {
        name: "dimension",
        symbol: "",
        unit: "",
        key: "dimension",
        value: |s| {
            text(if s.dimension == 2 {
                "2D, disks"
            } else {
                "3D, spheres"
            })
        },
    },
    Parameter {
        name: "grains",
        symbol: "N",
        unit: "",
        key: "particles.count",
        value: |s| num(s.particles.count as f64),
    },
    Parameter {
        name: "box",
        symbol: "L_x × H",
        unit: "d",
        key: "box.size",
        value: |s| {
            let sizes: Vec<String> = s.container.size.iter().map(|x| short(*x)).collect();
            text(sizes.join(" × "))
        },
    },
    Parameter {
        name: "boundaries",
        symbol: "",
        unit: "",
        key: "box.boundary",
        value: |s| {
            let axes = ["x", "y", "z"];
            let names: Vec<&str> = if s.dimension == 2 {
                vec!["x", "z"]
            } else {
                axes.to_vec()
            };
            let parts: Vec<String> = s
                .boundaries()
                .iter()
                .zip(names)
                .map(|(b, a)| match b {
                    Boundary::Periodic => format!("{a} periodic"),
                    Boundary::Wall => format!("{a} walls"),
                })
                .collect();
            text(parts.join(", "))
        },
    },
    Parameter {
        name: "filling fraction",
        symbol: "φ",
        unit: "",
        key: "N π ⟨d²⟩ / 4 per area (3D: ⟨d³⟩ / 6 per volume)",
        value: |s| filling_fraction(s).map(Value::Num),
    },
    Parameter {
        name: "mean diameter",
        symbol: "d",
        unit: "",
        key: "particles.diameter",
        value: |s| num(s.particles.diameter),
    },
    Parameter {
        name: "polydispersity",
        symbol: "σ_p",
        unit: "",
        key: "particles.polydispersity",
        value: |s| num(s.particles.polydispersity),
    },
    Parameter {
        name: "mass",
        symbol: "m",
        unit: "",
        key: "particles.mass",
        value: |s| num(s.particles.mass),
    },
    Parameter {
        name: "gravity",
        symbol: "g",
        unit: "",
        key: "gravity",
        value: |s| num(s.gravity),
    },
    Parameter {
        name: "restitution, grain-grain",
        symbol: "ε",
        unit: "",
        key: "contact.restitution",
        value: |s| num(s.contact.restitution),
    },
    Parameter {
        name: "restitution, grain-wall",
        symbol: "e_w",
        unit: "",
        key: "contact.wall_restitution",
        value: |s| num(s.contact.wall_restitution),
    },
    Parameter {
        name: "capillary bridges",
        symbol: "",
        unit: "",
        key: "capillary.model",
        value: |s| {
            text(match s.capillary.model {
                CapillaryModel::None => "none (dry)",
                CapillaryModel::ThinThread => "thin thread (hysteretic)",
            })
        },
    },
    Parameter {
        name: "rupture separation",
        symbol: "s_crit",
        unit: "d",
        key: "capillary.s_crit",
        value: |s| s.is_wet().then(|| Value::Num(s.s_crit())),
    },
    Parameter {
        name: "bridge energy",
        symbol: "E_cb",
        unit: "m g d",
        key: "capillary.e_cb",
        value: |s| s.is_wet().then(|| Value::Num(s.e_cb())),
    },
    Parameter {
        name: "bridge force",
        symbol: "F_B = E_cb / s_crit",
        unit: "m g",
        key: "docs/model.md 3.1",
        value: |s| (s.is_wet() && s.s_crit() > 0.0).then(|| Value::Num(s.e_cb() / s.s_crit())),
    },
    Parameter {
        name: "drive",
        symbol: "",
        unit: "",
        key: "drive.kind",
        value: |s| {
            text(match s.drive.kind {
                DriveKind::None => "none (static walls)",
                DriveKind::Sine => "shaken: z_w = A sin(ω t)",
                DriveKind::Shear => "shear: F_max cos(2π x / L_x) along y",
            })
        },
    },
    Parameter {
        name: "peak acceleration",
        symbol: "Γ",
        unit: "g",
        key: "drive.gamma",
        value: |s| s.drive.gamma.map(Value::Num),
    },
    Parameter {
        name: "driving energy",
        symbol: "E*",
        unit: "E_cb (dry: m g d)",
        key: "drive.e_star",
        value: |s| s.drive.e_star.map(Value::Num),
    },
    Parameter {
        name: "amplitude",
        symbol: "A",
        unit: "d",
        key: "from Γ and E* (docs/model.md 4.1)",
        value: |s| s.drive_motion().map(|(a, _)| Value::Num(a)),
    },
    Parameter {
        name: "angular frequency",
        symbol: "ω",
        unit: "√(g/d)",
        key: "from Γ and E* (docs/model.md 4.1)",
        value: |s| s.drive_motion().map(|(_, w)| Value::Num(w)),
    },
    Parameter {
        name: "peak shear force",
        symbol: "F_max",
        unit: "m g",
        key: "drive.f_max",
        value: |s| s.drive.f_max.map(Value::Num),
    },
    Parameter {
        name: "start",
        symbol: "",
        unit: "",
        key: "initial.start",
        value: |s| text(s.initial.start.to_string()),
    },
    Parameter {
        name: "initial temperature",
        symbol: "T_g(0)",
        unit: "m g d",
        key: "initial.temperature(_over_ecb)",
        value: |s| num(s.initial_temperature()),
    },
    Parameter {
        name: "engine",
        symbol: "",
        unit: "",
        key: "engine.kind",
        value: |s| {
            text(match s.engine.kind {
                EngineKind::Event => "event-driven (hard grains)",
                EngineKind::Time => "time-driven (soft Hertz grains)",
            })
        },
    },
    Parameter {
        name: "run length cap",
        symbol: "",
        unit: "√(d/g)",
        key: "run.duration",
        value: |s| num(s.run.duration),
    },
];

/// A value over the jobs: the one they share, or the range they span.
fn over_jobs(values: &[Value]) -> Option<(String, bool)> {
    let first = values.first()?;
    if values.iter().all(|v| v == first) {
        return Some(match first {
            Value::Num(x) => (short(*x), false),
            Value::Text(t) => (t.clone(), false),
        });
    }
    let nums: Vec<f64> = values
        .iter()
        .filter_map(|v| match v {
            Value::Num(x) => Some(*x),
            Value::Text(_) => None,
        })
        .collect();
    if nums.len() == values.len() {
        let lo = nums.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = nums.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut distinct = nums.clone();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup();
        return Some((
            format!("{} … {} ({} values)", short(lo), short(hi), distinct.len()),
            true,
        ));
    }
    let mut texts: Vec<String> = values
        .iter()
        .map(|v| match v {
            Value::Num(x) => short(*x),
            Value::Text(t) => t.clone(),
        })
        .collect();
    texts.sort();
    texts.dedup();
    Some((texts.join(", "), true))
}

/// The parameters table (HTML) of the scenes `scenes` (one per job, in job order): one row
/// per parameter a scene has, with its scene key; a row whose value differs between the jobs
/// is marked `varies` and shows the range.
pub(super) fn parameters_table(scenes: &[&Scene]) -> String {
    let mut h = String::from(
        "<table class=\"parameters\">\n<thead><tr><th>parameter</th><th>symbol</th>\
         <th>value</th><th>unit</th><th>scene key</th></tr></thead>\n<tbody>\n",
    );
    for p in PARAMETERS {
        let values: Vec<Value> = scenes.iter().filter_map(|s| (p.value)(s)).collect();
        if values.len() < scenes.len() {
            // Missing in some scene (a dry scene's s_crit, a shear drive's Gamma).
            if values.is_empty() {
                continue;
            }
        }
        let Some((value, varies)) = over_jobs(&values) else {
            continue;
        };
        let (class, note) = if varies {
            (
                " class=\"varies\"",
                " <span class=\"note\">varies over the jobs</span>",
            )
        } else {
            ("", "")
        };
        h.push_str(&format!(
            "<tr{class} data-key=\"{}\"><td>{}</td><td>{}</td><td>{}{note}</td>\
             <td>{}</td><td><code>{}</code></td></tr>\n",
            esc(p.key),
            esc(p.name),
            esc(p.symbol),
            esc(&value),
            esc(p.unit),
            esc(p.key)
        ));
    }
    h.push_str("</tbody>\n</table>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(gamma: f64) -> Scene {
        let text = format!(
            "dimension = 2\n[box]\nsize = [20.0, 9.0]\n[particles]\ncount = 40\n\
             polydispersity = 0.06\n[contact]\nrestitution = 0.9\n[capillary]\n\
             model = \"thin_thread\"\n[drive]\nkind = \"sine\"\ngamma = {gamma}\ne_star = 2.0\n\
             [initial]\ntemperature_over_ecb = 20.0\n[run]\nduration = 10.0\n"
        );
        Scene::from_toml_str(&text, "test").unwrap()
    }

    /// The cells of the row of `key`: (value cell, whether it is marked as varying).
    fn row<'a>(html: &'a str, key: &str) -> Option<&'a str> {
        let start = html.find(&format!("data-key=\"{key}\""))?;
        let rest = &html[start..];
        Some(&rest[..rest.find("</tr>").unwrap()])
    }

    #[test]
    fn shared_constants_show_once_and_swept_ones_as_ranges() {
        let (a, b) = (scene(1.5), scene(3.0));
        let html = parameters_table(&[&a, &b]);
        // N, eps and the docs/model.md defaults of s_crit and E_cb = 4 m g s_crit.
        assert!(row(&html, "particles.count").unwrap().contains(">40<"));
        assert!(row(&html, "contact.restitution").unwrap().contains(">0.9<"));
        assert!(row(&html, "capillary.s_crit").unwrap().contains(">0.0711<"));
        assert!(row(&html, "capillary.e_cb").unwrap().contains(">0.2844<"));
        assert!(row(&html, "box.size").unwrap().contains("20 × 9"));
        // Gamma is swept; A and omega follow it.
        let gamma = row(&html, "drive.gamma").unwrap();
        assert!(gamma.contains("1.5 … 3 (2 values)") && gamma.contains("varies"));
        assert!(!row(&html, "particles.count").unwrap().contains("varies"));
        // 40 disks of <d^2> = 1.0036 in 20 x 9.
        let phi = 40.0 * std::f64::consts::PI * 1.0036 / 4.0 / 180.0;
        assert!(
            row(&html, "N π ⟨d²⟩ / 4 per area (3D: ⟨d³⟩ / 6 per volume)")
                .unwrap()
                .contains(&short(phi))
        );
        // A shaken scene has no shear force row.
        assert!(row(&html, "drive.f_max").is_none());
    }
}
