//! `wetgran-bench memory`: peak resident memory of the event engine per particle.
//!
//! The system is the bulk gas of benchmark (a) at other sizes: `N` elastic monodisperse spheres
//! of diameter 1 at number density 0.5 in a periodic cube, no gravity, `T = 1`. For each `N`
//! the benchmark starts a child process (`wetgran-bench memory:N`, the same binary) so that the
//! peaks of different sizes do not accumulate. The child reads its resident set size
//! (`VmRSS`) at start, builds the engine (initial state, cells, first predictions), runs `2 N`
//! events with a renumbering in cell order every `N` events (so the renumbering's temporaries are
//! inside the measured window), and reads its peak resident set size (`VmHWM` of
//! `/proc/self/status`, the high-water mark of the whole process). It also prints the heap bytes
//! of every engine array (`Engine::memory`: capacity times element size), the breakdown by
//! structure.
//!
//! Reported per particle: the peak (`VmHWM / N`, everything the process ever held, including the
//! binary and the allocator's slack), the peak above the start (`(VmHWM - VmRSS at start) / N`)
//! and the engine's arrays (`sum of Engine::memory / N`).

use std::fmt::Write as _;
use wetgran_core::scene::Boundary;
use wetgran_core::sim::event_driven::Engine;
use wetgran_testkit::reference::base_scene;

/// Sizes measured at `scale = 1`.
pub(crate) const SIZES: [usize; 2] = [125_000, 1_000_000];
/// Fewest particles of a scaled size.
const MIN_PARTICLES: usize = 2_000;

/// What one child process measured.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct MemoryRow {
    pub particles: usize,
    /// Resident set size at the start of the child, before the engine (KiB).
    pub(crate) rss_start_kib: u64,
    /// Resident set size right after the engine was built (KiB).
    pub(crate) rss_built_kib: u64,
    /// Peak resident set size of the child over the build and the run (KiB).
    pub(crate) peak_kib: u64,
    /// Events run after the build.
    pub events: u64,
    /// Heap bytes of each engine array.
    pub(crate) structures: Vec<(String, usize)>,
}

impl MemoryRow {
    /// Bytes per particle of the engine's arrays.
    pub(crate) fn engine_bytes_per_particle(&self) -> f64 {
        self.structures.iter().map(|(_, b)| b).sum::<usize>() as f64 / self.particles as f64
    }
}

/// `VmRSS` and `VmHWM` of this process in KiB.
fn rss_and_peak_kib() -> Result<(u64, u64), String> {
    let status = std::fs::read_to_string("/proc/self/status")
        .map_err(|e| format!("cannot read /proc/self/status (Linux only): {e}"))?;
    let field = |name: &str| -> Result<u64, String> {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|rest| rest.trim().trim_end_matches("kB").trim().parse().ok())
            .ok_or_else(|| format!("no {name} in /proc/self/status"))
    };
    Ok((field("VmRSS:")?, field("VmHWM:")?))
}

/// The child's measurement, in this process: build, run `2 n` events, read the peak.
pub(crate) fn measure_here(n: usize) -> Result<MemoryRow, String> {
    // System (a) of `bench engine` at `n` particles (module doc).
    let side = (n as f64 / 0.5).cbrt();
    let mut scene = base_scene(3, 0.0, vec![side; 3], vec![Boundary::Periodic; 3]);
    scene.particles.count = n;
    scene
        .validate("bench memory system")
        .map_err(|e| e.to_string())?;
    let (rss_start_kib, _) = rss_and_peak_kib()?;
    let mut engine = Engine::<3, false, false>::new(&scene);
    let (rss_built_kib, _) = rss_and_peak_kib()?;
    engine.set_reorder_interval(n as u64);
    engine.run_until(f64::INFINITY, Some(2 * n as u64));
    let (_, peak_kib) = rss_and_peak_kib()?;
    Ok(MemoryRow {
        particles: n,
        rss_start_kib,
        rss_built_kib,
        peak_kib,
        events: engine.counts().total(),
        structures: engine
            .memory()
            .into_iter()
            .map(|(name, b)| (name.to_string(), b))
            .collect(),
    })
}

