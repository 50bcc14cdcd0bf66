//! The spatial domains (`domains.rs`) against the serial step and against themselves.
use super::*;
use crate::scene::Scene;

/// A rayon pool of `threads` threads.
fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a pool")
}

/// A shaken wet bed of 360 disks in a 120 x 9 box (bridges form and rupture, across the
/// cut too).
fn wet_bed() -> Scene {
    let text = "dimension = 2\ngravity = 1.0\n[box]\nsize = [120.0, 9.0]\n\
        boundary = [\"periodic\", \"wall\"]\n[particles]\ncount = 360\npolydispersity = 0.06\n\
        [contact]\ndamping = 1.5e-4\n[capillary]\nmodel = \"thin_thread\"\ns_crit = 0.0711\n\
        e_cb = 0.2844\n[drive]\nkind = \"sine\"\ngamma = 5.0\ne_star = 10.0\n\
        [initial]\ntemperature_over_ecb = 20.0\nseed = 3\n[run]\nduration = 1.0\n\
        [engine]\nkind = \"time\"\n";
    Scene::from_toml_str(text, "domain test").expect("valid scene")
}

type Wet = TimeEngine<2, true, true>;

/// Gear steps on the domains whatever the size (`TimeEngine::domains_from`), or never.
const ALWAYS: usize = 0;
const NEVER: usize = usize::MAX;

/// A door of a minute: every thread of the pool joins the team, even on a loaded machine.
const LONG_DOOR: std::time::Duration = std::time::Duration::from_secs(60);

fn engine(domains_from: usize) -> Wet {
    let mut e = Wet::new(&wet_bed());
    e.domains_from = domains_from;
    e.domains.door = LONG_DOOR;
    e
}

/// Every bit of the state and of the books.
fn bits<const D: usize, const W: bool>(e: &TimeEngine<D, true, W>) -> Vec<u64> {
    let mut v: Vec<u64> = e.positions_flat().iter().map(|x| x.to_bits()).collect();
    v.extend(e.velocities_flat().iter().map(|x| x.to_bits()));
    let c = e.counts();
    v.extend([
        c.pair_collisions,
        c.wall_collisions,
        c.bridge_formations,
        c.bridge_ruptures,
        e.steps(),
        e.list_builds(),
    ]);
    v.extend(e.bridges().iter().flat_map(|&(i, j)| [i as u64, j as u64]));
    // The list checks' state: where the next exact displacement test falls.
    if let Some(dec) = e.domains.decomposition.as_ref() {
        for dm in &dec.domains {
            let dm = super::super::domains::lock(dm);
            v.extend([dm.bound.to_bits(), u64::from(dm.since_check)]);
        }
    }
    let l = e.energy();
    v.extend(
        [
            l.kinetic,
            l.potential,
            l.dissipated_restitution,
            l.dissipated_ruptures,
            l.work_by_drive,
            e.max_overlap(),
        ]
        .map(f64::to_bits),
    );
    v
}

/// Asserts that `split` (on the domains) differs from `serial` (never on the domains) as a
/// change of the summation order does: the same list builds, counts and bridges, positions
/// within `1e-9`. Returns the largest position difference.
fn agree_to_round_off<const D: usize>(
    serial: &TimeEngine<D, true, true>,
    split: &TimeEngine<D, true, true>,
) -> f64 {
    assert_eq!(serial.list_builds(), split.list_builds());
    assert_eq!(serial.counts(), split.counts());
    assert_eq!(serial.bridges(), split.bridges());
    let (xs, xd) = (serial.positions_flat(), split.positions_flat());
    let dx = xs
        .iter()
        .zip(&xd)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(dx < 1e-9, "positions differ by {dx}");
    dx
}

/// Runs `e` to 1 time unit in `run_until` pieces of `piece` time units.
fn run_in_pieces(e: &mut Wet, piece: f64) {
    let mut t = 0.0f64;
    while t < 1.0 {
        t = (t + piece).min(1.0);
        e.run_until(t);
    }
}

