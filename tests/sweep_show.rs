//! `wetgran show` (one stored point: phase, decision, profiles from the stored observables, a
//! snapshot from re-running the stored spec) and `wetgran inflection` on a real database.

mod sweep_common;

use std::process::Output;
use sweep_common::*;

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

#[test]
fn show_redraws_a_stored_point_and_inflection_reads_the_lines() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.toml", TINY_SCENE);
    let sweep = write(
        dir.path(),
        "line_sweep.toml",
        "[sweep]\nname = \"line\"\nbase = \"tiny.toml\"\nperiods = 30\n\
         [[axis]]\nkey = \"gamma\"\nvalues = [3.0]\n\
         [[axis]]\nkey = \"e_star\"\nlog = { from = 0.3, to = 10.0, steps = 5 }\n",
    );
    let db = dir.path().join("w.sqlite");
    let db_s = db.to_str().unwrap();
    let run = wetgran()
        .args(["sweep", "run", sweep.to_str().unwrap(), "--db", db_s])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", text(&run));

    // The first job's id from the export.
    let export = wetgran().args(["export", "--db", db_s]).output().unwrap();
    let csv = String::from_utf8(export.stdout).unwrap();
    let row = csv.lines().nth(1).expect("a finished job");
    let column = |name: &str| {
        csv.lines()
            .next()
            .unwrap()
            .split(',')
            .position(|c| c == name)
    };
    let id = row
        .split(',')
        .nth(column("job_id").unwrap())
        .unwrap()
        .to_string();
    let phase_col = column("phase");
    let stored_phase = row.split(',').nth(phase_col.unwrap()).unwrap().to_string();

    let svg = dir.path().join("snap.svg");
    let xyz = dir.path().join("snap.xyz");
    let prof = dir.path().join("prof.svg");
    let show = wetgran()
        .args(["show", "--db", db_s, &id[..10]])
        .args(["--snapshot", svg.to_str().unwrap()])
        .args(["--snapshot", xyz.to_str().unwrap()])
        .args(["--profiles", prof.to_str().unwrap()])
        .output()
        .unwrap();
    let out = text(&show);
    assert!(show.status.success(), "{out}");
    assert!(
        out.contains(&format!("phase       {stored_phase}")),
        "{out}"
    );
    assert!(out.contains("decided on"), "{out}");
    // Same spec and seed, same numbers: the re-run is the stored run.
    assert!(out.contains("reproduces the stored run"), "{out}");
    assert!(std::fs::read_to_string(&svg).unwrap().starts_with("<svg"));
    assert!(std::fs::read_to_string(&prof).unwrap().starts_with("<svg"));
    // Extended XYZ: the particle count, then one line per particle.
    let x = std::fs::read_to_string(&xyz).unwrap();
    let n: usize = x.lines().next().unwrap().trim().parse().unwrap();
    assert_eq!(x.lines().count(), n + 2);

    // Bad job references are bad input (exit 2), named in the message.
    for bad in ["12", "zzzzzzzz", "ffffffffff"] {
        let o = wetgran()
            .args(["show", "--db", db_s, bad])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{}", text(&o));
        assert!(text(&o).contains(bad), "{}", text(&o));
    }

    // A reader that stops early (`wetgran export | head`) ends the export quietly with the
    // SIGPIPE status, not with a panic report.
    {
        use std::io::{BufRead, BufReader};
        let mut child = wetgran()
            .args(["export", "--db", db_s, "--format", "json"])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut first)
            .unwrap();
        assert_eq!(first.trim(), "[");
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(141), "{}", text(&out));
        assert!(!text(&out).contains("panicked"), "{}", text(&out));
    }

    // The job is found by its prefix in any case; a prefix no job has is a usage error.
    let upper = wetgran()
        .args(["show", "--db", db_s, &id[..8].to_ascii_uppercase()])
        .output()
        .unwrap();
    assert!(upper.status.success(), "{}", text(&upper));
    assert!(text(&upper).contains(&id), "{}", text(&upper));
    let absent = if id.starts_with('0') {
        "ffffff"
    } else {
        "000000"
    };
    let none = wetgran()
        .args(["show", "--db", db_s, absent])
        .output()
        .unwrap();
    assert_eq!(none.status.code(), Some(2), "{}", text(&none));
    assert!(
        text(&none).contains("no job id starts with"),
        "{}",
        text(&none)
    );

    // One line of constant Gamma with five E*: the analysis reports it.
    let inf = wetgran()
        .args(["inflection", "--db", db_s])
        .output()
        .unwrap();
    let out = text(&inf);
    assert!(inf.status.success(), "{out}");
    let line = out
        .lines()
        .find(|l| l.trim_start().starts_with("3.0000"))
        .unwrap_or_else(|| panic!("{out}"));
    assert_eq!(line.split_whitespace().nth(1), Some("5"), "{line}");
}
