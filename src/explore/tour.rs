//! A coarse tour over the frontier: the order in which the robot would visit the unknown
//! space left, so that a target is scored by what choosing it first does to the whole trip,
//! not only by the trip to it.
//!
//! The frontier viewpoints of a decision ([`super::reachable`]) are grouped into square
//! **clusters** of [`CLUSTER_CELLS`] cells a side (doubled until at most [`MAX_STOPS`] are
//! left); each cluster is one stop, at its viewpoint nearest the robot by path. An open tour
//! from the robot through every stop is built by nearest neighbour and improved by 2-opt
//! exchanges. Distances: from the robot, the path distance of the decision's distance field;
//! between two stops, `max(straight line, |d_a - d_b|)` with `d` their path distances from
//! the robot, a lower bound of the path between them (the straight line can cross a wall;
//! the triangle inequality on the path distances cannot) that costs nothing to compute.
//!
//! A candidate target whose stop is `s` costs the tour [`FrontierTour::extra_m`]`(s)`: how
//! much longer the tour becomes when `s` is moved to its front (the other stops keep their
//! order). The first stop of the tour costs nothing; a stop in the middle of a run of
//! frontier costs the detour of coming back for the stops before it. This is the cost of
//! Kulich, Faigl and Přeučil ("On distance utility in the exploration task", ICRA 2011): a
//! goal is rated by the length of a TSP tour through all frontier representatives starting
//! with it, not by the distance to it; and the global tour over coarse frontier clusters of
//! Cao et al. (TARE, RSS 2021). Here the tour is solved once per decision and a candidate's
//! tour is the one-move change of it, so the cost of a candidate is a lookup.

use crate::grid::Cell;
use crate::math;

use super::reachable::Viewpoint;

/// Most stops (clusters) of one tour.
pub const MAX_STOPS: usize = 96;
/// Side of the clusters before any doubling \[cells\] (2 m at 0.1 m cells).
pub const CLUSTER_CELLS: i32 = 20;
/// Most 2-opt passes over the tour.
const MAX_PASSES: usize = 8;

/// One stop of the tour.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Stop {
    /// The cluster's viewpoint nearest the robot by path.
    cell: Cell,
    /// Its path distance from the robot \[m\].
    distance_m: f32,
    /// Cluster coordinates at the tour's cluster side.
    key: (i32, i32),
}

const NO_STOP: Stop = Stop {
    cell: Cell::new(0, 0),
    distance_m: 0.0,
    key: (0, 0),
};

/// The tour of one decision.
#[derive(Clone, Debug)]
pub struct FrontierTour {
    stops: [Stop; MAX_STOPS],
    len: usize,
    /// Stop indices in tour order.
    order: [u8; MAX_STOPS],
    /// Extra tour length of each stop taken first, by stop index \[m\].
    extra: [f32; MAX_STOPS],
    side: i32,
    resolution_m: f32,
    length_m: f32,
}

impl Default for FrontierTour {
    fn default() -> Self {
        Self::new()
    }
}

impl FrontierTour {
    /// An empty tour.
    pub const fn new() -> Self {
        Self {
            stops: [NO_STOP; MAX_STOPS],
            len: 0,
            order: [0; MAX_STOPS],
            extra: [0.0; MAX_STOPS],
            side: CLUSTER_CELLS,
            resolution_m: 0.1,
            length_m: 0.0,
        }
    }

    /// Number of stops.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the tour has no stop.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Length of the tour from the robot through every stop \[m\].
    pub fn length_m(&self) -> f32 {
        self.length_m
    }

