//! `wetgran-bench shake`: the 2D standard wet system (docs/model.md 1, N = 1200) in the shaken
//! container at a cool and a hot point of the (Gamma, E*) plane, a fixed number of driving
//! periods with each wall solver (`table/raw`: the table without the corner check, as the
//! thesis printed it; table build time is excluded, `bench wall` reports it): wall time per
//! driving period next to the resulting
//! `T_g / E_cb` and bridge count (averaged over the second half of the run, sampled once per
//! period), so the effect of the solver's accuracy on the physics is visible.

use std::fmt::Write as _;
use std::time::Instant;
use wetgran_core::scene::WallSolverKind;
use wetgran_core::sim::event_driven::Engine;
use wetgran_testkit::reference::shaken_standard;

/// One (point, solver) run.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ShakeRow {
    pub gamma: f64,
    pub e_star: f64,
    pub solver: &'static str,
    pub periods: usize,
    pub seconds_per_period: f64,
    pub(crate) events_per_period: f64,
    pub tg_over_ecb: f64,
    pub bridges: f64,
}

/// Runs both points with every solver for `periods * scale` driving periods (at least 4).
pub(crate) fn measure(periods: usize, scale: f64) -> Vec<ShakeRow> {
    let periods = ((periods as f64 * scale).round() as usize).max(4);
    let e_cb = 0.2844;
    let mut rows = Vec::new();
    for (gamma, e_star) in [(2.0, 0.5), (5.0, 10.0)] {
        for (name, solver, checked) in [
            ("exact", WallSolverKind::Exact, true),
            ("bracket", WallSolverKind::Bracket, true),
            ("table", WallSolverKind::Table, true),
            ("table/raw", WallSolverKind::Table, false),
        ] {
            let mut scene = shaken_standard(gamma, e_star, solver);
            if !checked {
                // The thesis's table as printed: no corner check of the cells' linear models.
                scene.drive.table_corner_check = Some(false);
            }
            scene.validate("bench shake").expect("bench scene is valid");
            let (_, omega) = scene.drive_motion().expect("shaken");
            let period = 2.0 * std::f64::consts::PI / omega;
            let mut e = Engine::<2, true, true>::new(&scene);
            let (mut tg, mut bridges, mut n) = (0.0, 0.0, 0.0);
            let start = Instant::now();
            for k in 1..=periods {
                e.run_until(k as f64 * period, None);
                if 2 * k > periods {
                    tg += e.granular_temperature() / e_cb;
                    bridges += e.bridge_count() as f64;
                    n += 1.0;
                }
            }
            let seconds = start.elapsed().as_secs_f64();
            rows.push(ShakeRow {
                gamma,
                e_star,
                solver: name,
                periods,
                seconds_per_period: seconds / periods as f64,
                events_per_period: e.counts().total() as f64 / periods as f64,
                tg_over_ecb: tg / n,
                bridges: bridges / n,
            });
        }
    }
    rows
}

/// The table `wetgran-bench shake` prints.
pub(crate) fn report(rows: &[ShakeRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "wetgran-bench shake: 2D standard wet system (N = 1200, 400 x 9, eps 0.9) shaken;\n\
         averages over the second half of the run, sampled once per driving period\n"
    );
    s.push_str(
        " Gamma     E* solver     periods     s/period  events/period   T_g/E_cb   bridges\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{:>6} {:>6} {:<9} {:>8} {:>12.4} {:>14.0} {:>10.4} {:>9.1}",
            r.gamma,
            r.e_star,
            r.solver,
            r.periods,
            r.seconds_per_period,
            r.events_per_period,
            r.tg_over_ecb,
            r.bridges
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_solver_runs_both_points_and_the_hot_point_is_hotter() {
        let rows = measure(4, 1.0);
        assert_eq!(rows.len(), 8);
        assert!(
            rows.iter()
                .all(|r| r.seconds_per_period > 0.0 && r.tg_over_ecb.is_finite())
        );
        // Same physics within the noise of a short run: the hot point is far hotter with each.
        let (cool, hot) = rows.split_at(4);
        for (c, h) in cool.iter().zip(hot) {
            assert_eq!(c.solver, h.solver);
            assert!(h.tg_over_ecb > 3.0 * c.tg_over_ecb, "{c:?} {h:?}");
        }
    }
}
