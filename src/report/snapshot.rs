//! Snapshots of one configuration.
//!
//! - [`snapshot_xyz`]: extended XYZ (opens in OVITO): columns species, position (3 columns; a 2D
//!   frame `(x, z)` is written as `(x, 0, z)` so the vertical axis stays `z`), radius, velocity
//!   (3 columns), kinetic energy `m v^2 / 2` over the energy unit, and bridge count; the comment
//!   line carries the box (`Lattice`), the periodic axes (`pbc`), the time and the wall offset.
//! - [`snapshot_svg`]: the `x`-`z` plane (3D frames are projected along `y`, far grains first),
//!   disks coloured by kinetic energy over `E_cb` on a log scale from 10^-2 to 10^2, or by bridge
//!   count; bridges drawn as lines between centres (through the periodic seam where they cross
//!   it); the container's floor and lid at their current height.

use super::svg::{category, colour, esc, n};
use std::fmt::Write;
use std::path::Path;
use wetgran_core::sim::Frame;

/// What colours the disks of an SVG snapshot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColourBy {
    /// `log10(m v^2 / 2 / E_cb)` from -2 to 2.
    #[default]
    KineticEnergy,
    /// Number of bridges of the grain (0 to 7+).
    Bridges,
}

impl std::str::FromStr for ColourBy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "energy" | "kinetic_energy" => Ok(ColourBy::KineticEnergy),
            "bridges" => Ok(ColourBy::Bridges),
            _ => Err(format!(
                "unknown colouring `{s}`: expected `energy` or `bridges`"
            )),
        }
    }
}

/// Bridges per particle.
pub fn bridge_degree(frame: &Frame) -> Vec<usize> {
    let mut deg = vec![0; frame.len()];
    for &(i, j) in &frame.bridges {
        deg[i] += 1;
        deg[j] += 1;
    }
    deg
}

fn kinetic(frame: &Frame, i: usize) -> f64 {
    0.5 * frame.mass * frame.v(i).iter().map(|v| v * v).sum::<f64>()
}

/// Extended XYZ text of a frame; `energy_unit` divides the kinetic energies (`E_cb`).
pub fn snapshot_xyz(frame: &Frame, energy_unit: f64) -> String {
    let d = frame.dimension;
    let to3 = |v: &[f64]| -> [f64; 3] {
        if d == 2 {
            [v[0], 0.0, v[1]]
        } else {
            [v[0], v[1], v[2]]
        }
    };
    // A 2D box is one unit deep along y, and not periodic along it.
    let mut size = to3(&frame.box_size);
    size[1] = if d == 2 { 1.0 } else { size[1] };
    let tf = |k: usize| if frame.periodic[k] { "T" } else { "F" };
    let deg = bridge_degree(frame);
    let mut s = String::new();
    let _ = writeln!(s, "{}", frame.len());
    let _ = writeln!(
        s,
        "Lattice=\"{} 0 0 0 {} 0 0 0 {}\" Origin=\"0 {} {}\" \
         Properties=species:S:1:pos:R:3:radius:R:1:velo:R:3:kinetic_energy:R:1:bridges:I:1 \
         pbc=\"{} {} {}\" Time={} wall_offset={} energy_unit={}",
        size[0],
        size[1],
        size[2],
        if d == 2 { -0.5 } else { 0.0 },
        frame.wall_offset,
        tf(0),
        if d == 2 { "F" } else { tf(1) },
        tf(d - 1),
        frame.time,
        frame.wall_offset,
        energy_unit
    );
    for i in 0..frame.len() {
        let x = to3(frame.x(i));
        let v = to3(frame.v(i));
        let _ = writeln!(
            s,
            "P {:.8} {:.8} {:.8} {:.6} {:.8e} {:.8e} {:.8e} {:.6e} {}",
            x[0],
            x[1],
            x[2],
            frame.radii[i],
            v[0],
            v[1],
            v[2],
            kinetic(frame, i) / energy_unit,
            deg[i]
        );
    }
    s
}

/// The bridges as one SVG path, each a line between its grains' centres (a bridge across the
/// periodic `x` boundary drawn at both ends); `px`, `pz` map box coordinates to pixels.
fn bridge_lines(s: &mut String, frame: &Frame, px: &dyn Fn(f64) -> f64, pz: &dyn Fn(f64) -> f64) {
    let _ = write!(
        s,
        "<path stroke=\"#d62728\" stroke-width=\"0.7\" stroke-opacity=\"0.8\" fill=\"none\" d=\""
    );
    for &(i, j) in &frame.bridges {
        let (xi, zi) = (frame.wrap(0, frame.x(i)[0]), frame.height(i));
        let (xj, zj) = (frame.wrap(0, frame.x(j)[0]), frame.height(j));
        let dx = frame.min_image(0, xj - xi);
        let _ = write!(
            s,
            "M{} {}L{} {}",
            n(px(xi)),
            n(pz(zi)),
            n(px(xi + dx)),
            n(pz(zj))
        );
        if (xi + dx - xj).abs() > 1e-9 {
            let _ = write!(
                s,
                "M{} {}L{} {}",
                n(px(xj)),
                n(pz(zj)),
                n(px(xj - dx)),
                n(pz(zi))
            );
        }
    }
    let _ = writeln!(s, "\"/>");
}