    /// The stops' cells in tour order.
    pub fn cells(&self) -> impl Iterator<Item = Cell> + '_ {
        self.order[..self.len]
            .iter()
            .map(|&i| self.stops[i as usize].cell)
    }

    /// Builds the tour over `viewpoints` (listed with their path distances from the robot)
    /// on a grid of `resolution_m` cells.
    pub fn build(&mut self, viewpoints: &[Viewpoint], resolution_m: f32) {
        self.build_from(
            viewpoints.iter().map(|v| (v.cell, v.distance_m)),
            resolution_m,
        );
    }

    /// As [`Self::build`], over (cell, path distance from the robot \[m\]) pairs.
    pub fn build_from<I>(&mut self, viewpoints: I, resolution_m: f32)
    where
        I: Iterator<Item = (Cell, f32)> + Clone,
    {
        self.resolution_m = resolution_m;
        let mut side = CLUSTER_CELLS;
        while !self.cluster(viewpoints.clone(), side) {
            side *= 2;
        }
        self.side = side;
        self.solve();
    }

    /// Groups the viewpoints into clusters of `side` cells; `false` if they are too many.
    fn cluster<I: Iterator<Item = (Cell, f32)>>(&mut self, viewpoints: I, side: i32) -> bool {
        self.len = 0;
        for (cell, distance_m) in viewpoints {
            let key = (cell.col.div_euclid(side), cell.row.div_euclid(side));
            match self.stops[..self.len].iter_mut().find(|s| s.key == key) {
                Some(s) => {
                    if distance_m < s.distance_m {
                        s.cell = cell;
                        s.distance_m = distance_m;
                    }
                }
                None => {
                    if self.len == MAX_STOPS {
                        return false;
                    }
                    self.stops[self.len] = Stop {
                        cell,
                        distance_m,
                        key,
                    };
                    self.len += 1;
                }
            }
        }
        true
    }

    /// Distance between stops `a` and `b` \[m\] (a lower bound of the path, see the module
    /// documentation).
    fn between(&self, a: usize, b: usize) -> f32 {
        let (p, q) = (&self.stops[a], &self.stops[b]);
        let (dc, dr) = (
            (p.cell.col - q.cell.col) as f32,
            (p.cell.row - q.cell.row) as f32,
        );
        let straight = math::sqrt(dc * dc + dr * dr) * self.resolution_m;
        straight.max((p.distance_m - q.distance_m).abs())
    }

    /// Length of the leg into stop `s` at tour position `pos`, from the stop before it (the
    /// robot for 0) \[m\].
    fn leg_to(&self, pos: usize, s: usize) -> f32 {
        if pos == 0 {
            self.stops[s].distance_m
        } else {
            self.between(self.order[pos - 1] as usize, s)
        }
    }

    /// Nearest neighbour from the robot, then 2-opt; then each stop's extra length.
    fn solve(&mut self) {
        let n = self.len;
        // Nearest neighbour.
        let mut used = [false; MAX_STOPS];
        for pos in 0..n {
            let mut best = (f32::INFINITY, 0usize);
            for (s, &u) in used[..n].iter().enumerate() {
                if !u {
                    let d = self.leg_to(pos, s);
                    if d < best.0 {
                        best = (d, s);
                    }
                }
            }
            used[best.1] = true;
            self.order[pos] = best.1 as u8;
        }
        // 2-opt on the open tour: reverse positions i..=j.
        for _ in 0..MAX_PASSES {
            let mut improved = false;
            for i in 0..n {
                for j in i + 1..n {
                    let (oi, oj) = (self.order[i] as usize, self.order[j] as usize);
                    let before = self.leg_to(i, oi);
                    let after = self.leg_to(i, oj);
                    let (old_next, new_next) = if j + 1 < n {
                        let on = self.order[j + 1] as usize;
                        (self.between(oj, on), self.between(oi, on))
                    } else {
                        (0.0, 0.0)
                    };
                    if after + new_next < before + old_next - 1e-4 {
                        self.order[i..=j].reverse();
                        improved = true;
                    }
                }
            }
            if !improved {
                break;
            }
        }
        let mut length = 0.0;
        for pos in 0..n {
            length += self.leg_to(pos, self.order[pos] as usize);
        }
        self.length_m = length;
        // Moving the stop at position p to the front.
        for p in 0..n {
            let s = self.order[p] as usize;
            if p == 0 {
                self.extra[s] = 0.0;
                continue;
            }
            let first = self.order[0] as usize;
            let prev = self.order[p - 1] as usize;
            let mut delta = self.stops[s].distance_m + self.between(s, first)
                - self.stops[first].distance_m
                - self.between(prev, s);
            if p + 1 < n {
                let next = self.order[p + 1] as usize;
                delta += self.between(prev, next) - self.between(s, next);
            }
            self.extra[s] = delta.max(0.0);
        }
    }

    /// Extra tour length \[m\] of going to `cell` first: that of the cluster holding it, or of
    /// the nearest stop (straight line) when its cluster has none; 0 for an empty tour.
    pub fn extra_m(&self, cell: Cell) -> f32 {
        let key = (
            cell.col.div_euclid(self.side),
            cell.row.div_euclid(self.side),
        );
        if let Some(i) = self.stops[..self.len].iter().position(|s| s.key == key) {
            return self.extra[i];
        }
        let nearest = self.stops[..self.len]
            .iter()
            .enumerate()
            .min_by_key(|(_, s)| {
                let (dc, dr) = (s.cell.col - cell.col, s.cell.row - cell.row);
                dc * dc + dr * dr
            })
            .map(|(i, _)| i);
        nearest.map_or(0.0, |i| self.extra[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vp(col: i32, row: i32, distance_m: f32) -> (Cell, f32) {
        (Cell::new(col, row), distance_m)
    }

    /// Frontier along a corridor on both sides of the robot, the near end 2 m behind it and
    /// the far end 3..12 m ahead: the tour clears the short side first, and a stop in the
    /// middle of the long side costs the detour back.
    #[test]
    fn the_tour_clears_the_short_side_first_and_charges_a_detour() {
        // Robot at column 100 (not a stop); 0.1 m cells.
        let mut list = vec![vp(80, 0, 2.0)];
        for k in 0..4 {
            let col = 130 + 30 * k;
            list.push(vp(col, 0, (col - 100) as f32 * 0.1));
        }
        let mut tour = FrontierTour::new();
        tour.build_from(list.iter().copied(), 0.1);
        assert_eq!(tour.len(), 5);
        let first = tour.cells().next().unwrap();
        assert_eq!(first, Cell::new(80, 0), "the near side first");
        // 2 m back, 5 m to 3 m ahead, then 9 m: 16 m.
        assert!((tour.length_m() - 16.0).abs() < 1e-3, "{}", tour.length_m());
        assert_eq!(tour.extra_m(Cell::new(80, 0)), 0.0);
        // 3 m ahead first, the others in order: 3 + 5 back + 8 + 6 = 22, against 16.
        let extra = tour.extra_m(Cell::new(130, 0));
        assert!((extra - 6.0).abs() < 1e-3, "{extra}");
        // The far end first: 12 + 14 back + 5 + 3 + 3 = 37, against 16.
        let far = tour.extra_m(Cell::new(220, 0));
        assert!((far - 21.0).abs() < 1e-3, "{far}");
    }

    #[test]
    fn an_empty_tour_costs_nothing() {
        let mut tour = FrontierTour::new();
        tour.build(&[], 0.1);
        assert!(tour.is_empty());
        assert_eq!(tour.extra_m(Cell::new(3, 4)), 0.0);
    }

    /// Many viewpoints fold into at most [`MAX_STOPS`] clusters.
    #[test]
    fn many_viewpoints_fold_into_bounded_clusters() {
        let list: Vec<_> = (0..500)
            .map(|k| vp((k % 50) * 10, (k / 50) * 10, k as f32 * 0.1))
            .collect();
        let mut tour = FrontierTour::new();
        tour.build_from(list.iter().copied(), 0.1);
        assert!(tour.len() <= MAX_STOPS && !tour.is_empty());
    }
}
