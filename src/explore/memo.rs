//! Evaluations remembered within a decision, keyed by the candidates' target cells.
//!
//! A candidate's evaluation depends only on the cells its targets fall in (targets are snapped
//! to cell centres before planning), so two candidates with the same cells score the same: a
//! converging population re-proposes the same cells again and again (on the House benchmark,
//! 246 evaluations of one decision fall in 51 distinct cells). Open addressing with linear
//! probing; a generation number clears the table in O(1) per decision. When the table is
//! three-quarters full, further evaluations are computed without being remembered.

use super::MAX_TARGETS;
use super::evaluation::{CandidateStatus, Evaluation, WORST_FITNESS};

/// Slots of the table.
pub const MEMO_SLOTS: usize = 512;
/// Most evaluations remembered per decision.
pub const MEMO_CAPACITY: usize = MEMO_SLOTS * 3 / 4;

#[derive(Clone, Copy, Debug)]
struct Entry {
    generation: u32,
    len: u8,
    cells: [u32; MAX_TARGETS],
    eval: Evaluation,
}

const EMPTY: Entry = Entry {
    generation: 0,
    len: 0,
    cells: [0; MAX_TARGETS],
    eval: Evaluation {
        status: CandidateStatus::Feasible,
        gain_cells: 0,
        energy_steps: 0.0,
        path_length_m: 0.0,
        fitness: WORST_FITNESS,
    },
};

/// Remembered evaluations of the current decision.
#[derive(Clone, Debug)]
pub(crate) struct EvalMemo {
    generation: u32,
    stored: usize,
    hits: u32,
    entries: [Entry; MEMO_SLOTS],
}

impl EvalMemo {
    pub(crate) const fn new() -> Self {
        Self {
            generation: 1,
            stored: 0,
            hits: 0,
            entries: [EMPTY; MEMO_SLOTS],
        }
    }

    /// Forgets everything (a new decision).
    pub(crate) fn clear(&mut self) {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            for e in self.entries.iter_mut() {
                e.generation = 0;
            }
            self.generation = 1;
        }
        self.stored = 0;
        self.hits = 0;
    }

    /// Lookups answered from the table since the last [`Self::clear`].
    pub(crate) fn hits(&self) -> u32 {
        self.hits
    }

    fn start(cells: &[u32]) -> usize {
        let mut h = cells.len() as u32;
        for &c in cells {
            h = (h ^ c).wrapping_mul(0x9E37_79B1).rotate_left(13);
        }
        h as usize % MEMO_SLOTS
    }

    /// The slot holding `cells`, or the empty slot where they would go.
    fn find(&self, cells: &[u32]) -> Option<usize> {
        let mut i = Self::start(cells);
        for _ in 0..MEMO_SLOTS {
            let e = &self.entries[i];
            if e.generation != self.generation
                || (e.len as usize == cells.len() && &e.cells[..cells.len()] == cells)
            {
                return Some(i);
            }
            i = (i + 1) % MEMO_SLOTS;
        }
        None
    }

    /// The remembered evaluation of the candidate whose targets lie in `cells` (flat indices).
    pub(crate) fn get(&mut self, cells: &[u32]) -> Option<Evaluation> {
        let i = self.find(cells)?;
        let e = &self.entries[i];
        if e.generation != self.generation {
            return None;
        }
        self.hits += 1;
        Some(e.eval)
    }

    /// Remembers `eval` for `cells` (at most [`MAX_TARGETS`] of them) if there is room.
    pub(crate) fn put(&mut self, cells: &[u32], eval: Evaluation) {
        if self.stored >= MEMO_CAPACITY || cells.len() > MAX_TARGETS {
            return;
        }
        let Some(i) = self.find(cells) else { return };
        let e = &mut self.entries[i];
        if e.generation != self.generation {
            self.stored += 1;
        }
        e.generation = self.generation;
        e.len = cells.len() as u8;
        e.cells[..cells.len()].copy_from_slice(cells);
        e.eval = eval;
    }
}
