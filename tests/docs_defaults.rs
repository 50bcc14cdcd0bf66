//! Documented defaults cannot go stale. Every Markdown table of README.md and docs/*.md whose
//! first column is `key` (scene keys, dotted: `particles.count`) or `sweep key` (keys of a sweep
//! file: `sweep.replicas`, `refine.rounds`, `axis.key`, and the scene keys a sweep sets otherwise
//! than a scene does) and which has a `default` column is compared with the code:
//!
//! - the keys come from the code itself: each section is probed with an unknown key and the
//!   parser's "expected one of ..." list is the section's key list (serde `deny_unknown_fields`);
//! - every key of every scene section must be in docs/scene-reference.md, every key of the sweep
//!   sections in docs/sweep-reference.md; a documented key the code does not know fails;
//! - a default written as a value (`1e-3`, `true`, `` `gear5` ``, `[128, 128]`) must equal the
//!   code's default: the parsed minimal scene or sweep, or where the parsed field is left empty
//!   the accessor that fills it in (`Scene::e_cb`, `Scene::wall_table_spec`, ...); `required`
//!   must be a key the parser cannot do without; `none` a key that stays empty;
//! - a default that is a rule (`4 m g s_crit`, `T / 1000`) must be written exactly as listed in
//!   [`RULES`], and that entry checks the rule against the code.

use serde_json::{Value, json};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use wetgran::sweep::SweepFile;
use wetgran_core::scene::{self, Scene, damping};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

// ---------------------------------------------------------------------------------------------
// What the code says

/// A scene that only has its required keys (and `initial.temperature`, one of two alternatives).
const MINIMAL: [(&str, &str); 5] = [
    ("", "dimension = 2"),
    ("box", "size = [20.0, 10.0]"),
    ("particles", "count = 10"),
    ("initial", "temperature = 1.0"),
    ("run", "duration = 4.0"),
];

/// The minimal scene as TOML, without the key `skip` (`section.key`), plus `extra` at the end.
fn minimal_text(skip: &str, extra: &str) -> String {
    let mut text = String::new();
    for (section, line) in MINIMAL {
        let key = line.split(" =").next().unwrap_or("");
        let full = if section.is_empty() {
            key.to_string()
        } else {
            format!("{section}.{key}")
        };
        if !section.is_empty() {
            text.push_str(&format!("[{section}]\n"));
        }
        if full != skip {
            text.push_str(line);
            text.push('\n');
        }
    }
    text + extra
}

/// The field list serde prints for an unknown key (`expected one of `a`, `b``).
fn probe<T: serde::de::DeserializeOwned + std::fmt::Debug>(doc: &str) -> Option<Vec<String>> {
    let err = toml::from_str::<T>(doc).err()?.to_string();
    let line = err
        .lines()
        .find(|l| l.contains("unknown field `zz_probe`"))?;
    let expected = line.split("expected").nth(1).unwrap_or("");
    Some(
        expected
            .split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect(),
    )
}

/// Every key of every scene section, dotted (`dimension`, `box.size`, ...).
fn scene_keys() -> Vec<String> {
    let top = probe::<Scene>("zz_probe = 1").expect("the scene rejects unknown keys");
    let mut keys = Vec::new();
    for field in top {
        match probe::<Scene>(&format!("[{field}]\nzz_probe = 1\n")) {
            Some(inner) => keys.extend(inner.into_iter().map(|k| format!("{field}.{k}"))),
            None => keys.push(field),
        }
    }
    keys
}

/// A default as the code has it.
#[derive(Debug, Clone, PartialEq)]
enum Code {
    /// The parser refuses a file without the key.
    Required,
    /// This value where the key is left out.
    Value(Value),
    /// Nothing (the option stays off, or a rule fills it in: see [`RULES`]).
    Absent,
}

fn parse_scene(text: &str) -> Scene {
    toml::from_str(text).unwrap_or_else(|e| panic!("{text}\n{e}"))
}

fn lookup(v: &Value, dotted: &str) -> Option<Value> {
    let mut node = v;
    for part in dotted.split('.') {
        node = node.get(part)?;
    }
    (!node.is_null()).then(|| node.clone())
}

