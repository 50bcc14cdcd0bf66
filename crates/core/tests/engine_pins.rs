//! Trajectory pins of the event-driven engine: a digest of the exact state (every bit of every
//! position and velocity, the clock, the event counts and the energy ledger) after a fixed number
//! of events, for one scene per engine configuration. The digests were recorded on the engine as
//! it was before the event sources were split out (issue 16, commit on branch `arch-sources`
//! before the refactor); a structural change that keeps the event order must reproduce them bit
//! for bit. A change that alters the physics or the event order on purpose must re-record them
//! and say why in its commit.
//!
//! Every pinned run is made twice, on the default queue and on the naive reference queue, and
//! the two trajectories must agree bit for bit (`pinned_run`).

use wetgran_testkit as common;

use common::scene;
use wetgran_core::scene::Scene;
use wetgran_core::sim::event_driven::Engine;
use wetgran_core::sim::event_driven::queue::{CalendarQueue, EventQueue};
use wetgran_testkit::NaiveQueue;

/// FNV-1a over 64-bit words.
struct Digest(u64);

impl Digest {
    fn new() -> Self {
        Digest(0xcbf2_9ce4_8422_2325)
    }
    fn word(&mut self, w: u64) {
        for b in w.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn float(&mut self, x: f64) {
        self.word(x.to_bits());
    }
}

/// Digest of the full observable state of an engine.
fn digest<const D: usize, const G: bool, const W: bool, const S: bool, Q: EventQueue>(
    e: &Engine<D, G, W, S, Q>,
) -> u64 {
    let mut h = Digest::new();
    h.float(e.time());
    for x in e.positions() {
        for a in x.iter() {
            h.float(*a);
        }
    }
    for v in e.velocities() {
        for a in v.iter() {
            h.float(*a);
        }
    }
    let c = e.counts();
    for w in [
        c.pair_collisions,
        c.wall_collisions,
        c.cell_crossings,
        c.bridge_formations,
        c.bridge_ruptures,
        c.well_bounces,
        c.wall_rechecks,
        c.invalidated,
        c.slab_crossings,
    ] {
        h.word(w);
    }
    for (i, j) in e.bridges() {
        h.word(i as u64);
        h.word(j as u64);
    }
    let l = e.energy();
    for x in [
        l.kinetic,
        l.potential,
        l.dissipated_restitution,
        l.dissipated_ruptures,
        l.added_by_collapse_remedies,
        l.added_by_wall_placement,
        l.work_by_drive,
    ] {
        h.float(x);
    }
    h.0
}

/// The shaken 2D wet system (scenes/shaken_wet_2d.toml) with the given wall solver.
fn shaken_wet_2d(solver: &str) -> Scene {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/shaken_wet_2d.toml"
    ))
    .unwrap();
    let text = text.replace(
        "[drive]\n",
        &format!("[drive]\nwall_solver = \"{solver}\"\n"),
    );
    scene(&text)
}

fn shear_3d() -> Scene {
    scene(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/shear_small_3d.toml"
        ))
        .unwrap(),
    )
}

fn dry_gas_3d() -> Scene {
    scene(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/dry_gas_3d.toml"
        ))
        .unwrap(),
    )
}

fn settling_3d() -> Scene {
    scene(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/wet_settling_3d.toml"
        ))
        .unwrap(),
    )
}

/// Runs `events` events on queue `Q` (renumbering in cell order every 20 000, so the pin
/// covers it) and returns the digest.
fn run_on<const D: usize, const G: bool, const W: bool, const S: bool, Q: EventQueue>(
    s: &Scene,
    events: u64,
) -> u64 {
    let mut e = Engine::<D, G, W, S, Q>::new(s);
    e.set_reorder_interval(20_000);
    e.run_until(f64::INFINITY, Some(events));
    e.sanity_check().unwrap();
    digest(&e)
}

/// The digest on the default [`CalendarQueue`], after checking that the same engine on the
/// naive reference queue ([`NaiveQueue`], a linear scan) took the same trajectory bit for bit.
fn pinned_run<const D: usize, const G: bool, const W: bool, const S: bool>(
    s: &Scene,
    events: u64,
) -> u64 {
    let naive = run_on::<D, G, W, S, NaiveQueue>(s, events);
    let calendar = run_on::<D, G, W, S, CalendarQueue>(s, events);
    assert_eq!(
        calendar, naive,
        "the engine on the calendar queue and on the naive queue took different trajectories"
    );
    calendar
}

fn check(name: &str, got: u64, pinned: u64) {
    eprintln!("{name}: digest {got:#018x}");
    assert_eq!(
        got, pinned,
        "{name}: trajectory changed (digest {got:#018x}, pinned {pinned:#018x})"
    );
}

#[test]
fn shaken_wet_2d_exact_solver_trajectory_is_pinned() {
    let d = pinned_run::<2, true, true, false>(&shaken_wet_2d("exact"), 120_000);
    check("shaken wet 2d, exact", d, PIN_SHAKEN_EXACT);
}

#[test]
fn shaken_wet_2d_bracket_solver_trajectory_is_pinned() {
    let d = pinned_run::<2, true, true, false>(&shaken_wet_2d("bracket"), 60_000);
    check("shaken wet 2d, bracket", d, PIN_SHAKEN_BRACKET);
}

#[test]
fn shaken_wet_2d_table_solver_trajectory_is_pinned() {
    let d = pinned_run::<2, true, true, false>(&shaken_wet_2d("table"), 120_000);
    check("shaken wet 2d, table", d, PIN_SHAKEN_TABLE);
}

#[test]
fn sheared_wet_3d_trajectory_is_pinned() {
    let d = pinned_run::<3, true, true, true>(&shear_3d(), 120_000);
    check("sheared wet 3d", d, PIN_SHEAR);
}

#[test]
fn settling_wet_3d_trajectory_is_pinned() {
    let d = pinned_run::<3, true, true, false>(&settling_3d(), 120_000);
    check("settling wet 3d", d, PIN_SETTLING);
}

#[test]
fn dry_gas_3d_trajectory_is_pinned() {
    let d = pinned_run::<3, false, false, false>(&dry_gas_3d(), 120_000);
    check("dry gas 3d", d, PIN_DRY_GAS);
}

const PIN_SHAKEN_EXACT: u64 = 0x40eb9e7ead6df1bf;
const PIN_SHAKEN_BRACKET: u64 = 0x8aed632edb2f61cd;
const PIN_SHAKEN_TABLE: u64 = 0x9572bfc634d94b08;
const PIN_SHEAR: u64 = 0x9c090f203b281ef3;
const PIN_SETTLING: u64 = 0x59b580a1b2209492;
const PIN_DRY_GAS: u64 = 0x8f874b57e5e2811b;
