//! The text of `wetgran simulate`: the run summary (events by kind, energy books) and the
//! observables with the classification, from a [`RunReport`] and an [`ObservedRun`].

use std::fmt::Write;
use wetgran_core::observe::ObservedRun;
use wetgran_core::sim::{EnergyLedger, RunReport};

/// One line of the run summary: the name in a column of 19 characters, then the value.
fn row(s: &mut String, name: &str, value: impl std::fmt::Display) {
    let _ = writeln!(s, "{name:<19} {value}");
}

/// Human-readable summary of a run.
pub fn summary_text(r: &RunReport) -> String {
    let e = &r.events;
    let mut s = String::new();
    let _ = writeln!(s, "{}D, {} particles", r.dimension, r.particles);
    let capped = if r.stopped_on_event_cap {
        "  (stopped on run.max_events)"
    } else {
        ""
    };
    let time = format!("{:.6}{capped}", r.simulated_time);
    row(&mut s, "simulated time", time);
    let wall = r.wall_seconds.max(1e-9);
    if r.engine == "time" {
        // Time-driven: the counts are contact onsets, formations and ruptures, not events.
        let rate = r.steps as f64 * r.particles as f64 / wall;
        let wall_text = format!("{:.3} s  ({rate:.3e} particle-steps/s)", r.wall_seconds);
        row(&mut s, "wall time", wall_text);
        row(&mut s, "engine", format!("time-driven, {} steps", r.steps));
        if let Some(ov) = r.max_overlap {
            row(&mut s, "largest overlap", format!("{ov:.5} d"));
        }
        row(&mut s, "contact onsets etc.", r.events_total);
    } else {
        let rate = r.events_total as f64 / wall;
        let wall_text = format!("{:.3} s  ({rate:.3e} events/s)", r.wall_seconds);
        row(&mut s, "wall time", wall_text);
        row(&mut s, "events", r.events_total);
    }
    for (name, n, always) in [
        ("  pair collisions", e.pair_collisions, true),
        ("  wall collisions", e.wall_collisions, true),
        ("  cell crossings", e.cell_crossings, true),
        ("  bridge formations", e.bridge_formations, true),
        ("  bridge ruptures", e.bridge_ruptures, true),
        ("  well bounces", e.well_bounces, true),
        ("  wall re-checks", e.wall_rechecks, false),
        ("  re-predictions", e.invalidated, true),
        ("  slab crossings", e.slab_crossings, false),
    ] {
        if always || n > 0 {
            row(&mut s, name, n);
        }
    }
    let t_over_ecb = r
        .granular_temperature_over_ecb
        .map_or_else(String::new, |x| format!("  (T_g/E_cb = {x:.4})"));
    let t_g = format!("{:.6}{t_over_ecb}", r.granular_temperature);
    row(&mut s, "granular temp. T_g", t_g);
    row(&mut s, "bridges", r.bridges);
    let (a, b) = (&r.energy_initial, &r.energy_final);
    row(&mut s, "energy", "initial        final");
    type Field = fn(&EnergyLedger) -> f64;
    let rows: [(&str, Field, bool); 7] = [
        ("kinetic", |e| e.kinetic, false),
        ("potential", |e| e.potential, false),
        ("dissipated (rest.)", |e| e.dissipated_restitution, false),
        ("dissipated (rupt.)", |e| e.dissipated_ruptures, false),
        ("added (remedies)", |e| e.added_by_collapse_remedies, true),
        ("added (placement)", |e| e.added_by_wall_placement, true),
        ("work by the drive", |e| e.work_by_drive, false),
    ];
    for (name, field, sci) in rows {
        let (x, y) = (field(a), field(b));
        if name == "added (placement)" && y == 0.0 {
            continue;
        }
        let (x, y) = if sci {
            (format!("{x:.3e}"), format!("{y:.3e}"))
        } else {
            (format!("{x:.6}"), format!("{y:.6}"))
        };
        // The initial values from column 21 (20 after a long name), the final ones after
        // column 34.
        let start = format!("  {name:<17} {x}");
        let _ = writeln!(s, "{start:<34} {y}");
    }
    let error = r.energy_bookkeeping_error;
    let _ = writeln!(s, "  bookkeeping error {error:.3e} (relative)");
    s
}