/// Defaults of the keys whose parsed field is empty or not serialized at its default: what the
/// code fills in.
fn scene_fill_in(key: &str, s: &Scene) -> Option<Value> {
    let table = s.wall_table_spec(1.0, 1.0);
    Some(match key {
        "contact.stiffness" => json!(s.contact.stiffness.unwrap_or(scene::DEFAULT_STIFFNESS)),
        "contact.restitution_speed" => match damping::calibration(s) {
            damping::Calibration::Maxwellian(_) => json!("auto"),
            damping::Calibration::Speed(v) => json!(v),
        },
        "capillary.rupture_rule" => serde_json::to_value(s.rupture_rule()).ok()?,
        "drive.root_tolerance" => {
            json!(
                s.drive
                    .root_tolerance
                    .unwrap_or(scene::DEFAULT_ROOT_TOLERANCE)
            )
        }
        "drive.table_cells" => json!([table.phase_cells, table.velocity_cells]),
        "drive.table_v_min" => json!(table.v_min),
        "drive.table_v_max" => json!(table.v_max),
        "drive.table_corner_check" => json!(table.corner_tolerance.is_some()),
        "drive.table_corner_tolerance" => json!(table.corner_tolerance),
        "initial.start" => serde_json::to_value(s.initial.start).ok()?,
        "engine.kind" => serde_json::to_value(s.engine.kind).ok()?,
        "engine.integrator" => {
            serde_json::to_value(s.engine.integrator.unwrap_or_default()).ok()?
        }
        "engine.skin" => json!(s.engine.skin.unwrap_or(scene::DEFAULT_SKIN)),
        "observe.transient_time" => json!(s.observe.transient_time),
        "observe.min_sample_interval" => json!(s.observe.min_sample_interval),
        "observe.bond_time" => json!(s.observe.bond_time),
        "observe.cluster_min_size" => json!(s.observe.cluster_min_size),
        _ => return None,
    })
}

/// The code's default of every scene key.
fn scene_defaults() -> BTreeMap<String, Code> {
    // With an empty `[convergence]` so that its defaults are the parser's too.
    let s = parse_scene(&minimal_text("", "[convergence]\n"));
    let tree = serde_json::to_value(&s).expect("a scene serializes");
    let mut out = BTreeMap::new();
    for key in scene_keys() {
        let required = toml::from_str::<Scene>(&minimal_text(&key, "")).is_err();
        let code = if required {
            Code::Required
        } else if let Some(v) = scene_fill_in(&key, &s).or_else(|| lookup(&tree, &key)) {
            if v.is_null() {
                Code::Absent
            } else {
                Code::Value(v)
            }
        } else {
            Code::Absent
        };
        out.insert(key, code);
    }
    out
}

/// A minimal sweep file: the minimal scene inline, one axis, and `extra` (more tables).
fn sweep_text(header: &str, extra: &str) -> String {
    let mut text = format!("[sweep]\n{header}\n");
    for (section, line) in MINIMAL {
        if section.is_empty() {
            text.push_str(&format!("[scene]\n{line}\n"));
        } else {
            text.push_str(&format!("[scene.{section}]\n{line}\n"));
        }
    }
    text + "[[axis]]\nkey = \"gravity\"\nvalues = [1.0, 2.0]\n" + extra
}

fn parse_sweep(text: &str) -> Result<SweepFile, String> {
    SweepFile::parse(text, Path::new("defaults.toml")).map_err(|e| e.to_string())
}

fn sweep_keys() -> Vec<String> {
    use wetgran::sweep::file::RawSweep;
    let probes = [
        ("sweep", "[sweep]\nzz_probe = 1\n"),
        ("sweep.continuation", "[sweep.continuation]\nzz_probe = 1\n"),
        ("refine", "[refine]\nzz_probe = 1\n"),
        ("axis", "[[axis]]\nzz_probe = 1\n"),
    ];
    let mut keys = Vec::new();
    for (section, doc) in probes {
        let fields = probe::<RawSweep>(doc).expect("sweep sections reject unknown keys");
        for f in fields {
            // `[sweep.continuation]` is a section of its own, probed above.
            if !(section == "sweep" && f == "continuation") {
                keys.push(format!("{section}.{f}"));
            }
        }
    }
    keys
}

