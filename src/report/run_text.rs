//! The text of `wetgran simulate`: the run summary (events by kind, energy books) and the
//! observables with the classification, from a [`RunReport`] and an [`ObservedRun`].

use wetgran_core::observe::ObservedRun;
use wetgran_core::sim::RunReport;

/// Human-readable summary of a run.
pub fn summary_text(r: &RunReport) -> String {
    let e = &r.events;
    let mut s = String::new();
    use std::fmt::Write;
    let _ = writeln!(s, "{}D, {} particles", r.dimension, r.particles);
    let _ = writeln!(
        s,
        "simulated time      {:.6}{}",
        r.simulated_time,
        if r.stopped_on_event_cap {
            "  (stopped on run.max_events)"
        } else {
            ""
        }
    );
    if r.engine == "time" {
        // Time-driven: the counts are contact onsets, formations and ruptures, not events.
        let _ = writeln!(
            s,
            "wall time           {:.3} s  ({:.3e} particle-steps/s)",
            r.wall_seconds,
            r.steps as f64 * r.particles as f64 / r.wall_seconds.max(1e-9)
        );
        let _ = writeln!(s, "engine              time-driven, {} steps", r.steps);
        if let Some(ov) = r.max_overlap {
            let _ = writeln!(s, "largest overlap     {ov:.5} d");
        }
        let _ = writeln!(s, "contact onsets etc. {}", r.events_total);
    } else {
        let _ = writeln!(
            s,
            "wall time           {:.3} s  ({:.3e} events/s)",
            r.wall_seconds,
            r.events_total as f64 / r.wall_seconds.max(1e-9)
        );
        let _ = writeln!(s, "events              {}", r.events_total);
    }
    let _ = writeln!(s, "  pair collisions   {}", e.pair_collisions);
    let _ = writeln!(s, "  wall collisions   {}", e.wall_collisions);
    let _ = writeln!(s, "  cell crossings    {}", e.cell_crossings);
    let _ = writeln!(s, "  bridge formations {}", e.bridge_formations);
    let _ = writeln!(s, "  bridge ruptures   {}", e.bridge_ruptures);
    let _ = writeln!(s, "  well bounces      {}", e.well_bounces);
    if e.wall_rechecks > 0 {
        let _ = writeln!(s, "  wall re-checks    {}", e.wall_rechecks);
    }
    let _ = writeln!(s, "  re-predictions    {}", e.invalidated);
    if e.slab_crossings > 0 {
        let _ = writeln!(s, "  slab crossings    {}", e.slab_crossings);
    }
    let _ = write!(s, "granular temp. T_g  {:.6}", r.granular_temperature);
    if let Some(x) = r.granular_temperature_over_ecb {
        let _ = write!(s, "  (T_g/E_cb = {x:.4})");
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "bridges             {}", r.bridges);
    let (a, b) = (&r.energy_initial, &r.energy_final);
    let _ = writeln!(s, "energy              initial        final");
    let _ = writeln!(
        s,
        "  kinetic           {:<14.6} {:.6}",
        a.kinetic, b.kinetic
    );
    let _ = writeln!(
        s,
        "  potential         {:<14.6} {:.6}",
        a.potential, b.potential
    );
    let _ = writeln!(
        s,
        "  dissipated (rest.) {:<13.6} {:.6}",
        a.dissipated_restitution, b.dissipated_restitution
    );
    let _ = writeln!(
        s,
        "  dissipated (rupt.) {:<13.6} {:.6}",
        a.dissipated_ruptures, b.dissipated_ruptures
    );
    let _ = writeln!(
        s,
        "  added (remedies)  {:<14.3e} {:.3e}",
        a.added_by_collapse_remedies, b.added_by_collapse_remedies
    );
    if b.added_by_wall_placement != 0.0 {
        let _ = writeln!(
            s,
            "  added (placement) {:<14.3e} {:.3e}",
            a.added_by_wall_placement, b.added_by_wall_placement
        );
    }
    let _ = writeln!(
        s,
        "  work by the drive {:<14.6} {:.6}",
        a.work_by_drive, b.work_by_drive
    );
    let _ = writeln!(
        s,
        "  bookkeeping error {:.3e} (relative)",
        r.energy_bookkeeping_error
    );
    s
}

/// Human-readable summary of the observables and the classification.
pub fn observed_text(run: &ObservedRun) -> String {
    use std::fmt::Write;
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
    let st = &o.stationarity;
    let _ = writeln!(
        s,
        "  stationary        {} (first vs second half, tolerance {}): {}",
        if st.stationary { "yes" } else { "NO" },
        st.tolerance,
        st.checks
            .iter()
            .map(|c| format!(
                "{} {:.4} -> {:.4}{}",
                c.quantity,
                c.first_half,
                c.second_half,
                if c.ok { "" } else { " (!)" }
            ))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(s, "phase               {}", c.phase);
    let _ = writeln!(s, "  because           {}", c.decided_on.reason);
    s
}
