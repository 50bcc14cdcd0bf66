//! `wetgran lines` on a dry sweep (issue 33, item 3): temperatures in `m g d`, no bridge panel or
//! columns, and the packing contrast `Delta n_area` in place of `Delta n_cb`, read from a real
//! sweep's database.

mod sweep_common;

use sweep_common::*;

const DRY_SCENE: &str = r#"
dimension = 2
[box]
size = [20.0, 9.0]
[particles]
count = 40
polydispersity = 0.06
[contact]
restitution = 0.9
[drive]
kind = "sine"
gamma = 3.0
e_star = 2.0
[initial]
temperature = 5.0
seed = 7
[run]
duration = 10.0
[observe]
time_series = false
"#;

#[test]
fn lines_of_a_dry_sweep_show_packing_and_no_bridges() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "dry.toml", DRY_SCENE);
    let sweep = write(
        dir.path(),
        "dry-sweep.toml",
        "[sweep]\nname = \"dry\"\nbase = \"dry.toml\"\nperiods = 4\n\n[[axis]]\nkey = \
         \"gamma\"\nvalues = [3.0, 6.0]\n\n[[axis]]\nkey = \"e_star\"\nvalues = [1.0, 2.0, 4.0]\n",
    );
    let db = dir.path().join("dry.sqlite");
    let db = db.to_str().unwrap();
    let o = run(&[
        "sweep",
        "run",
        sweep.to_str().unwrap(),
        "--db",
        db,
        "--jobs",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = dir.path().join("lines.csv");
    let svg = dir.path().join("lines.svg");
    let o = run(&[
        "lines",
        "--db",
        db,
        "-o",
        svg.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(json["wet"], false, "{json}");
    assert_eq!(json["energy_unit"], "m g d");
    let lines = json["lines"].as_array().unwrap();
    assert_eq!(lines.len(), 2);
    for l in lines {
        let pts = l["points"].as_array().unwrap();
        assert_eq!(pts.len(), 3);
        for p in pts {
            assert!(p["bridges"].is_null(), "{p}");
            assert!(p["temperature"].as_f64().unwrap() > 0.0);
            assert!(p["contrast"].as_f64().unwrap() >= 0.0);
        }
    }
    let head = std::fs::read_to_string(&csv).unwrap();
    let head = head.lines().next().unwrap();
    assert!(head.ends_with(",delta_n_area,delta_n_area_se"), "{head}");
    assert!(!head.contains("bridges"), "{head}");
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(picture.contains("<svg"));
    assert!(
        !picture.contains("bridges per grain"),
        "a bridge panel on a dry sweep"
    );
}