/// The code's default of every key of the sweep sections, and of the scene keys whose default in
/// a sweep differs from a scene's (found by comparing an expanded job with the minimal scene).
fn sweep_defaults() -> BTreeMap<String, Code> {
    let name = "name = \"d\"";
    let sweep = parse_sweep(&sweep_text(name, "")).expect("the minimal sweep parses");
    let cont = parse_sweep(&sweep_text(
        name,
        "[sweep.continuation]\naxis = \"gravity\"\n",
    ))
    .expect("a continuation parses")
    .continuation
    .expect("continuation");
    let refine = parse_sweep(&sweep_text(name, "[refine]\nbudget = 4\n"))
        .expect("a refine table parses")
        .refine
        .expect("refine");
    let opt = |v: Option<Value>| v.map_or(Code::Absent, Code::Value);
    let mut out = BTreeMap::new();
    for key in sweep_keys() {
        let code = match key.as_str() {
            "sweep.name" | "sweep.continuation.axis" | "refine.budget" | "axis.key" => {
                Code::Required
            }
            "sweep.description" => opt(sweep.description.clone().map(Value::from)),
            "sweep.base" => opt(sweep.base.as_ref().map(|b| json!(b.0))),
            "sweep.replicas" => Code::Value(json!(sweep.replicas)),
            "sweep.periods" => opt(sweep.periods.map(Value::from)),
            "sweep.cost" => opt(sweep.cost.clone().map(Value::from)),
            "sweep.skip_invalid" => Code::Value(json!(sweep.skip_invalid)),
            "sweep.continuation.direction" => Code::Value(json!(if cont.descending {
                "descending"
            } else {
                "ascending"
            })),
            "sweep.continuation.first" => Code::Value(json!(cont.first.to_string())),
            "refine.rounds" => Code::Value(json!(refine.rounds)),
            "refine.resolution" => Code::Value(json!(refine.resolution)),
            "refine.max_replicas" | "axis.values" | "axis.linear" | "axis.log" => Code::Absent,
            other => panic!("sweep key {other} is new: give it a default in this test"),
        };
        out.insert(key, code);
    }
    // The scene keys a sweep sets otherwise than a scene file does.
    let sweep = parse_sweep(&sweep_text(&format!("{name}\nperiods = 8"), "")).expect("periods");
    let job = &sweep.expand().expect("the minimal sweep expands")[0]
        .spec
        .scene;
    let job = serde_json::to_value(job).expect("a job's scene serializes");
    let plain = Scene::from_toml_str(&minimal_text("", ""), "minimal.toml").expect("valid");
    let plain = serde_json::to_value(plain).expect("a scene serializes");
    for section in ["observe", "classify", "run"] {
        for (k, v) in job[section].as_object().expect("a section is an object") {
            // `run.duration` is `sweep.periods` driving periods.
            if plain[section].get(k) != Some(v) && k != "duration" {
                out.insert(format!("{section}.{k}"), Code::Value(v.clone()));
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Rules: defaults that are not one value

type Check = fn() -> Result<(), String>;

/// `(key, the default cell exactly as documented, the check of that rule against the code)`.
const RULES: &[(&str, &str, Check)] = &[
    (
        "box.boundary",
        "periodic laterally, `wall` vertically",
        boundary_rule,
    ),
    (
        "contact.damping",
        "from `contact.restitution`",
        damping_rule,
    ),
    (
        "contact.wall_damping",
        "from `contact.wall_restitution`",
        damping_rule,
    ),
    (
        "contact.restitution_temperature",
        "the initial temperature of a hot start (else the drive's scale, docs/model-choices.md)",
        restitution_temperature_rule,
    ),
    ("capillary.s_crit", "0.0711 d", s_crit_rule),
    ("capillary.e_cb", "`4 m g s_crit`", e_cb_rule),
    ("drive.f_max", "required with `shear`", f_max_rule),
    ("drive.slab_width", "1 d", slab_width_rule),
    ("drive.t_min", "`T / 1000`", t_min_rule),
    ("initial.temperature", "one of the two", one_of_two_rule),
    (
        "initial.temperature_over_ecb",
        "one of the two",
        one_of_two_rule,
    ),
    (
        "engine.dt",
        "1e-4, or the largest allowed step where that is shorter",
        dt_rule,
    ),
    (
        "observe.location_changes",
        "off, unless `classify.mobility = \"location_changes\"`",
        location_changes_rule,
    ),
    ("convergence.max_periods", "`4 t_1 / T`", max_periods_rule),
    (
        "refine.max_replicas",
        "3 x `sweep.replicas`",
        max_replicas_rule,
    ),
    ("axis.values", "one of the three", axis_rule),
    ("axis.linear", "one of the three", axis_rule),
    ("axis.log", "one of the three", axis_rule),
    (
        "observe.transient_periods",
        "a quarter of the run",
        transient_rule,
    ),
    (
        "run.sample_interval",
        "one observer sample",
        sample_interval_rule,
    ),
];

fn ensure(ok: bool, what: String) -> Result<(), String> {
    if ok { Ok(()) } else { Err(what) }
}

fn checked(extra: &str) -> Result<Scene, String> {
    Scene::from_toml_str(&minimal_text("", extra), "rule.toml").map_err(|e| e.to_string())
}

fn boundary_rule() -> Result<(), String> {
    use scene::Boundary::{Periodic, Wall};
    let b = checked("")?.boundaries();
    ensure(b == [Periodic, Wall], format!("2D boundaries {b:?}"))
}

fn damping_rule() -> Result<(), String> {
    let time = "[engine]\nkind = \"time\"\n";
    let elastic = damping::contact_damping(&checked(time)?);
    let lossy = checked(&format!(
        "{time}[contact]\nrestitution = 0.9\nwall_restitution = 0.8\n"
    ))?;
    let (pair, wall) = damping::contact_damping(&lossy);
    ensure(
        elastic == (0.0, 0.0) && pair > 0.0 && wall > pair,
        format!("A_d elastic {elastic:?}, for restitutions 0.9 and 0.8 ({pair}, {wall})"),
    )
}

fn restitution_temperature_rule() -> Result<(), String> {
    let s = checked("[engine]\nkind = \"time\"\n[contact]\nrestitution = 0.9\n")?;
    let cal = damping::calibration(&s);
    ensure(
        cal == damping::Calibration::Maxwellian(s.initial_temperature()),
        format!("calibration {cal:?}"),
    )
}

fn s_crit_rule() -> Result<(), String> {
    let text = minimal_text("", "[capillary]\nmodel = \"thin_thread\"\n")
        .replace("count = 10", "count = 10\ndiameter = 2.0");
    let s = Scene::from_toml_str(&text, "rule.toml").map_err(|e| e.to_string())?;
    ensure(
        (s.s_crit() - 0.1422).abs() < 1e-12,
        format!("s_crit {} at d = 2", s.s_crit()),
    )
}

fn e_cb_rule() -> Result<(), String> {
    let text = minimal_text("", "[capillary]\nmodel = \"thin_thread\"\ns_crit = 0.1\n")
        .replace("count = 10", "count = 10\nmass = 2.0")
        .replace("dimension = 2", "dimension = 2\ngravity = 0.5");
    let s = Scene::from_toml_str(&text, "rule.toml").map_err(|e| e.to_string())?;
    ensure(
        (s.e_cb() - 4.0 * 2.0 * 0.5 * 0.1).abs() < 1e-12,
        format!("E_cb {} for m = 2, g = 0.5, s_crit = 0.1", s.e_cb()),
    )
}

fn shear_text(drive: &str, diameter: f64) -> String {
    format!(
        "dimension = 3\n[box]\nsize = [12.0, 12.0, 6.0]\nboundary = [\"periodic\", \"periodic\", \
         \"wall\"]\n[particles]\ncount = 10\ndiameter = {diameter}\n[initial]\ntemperature = 1.0\n\
         [run]\nduration = 1.0\n[drive]\nkind = \"shear\"\n{drive}"
    )
}

fn f_max_rule() -> Result<(), String> {
    let with = Scene::from_toml_str(&shear_text("f_max = 0.5\n", 1.0), "rule.toml");
    let without = Scene::from_toml_str(&shear_text("", 1.0), "rule.toml");
    ensure(
        with.is_ok() && without.as_ref().is_err_and(|e| e.key == "drive.f_max"),
        format!("shear with f_max: {with:?}; without: {without:?}"),
    )
}

fn slab_width_rule() -> Result<(), String> {
    let s = Scene::from_toml_str(&shear_text("f_max = 0.5\n", 1.5), "rule.toml")
        .map_err(|e| e.to_string())?;
    let slabs = s.shear_slabs().ok_or("no slabs")?;
    ensure(
        slabs.count == 8 && (slabs.width - 1.5).abs() < 1e-12,
        format!("slabs {slabs:?} for L_x = 12, d = 1.5"),
    )
}

fn t_min_rule() -> Result<(), String> {
    let s = checked("")?;
    let step = s.bracket_step(2.0);
    ensure(
        (step - std::f64::consts::PI / 1000.0).abs() < 1e-15,
        format!("t_min {step} at omega = 2"),
    )
}

fn one_of_two_rule() -> Result<(), String> {
    let neither = Scene::from_toml_str(&minimal_text("initial.temperature", ""), "rule.toml");
    let ratio = minimal_text("", "[capillary]\nmodel = \"thin_thread\"\n")
        .replace("temperature = 1.0", "temperature_over_ecb = 2.0");
    let by_ratio = Scene::from_toml_str(&ratio, "rule.toml").map_err(|e| e.to_string())?;
    ensure(
        neither.is_err() && (by_ratio.initial_temperature() - 2.0 * by_ratio.e_cb()).abs() < 1e-12,
        format!("without a temperature: {neither:?}"),
    )
}

fn dt_rule() -> Result<(), String> {
    let s = checked("[engine]\nkind = \"time\"\n")?;
    let stiff = checked("[engine]\nkind = \"time\"\n[contact]\nstiffness = 1e12\n")?;
    ensure(
        s.time_step() == scene::DEFAULT_DT
            && scene::DEFAULT_DT == 1e-4
            && stiff.time_step() == stiff.largest_time_step()
            && stiff.time_step() < 1e-4,
        format!("dt {} and, stiff, {}", s.time_step(), stiff.time_step()),
    )
}

fn location_changes_rule() -> Result<(), String> {
    let off = checked("")?;
    let on = checked("[classify]\nmobility = \"location_changes\"\n")?;
    ensure(
        off.observe.location_changes == Some(false) && on.observe.location_changes == Some(true),
        format!(
            "default {:?}, with mobility = location_changes {:?}",
            off.observe.location_changes, on.observe.location_changes
        ),
    )
}

fn max_periods_rule() -> Result<(), String> {
    // Longer than the two mobility lags (20 time units) the first check holds at least.
    let s = checked("[convergence]\nmin_time = 30.0\n")?;
    let schedule = s.convergence.as_ref().ok_or("no convergence")?.schedule(&s);
    ensure(
        schedule.cap == 4.0 * schedule.first_check && schedule.first_check == 30.0,
        format!("{schedule:?}"),
    )
}

fn max_replicas_rule() -> Result<(), String> {
    let sweep = parse_sweep(&sweep_text(
        "name = \"d\"\nreplicas = 2",
        "[refine]\nbudget = 4\n",
    ))?;
    let r = sweep.refine.ok_or("no refine")?;
    ensure(
        r.max_replicas == 6,
        format!("max_replicas {}", r.max_replicas),
    )
}

fn axis_rule() -> Result<(), String> {
    let bare = sweep_text("name = \"d\"", "[[axis]]\nkey = \"initial.seed\"\n");
    ensure(
        parse_sweep(&bare).is_err(),
        "an axis without values parses".into(),
    )
}

fn transient_rule() -> Result<(), String> {
    let sweep = parse_sweep(&sweep_text("name = \"d\"\nperiods = 8", ""))?;
    let job = &sweep.expand().map_err(|e| e.to_string())?[0].spec.scene;
    let t = job.observe.transient_periods;
    ensure(t == 2.0, format!("transient {t} periods of 8"))
}

fn sample_interval_rule() -> Result<(), String> {
    let sweep = parse_sweep(&sweep_text("name = \"d\"\nperiods = 8", ""))?;
    let job = &sweep.expand().map_err(|e| e.to_string())?[0].spec.scene;
    let (dt, obs) = (job.run.sample_interval, job.observe.sample_interval(job));
    ensure(
        dt == obs,
        format!("run.sample_interval {dt}, observer {obs}"),
    )
}

// ---------------------------------------------------------------------------------------------
// What the documents say

/// One documented default.
#[derive(Debug, Clone)]
struct Documented {
    place: String,
    /// `true` in a `sweep key` table.
    sweep: bool,
    key: String,
    cell: String,
}

/// Splits the cell of a row naming several keys: `4, 3, 0.02` for three keys, or one value for
/// all of them.
fn split_cell(cell: &str, n: usize) -> Vec<String> {
    let parts: Vec<String> = cell.split(", ").map(|s| s.trim().to_string()).collect();
    if n > 1 && parts.len() == n {
        parts
    } else {
        vec![cell.trim().to_string(); n]
    }
}

fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
    inner.split('|').map(|c| c.trim().to_string()).collect()
}

/// Every row of every key/default table of one document.
fn documented_in(path: &Path) -> Vec<Documented> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i + 1 < lines.len() {
        let header = cells(lines[i]);
        let is_table = lines[i].starts_with('|') && lines[i + 1].starts_with("|--");
        let sweep = header.first().is_some_and(|h| h == "sweep key");
        let keyed = header.first().is_some_and(|h| h == "key") || sweep;
        let default = header.iter().position(|h| h == "default");
        let (true, true, Some(col)) = (is_table, keyed, default) else {
            i += 1;
            continue;
        };
        i += 2;
        while i < lines.len() && lines[i].starts_with('|') {
            let row = cells(lines[i]);
            let keys: Vec<String> = row[0]
                .split('`')
                .skip(1)
                .step_by(2)
                .map(str::to_string)
                .collect();
            let cell = row.get(col).cloned().unwrap_or_default();
            for (key, part) in keys.iter().zip(split_cell(&cell, keys.len())) {
                out.push(Documented {
                    place: format!("{}:{}", path.display(), i + 1),
                    sweep,
                    key: key.clone(),
                    cell: part,
                });
            }
            i += 1;
        }
    }
    out
}

fn documents() -> Vec<PathBuf> {
    let mut files = vec![root().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/ is readable")
        .map(|e| e.expect("docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

/// The value a documented default cell stands for, where it is one value.
fn literal(cell: &str) -> Option<Value> {
    let c = cell.trim();
    let quoted = c
        .strip_prefix('`')
        .and_then(|s| s.strip_suffix('`'))
        .filter(|s| !s.contains('`'));
    let c = quoted.unwrap_or(c);
    if let Ok(v) = serde_json::from_str::<Value>(c) {
        return Some(v);
    }
    if let Ok(x) = c.parse::<f64>() {
        return Some(json!(x));
    }
    let word = c.trim_matches('"');
    let is_word = !word.is_empty()
        && word
            .chars()
            .all(|ch| ch.is_ascii_lowercase() || ch == '_' || ch.is_ascii_digit());
    // Bare `none` and `required` are the words of the table's legend; `` `none` `` is a value.
    (is_word && (quoted.is_some() || (word != "none" && word != "required"))).then(|| json!(word))
}

/// Numbers compare as `f64` (`1e-3` and `0.001`, `4` and `4.0` are one default).
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.as_f64() == y.as_f64(),
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same(p, q))
        }
        _ => a == b,
    }
}

/// `None` where the documented default agrees with the code, else what is wrong.
fn disagreement(doc: &Documented, code: &Code) -> Option<String> {
    let cell = doc.cell.as_str();
    let rule = RULES.iter().find(|(k, _, _)| *k == doc.key);
    let verdict = match (cell, code, rule) {
        ("required", Code::Required, _) | ("none", Code::Absent, _) => Ok(()),
        (_, _, Some((_, text, check))) if *text == cell => check(),
        (_, Code::Value(v), _) => match literal(cell) {
            Some(d) if same(&d, v) => Ok(()),
            Some(d) => Err(format!("documented {d}, the code's default is {v}")),
            None => Err(format!("the code's default is {v}, documented as {cell:?}")),
        },
        (_, _, Some((_, text, _))) => Err(format!("write the rule as {text:?}, not {cell:?}")),
        _ => Err(format!(
            "the code's default is {code:?}, documented as {cell:?}"
        )),
    };
    verdict
        .err()
        .map(|e| format!("{}: `{}`: {e}", doc.place, doc.key))
}

fn check_documents(
    docs: &[Documented],
    scene: &BTreeMap<String, Code>,
    sweep: &BTreeMap<String, Code>,
) -> Vec<String> {
    let mut problems = Vec::new();
    for doc in docs {
        let known = if doc.sweep { sweep } else { scene };
        match known.get(&doc.key) {
            None => problems.push(format!(
                "{}: `{}` is no {} key of the code",
                doc.place,
                doc.key,
                if doc.sweep { "sweep" } else { "scene" }
            )),
            Some(code) => problems.extend(disagreement(doc, code)),
        }
    }
    problems
}

fn missing_from(file: &str, docs: &[Documented], keys: &BTreeMap<String, Code>, sweep: bool) {
    let here: BTreeSet<&str> = docs
        .iter()
        .filter(|d| d.sweep == sweep && d.place.contains(file))
        .map(|d| d.key.as_str())
        .collect();
    let missing: Vec<&str> = keys
        .keys()
        .map(String::as_str)
        .filter(|k| !here.contains(k))
        .collect();
    assert!(missing.is_empty(), "{file} does not document: {missing:?}");
}

#[test]
fn every_documented_default_is_the_codes() {
    let docs: Vec<Documented> = documents().iter().flat_map(|p| documented_in(p)).collect();
    let (scene, sweep) = (scene_defaults(), sweep_defaults());
    assert!(
        scene.len() > 80 && sweep.len() > 15,
        "probing found too few keys"
    );
    let problems = check_documents(&docs, &scene, &sweep);
    assert!(
        problems.is_empty(),
        "documented defaults that disagree with the code:\n{}",
        problems.join("\n")
    );
    missing_from("docs/scene-reference.md", &docs, &scene, false);
    missing_from("docs/sweep-reference.md", &docs, &sweep, true);
}

#[test]
fn every_rule_holds_in_the_code() {
    for (key, text, check) in RULES {
        if let Err(e) = check() {
            panic!("`{key}` = {text:?}: {e}");
        }
    }
}

#[test]
fn a_wrong_missing_or_extra_default_is_caught() {
    let (scene, sweep) = (scene_defaults(), sweep_defaults());
    let doc = |key: &str, cell: &str, sweep: bool| Documented {
        place: "t.md:1".into(),
        sweep,
        key: key.into(),
        cell: cell.into(),
    };
    let good = [
        doc("engine.min_rebound_speed", "1e-3", false),
        doc("drive.table_cells", "`[128, 128]`", false),
        doc("engine.integrator", "`gear5`", false),
        doc("capillary.e_cb", "`4 m g s_crit`", false),
        doc("run.duration", "required", false),
        doc("run.max_events", "none", false),
        doc("refine.rounds", "4", true),
    ];
    assert_eq!(check_documents(&good, &scene, &sweep), Vec::<String>::new());
    let bad = [
        doc("engine.min_rebound_speed", "1e-2", false),
        doc("classify.mobility", "`location_changes`", false),
        doc("capillary.e_cb", "`2 m g s_crit`", false),
        doc("run.duration", "1", false),
        doc("engine.no_such_key", "1", false),
        doc("refine.rounds", "4", false),
    ];
    assert_eq!(check_documents(&bad, &scene, &sweep).len(), bad.len());
    assert!(scene.contains_key("observe.mobility_lag") && sweep.contains_key("refine.rounds"));
}

/// Every sweep file shown in README.md and docs/*.md (a ```toml block starting with `[sweep]`)
/// parses and expands as if it were a file in `sweeps/`.
#[test]
fn every_sweep_example_in_the_docs_expands() {
    let mut examples = 0;
    for path in documents() {
        let text = std::fs::read_to_string(&path).expect("readable");
        for block in text.split("```toml\n").skip(1) {
            let body = block.split("```").next().unwrap_or("");
            if !body.starts_with("[sweep]") {
                continue;
            }
            examples += 1;
            let file = root().join("sweeps/example-from-the-docs.toml");
            let jobs = SweepFile::parse(body, &file).and_then(|s| s.expand());
            assert!(
                jobs.as_ref().is_ok_and(|j| !j.is_empty()),
                "{}: the example sweep does not expand: {:?}",
                path.display(),
                jobs.err()
            );
        }
    }
    assert!(examples >= 2, "only {examples} example sweeps found");
}
