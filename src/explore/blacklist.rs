//! Places the robot failed to reach, which a decision avoids until the map around them
//! changes.
//!
//! One list serves every selector and the mission: the mission lists the last target of a
//! decision it had to drop, and each selector skips targets (or frontier cells) within
//! [`Blacklist::radius_m`] of a listed place. An entry remembers how many cells around it were
//! known when it was listed; once that number changes the map there was updated (a door seen
//! open, a corner explored), so the place may have become reachable and the entry lapses
//! ([`Blacklist::forget_changed`]): the robot does not give up with unknown space left. This is
//! explore_lite's blacklist with that self-clearing rule.

use crate::geometry::Point2;
use crate::grid::{Cell, OccupancyGrid};

use super::DecideError;

/// Most places a [`Blacklist`] holds.
pub const MAX_BLACKLISTED: usize = 32;
/// A target this close to a listed place counts as listed, by default \[m\].
pub const BLACKLIST_RADIUS_M: f32 = 0.5;
/// Half-width of the window whose known-cell count decides when an entry lapses \[m\].
pub(crate) const WINDOW_HALF_M: f32 = 1.0;
/// The known-cell count of an entry's window must move by at least this many cells for the
/// map there to count as changed ([`changed_around`]). A cell whose evidence hovers at the
/// Unknown threshold (a precise laser's beams ending on and passing by a wall's edge from a
/// robot standing still) flips in and out of the count scan after scan: under the 0.3 %
/// laser an entry lapsed every control period and the livelock rule never saw the same map
/// twice (gen-09 seed 25, realistic slip, matcher on: 55 804 decisions of one target 1.4 cm
/// away until the time limit).
pub(crate) const CHANGED_CELLS: u32 = 5;

/// Whether `known_now` known cells in a window that held `known_then` mean the map there
/// changed: by at least [`CHANGED_CELLS`] either way.
pub(crate) fn changed_around(known_then: u32, known_now: u32) -> bool {
    known_then.abs_diff(known_now) >= CHANGED_CELLS
}

/// One listed place.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    point: Point2,
    /// Known cells within [`WINDOW_HALF_M`] of `point` when it was listed.
    known_around: u32,
}

/// Places the robot failed to reach: a decision never chooses a target within
/// [`Blacklist::radius_m`] of one of them.
#[derive(Clone, Debug, PartialEq)]
pub struct Blacklist {
    /// A target this close to a listed place counts as listed \[m\].
    pub radius_m: f32,
    entries: heapless::Vec<Entry, MAX_BLACKLISTED>,
}

impl Default for Blacklist {
    fn default() -> Self {
        Self::new(BLACKLIST_RADIUS_M)
    }
}

impl Blacklist {
    /// An empty list covering `radius_m` around each place.
    pub const fn new(radius_m: f32) -> Self {
        Self {
            radius_m,
            entries: heapless::Vec::new(),
        }
    }

    /// Lists `p`, failed to reach on the map `grid`; [`DecideError::BlacklistFull`] when
    /// [`MAX_BLACKLISTED`] places are listed.
    pub fn push<const N: usize>(
        &mut self,
        grid: &OccupancyGrid<N>,
        p: Point2,
    ) -> Result<(), DecideError> {
        self.entries
            .push(Entry {
                point: p,
                known_around: known_around(grid, p),
            })
            .map_err(|_| DecideError::BlacklistFull {
                capacity: MAX_BLACKLISTED,
            })
    }

    /// Lists `p` as [`Self::push`] does, forgetting the oldest entry when the list is full.
    pub fn push_forgetting_oldest<const N: usize>(&mut self, grid: &OccupancyGrid<N>, p: Point2) {
        if self.entries.is_full() {
            self.entries.remove(0);
        }
        // Room was made above.
        let _ = self.push(grid, p);
    }

    /// Forgets the entries whose surroundings on `grid` changed since they were listed (by
    /// `CHANGED_CELLS` known cells or more).
    pub fn forget_changed<const N: usize>(&mut self, grid: &OccupancyGrid<N>) {
        self.entries
            .retain(|e| !changed_around(e.known_around, known_around(grid, e.point)));
    }

    /// Listed places.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether nothing is listed.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Whether `p` lies within the radius of a listed place.
    pub fn contains(&self, p: Point2) -> bool {
        self.entries
            .iter()
            .any(|e| e.point.distance(p) <= self.radius_m)
    }
}

/// Known cells (Free or Occupied) in the square of half-width [`WINDOW_HALF_M`] around `p`.
pub(crate) fn known_around<const N: usize>(grid: &OccupancyGrid<N>, p: Point2) -> u32 {
    let g = grid.geometry();
    let c = g.cell_at_unchecked(p);
    let r = (WINDOW_HALF_M / g.resolution_m) as i32;
    let mut n = 0u32;
    for row in c.row - r..=c.row + r {
        for col in c.col - r..=c.col + r {
            if grid
                .class_of(Cell::new(col, row))
                .is_some_and(|k| k.is_known())
            {
                n += 1;
            }
        }
    }
    n
}