/// The colour legend: one swatch per step of the colour scale, baseline at `ly`.
fn colour_legend(s: &mut String, colour_by: ColourBy, ml: f64, ly: f64) {
    for k in 0..=8 {
        let (fill, text) = match colour_by {
            ColourBy::KineticEnergy => (
                colour(k as f64 / 8.0),
                format!("{:.1}", -2.0 + 0.5 * k as f64),
            ),
            ColourBy::Bridges if k < 8 => (
                category(k).to_string(),
                if k == 7 { "7+".into() } else { k.to_string() },
            ),
            ColourBy::Bridges => continue,
        };
        let x = ml + 42.0 * k as f64;
        let _ = writeln!(
            s,
            "<rect x=\"{}\" y=\"{}\" width=\"12\" height=\"10\" fill=\"{fill}\"/><text x=\"{}\" y=\"{}\">{text}</text>",
            n(x),
            n(ly - 9.0),
            n(x + 15.0),
            n(ly)
        );
    }
}

/// SVG picture of a frame (see the module header); `energy_unit` is `E_cb`.
pub fn snapshot_svg(frame: &Frame, colour_by: ColourBy, energy_unit: f64) -> String {
    let d = frame.dimension;
    let (lx, h) = (frame.box_size[0], frame.box_size[d - 1]);
    let scale = (1200.0 / lx).clamp(3.0, 40.0);
    let (ml, mt) = (10.0, 24.0);
    let top_extra = frame.wall_offset.abs() + 0.5;
    let (w, ht) = (
        lx * scale + 2.0 * ml,
        (h + 2.0 * top_extra) * scale + mt + 34.0,
    );
    let px = |x: f64| ml + x * scale;
    let pz = |z: f64| mt + (h + top_extra - z) * scale;
    let mut s = super::svg::open(w, ht);
    let _ = writeln!(
        s,
        "<defs><clipPath id=\"box\"><rect x=\"{}\" y=\"0\" width=\"{}\" height=\"{}\"/></clipPath></defs>",
        n(px(0.0)),
        n(lx * scale),
        n(ht)
    );
    let _ = writeln!(s, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
    let title = match colour_by {
        ColourBy::KineticEnergy => {
            "colour: log10(kinetic energy / E_cb) from -2 (dark) to 2 (yellow)"
        }
        ColourBy::Bridges => "colour: bridges per grain 0 (grey), 1, 2, ... 7+ (red)",
    };
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"14\">t = {:.3}, N = {}, bridges = {}; {}</text>",
        n(ml),
        frame.time,
        frame.len(),
        frame.bridges.len(),
        esc(title)
    );
    // Floor and lid.
    for z in [frame.wall_offset, h + frame.wall_offset] {
        let _ = writeln!(
            s,
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\" stroke-width=\"1.5\"/>",
            n(px(0.0)),
            n(pz(z)),
            n(px(lx)),
            n(pz(z))
        );
    }
    let _ = writeln!(s, "<g clip-path=\"url(#box)\">");
    let deg = bridge_degree(frame);
    let mut order: Vec<usize> = (0..frame.len()).collect();
    if d == 3 {
        order.sort_by(|&a, &b| frame.x(b)[1].total_cmp(&frame.x(a)[1]));
    }
    let periodic_x = frame.periodic[0];
    for &i in &order {
        let fill = match colour_by {
            ColourBy::KineticEnergy => {
                let e = kinetic(frame, i) / energy_unit;
                colour((e.max(1e-12).log10() + 2.0) / 4.0)
            }
            ColourBy::Bridges => category(deg[i]).to_string(),
        };
        let x = frame.wrap(0, frame.x(i)[0]);
        let z = frame.height(i);
        let r = frame.radii[i];
        let mut images = vec![x];
        if periodic_x && x < r {
            images.push(x + lx);
        }
        if periodic_x && x > lx - r {
            images.push(x - lx);
        }
        for xi in images {
            let _ = writeln!(
                s,
                "<circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"{fill}\" stroke=\"#333\" stroke-width=\"0.3\"/>",
                n(px(xi)),
                n(pz(z)),
                n(r * scale)
            );
        }
    }
    bridge_lines(&mut s, frame, &px, &pz);
    let _ = writeln!(s, "</g>");
    colour_legend(&mut s, colour_by, ml, ht - 14.0);
    s.push_str("</svg>\n");
    s
}

/// Writes a snapshot to `path` (whole, and never over a file of `protected`: `output`):
/// extended XYZ for `.xyz`, SVG for `.svg`.
pub fn write_snapshot(
    path: &Path,
    frame: &Frame,
    colour_by: ColourBy,
    energy_unit: f64,
    protected: &crate::output::Protected,
) -> Result<(), crate::output::OutputError> {
    let text = match path.extension().and_then(|e| e.to_str()) {
        Some("xyz") => snapshot_xyz(frame, energy_unit),
        Some("svg") => snapshot_svg(frame, colour_by, energy_unit),
        _ => {
            return Err(crate::output::OutputError::Refused(format!(
                "{}: unknown snapshot format: the file name must end in .xyz or .svg",
                path.display()
            )));
        }
    };
    crate::output::write_file(path, text, protected)
}
