//! The text of `wetgran-bench stress`: one line per hard case (work done, simulated time, largest
//! overlap, energy-ledger error, non-finite numbers, wall time, verdict), the broken invariant
//! of a failed case below the table.

use crate::stress::StressRow;
use std::fmt::Write as _;

/// The table of a stress run; `events` the work asked of each case.
pub fn stress_text(rows: &[StressRow], events: u64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "stress: {events} events (time engine: steps) per case, invariants checked {} times per case",
        crate::stress::CHECKS
    );
    s.push_str("case                         work   unit    sim. time  max overlap   ledger err   NaN    wall s  verdict\n");
    for r in rows {
        let m = &r.measured;
        let _ = writeln!(
            s,
            "{:<20} {:>12} {:>6} {:>12.4e} {:>12.3e} {:>12.3e} {:>5} {:>9.2}  {}",
            r.case.name(),
            m.work,
            r.unit,
            m.simulated_time,
            m.max_overlap,
            m.ledger_error,
            m.nan_count,
            r.wall_seconds,
            if r.passed() { "ok" } else { "FAILED" }
        );
    }
    for r in rows.iter().filter(|r| !r.passed()) {
        let why = (r.measured.violation.clone())
            .unwrap_or_else(|| format!("{} non-finite numbers", r.measured.nan_count));
        let _ = writeln!(s, "{}: {why}", r.case.name());
    }
    let failed = rows.iter().filter(|r| !r.passed()).count();
    let _ = writeln!(s, "{} passed, {failed} failed", rows.len() - failed);
    s
}
