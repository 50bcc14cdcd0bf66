//! The conventions of issue 45 through the binary: `sweep run` prints its results on stdout
//! and its progress on stderr; every command that reads a sweep's results takes one sweep by
//! one rule (the one registered or refined last, named on stderr; `--sweep NAME`;
//! `--all-sweeps` where a command combines them) and says so in its `--help`; `export` carries
//! standard errors and writes the system's constants to a sidecar beside its file.

mod sweep_common;

use serde_json::Value;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use sweep_common::*;

/// A sweep `name` of the tiny scene over the given Gamma and E* values, 4 periods a job.
fn sweep(dir: &Path, name: &str, gammas: &str, e_stars: &str) -> PathBuf {
    write(dir, "tiny.toml", TINY_SCENE);
    write(
        dir,
        &format!("{name}.toml"),
        &format!(
            "[sweep]\nname = \"{name}\"\nbase = \"tiny.toml\"\nperiods = 4\n\
             [[axis]]\nkey = \"gamma\"\nvalues = [{gammas}]\n\
             [[axis]]\nkey = \"e_star\"\nvalues = [{e_stars}]\n"
        ),
    )
}

fn ok(args: &[&str]) -> std::process::Output {
    let o = run(args);
    assert!(o.status.success(), "{args:?}: {}", both(&o));
    o
}

/// A database with two sweeps: `a` (4 jobs), then `b` (2 jobs, one of them shared with `a`:
/// Gamma = 3, E* = 2), registered in that order; returns the folder, the database and the
/// output of `b`'s `sweep run`.
fn two_sweeps() -> (tempfile::TempDir, PathBuf, std::process::Output) {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("w.sqlite");
    let a = sweep(dir.path(), "a", "2.0, 3.0", "1.0, 2.0");
    let b = sweep(dir.path(), "b", "3.0", "2.0, 3.0");
    let d = db.to_str().unwrap();
    ok(&[
        "sweep",
        "run",
        a.to_str().unwrap(),
        "--db",
        d,
        "--jobs",
        "1",
    ]);
    let out = ok(&[
        "sweep",
        "run",
        b.to_str().unwrap(),
        "--db",
        d,
        "--jobs",
        "1",
    ]);
    (dir, db, out)
}

/// The note the rule prints when it picks `name` of two sweeps.
fn picked(o: &std::process::Output, name: &str) -> bool {
    stderr(o).contains(&format!(
        "sweep {name} (registered or refined last of the 2 sweeps"
    ))
}

/// The cells of one CSV line (quoted cells may hold commas and doubled quotes).
fn cells(line: &str) -> Vec<String> {
    let (mut out, mut cell, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cell.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cell)),
            (c, _) => cell.push(c),
        }
    }
    out.push(cell);
    out
}

/// Rows of a CSV text (no line break inside a cell) as maps from column to cell.
fn csv_rows(text: &str) -> Vec<HashMap<String, String>> {
    let mut lines = text.lines();
    let header = cells(lines.next().unwrap());
    lines
        .map(|l| {
            let row = cells(l);
            assert_eq!(row.len(), header.len(), "{l}");
            header.iter().cloned().zip(row).collect()
        })
        .collect()
}

#[test]
fn sweep_run_prints_results_on_stdout_and_progress_on_stderr() {
    let (_dir, _db, out) = two_sweeps();
    let (o, e) = (stdout(&out), stderr(&out));
    // `sweep run > log` keeps one line per finished job and the summary.
    assert_eq!(
        o.matches("] done ").count(),
        1,
        "stdout:\n{o}\nstderr:\n{e}"
    );
    assert!(o.contains("finished: 1 job(s) done, 0 failed"), "{o}");
    for line in o.lines().filter(|l| l.contains("] done ")) {
        assert!(line.contains("(job ") && line.contains("phase "), "{line}");
    }
    // The status note stays on stderr, and no job line goes there.
    assert!(
        e.contains("sweep b: 2 jobs, 1 finished before, 1 to run"),
        "{e}"
    );
    assert!(!e.contains("] done "), "{e}");
}

