//! Legs remembered within a decision, keyed by their end cells.
//!
//! Under the long-term strategy each candidate is a tour of several targets; its first leg is
//! the path on the decision's distance field from the robot's cell, every leg after it an A*
//! search from one target's cell to the next ([`crate::planner::Planner`]), and each is pruned
//! to waypoints. Within one decision the map does not change, so a
//! leg's waypoints depend only on its two cells, and a converging population proposes the same
//! pairs of (snapped) cells again and again: the pruned waypoints are remembered and copied
//! instead of searched again, which gives the same waypoints, so the same evaluation. A
//! direct-mapped table (one slot per hash of the pair; a new leg replaces the slot's old one);
//! a generation number clears it in O(1) per decision. Legs with more waypoints than a slot
//! holds are not remembered. An objective with a visibility cache (every mission's) uses the
//! larger table the cache carries on the heap ([`DECISION_LEG_SLOTS`]); one without keeps a
//! small one in itself ([`LEG_SLOTS`]).

use crate::geometry::Point2;
use crate::grid::Cell;

use super::evaluation::CandidateStatus;

/// Slots of the table an objective keeps in itself (without a visibility cache).
pub const LEG_SLOTS: usize = 64;
/// Slots of the table a visibility cache carries for the decisions it serves
/// ([`super::view_cache::ViewCache`], on the heap): a population of 20 proposing tours of three
/// targets for 30 generations plans a few thousand distinct legs per decision, which 64
/// slots mostly forget before they come round again (docs/benchmarks.md, "Legs remembered
/// over the whole decision").
pub const DECISION_LEG_SLOTS: usize = 4096;
/// Most waypoints of a remembered leg.
pub const LEG_WAYPOINTS: usize = 16;

/// One remembered leg. All zeros is an empty slot (generation 0 is never current).
#[derive(Clone, Copy, Debug, bytemuck::Zeroable)]
struct Entry {
    generation: u32,
    from: Cell,
    to: Cell,
    /// The leg starts at the robot (planned on the decision's distance field), not at a
    /// target (planned by A*): the two may differ between the same cells.
    from_robot: bool,
    /// The waypoints' count when `status` is `Feasible`.
    count: u8,
    /// `Feasible` for a planned leg, else why it could not be planned.
    status: CandidateStatus,
    waypoints: [Point2; LEG_WAYPOINTS],
}

const EMPTY: Entry = Entry {
    generation: 0,
    from: Cell::new(0, 0),
    to: Cell::new(0, 0),
    from_robot: false,
    count: 0,
    status: CandidateStatus::Feasible,
    waypoints: [Point2::new(0.0, 0.0); LEG_WAYPOINTS],
};

/// A leg as remembered: its pruned waypoints, or why it could not be planned.
pub(crate) type Leg<'a> = Result<&'a [Point2], CandidateStatus>;

/// Remembered legs of the current decision, in `SLOTS` slots (a power of two, at most 2^16).
#[derive(Clone, Debug, bytemuck::Zeroable)]
pub(crate) struct LegMemo<const SLOTS: usize> {
    /// Current generation; 0 (all zeros) until the first [`Self::clear`].
    generation: u32,
    entries: [Entry; SLOTS],
}

impl<const SLOTS: usize> LegMemo<SLOTS> {
    /// The slot is taken from the hash's upper 16 bits.
    const POWER_OF_TWO: () = assert!(SLOTS.is_power_of_two() && SLOTS <= 1 << 16);

    pub(crate) const fn new() -> Self {
        let () = Self::POWER_OF_TWO;
        Self {
            generation: 1,
            entries: [EMPTY; SLOTS],
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
        (h >> 16) as usize & (SLOTS - 1)
    }

    /// The leg from `from` to `to` (from the robot's cell on the distance field if
    /// `from_robot`), if remembered in this decision.
    pub(crate) fn get(&self, from: Cell, to: Cell, from_robot: bool) -> Option<Leg<'_>> {
        let e = &self.entries[Self::slot(from, to)];
        if self.generation == 0
            || e.generation != self.generation
            || e.from != from
            || e.to != to
            || e.from_robot != from_robot
        {
            return None;
        }
        Some(match e.status {
            CandidateStatus::Feasible => Ok(&e.waypoints[..usize::from(e.count)]),
            failed => Err(failed),
        })
    }

    /// Remembers the leg from `from` to `to` (replacing the slot's leg); a leg with more than
    /// [`LEG_WAYPOINTS`] waypoints is not remembered, nor anything before the first
    /// [`Self::clear`] of a zeroed table.
    pub(crate) fn put(&mut self, from: Cell, to: Cell, from_robot: bool, leg: Leg<'_>) {
        if self.generation == 0 {
            return;
        }
        let (count, status) = match leg {
            Ok(w) if w.len() > LEG_WAYPOINTS => return,
            Ok(w) => (w.len() as u8, CandidateStatus::Feasible),
            // A leg is remembered as planned or not; `Feasible` is no reason for failing.
            Err(CandidateStatus::Feasible) => return,
            Err(s) => (0, s),
        };
        let generation = self.generation;
        let e = &mut self.entries[Self::slot(from, to)];
        if let Ok(w) = leg {
            e.waypoints[..w.len()].copy_from_slice(w);
        }
        e.generation = generation;
        e.from = from;
        e.to = to;
        e.from_robot = from_robot;
        e.count = count;
        e.status = status;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remembers_legs_of_this_decision_only() {
        let mut m = LegMemo::<LEG_SLOTS>::new();
        let (a, b, c) = (Cell::new(1, 2), Cell::new(3, 4), Cell::new(5, 6));
        let w = [Point2::new(0.1, 0.2), Point2::new(0.3, 0.4)];
        assert!(m.get(a, b, false).is_none());
        m.put(a, b, false, Ok(&w));
        m.put(b, c, false, Err(CandidateStatus::Unreachable));
        assert_eq!(m.get(a, b, false), Some(Ok(&w[..])));
        assert!(m.get(b, a, false).is_none(), "a leg is directed");
        assert!(
            m.get(a, b, true).is_none(),
            "a leg from the robot is planned another way"
        );
        assert_eq!(m.get(b, c, false), Some(Err(CandidateStatus::Unreachable)));
        m.clear();
        assert!(m.get(a, b, false).is_none() && m.get(b, c, false).is_none());
        let long = [Point2::new(0.0, 0.0); LEG_WAYPOINTS + 1];
        m.put(a, c, false, Ok(&long));
        assert!(
            m.get(a, c, false).is_none(),
            "too many waypoints to remember"
        );
    }
}