/// The bed on the domains gives the bits of one thread on two and three threads, on a team of
/// changing size (a door of 20 us, so that the pool's second thread joins some regions and
/// not others, as on a busy machine: the mix depends on the machine and is printed, not
/// asserted), in `run_until` pieces (regions end anywhere) and step by step (a region per
/// step, which builds between regions). A region goes on through the list builds (the team
/// builds the list itself): one run takes far fewer regions than builds.
#[test]
fn the_domains_give_the_same_bits_on_any_team_and_wherever_regions_end() {
    let run = |threads: usize, door: std::time::Duration, how: &(dyn Fn(&mut Wet) + Sync)| {
        pool(threads).install(|| {
            let mut e = engine(ALWAYS);
            e.domains.door = door;
            how(&mut e);
            e
        })
    };
    let micros = std::time::Duration::from_micros;
    let whole = |e: &mut Wet| {
        e.run_until(1.0);
    };
    let one = run(1, LONG_DOOR, &whole);
    let two = run(2, LONG_DOOR, &whole);
    let three = run(3, LONG_DOOR, &whole);
    let varying = run(2, micros(20), &|e| run_in_pieces(e, 0.01));
    let pieces = run(2, LONG_DOOR, &|e| run_in_pieces(e, 0.0173));
    let stepwise = run(2, LONG_DOOR, &|e| {
        while e.time() < 1.0 - 0.5 * e.s.p.dt {
            e.step();
        }
    });
    assert!(one.counts().bridge_ruptures > 0, "bridges rupture");
    assert_eq!(one.domains.team_steps, 0, "one thread runs no team");
    // The long door admits both members: nearly every step ran on two threads (the first,
    // predicting, step runs alone).
    for e in [&two, &three] {
        assert!(
            e.domains.team_steps + 1 >= e.steps(),
            "{}",
            e.domains.team_steps
        );
    }
    let (regions, builds, partitions) = (
        two.domains.regions,
        two.list_builds(),
        two.domains.partitions,
    );
    assert!(builds > 20, "{builds} builds");
    assert!(
        regions <= partitions + 1,
        "{regions} regions for {builds} builds and {partitions} partitions"
    );
    println!(
        "{} of {} steps on a team of two",
        varying.domains.team_steps,
        varying.steps()
    );
    let want = bits(&one);
    for (e, what) in [
        (&two, "two threads"),
        (&three, "three threads"),
        (&varying, "a team of changing size"),
        (&pieces, "a run in pieces"),
        (&stepwise, "a run step by step"),
    ] {
        assert!(bits(e) == want, "{what} differs from one thread");
    }
}

/// On one thread (the domains in turn), so that a domain reading a halo of the wrong step
/// parity sees the other's newer state and fails here (on two threads the halo locks
/// would then deadlock instead).
#[test]
fn both_copies_of_a_cross_pair_take_the_same_decisions() {
    pool(1).install(|| {
        let mut e = engine(ALWAYS);
        let mut bonded = 0;
        for k in 1..=20 {
            e.run_until(0.05 * k as f64);
            let t = e.time();
            let dec = e.domains.decomposition.as_mut().expect("a decomposition");
            assert!(dec.cross_flags_agree(), "cross flags differ at t = {t}");
            let d0 = super::super::domains::lock(&dec.domains[0]);
            bonded = bonded.max(d0.cross_flags.iter().filter(|&&f| f & BOND != 0).count());
        }
        assert!(bonded > 0, "some cross pair is bonded");
    });
}

/// 3D (the same code): 400 wet spheres, cut across the longest (periodic) axis; one and
/// two threads give the same bits, and the serial path agrees to round-off.
#[test]
fn spheres_on_domains_agree_with_the_serial_step() {
    let text = "dimension = 3\ngravity = 1.0\n[box]\nsize = [16.0, 8.0, 8.0]\n\
        boundary = [\"periodic\", \"periodic\", \"wall\"]\n[particles]\ncount = 400\n\
        polydispersity = 0.06\n[contact]\ndamping = 1.5e-4\n[capillary]\n\
        model = \"thin_thread\"\ns_crit = 0.0711\ne_cb = 0.2844\n[drive]\nkind = \"sine\"\n\
        gamma = 5.0\ne_star = 10.0\n[initial]\ntemperature_over_ecb = 20.0\nseed = 5\n\
        [run]\nduration = 1.0\n[engine]\nkind = \"time\"\n";
    let scene = Scene::from_toml_str(text, "domain test 3D").expect("valid scene");
    let run = |domains_from: usize, threads: usize| {
        pool(threads).install(|| {
            let mut e = TimeEngine::<3, true, true>::new(&scene);
            e.domains_from = domains_from;
            e.domains.door = LONG_DOOR;
            e.run_until(0.4);
            e
        })
    };
    let one = run(ALWAYS, 1);
    let two = run(ALWAYS, 2);
    let serial = run(NEVER, 1);
    assert!(
        two.domains.team_steps + 1 >= two.steps(),
        "two members ran the steps"
    );
    assert!(one.counts().bridge_formations > 0, "bridges form");
    assert!(bits(&one) == bits(&two), "one and two threads differ");
    agree_to_round_off(&serial, &one);
}