#[test]
fn every_reading_command_takes_the_latest_sweep_unless_told() {
    let (dir, db, _) = two_sweeps();
    let d = db.to_str().unwrap();
    // boundaries: b, named on stderr; --sweep a; --all-sweeps both.
    let o = ok(&["boundaries", "--db", d, "--json"]);
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    let names = |v: &Value| -> Vec<String> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|s| s["sweep"].as_str().unwrap().to_string())
            .collect()
    };
    assert_eq!(names(&v), ["b"], "{v}");
    assert!(picked(&o, "b"), "{}", stderr(&o));
    let o = ok(&["boundaries", "--db", d, "--json", "--sweep", "a"]);
    assert_eq!(names(&serde_json::from_str(&stdout(&o)).unwrap()), ["a"]);
    assert!(!stderr(&o).contains("registered or refined last"));
    let o = ok(&["boundaries", "--db", d, "--json", "--all-sweeps"]);
    assert_eq!(
        names(&serde_json::from_str(&stdout(&o)).unwrap()),
        ["a", "b"]
    );
    let o = run(&["boundaries", "--db", d, "--sweep", "a", "--all-sweeps"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // export: the rows of b only, unless --all-sweeps.
    let o = ok(&["export", "--db", d]);
    let rows = csv_rows(&stdout(&o));
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r["sweep"] == "b"));
    assert!(picked(&o, "b"), "{}", stderr(&o));
    let rows = csv_rows(&stdout(&ok(&["export", "--db", d, "--all-sweeps"])));
    assert_eq!(rows.len(), 6);
    // inflection and lines: b.
    let o = ok(&["inflection", "--db", d, "--json"]);
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v.as_array().unwrap().len(), 1, "{v}");
    assert_eq!(v[0]["sweep"], "b", "{v}");
    assert!(picked(&o, "b"));
    let o = ok(&["lines", "--db", d, "--json"]);
    assert!(picked(&o, "b"), "{}", stderr(&o));
    assert_eq!(
        serde_json::from_str::<Value>(&stdout(&o)).unwrap()["sweep"],
        "b"
    );
    // plot: b (its title names the sweep).
    let svg = dir.path().join("map.svg");
    let o = ok(&["plot", "--db", d, "-o", svg.to_str().unwrap()]);
    assert!(picked(&o, "b"), "{}", stderr(&o));
    // sweep refine takes b too (and refuses the zero budget only after picking it).
    let o = run(&["sweep", "refine", "--db", d, "--budget", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(picked(&o, "b"), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--budget: = 0 is out of range"),
        "{}",
        stderr(&o)
    );
    // show: the job of both sweeps under b, unless --sweep a.
    let shared = csv_rows(&stdout(&ok(&["export", "--db", d, "--sweep", "a"])))
        .into_iter()
        .find(|r| {
            let at = |k: &str| r[k].parse::<f64>().unwrap();
            at("drive.gamma") == 3.0 && at("drive.e_star") == 2.0
        })
        .unwrap()["job_id"][..12]
        .to_string();
    let o = ok(&["show", &shared, "--db", d]);
    assert!(stdout(&o).contains("(sweep b, point 0"), "{}", stdout(&o));
    assert!(
        stderr(&o).contains("job in 2 sweeps: shown under sweep b"),
        "{}",
        stderr(&o)
    );
    let o = ok(&["show", &shared, "--db", d, "--sweep", "a"]);
    assert!(stdout(&o).contains("(sweep a, point "), "{}", stdout(&o));
    // The rule is in every such command's --help.
    for cmd in [
        &["boundaries"][..],
        &["export"],
        &["plot"],
        &["lines"],
        &["report"],
        &["inflection"],
        &["show"],
        &["sweep", "refine"],
    ] {
        let help = stdout(&ok(&[cmd, &["--help"]].concat()));
        let flat = help.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(
            flat.contains("registered (`sweep run`) or refined last"),
            "{cmd:?}: {help}"
        );
    }
}

#[test]
fn export_carries_standard_errors_and_a_sidecar_of_the_system() {
    let (dir, db, _) = two_sweeps();
    let d = db.to_str().unwrap();
    let csv = dir.path().join("r.csv");
    let o = ok(&[
        "export",
        "--db",
        d,
        "--sweep",
        "a",
        "-o",
        csv.to_str().unwrap(),
    ]);
    let rows = csv_rows(&std::fs::read_to_string(&csv).unwrap());
    assert_eq!(rows.len(), 4);
    // Beside each averaged observable its standard error, the same as `lines` gives.
    let lines_csv = dir.path().join("l.csv");
    ok(&[
        "lines",
        "--db",
        d,
        "--sweep",
        "a",
        "-o",
        lines_csv.to_str().unwrap(),
    ]);
    let lines = csv_rows(&std::fs::read_to_string(&lines_csv).unwrap());
    for r in &rows {
        let l = lines.iter().find(|l| l["job_id"] == r["job_id"]).unwrap();
        for (export, line) in [
            ("obs.granular_temperature_reduced_se", "T_g_reduced_se"),
            ("obs.bridges_per_particle_se", "bridges_per_grain_se"),
            ("obs.profiles.delta_n_cb_se", "delta_n_cb_se"),
        ] {
            let (x, y): (f64, f64) = (r[export].parse().unwrap(), l[line].parse().unwrap());
            assert!(
                x > 0.0 && (x - y).abs() <= 1e-12 * x,
                "{export}: {x} vs {y}"
            );
        }
    }
    // The constants are not in the rows but in r.csv.meta.json.
    assert!(!rows[0].contains_key("sys.N"), "{:?}", rows[0].keys());
    let meta_path = dir.path().join("r.csv.meta.json");
    assert!(stderr(&o).contains("r.csv.meta.json"), "{}", stderr(&o));
    let meta: Value = serde_json::from_str(&std::fs::read_to_string(&meta_path).unwrap()).unwrap();
    let sys = &meta["system"];
    assert_eq!(sys["N"], 40, "{meta}");
    assert_eq!(
        (sys["box.0"].as_f64(), sys["box.1"].as_f64()),
        (Some(20.0), Some(9.0))
    );
    assert_eq!(sys["eps"].as_f64(), Some(0.9));
    assert_eq!(sys["capillary"], "thin_thread");
    // Defaults filled in: s_crit = 0.0711 d, E_cb = 4 m g s_crit.
    assert_eq!(sys["s_crit"].as_f64(), Some(0.0711));
    assert!(
        (sys["E_cb"].as_f64().unwrap() - 0.2844).abs() < 1e-12,
        "{sys}"
    );
    assert_eq!(
        (sys["mass"].as_f64(), sys["gravity"].as_f64()),
        (Some(1.0), Some(1.0))
    );
    assert_eq!(meta["sweeps"], serde_json::json!(["a"]));
    assert_eq!(meta["rows"], 4);
    assert_eq!(meta["wetgran_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(meta["constant"]["obs.particles"], 40, "{meta}");
    // --all keeps the constants in the rows too.
    let all = dir.path().join("all.csv");
    ok(&["export", "--db", d, "--all", "-o", all.to_str().unwrap()]);
    let rows = csv_rows(&std::fs::read_to_string(&all).unwrap());
    assert_eq!(rows[0]["sys.N"], "40");
    // Standard output and a stream get no sidecar (nothing is written beside /dev/stdout).
    let o = ok(&["export", "--db", d, "-o", "/dev/stdout"]);
    assert_eq!(csv_rows(&stdout(&o)).len(), 2);
    assert!(stderr(&o).contains("no sidecar beside standard output or a stream"));
    // --meta puts it anywhere, under the outputs' guards: never over the database.
    let m = dir.path().join("m.json");
    ok(&["export", "--db", d, "--meta", m.to_str().unwrap()]);
    let meta: Value = serde_json::from_str(&std::fs::read_to_string(&m).unwrap()).unwrap();
    assert_eq!(meta["sweeps"], serde_json::json!(["b"]));
    let before = std::fs::read(&db).unwrap();
    let o = run(&["export", "--db", d, "--meta", d]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("would overwrite the database"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(&db).unwrap(), before);
    // The sidecar beside -o collides with another output: refused before anything is written.
    let o = run(&[
        "export",
        "--db",
        d,
        "-o",
        csv.to_str().unwrap(),
        "--series",
        meta_path.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// docs/cli.md names the panels of `--profiles` (issue 45: it named `f_lc` where the plot drew
/// `D_lat`): the sentence lists exactly the panels `report::profiles_svg` draws for a run that
/// observed everything.
#[test]
fn docs_cli_names_the_panels_that_profiles_draws() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/cli.md")).unwrap();
    let flat = doc.split_whitespace().collect::<Vec<_>>().join(" ");
    let from = flat
        .find("`--profiles FILE.svg` the lateral profiles, one panel each:")
        .expect("the --profiles sentence of docs/cli.md");
    let sentence = &flat[from..from + flat[from..].find(". ").unwrap()];
    let list = sentence.split_once("one panel each:").unwrap().1;
    let mut named: Vec<String> = list
        .split('`')
        .skip(1)
        .step_by(2)
        .map(String::from)
        .collect();
    if list.contains("packing fraction") {
        named.push("packing fraction".to_string());
    }
    let scene = wetgran_core::scene::Scene::from_toml_str(
        "dimension = 2\n[box]\nsize = [24.0, 9.0]\n[particles]\ncount = 40\n\
         polydispersity = 0.06\n[contact]\nrestitution = 0.9\n[capillary]\n\
         model = \"thin_thread\"\n[drive]\nkind = \"sine\"\ngamma = 4.0\ne_star = 3.0\n\
         [initial]\ntemperature_over_ecb = 20.0\nseed = 1\n[run]\nduration = 8.0\n\
         [observe]\ntransient_periods = 1.0\nlocation_changes = true\n",
        "profiles scene",
    )
    .unwrap();
    let (run, _) =
        wetgran_core::observe::run_observed_with_frame(&scene, &Default::default(), &mut |_| {});
    let svg = wetgran::report::profiles_svg(&run.observables);
    // Each panel has one frame; its title starts with the quantity's name. The names are
    // typeset (subscripts as `<tspan>`s), so a title is its text element's characters joined,
    // and names compare without the `_` and spaces of their plain spelling.
    let plain = |t: &str| t.replace(['_', ' '], "");
    let texts = wetgran_testkit::figures::svg_texts(&svg);
    let titles: Vec<String> = texts
        .iter()
        .map(|t| plain(t))
        .filter(|t| named.iter().any(|n| t.starts_with(&plain(n))))
        .collect();
    assert_eq!(
        svg.matches("<rect x=").count(),
        named.len(),
        "{named:?}: {svg}"
    );
    for n in &named {
        assert!(
            titles.iter().any(|t| t.starts_with(&plain(n))),
            "docs/cli.md names `{n}`, the plot draws no such panel: {titles:?}"
        );
    }
}
