//! The line study's picture (docs/validation.md): `T_g / E_cb`, bridges per grain and
//! `Delta n_cb` (with its noise threshold) against `E*`, all on log axes, labelled by the line
//! rule (as a sweep labels them), for one or more lines of saved
//! `wetgran simulate --json` results, each point marked with its label.
//!
//! `cargo run --release --example line_plot -- OUT.svg NAME:RESULT.json,RESULT.json,... [NAME:...]`

use plotters::prelude::*;
use wetgran_core::observe::line::classify_line;
use wetgran_core::observe::{Observables, Thresholds};
use wetgran_core::scene::Scene;

/// One point: `E*`, `T_g/E_cb`, bridges per grain, `Delta n_cb`, noise threshold, label.
type Point = (f64, f64, f64, f64, f64, String);

/// The points of one line, labelled by the line rule (as a sweep labels them).
fn load_line(paths: &[&str]) -> Vec<Point> {
    let mut scenes = Vec::new();
    let mut obs = Vec::new();
    for path in paths {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).expect("result file"))
                .expect("JSON");
        obs.push(
            serde_json::from_value::<Observables>(v["observables"].clone()).expect("observables"),
        );
        scenes
            .push(Scene::load(&std::path::Path::new(path).with_extension("toml")).expect("scene"));
    }
    let e: Vec<f64> = scenes
        .iter()
        .map(|s| s.drive.e_star.expect("E* given"))
        .collect();
    let pts: Vec<(f64, &Observables)> = e.iter().copied().zip(&obs).collect();
    let labels = classify_line(
        scenes[0].drive.gamma.expect("Gamma given"),
        &pts,
        &Thresholds::default(),
        scenes[0].contact.restitution >= 1.0,
    );
    labels
        .iter()
        .zip(&obs)
        .zip(&e)
        .map(|((c, o), &e)| {
            let t = c.decided_on.coexistence.as_ref().expect("coexistence test");
            (
                e,
                o.granular_temperature_reduced,
                o.bridges_per_particle,
                t.delta,
                t.noise_threshold.unwrap_or(f64::NAN),
                c.phase.to_string(),
            )
        })
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = args.first().expect("OUT.svg").clone();
    let mut lines: Vec<(String, Vec<Point>)> = Vec::new();
    for a in &args[1..] {
        let (name, files) = a.split_once(':').expect("NAME:FILES");
        let mut pts: Vec<Point> = load_line(&files.split(',').collect::<Vec<_>>());
        pts.sort_by(|x, y| x.0.total_cmp(&y.0));
        lines.push((name.to_string(), pts));
    }
    let all: Vec<&Point> = lines.iter().flat_map(|l| l.1.iter()).collect();
    let (e0, e1) = all
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let root = SVGBackend::new(&out, (900, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((3, 1));
    let colours = [BLUE, RED, GREEN, MAGENTA];
    type Get = fn(&Point) -> f64;
    let specs: [(&str, Get); 3] = [
        ("T_g / E_cb", |p| p.1),
        ("bridges per grain", |p| p.2),
        ("Delta n_cb (dashed: noise threshold)", |p| p.3),
    ];
    for (panel, (name, get)) in panels.iter().zip(specs) {
        let mut ys: Vec<f64> = all.iter().map(|p| get(p)).collect();
        if name.starts_with("Delta") {
            ys.extend(all.iter().map(|p| p.4));
        }
        let ys: Vec<f64> = ys
            .into_iter()
            .filter(|y| y.is_finite() && *y > 0.0)
            .collect();
        let (y0, y1) = ys
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &y| (a.min(y), b.max(y)));
        let mut chart = ChartBuilder::on(panel)
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .caption(name, ("sans-serif", 16))
            .build_cartesian_2d(
                (e0 * 0.9..e1 * 1.1).log_scale(),
                (y0 * 0.7..y1 * 1.4).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc("E*")
            .y_label_formatter(&|y| format!("{y:.3}"))
            .draw()?;
        for (k, (lname, pts)) in lines.iter().enumerate() {
            let c = colours[k % colours.len()];
            chart
                .draw_series(LineSeries::new(pts.iter().map(|p| (p.0, get(p))), c))?
                .label(lname.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
            chart.draw_series(
                pts.iter()
                    .map(|p| Circle::new((p.0, get(p)), 3, c.filled())),
            )?;
            chart
                .draw_series(pts.iter().map(|p| {
                    Text::new(p.5.clone(), (p.0, get(p)), ("sans-serif", 12).into_font())
                }))?;
            if name.starts_with("Delta") {
                chart.draw_series(DashedLineSeries::new(
                    pts.iter().map(|p| (p.0, p.4)),
                    4,
                    3,
                    c.into(),
                ))?;
            }
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()?;
    }
    root.present()?;
    Ok(())
}
