//! Putting the shared map back after a robot's period: its own body lifted off, the robots
//! near it stamped on (`machine/robots.rs`). Undoing those changes cell by cell costs as
//! much as making them, since every class change refreshes the traversability layer over
//! the inflation disc around the cell (about 5 000 instructions a cell; 54.5 % of a
//! 100-robot run, docs/benchmarks.md). Instead the rectangle the changes can reach (the
//! changed cells' box grown by the layer's reach) is copied aside before the changes and
//! copied back after: a checkpoint of a window, the textbook alternative to an undo log
//! (state saving versus reverse computation, as in optimistic simulation: Fujimoto,
//! *Parallel and Distributed Simulation Systems*, 2000, ch. 4).
//!
//! The result equals undoing cell by cell: the log-odds, class counters and per-cell layer
//! state come back exactly; the grid's box of known cells and the layer's box of marked
//! cells keep what they grew by, as they do when undoing cell by cell (they never shrink).
//! Nothing may change the map between the save and the restore except the changes inside
//! the window; a window larger than the buffer is not saved, and the caller undoes cell by
//! cell.

use crate::grid::{CellBox, CellCounts};
use crate::planner::TravWindow;

use super::SharedMap;

/// Cells in the saved window: 128 x 128, room for the disc of robots 3 m away on every
/// side plus the layer's reach at 0.1 m (about 83 x 83 cells with the default bands).
pub(crate) const STAMP_WINDOW_CELLS: usize = 128 * 128;

/// A saved window of the shared map (grid and traversability layer).
#[derive(bytemuck::Zeroable)]
pub(crate) struct StampWindow<const C: usize> {
    /// The saved rectangle; empty when nothing is saved.
    area: CellBox,
    counts: CellCounts,
    log_odds: [f32; C],
    trav: TravWindow<C>,
}

impl<const C: usize> StampWindow<C> {
    /// Nothing saved, built on the stack (or in a `static`).
    pub(crate) const fn new() -> Self {
        Self {
            area: CellBox::EMPTY,
            counts: CellCounts {
                free: 0,
                occupied: 0,
            },
            log_odds: [0.0; C],
            trav: TravWindow::new(),
        }
    }

    /// Saves `area` of `map`; `false` (nothing saved) when it is empty, leaves the map or
    /// holds more than `C` cells.
    pub(crate) fn save<const N: usize>(&mut self, map: &SharedMap<N>, area: CellBox) -> bool {
        self.area = CellBox::EMPTY;
        if area.is_empty() || map.trav.geometry() != map.grid.geometry() {
            return false;
        }
        let Some(counts) = map.grid.save_window(area, &mut self.log_odds) else {
            return false;
        };
        if !map.trav.save_window(area, &mut self.trav) {
            return false;
        }
        self.area = area;
        self.counts = counts;
        true
    }

    /// Puts back the window saved last (nothing if none); the window is then forgotten.
    pub(crate) fn restore<const N: usize>(&mut self, map: &mut SharedMap<N>) {
        let area = core::mem::replace(&mut self.area, CellBox::EMPTY);
        if area.is_empty() {
            return;
        }
        map.grid.restore_window(area, &self.log_odds, self.counts);
        map.trav.restore_window(area, &self.trav);
    }
}