/// Human-readable summary of the observables and the classification.
pub fn observed_text(run: &ObservedRun) -> String {
    let o = &run.observables;
    let c = &run.classification;
    let mut s = String::new();
    let unit = &o.temperature_unit_name;
    let _ = writeln!(
        s,
        "observables         window t = {:.4} .. {:.4} ({} samples, {:.4} periods of {:.4})",
        o.window_start,
        o.window_end,
        o.window_samples,
        (o.window_end - o.window_start) / o.period,
        o.period
    );
    let _ = writeln!(
        s,
        "  T_g / {unit:<12} {:.6}",
        o.granular_temperature_reduced
    );
    let _ = writeln!(s, "  bridges/particle  {:.4}", o.bridges_per_particle);
    if let Some(sh) = &o.shear {
        let _ = writeln!(
            s,
            "  E_par / {unit:<10} {:.6}  (E_perp {:.6}; {} complete cycles)",
            sh.e_par,
            sh.e_perp,
            sh.cycles.len()
        );
    }
    if let Some(m) = &o.mobility {
        let _ = writeln!(
            s,
            "  D_lat             {:.4e} (lateral MSD over {:.3} time units; clustered grains {})",
            m.diffusion,
            m.lag,
            m.diffusion_clustered
                .map_or_else(|| "-".to_string(), |x| format!("{x:.4e}"))
        );
    }
    if let Some(l) = &o.location_changes {
        let _ = writeln!(
            s,
            "  f_lc              {:.6} per particle per period, {} per time unit ({} changes, {}, sampled every {:.4})",
            l.per_particle_per_period,
            l.per_particle_per_time
                .map_or_else(|| "-".to_string(), |x| format!("{x:.6}")),
            l.count,
            l.method,
            l.sample_interval
        );
    }
    let p = &o.profiles;
    let grid = p.grid.map_or_else(
        || format!("{} slabs", p.n_cb.len()),
        |(nx, ny)| format!("{nx} x {ny} cells"),
    );
    let se = |x: Option<f64>| x.map_or_else(|| "-".to_string(), |v| format!("{v:.4}"));
    let _ = writeln!(
        s,
        "  Delta n_cb        {:.4} (per bin error {}; {grid} of {:.3}); Delta n_area {:.4} (error {})",
        p.delta_n_cb,
        se(p.n_cb_standard_error),
        p.bin_width,
        p.delta_n_area,
        se(p.packing_standard_error)
    );
    if let Some(d) = &o.diffusion {
        for (k, l) in d.layers.iter().enumerate() {
            let _ = writeln!(
                s,
                "  layer {k} (z = {:.2})  D = {:.4e}, MSD = {:.4e} ({} particles)",
                l.mean_height, l.coefficient, l.msd_end, l.particles
            );
        }
    }
    let k = &o.counts;
    let _ = writeln!(
        s,
        "  in the window     {} pair, {} wall collisions ({} pair per wall), {} formations, {} ruptures",
        k.pair_collisions,
        k.wall_collisions,
        k.pair_per_wall
            .map_or_else(|| "-".to_string(), |x| format!("{x:.3}")),
        k.bridge_formations,
        k.bridge_ruptures
    );
    let _ = writeln!(s, "  settled           {}", c.verdict());
    for u in c.decided_on.settling.unsettled_text() {
        let _ = writeln!(s, "                    {u}");
    }
    let _ = writeln!(s, "phase               {}", c.phase);
    let _ = writeln!(s, "  because           {}", c.decided_on.reason);
    s
}
