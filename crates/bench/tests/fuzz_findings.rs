//! Findings of the input fuzzer (`fuzz_inputs.rs`) in sweep files and job specs, each fixed and
//! frozen as a named test (docs/reliability.md, "Findings"): errors name the dotted key, unknown
//! keys are refused, and continuation jobs are validated with the start they run.

use std::path::Path;
use wetgran::sweep::{JobSpec, SweepFile};

/// Bug found by the sweep-file fuzzer: a TOML type or unknown-key error in a sweep file named
/// the field without its table (`zz_not_a_key` for `[sweep] zz_not_a_key`), or no key at all
/// for a type error (`replicas = "x"`). They now carry the dotted key, as a scene's do.
#[test]
fn regression_sweep_toml_errors_name_the_dotted_key() {
    let path = Path::new("fuzz/sweep.toml");
    for (text, key) in [
        (
            "[sweep]\nname = \"a\"\nzz_not_a_key = 1\n",
            "sweep.zz_not_a_key",
        ),
        (
            "[sweep]\nname = \"a\"\nreplicas = \"x\"\n",
            "sweep.replicas",
        ),
        (
            "[sweep]\nname = \"a\"\n[[axis]]\nkey = \"gamma\"\nlinear = { from = 1.0, to = 2.0, steps = \"3\" }\n",
            "axis.linear.steps",
        ),
    ] {
        let e = SweepFile::parse(text, path).unwrap_err();
        assert_eq!(e.key, key, "{e}");
        let shown = e.to_string();
        assert!(
            shown.starts_with("fuzz/sweep.toml:") && shown.contains(&format!("key `{key}`")),
            "{shown}"
        );
    }
}

/// Bug found by the sweep-file fuzzer: a time-driven continuation sweep along `capillary.e_cb`
/// at `temperature_over_ecb = 1e-300` expanded, although its chain's first job, once given its
/// hot start, calibrated the damping at `T_0 = 1e-301` (`A_d = 1.4e26`) and failed validation:
/// the jobs were validated as `"continue"` members, calibrated at the drive's scale. Chain
/// members are now calibrated as their point with a hot start (one contact law along a chain),
/// and a chain's first job is validated again with its real start.
#[test]
fn regression_continuation_jobs_are_validated_with_the_start_they_run() {
    let text = "[[axis]]\nkey = \"capillary.e_cb\"\n[axis.linear]\nfrom = 0.1\nsteps = 2\nto = 1.0\n\
                [scene]\ndimension = 3\ngravity = 0.0\n[scene.box]\nsize = [5.0, 5.0, 5.64]\n\
                [scene.capillary]\ne_cb = 0.2844\nmodel = \"thin_thread\"\n\
                [scene.contact]\nrestitution = 0.91\n[scene.engine]\ndt = 0.00001\nkind = \"time\"\n\
                [scene.initial]\nseed = 0\ntemperature_over_ecb = 1e-300\n\
                [scene.particles]\ncount = 1\n[scene.run]\nduration = 1.0\n\
                [sweep]\nname = \"fuzz\"\nperiods = 0.5\n[sweep.continuation]\naxis = \"capillary.e_cb\"\n";
    let e = SweepFile::parse(text, Path::new("fuzz/sweep.toml"))
        .and_then(|f| f.expand())
        .expect_err("the sweep must be refused");
    assert_eq!(e.key, "contact.restitution", "{e}");
    // The same sweep at a sound temperature expands, and its jobs validate as they will run.
    let sound = text.replace(
        "temperature_over_ecb = 1e-300",
        "temperature_over_ecb = 20.0",
    );
    let jobs = SweepFile::parse(&sound, Path::new("fuzz/sweep.toml"))
        .and_then(|f| f.expand())
        .expect("a sound sweep");
    assert_eq!(jobs.len(), 2);
    for j in &jobs {
        j.spec.scene.validate("job").expect("validates as it runs");
    }
}

/// Bug found by the job-spec fuzzer: a JSON job spec with a value of the wrong type said where
/// in the text (line, column) but not which key; an unknown top-level key (a misspelt
/// `start_from`) was silently ignored.
#[test]
fn regression_job_spec_errors_name_the_key_and_unknown_keys_are_refused() {
    let text = "[sweep]\nname = \"t\"\n[scene]\ndimension = 2\ngravity = 0.0\n[scene.box]\n\
                size = [8.0, 8.0]\nboundary = [\"periodic\", \"periodic\"]\n\
                [scene.particles]\ncount = 4\n[scene.initial]\ntemperature = 1.0\n\
                [scene.run]\nduration = 2.0\n";
    let spec = SweepFile::parse(text, Path::new("t.toml"))
        .unwrap()
        .expand()
        .unwrap()
        .remove(0)
        .spec;
    let good = serde_json::to_value(&spec).unwrap();
    assert!(JobSpec::from_json(&good.to_string(), "s.json").is_ok());
    let mut wrong = good.clone();
    wrong["scene"]["particles"]["count"] = serde_json::json!("four");
    let e = JobSpec::from_json(&wrong.to_string(), "s.json").unwrap_err();
    assert!(e.starts_with("s.json: key `scene.particles.count`:"), "{e}");
    let mut missing = good.clone();
    missing["scene"]["run"]
        .as_object_mut()
        .unwrap()
        .remove("duration");
    let e = JobSpec::from_json(&missing.to_string(), "s.json").unwrap_err();
    assert!(e.starts_with("s.json: key `scene.run.duration`:"), "{e}");
    let mut unknown = good.clone();
    unknown["start_frm"] = serde_json::json!("abc");
    let e = JobSpec::from_json(&unknown.to_string(), "s.json").unwrap_err();
    assert!(e.starts_with("s.json: key `start_frm`:"), "{e}");
}
