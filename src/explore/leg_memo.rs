//! Legs between two targets remembered within a decision, keyed by their end cells.
//!
//! Under the long-term strategy each candidate is a tour of several targets; every leg after
//! the first is an A* search from one target's cell to the next ([`crate::planner::Planner`])
//! and a pruning of its cells to waypoints. Within one decision the map does not change, so a
//! leg's waypoints depend only on its two cells, and a converging population proposes the same
//! pairs of (snapped) cells again and again: the pruned waypoints are remembered and copied
//! instead of searched again, which gives the same waypoints, so the same evaluation. A
//! direct-mapped table (one slot per hash of the pair; a new leg replaces the slot's old one);
//! a generation number clears it in O(1) per decision. Legs with more waypoints than a slot
//! holds are not remembered.

use crate::geometry::Point2;
use crate::grid::Cell;

use super::evaluation::CandidateStatus;

/// Slots of the table.
pub const LEG_SLOTS: usize = 64;
/// Most waypoints of a remembered leg.
pub const LEG_WAYPOINTS: usize = 16;

#[derive(Clone, Copy, Debug)]
struct Entry {
    generation: u32,
    from: Cell,
    to: Cell,
    /// The waypoints' count, or why the leg could not be planned.
    outcome: Result<u8, CandidateStatus>,
    waypoints: [Point2; LEG_WAYPOINTS],
}

const EMPTY: Entry = Entry {
    generation: 0,
    from: Cell::new(0, 0),
    to: Cell::new(0, 0),
    outcome: Ok(0),
    waypoints: [Point2::new(0.0, 0.0); LEG_WAYPOINTS],
};

/// A leg as remembered: its pruned waypoints, or why it could not be planned.
pub(crate) type Leg<'a> = Result<&'a [Point2], CandidateStatus>;

/// Remembered legs of the current decision.
#[derive(Clone, Debug)]
pub(crate) struct LegMemo {
    generation: u32,
    entries: [Entry; LEG_SLOTS],
}

impl LegMemo {
    pub(crate) const fn new() -> Self {
        Self {
            generation: 1,
            entries: [EMPTY; LEG_SLOTS],
        }
    }

    /// Forgets everything (a new decision or re-plan: the map may have changed).
    pub(crate) fn clear(&mut self) {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            for e in self.entries.iter_mut() {
                e.generation = 0;
            }
            self.generation = 1;
        }
    }

    fn slot(from: Cell, to: Cell) -> usize {
        let h = (from.col as u32)
            .wrapping_mul(0x9E37_79B1)
            .wrapping_add((from.row as u32).wrapping_mul(0x85EB_CA77))
            .wrapping_add((to.col as u32).wrapping_mul(0xC2B2_AE3D))
            .wrapping_add((to.row as u32).wrapping_mul(0x27D4_EB2F));
        (h >> 16) as usize % LEG_SLOTS
    }

    /// The leg from `from` to `to`, if remembered in this decision.
    pub(crate) fn get(&self, from: Cell, to: Cell) -> Option<Leg<'_>> {
        let e = &self.entries[Self::slot(from, to)];
        if e.generation != self.generation || e.from != from || e.to != to {
            return None;
        }
        Some(e.outcome.map(|n| &e.waypoints[..usize::from(n)]))
    }

    /// Remembers the leg from `from` to `to` (replacing the slot's leg); a leg with more than
    /// [`LEG_WAYPOINTS`] waypoints is not remembered.
    pub(crate) fn put(&mut self, from: Cell, to: Cell, leg: Leg<'_>) {
        let outcome = match leg {
            Ok(w) if w.len() > LEG_WAYPOINTS => return,
            Ok(w) => Ok(w.len() as u8),
            Err(s) => Err(s),
        };
        let generation = self.generation;
        let e = &mut self.entries[Self::slot(from, to)];
        if let Ok(w) = leg {
            e.waypoints[..w.len()].copy_from_slice(w);
        }
        e.generation = generation;
        e.from = from;
        e.to = to;
        e.outcome = outcome;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remembers_legs_of_this_decision_only() {
        let mut m = LegMemo::new();
        let (a, b, c) = (Cell::new(1, 2), Cell::new(3, 4), Cell::new(5, 6));
        let w = [Point2::new(0.1, 0.2), Point2::new(0.3, 0.4)];
        assert!(m.get(a, b).is_none());
        m.put(a, b, Ok(&w));
        m.put(b, c, Err(CandidateStatus::Unreachable));
        assert_eq!(m.get(a, b), Some(Ok(&w[..])));
        assert!(m.get(b, a).is_none(), "a leg is directed");
        assert_eq!(m.get(b, c), Some(Err(CandidateStatus::Unreachable)));
        m.clear();
        assert!(m.get(a, b).is_none() && m.get(b, c).is_none());
        let long = [Point2::new(0.0, 0.0); LEG_WAYPOINTS + 1];
        m.put(a, c, Ok(&long));
        assert!(m.get(a, c).is_none(), "too many waypoints to remember");
    }
}
