//! Pictures and exports: the extended XYZ round-trips the configuration, the SVG snapshot draws
//! every grain (and its periodic image at the seam) and every bridge, the profile plot has one
//! panel per profile, and `wetgran simulate` writes them all.

use wetgran_testkit as common;

use std::process::Command;
use wetgran::report::{ColourBy, profiles_svg, snapshot_svg, snapshot_xyz};
use wetgran_core::observe::run_observed_with_frame;
use wetgran_core::sim::Frame;

fn small_frame() -> Frame {
    // Box 10 x 4, periodic in x; grain 2 straddles the seam (x = 0.2 < r), bridge 2-3 crosses it.
    Frame::from_parts(
        2,
        vec![10.0, 4.0],
        vec![true, false],
        vec![2.0, 1.0, 3.0, 1.0, 0.2, 2.0, 9.6, 2.0, 5.0, 3.0],
        vec![1.0, 0.0, -1.0, 0.5, 0.0, 0.0, 0.3, -0.2, 2.0, 2.0],
        vec![0.5, 0.5, 0.45, 0.55, 0.5],
        vec![(0, 1), (2, 3), (1, 4)],
    )
}

#[test]
fn xyz_round_trips_the_configuration() {
    let f = small_frame();
    let text = snapshot_xyz(&f, 0.2844);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "5");
    assert!(
        lines[1].contains("Lattice=\"10 0 0 0 1 0 0 0 4\""),
        "{}",
        lines[1]
    );
    assert!(lines[1].contains("pbc=\"T F F\""));
    assert!(lines[1].contains(
        "Properties=species:S:1:pos:R:3:radius:R:1:velo:R:3:kinetic_energy:R:1:bridges:I:1"
    ));
    assert_eq!(lines.len(), 2 + 5);
    let mut degree_sum = 0;
    for (i, line) in lines[2..].iter().enumerate() {
        let c: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(c.len(), 10, "{line}");
        let num = |k: usize| c[k].parse::<f64>().unwrap();
        assert!(
            (num(1) - f.x(i)[0]).abs() < 1e-8 && num(2) == 0.0 && (num(3) - f.x(i)[1]).abs() < 1e-8
        );
        assert!((num(4) - f.radii[i]).abs() < 1e-6);
        assert!((num(5) - f.v(i)[0]).abs() < 1e-8 && (num(7) - f.v(i)[1]).abs() < 1e-8);
        let ke = 0.5 * (f.v(i)[0].powi(2) + f.v(i)[1].powi(2)) / 0.2844;
        assert!((num(8) - ke).abs() <= 1e-6 * ke.max(1e-300));
        degree_sum += c[9].parse::<usize>().unwrap();
    }
    assert_eq!(degree_sum, 2 * f.bridges.len());
}

