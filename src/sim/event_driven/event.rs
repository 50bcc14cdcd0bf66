//! The event value the scheduler pops, validates and dispatches: a time and a kind ([`Event`],
//! `Copy`, 24 bytes); the compact per-particle predictions the sources keep ([`PairEvent`],
//! [`PlaneEvent`]) from which they build it; and [`EventSource`], what every source offers the
//! scheduler.

/// Sentinel partner index: no partner.
pub const NONE: u32 = u32::MAX;

/// What happens at an event, with what the source needs to carry it out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// Nothing predicted (time `+inf`).
    Never,
    /// Contact of `i` with `partner` (hard-core collision, and bridge formation if wet). Valid
    /// only while the partner's velocity-change counter still reads `partner_count`.
    Collide { partner: u32, partner_count: u32 },
    /// A bonded pair at `s = s_crit`: bounce off the well wall or rupture (MODEL.md 3.2);
    /// validated like [`EventKind::Collide`].
    Well { partner: u32, partner_count: u32 },
    /// Crossing of a cell face along `axis`, upwards or downwards.
    Cell { axis: u8, up: bool },
    /// Collision with the wall across `axis` (`up`: the upper wall, the lid).
    Wall { axis: u8, up: bool },
    /// Crossing of a slab face of the shear drive (`up`: towards larger `x`).
    Slab { up: bool },
}

/// One event of one particle: when, and what.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    pub time: f64,
    pub kind: EventKind,
}

impl Event {
    pub const NEVER: Event = Event {
        time: f64::INFINITY,
        kind: EventKind::Never,
    };

    /// `other` if it is strictly earlier than `self`, else `self`: among equal times the
    /// candidate offered first wins, which fixes the precedence of the sources.
    #[inline]
    pub fn earlier(self, other: Event) -> Event {
        if other.time < self.time { other } else { self }
    }
}

/// What every event source offers the scheduler. Prediction and firing are the sources' own
/// methods (`predict`, `fire`, `scan`, `collide`, ...), because each needs different parts of
/// the engine (a pair scan reads the cells and the slabs, a wall hit may move a particle to
/// another cell); the scheduler calls them on the concrete source types, so everything is
/// monomorphised.
pub trait EventSource {
    /// The source's stored prediction for particle `i`, as an event (`Event::NEVER`-timed if
    /// none).
    fn candidate(&self, i: usize) -> Event;
    /// Renumbers the particles: new index `k` holds old particle `order[k]`, and
    /// `new_of_old[old] = new` renames stored particle indices (partners, bonds, memories).
    fn permute(&mut self, order: &[u32], new_of_old: &[u32]);
}

/// Kind of a pair event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairKind {
    Collide,
    Well,
}

/// A particle's earliest pair event, as the pair source stores it.
#[derive(Debug, Clone, Copy)]
pub struct PairEvent {
    pub time: f64,
    pub partner: u32,
    pub partner_count: u32,
    pub kind: PairKind,
}

impl PairEvent {
    pub const NEVER: PairEvent = PairEvent {
        time: f64::INFINITY,
        partner: NONE,
        partner_count: 0,
        kind: PairKind::Collide,
    };

    #[inline]
    pub fn event(&self) -> Event {
        let (partner, partner_count) = (self.partner, self.partner_count);
        Event {
            time: self.time,
            kind: match self.kind {
                PairKind::Collide => EventKind::Collide {
                    partner,
                    partner_count,
                },
                PairKind::Well => EventKind::Well {
                    partner,
                    partner_count,
                },
            },
        }
    }
}

/// A plane event (cell crossing, wall collision, slab crossing) as its source stores it: when,
/// along which axis, in which direction.
#[derive(Debug, Clone, Copy)]
pub struct PlaneEvent {
    pub time: f64,
    pub axis: u8,
    pub up: bool,
}

impl PlaneEvent {
    pub const NEVER: PlaneEvent = PlaneEvent {
        time: f64::INFINITY,
        axis: 0,
        up: false,
    };

    /// Replaces this event by `(time, axis, up)` if that is earlier.
    #[inline]
    pub fn keep_earlier(&mut self, time: f64, axis: usize, up: bool) {
        if time < self.time {
            *self = PlaneEvent {
                time,
                axis: axis as u8,
                up,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_event_is_small_and_ties_go_to_the_first_candidate() {
        assert!(std::mem::size_of::<Event>() <= 24);
        let a = Event {
            time: 1.0,
            kind: EventKind::Cell { axis: 0, up: true },
        };
        let b = Event {
            time: 1.0,
            kind: EventKind::Wall { axis: 1, up: false },
        };
        assert_eq!(a.earlier(b), a);
        assert_eq!(b.earlier(a), b);
        let c = Event { time: 0.5, ..b };
        assert_eq!(a.earlier(c), c);
        assert_eq!(Event::NEVER.earlier(a), a);
    }
}
