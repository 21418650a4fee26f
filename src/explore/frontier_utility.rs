//! Frontier utility exploration: explore_lite's rule (Hörner, "Map-merging for multi-robot
//! system", Charles University 2016; ROS package `explore_lite`): each frontier costs
//! `potential_scale * distance - gain_scale * size * resolution` and the cheapest is chosen.
//!
//! Two changes fix the failures its users report most:
//! - the distance is the **path** distance from the decision's distance field, not the
//!   straight-line distance, and a frontier no path reaches is never chosen, so the robot does
//!   not try forever to reach it;
//! - a place the robot failed to reach can be blacklisted ([`FrontierUtility::blacklist`]):
//!   frontier cells near it are skipped (the rest of the frontier stays selectable);
//!   the entry lapses as soon as the number of known cells around it changes (the map there
//!   was updated, so the frontier may have become reachable), so the robot does not give up
//!   with unknown space left.

use crate::frontier::{FrontierConfig, FrontierWorkspace, find_frontiers};
use crate::geometry::Point2;
use crate::grid::{Cell, OccupancyGrid};

use super::objective::ExploreObjective;
use super::{
    DecideError, DecisionRequest, ExploreConfig, Outcome, TargetSelector, reach_frontier_cell,
};

/// Blacklist capacity.
pub const MAX_BLACKLIST: usize = 32;

/// One blacklisted place.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Blacklisted {
    point: Point2,
    known_around: u32,
}

/// explore_lite's frontier rule with path distance and a self-clearing blacklist.
pub struct FrontierUtility<'o, 'm, 'w, const N: usize, const C: usize, const F: usize> {
    /// Decision settings (only the reserve and viewpoint spacing apply: one target).
    pub config: ExploreConfig,
    /// Frontier search settings.
    pub frontier: FrontierConfig,
    /// Weight of the path distance \[1/m\] (explore_lite's default 3).
    pub potential_scale: f32,
    /// Weight of the frontier size \[1/m\] (explore_lite's default 1).
    pub gain_scale: f32,
    /// A frontier whose chosen cell lies within this distance of a blacklisted point is skipped
    /// \[m\].
    pub blacklist_radius_m: f32,
    blacklist: heapless::Vec<Blacklisted, MAX_BLACKLIST>,
    objective: &'o mut ExploreObjective<'m, N>,
    workspace: &'w mut FrontierWorkspace<C, F>,
}

impl<const N: usize, const C: usize, const F: usize> core::fmt::Debug
    for FrontierUtility<'_, '_, '_, N, C, F>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FrontierUtility")
            .field("config", &self.config)
            .field("potential_scale", &self.potential_scale)
            .field("gain_scale", &self.gain_scale)
            .field("blacklist", &self.blacklist)
            .finish_non_exhaustive()
    }
}

/// Half-width of the window whose known-cell count decides when a blacklist entry lapses
/// \[m\].
pub(crate) const WINDOW_HALF_M: f32 = 1.0;

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

impl<'o, 'm, 'w, const N: usize, const C: usize, const F: usize>
    FrontierUtility<'o, 'm, 'w, N, C, F>
{
    /// A selector with explore_lite's default weights (potential 3, gain 1) and a 0.5 m
    /// blacklist radius.
    pub fn new(
        config: ExploreConfig,
        objective: &'o mut ExploreObjective<'m, N>,
        workspace: &'w mut FrontierWorkspace<C, F>,
    ) -> Self {
        Self {
            config: ExploreConfig {
                targets: 1,
                ..config
            },
            frontier: FrontierConfig::default(),
            potential_scale: 3.0,
            gain_scale: 1.0,
            blacklist_radius_m: 0.5,
            blacklist: heapless::Vec::new(),
            objective,
            workspace,
        }
    }

    /// Records that the robot failed to reach `target` on the map `grid`: frontiers near it are
    /// skipped until the map around it changes.
    pub fn blacklist(
        &mut self,
        grid: &OccupancyGrid<N>,
        target: Point2,
    ) -> Result<(), DecideError> {
        self.blacklist
            .push(Blacklisted {
                point: target,
                known_around: known_around(grid, target),
            })
            .map_err(|_| DecideError::BlacklistFull {
                capacity: MAX_BLACKLIST,
            })
    }

    /// Active blacklist entries.
    pub fn blacklisted(&self) -> usize {
        self.blacklist.len()
    }

    fn is_blacklisted(&self, p: Point2) -> bool {
        self.blacklist
            .iter()
            .any(|b| b.point.distance(p) <= self.blacklist_radius_m)
    }
}

impl<const N: usize, const C: usize, const F: usize> TargetSelector<N>
    for FrontierUtility<'_, '_, '_, N, C, F>
{
    fn decide<R: rand_core::Rng>(
        &mut self,
        req: &DecisionRequest<'_, N>,
        _rng: &mut R,
    ) -> Result<Outcome, DecideError> {
        self.objective.prepare(req, &self.config)?;
        // Entries lapse once the map around them changed.
        self.blacklist
            .retain(|b| known_around(req.grid, b.point) == b.known_around);
        find_frontiers(
            req.grid,
            req.pose.position(),
            &self.frontier,
            self.workspace,
        )
        .map_err(DecideError::Frontier)?;
        let ws = &*self.workspace;
        let res = req.grid.geometry().resolution_m;
        let mut best: Option<(Cell, f32)> = None;
        let mut reachable = false;
        let mut evaluations = 0u32;
        for fr in ws.frontiers() {
            evaluations += 1;
            let mut near: Option<(Cell, f32)> = None;
            for &i in ws.cells_of(fr) {
                let Some((c, d)) =
                    reach_frontier_cell(req.grid, self.objective.field(), i as usize)
                else {
                    continue;
                };
                reachable = true;
                if near.is_none_or(|(_, b)| d < b)
                    && !self.is_blacklisted(req.grid.geometry().cell_center(c))
                {
                    near = Some((c, d));
                }
            }
            let Some((cell, d)) = near else { continue };
            let cost = self.potential_scale * d - self.gain_scale * fr.size_cells as f32 * res;
            if best.is_none_or(|(_, b)| cost < b) {
                best = Some((cell, cost));
            }
        }
        let Some((cell, _)) = best else {
            return if reachable {
                Err(DecideError::AllBlacklisted {
                    entries: self.blacklist.len(),
                })
            } else {
                Ok(Outcome::Done)
            };
        };
        let target = req.grid.geometry().cell_center(cell);
        let eval = self.objective.evaluate_targets(req, &[target]);
        self.objective
            .decision(&eval, evaluations, &[])
            .map(Outcome::Go)
            .ok_or(DecideError::NoFeasibleTarget {
                battery_steps: req.battery_steps,
            })
    }
}