#[test]
fn svg_snapshot_draws_grains_images_and_bridges() {
    let f = small_frame();
    for by in [ColourBy::KineticEnergy, ColourBy::Bridges] {
        let svg = snapshot_svg(&f, by, 0.2844);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        // 5 grains plus the image of grain 2 (x = 0.2 < r) and of grain 3 (x = 9.6 > L - r).
        assert_eq!(svg.matches("<circle").count(), 7);
        // Bridges 0-1 and 1-4 once, 2-3 from both sides of the seam.
        let path = svg.split("stroke=\"#d62728\"").nth(1).unwrap();
        let d = path
            .split("d=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        assert_eq!(d.matches('M').count(), 4, "{d}");
    }
    // Colour by bridges: grain 1 has 2 bridges, grain 0 one: different fills.
    let svg = snapshot_svg(&f, ColourBy::Bridges, 0.2844);
    assert!(svg.contains("#4575b4") && svg.contains("#74add1"));
}

#[test]
fn profile_plot_and_cli_outputs() {
    let scene_text = "dimension = 2\n[box]\nsize = [24.0, 9.0]\n[particles]\ncount = 40\npolydispersity = 0.06\n\
         [contact]\nrestitution = 0.9\n[capillary]\nmodel = \"thin_thread\"\n\
         [drive]\nkind = \"sine\"\ngamma = 4.0\ne_star = 3.0\n\
         [initial]\ntemperature_over_ecb = 20.0\nseed = 1\n[run]\nduration = 8.0\n\
         [observe]\ntransient_periods = 1.0\nlocation_changes = true\n";
    let s = common::scene(scene_text);
    let (run, _) = run_observed_with_frame(&s, &Default::default(), &mut |_| {});
    let svg = profiles_svg(&run.observables);
    // T_g, packing, n_cb, D_lat and f_lc panels: one frame and one curve each.
    assert_eq!(svg.matches("<rect x=").count(), 5);
    assert_eq!(
        svg.matches("stroke=\"#1f77b4\" stroke-width=\"1.5\"")
            .count(),
        5
    );
    // Error bars of one standard error on the packing and n_cb panels (their stored
    // rms-over-bins errors), one bar per bin with a value.
    let p = &run.observables.profiles;
    assert!(p.packing_standard_error.is_some() && p.n_cb_standard_error.is_some());
    let bars: Vec<&str> = svg
        .split("<path class=\"errorbar\" d=\"")
        .skip(1)
        .map(|t| t.split('"').next().unwrap())
        .collect();
    assert_eq!(bars.len(), 2, "packing and n_cb");
    for (d, values) in bars.iter().zip([&p.packing, &p.n_cb]) {
        // Each bar is three strokes (the bar and its two caps).
        assert_eq!(d.matches('M').count(), 3 * values.len(), "{d}");
    }
    let titles = svg.matches("bars: one standard error").count();
    assert_eq!(titles, 2, "the panels with bars say so");
    // Ticks at round steps in one format per axis (not min/mid/max of the data): the x axis
    // of the 24 d wide box at 0, 5, 10, 15, 20 in each of the 5 panels; units named.
    let texts = wetgran_testkit::figures::svg_texts(&svg);
    for x in ["0", "5", "10", "15", "20"] {
        assert!(
            texts.iter().filter(|t| *t == x).count() >= 5,
            "x tick {x}: {texts:?}"
        );
    }
    assert!(
        texts.iter().any(|t| t == "x (grain diameters d)"),
        "{texts:?}"
    );

    let dir = std::env::temp_dir().join(format!("wetgran-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, scene_text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_wetgran"))
        .arg("simulate")
        .arg(&scene)
        .arg("--json")
        .args(["--snapshot", dir.join("a.svg").to_str().unwrap()])
        .args(["--snapshot", dir.join("a.xyz").to_str().unwrap()])
        .args(["--profiles", dir.join("p.svg").to_str().unwrap()])
        .args(["--colour-by", "bridges"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        json["classification"]["phase"].as_str().unwrap(),
        run.classification.phase.to_string()
    );
    assert_eq!(json["observables"]["particles"], 40);
    let xyz = std::fs::read_to_string(dir.join("a.xyz")).unwrap();
    assert_eq!(xyz.lines().count(), 42);
    assert!(
        std::fs::read_to_string(dir.join("a.svg"))
            .unwrap()
            .contains("<circle")
    );
    assert_eq!(std::fs::read_to_string(dir.join("p.svg")).unwrap(), svg);
    // The same profiles as PDF: one page of the figure's size (760 px wide: 760 pt).
    let out = Command::new(env!("CARGO_BIN_EXE_wetgran"))
        .arg("simulate")
        .arg(&scene)
        .args(["--profiles", dir.join("p.pdf").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let pdf = lopdf::Document::load(dir.join("p.pdf")).unwrap();
    assert_eq!(pdf.get_pages().len(), 1);
    let text = pdf.extract_text(&[1]).unwrap().replace('\n', "");
    assert!(text.contains("packing"), "{text}");
    // The table names the phase; a bad snapshot extension is refused before running.
    let out = Command::new(env!("CARGO_BIN_EXE_wetgran"))
        .arg("simulate")
        .arg(&scene)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(&format!("phase               {}", run.classification.phase)),
        "{text}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_wetgran"))
        .args(["simulate", scene.to_str().unwrap(), "--snapshot", "x.png"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("must end in .xyz or .svg"));
    std::fs::remove_dir_all(&dir).ok();
}

/// 3D plane bins: the profile picture draws one map over (x, y) per observable, one cell per
/// bin.
#[test]
fn three_dimensional_profiles_are_maps_over_the_plane() {
    let s = common::scene(
        "dimension = 3\n[box]\nsize = [8.0, 8.0, 6.0]\n[particles]\ncount = 120\n\
         [capillary]\nmodel = \"thin_thread\"\n[initial]\ntemperature_over_ecb = 5.0\nseed = 1\n\
         [run]\nduration = 3.0\n[observe]\nbin_width = 2.0\ntransient_periods = 1.0\n\
         location_changes = false\nmobility_lag = 0.5\n",
    );
    let (run, _) = run_observed_with_frame(&s, &Default::default(), &mut |_| {});
    assert_eq!(run.observables.profiles.grid, Some((4, 4)));
    let svg = profiles_svg(&run.observables);
    assert!(svg.contains("lateral maps over (x, y)"), "{svg}");
    // T_g, packing, n_cb and D_lat maps: 16 cells and one frame each, plus the background.
    assert_eq!(svg.matches("<rect ").count(), 1 + 4 * (16 + 1));
}