/// The point of the domains: in the bench system (`wetgran-bench tdmd`: 1200 dry disks,
/// 400 x 9, shaken at `A = 0.05`, `Gamma = 15`, cut across x)
/// the threads exchange only a small halo per step. Prints the figures quoted in
/// docs/performance-history.md ("Sixth round: spatial domains").
#[test]
fn the_halo_is_a_small_part_of_the_bench_system() {
    let kr = crate::scene::DEFAULT_STIFFNESS * 0.25f64.sqrt();
    let a_d = crate::physics::hertz::damping_for_restitution(kr, 0.5, 1.0, 0.9);
    let text = format!(
        "dimension = 2\ngravity = 1.0\n[box]\nsize = [400.0, 9.0]\nboundary = [\"periodic\", \"wall\"]\n\
         [particles]\ncount = 1200\npolydispersity = 0.06\n[contact]\ndamping = {a_d}\n\
         [drive]\nkind = \"sine\"\namplitude = 0.05\nomega = {}\n\
         [initial]\ntemperature = 1.0\nseed = 1\n[run]\nduration = 1.0\n\
         [engine]\nkind = \"time\"\ndt = 1e-4\nintegrator = \"gear5\"\n",
        (15.0f64 / 0.05).sqrt()
    );
    let s = Scene::from_toml_str(&text, "the bench system").expect("valid scene");
    let mut e = TimeEngine::<2, true, false>::new(&s);
    assert!(e.uses_domains(), "N = 1200 runs on the domains by default");
    e.run_until(0.5);
    let dec = e.domains.decomposition.as_ref().expect("a decomposition");
    for (d, dm) in dec.domains.iter().enumerate() {
        let dm = super::super::domains::lock(dm);
        let m = dm.ids.len();
        println!(
            "domain {d}: {m} particles, {} inner entries, {} cross entries, {} ghosts, {} published",
            dm.partner.len(),
            dm.cross_own.len(),
            dm.ghost_radius.len(),
            dm.halo_out.len()
        );
        assert_eq!(m, 600);
        let ghosts = dm.ghost_radius.len();
        assert!(ghosts > 0 && ghosts * 10 < m, "{ghosts} ghosts");
    }
    println!(
        "{} partitions over {} list builds",
        e.domains.partitions,
        e.list_builds()
    );
}

/// The domains change the serial trajectory by round-off only: the same list builds,
/// counts and (to round-off) positions and books, over a run long enough for several
/// partitions. The books would differ by the cross pairs' share if both domains booked
/// them.
#[test]
fn domains_change_the_serial_trajectory_by_round_off() {
    let mut serial = engine(NEVER);
    let mut split = engine(ALWAYS);
    let t = 1.2;
    serial.run_until(t);
    split.run_until(t);
    assert!(
        split.domains.partitions > 1,
        "{} partitions",
        split.domains.partitions
    );
    let dx = agree_to_round_off(&serial, &split);
    assert!(dx > 0.0, "the summation order differs, so some bit should");
    let (ls, ld) = (serial.energy(), split.energy());
    for (a, b, what) in [
        (
            ls.dissipated_restitution,
            ld.dissipated_restitution,
            "damping",
        ),
        (ls.dissipated_ruptures, ld.dissipated_ruptures, "ruptures"),
        (ls.work_by_drive, ld.work_by_drive, "drive work"),
        (ls.kinetic, ld.kinetic, "kinetic"),
    ] {
        assert!(
            (a - b).abs() <= 1e-9 * a.abs().max(1.0),
            "{what}: {a} vs {b}"
        );
    }
}
