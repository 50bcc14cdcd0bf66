//! The calendar queue against the reference linear scan (`wetgran_testkit::NaiveQueue`) under
//! random updates, and its own edge cases.

use rand::{Rng, SeedableRng};
use wetgran_core::sim::event_driven::queue::{CalendarQueue, EventQueue};
use wetgran_testkit::NaiveQueue;

/// Random updates on `Q` and on the naive queue; the two must pop the same particle with
/// the same key after every update.
fn agrees_with_naive_queue<Q: EventQueue>(
    n: usize,
    seed: u64,
    draw: impl Fn(usize, &mut rand_xoshiro::Xoshiro256PlusPlus) -> f64,
) {
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
    let (mut q, mut r) = (Q::new(n), NaiveQueue::new(n));
    for step in 0..200_000 {
        let i = rng.gen_range(0..n);
        let t = draw(step, &mut rng);
        q.update(i, t);
        r.update(i, t);
        let (qi, qt) = q.min().unwrap();
        let (ri, rt) = r.min().unwrap();
        assert_eq!(qt, rt, "step {step}");
        // Same tie-break: the same particle, so engines on either queue agree bitwise.
        assert_eq!(qi, ri, "step {step}");
        assert_eq!(q.key(qi), qt);
    }
}

#[test]
fn calendar_agrees_with_naive_queue_under_random_updates() {
    // A mix of increases, decreases, repeated values and infinities.
    agrees_with_naive_queue::<CalendarQueue>(257, 3, |step, rng| match step % 7 {
        0 => f64::INFINITY,
        1 => (rng.gen_range(0..50) as f64) * 0.5,
        _ => rng.gen_range(0.0..100.0),
    });
    // A clock that advances like an engine's, with keys spread over many decades ahead of
    // it (a year of buckets without a due entry, saturated buckets), exact ties, keys in
    // the past and 0.
    let clock = std::cell::Cell::new(0.0f64);
    agrees_with_naive_queue::<CalendarQueue>(100, 5, |step, rng| {
        clock.set(clock.get() + 1e-3);
        let now = clock.get();
        match step % 11 {
            0 => f64::INFINITY,
            1 => now + 10f64.powi(rng.gen_range(-8..12)),
            2 => now.floor(),
            3 => 0.0,
            4 => now - 1e-12,
            5 => 1e300,
            _ => now + rng.gen_range(0.0..1.0),
        }
    });
    // Every key infinite, then one finite.
    let mut q = CalendarQueue::new(3);
    assert_eq!(q.min(), Some((0, f64::INFINITY)));
    q.update(2, 5.0);
    assert_eq!(q.min(), Some((2, 5.0)));
    assert_eq!(CalendarQueue::new(0).min(), None);
}

#[test]
fn calendar_jumps_over_a_long_gap_instead_of_walking_it() {
    // Width 0.1 from keys 0.1..0.4, then every key moved 10^15 ahead: 10^16 empty buckets to
    // walk without the jump (the thread would not finish), one year of 4 lists with it.
    let (done, finished) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut q = CalendarQueue::new(4);
        for i in 0..4 {
            q.update(i, 0.1 * (i + 1) as f64);
        }
        assert_eq!(q.min(), Some((0, 0.1)));
        for i in (0..4).rev() {
            q.update(i, 1e15 + i as f64);
        }
        let first = q.min();
        q.update(0, f64::INFINITY);
        let _ = done.send((first, q.min()));
    });
    let got = finished
        .recv_timeout(std::time::Duration::from_secs(20))
        .expect("the calendar queue walked the gap bucket by bucket");
    assert_eq!(got, (Some((0, 1e15)), Some((1, 1e15 + 1.0))));
}