/// The child's output: the row as JSON.
pub(crate) fn child_text(row: &MemoryRow) -> String {
    serde_json::to_string_pretty(row).expect("a memory row serializes") + "\n"
}

/// Parses [`child_text`].
pub(crate) fn parse_child(text: &str) -> Result<MemoryRow, String> {
    let row: MemoryRow = serde_json::from_str(text)
        .map_err(|x| format!("bench memory: cannot read the child's output ({x}): {text}"))?;
    if row.particles == 0 {
        return Err("bench memory: the child reported no particles".into());
    }
    Ok(row)
}

/// Runs one child process per size (`SIZES` times `scale`).
pub(crate) fn measure(scale: f64) -> Result<Vec<MemoryRow>, String> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this binary: {e}"))?;
    let mut rows = Vec::new();
    for n in SIZES {
        let n = ((n as f64 * scale).round() as usize).max(MIN_PARTICLES);
        let out = std::process::Command::new(&exe)
            .arg(format!("memory:{n}"))
            .output()
            .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
        if !out.status.success() {
            return Err(format!(
                "bench memory:{n} failed: {}",
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        rows.push(parse_child(&String::from_utf8_lossy(&out.stdout))?);
    }
    Ok(rows)
}

/// The printed table and the breakdown of the largest size.
pub(crate) fn report(rows: &[MemoryRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "wetgran-bench memory: event engine, N elastic spheres at density 0.5 in a periodic cube \
         (system (a) at size N); one child process per N: build, then 2 N events with a \
         renumbering every N events"
    );
    let _ = writeln!(
        s,
        "peak = VmHWM of the child (whole process); start = VmRSS before the engine; engine = heap \
         bytes of the engine's arrays (capacity x element size)"
    );
    let _ = writeln!(s);
    s.push_str(
        "        N    events  start MiB  built MiB   peak MiB  peak B/N   peak-start engine B/N\n",
    );
    let mib = |k: u64| k as f64 / 1024.0;
    for r in rows {
        let per_particle = |kib: u64| kib as f64 * 1024.0 / r.particles as f64;
        let _ = writeln!(
            s,
            "{:>9} {:>9} {:>10.1} {:>10.1} {:>10.1} {:>9.1} {:>12.1} {:>10.1}",
            r.particles,
            r.events,
            mib(r.rss_start_kib),
            mib(r.rss_built_kib),
            mib(r.peak_kib),
            per_particle(r.peak_kib),
            per_particle(r.peak_kib.saturating_sub(r.rss_start_kib)),
            r.engine_bytes_per_particle(),
        );
    }
    if let Some(r) = rows.iter().max_by_key(|r| r.particles) {
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "engine arrays at N = {} (bytes per particle):",
            r.particles
        );
        for (name, b) in &r.structures {
            if *b > 0 {
                let _ = writeln!(s, "  {:<32} {:>8.2}", name, *b as f64 / r.particles as f64);
            }
        }
        let _ = writeln!(
            s,
            "  {:<32} {:>8.2}",
            "total",
            r.engine_bytes_per_particle()
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_breakdown_adds_up_and_the_child_text_round_trips() {
        let n = 3_000;
        let row = measure_here(n).expect("small engine builds and runs");
        assert_eq!(row.particles, n);
        assert!(row.events >= 2 * n as u64);
        // Exact bookkeeping: one 64-byte state record and one scene index per particle.
        let get = |name: &str| {
            row.structures
                .iter()
                .find(|(k, _)| k.starts_with(name))
                .map(|(_, b)| *b)
                .unwrap()
        };
        assert_eq!(get("bodies.body"), 64 * n);
        assert_eq!(get("bodies.id"), 4 * n);
        // The high-water mark is at least any resident size read before it.
        assert!(row.peak_kib >= row.rss_built_kib && row.peak_kib >= row.rss_start_kib);
        let back = parse_child(&child_text(&row)).unwrap();
        assert_eq!(back, row);
        let text = report(&[row]);
        assert!(text.contains("engine arrays at N = 3000"));
        assert!(parse_child("nonsense 1").is_err());
    }
}
