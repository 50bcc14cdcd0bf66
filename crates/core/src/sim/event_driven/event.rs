//! The event value the scheduler pops, validates and dispatches: a time and a kind ([`Event`],
//! `Copy`, 24 bytes); the compact per-particle predictions the sources keep ([`PairEvent`],
//! [`PlaneEvent`]) from which they build it; and [`EventSource`], what every source offers the
//! scheduler.

/// Sentinel partner index: no partner.
pub(crate) const NONE: u32 = u32::MAX;

/// What happens at an event, with what the source needs to carry it out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// Nothing predicted (time `+inf`).
    Never,
    /// Contact of `i` with `partner` (hard-core collision, and bridge formation if wet). Valid
    /// only while the partner's velocity-change counter still reads `partner_count`.
    Collide { partner: u32, partner_count: u32 },
    /// A bonded pair at `s = s_crit`: bounce off the well wall or rupture (docs/model.md 3.2);
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
    /// `other` if it is strictly earlier than `self`, else `self`: among equal times the
    /// candidate offered first wins, which fixes the precedence of the sources.
    #[inline]
    pub fn earlier(self, other: Event) -> Event {
        if other.time < self.time { other } else { self }
    }
}

/// What every event source offers the scheduler. Prediction and firing are the sources' own
/// methods, because each needs different parts of the engine; the scheduler calls them on the
/// concrete source types, so everything is monomorphised.
pub(crate) trait EventSource {
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

/// Bit of [`PairEvent`]'s packed partner field that marks a well event.
const WELL_BIT: u32 = 1 << 31;

/// A particle's earliest pair event, as the pair source stores it: 16 bytes (time, partner
/// index with the kind in its top bit, the partner's velocity-change count), four to a cache
/// line. Particle indices stay below `2^31 - 1` (checked when the engine is built).
#[derive(Debug, Clone, Copy)]
pub struct PairEvent {
    pub time: f64,
    /// Partner index, `WELL_BIT` set for a well event; `NONE` for no partner.
    partner_kind: u32,
    pub(crate) partner_count: u32,
}

impl PairEvent {
    pub(crate) const NEVER: PairEvent = PairEvent {
        time: f64::INFINITY,
        partner_kind: NONE,
        partner_count: 0,
    };

    /// The event with `partner` (index below `2^31 - 1`) at `time`.
    #[inline]
    pub fn new(time: f64, partner: u32, partner_count: u32, kind: PairKind) -> Self {
        debug_assert!(partner < WELL_BIT - 1);
        let well = if kind == PairKind::Well { WELL_BIT } else { 0 };
        PairEvent {
            time,
            partner_kind: partner | well,
            partner_count,
        }
    }

    /// The partner's index (`NONE`: no partner).
    #[inline]
    pub fn partner(&self) -> u32 {
        if self.partner_kind == NONE {
            NONE
        } else {
            self.partner_kind & !WELL_BIT
        }
    }

    #[inline]
    pub fn kind(&self) -> PairKind {
        if self.partner_kind != NONE && self.partner_kind & WELL_BIT != 0 {
            PairKind::Well
        } else {
            PairKind::Collide
        }
    }

    /// Renames the partner (renumbering: `new_of_old[old] = new`).
    #[inline]
    pub(crate) fn rename_partner(&mut self, new_of_old: &[u32]) {
        if self.partner_kind != NONE {
            let well = self.partner_kind & WELL_BIT;
            self.partner_kind = new_of_old[self.partner() as usize] | well;
        }
    }

    #[inline]
    pub fn event(&self) -> Event {
        let (partner, partner_count) = (self.partner(), self.partner_count);
        Event {
            time: self.time,
            kind: match self.kind() {
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
    pub(crate) const NEVER: PlaneEvent = PlaneEvent {
        time: f64::INFINITY,
        axis: 0,
        up: false,
    };

    /// The stored event as the scheduler's, of the kind `kind(axis, up)`.
    #[inline]
    pub(crate) fn event(self, kind: impl Fn(u8, bool) -> EventKind) -> Event {
        Event {
            time: self.time,
            kind: kind(self.axis, self.up),
        }
    }

    /// Replaces this event by `(time, axis, up)` if that is earlier.
    #[inline]
    pub(crate) fn keep_earlier(&mut self, time: f64, axis: usize, up: bool) {
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
    fn the_pair_event_packs_partner_and_kind() {
        assert_eq!(std::mem::size_of::<PairEvent>(), 16);
        let mut w = PairEvent::new(2.0, 7, 3, PairKind::Well);
        assert_eq!(
            (w.partner(), w.kind(), w.partner_count),
            (7, PairKind::Well, 3)
        );
        let c = PairEvent::new(1.0, (1 << 31) - 2, 0, PairKind::Collide);
        assert_eq!((c.partner(), c.kind()), ((1 << 31) - 2, PairKind::Collide));
        assert_eq!(
            (PairEvent::NEVER.partner(), PairEvent::NEVER.kind()),
            (NONE, PairKind::Collide)
        );
        let new_of_old: Vec<u32> = (0..8).rev().collect();
        w.rename_partner(&new_of_old);
        assert_eq!((w.partner(), w.kind()), (0, PairKind::Well));
        assert_eq!(
            w.event().kind,
            EventKind::Well {
                partner: 0,
                partner_count: 3
            }
        );
    }

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
        let never = Event {
            time: f64::INFINITY,
            kind: EventKind::Never,
        };
        assert_eq!(never.earlier(a), a);
    }
}
