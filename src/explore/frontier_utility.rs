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
//!   with unknown space left (see [`super::blacklist`]).

use crate::frontier::{FrontierConfig, FrontierWorkspace, find_frontiers};
use crate::grid::Cell;
use crate::planner::{AStar, Planner};

use super::objective::ExploreObjective;
use super::{
    Blacklist, DecideError, DecisionRequest, ExploreConfig, Outcome, TargetSelector,
    reach_frontier_cell,
};

/// explore_lite's frontier rule with path distance and a self-clearing blacklist.
pub struct FrontierUtility<
    'o,
    'm,
    'w,
    const N: usize,
    const C: usize,
    const F: usize,
    P: Planner<N> = AStar<N>,
> {
    /// Decision settings (only the reserve and viewpoint spacing apply: one target).
    pub config: ExploreConfig,
    /// Frontier search settings.
    pub frontier: FrontierConfig,
    /// Weight of the path distance \[1/m\] (explore_lite's default 3).
    pub potential_scale: f32,
    /// Weight of the frontier size \[1/m\] (explore_lite's default 1).
    pub gain_scale: f32,
    /// Places the robot failed to reach: a frontier cell near one is skipped (empty by
    /// default).
    pub blacklist: Blacklist,
    objective: &'o mut ExploreObjective<'m, N, P>,
    workspace: &'w mut FrontierWorkspace<C, F>,
}

impl<const N: usize, const C: usize, const F: usize, P: Planner<N>> core::fmt::Debug
    for FrontierUtility<'_, '_, '_, N, C, F, P>
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

impl<'o, 'm, 'w, const N: usize, const C: usize, const F: usize, P: Planner<N>>
    FrontierUtility<'o, 'm, 'w, N, C, F, P>
{
    /// A selector with explore_lite's default weights (potential 3, gain 1) and an empty
    /// blacklist.
    pub fn new(
        config: ExploreConfig,
        objective: &'o mut ExploreObjective<'m, N, P>,
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
            blacklist: Blacklist::default(),
            objective,
            workspace,
        }
    }
}

impl<const N: usize, const C: usize, const F: usize, P: Planner<N>> TargetSelector<N>
    for FrontierUtility<'_, '_, '_, N, C, F, P>
{
    fn decide<R: rand_core::Rng>(
        &mut self,
        req: &DecisionRequest<'_, N>,
        _rng: &mut R,
    ) -> Result<Outcome, DecideError> {
        // The frontier rules plan to the cells they chose: no snapping, no set-back...
        let plan_only = ExploreConfig {
            objective: super::ObjectiveKind::Thesis,
            ..self.config
        };
        self.objective.prepare(req, &plan_only)?;
        // ... but end where the robot can turn for the next plan's first turn.
        self.objective.end_where_turnable(true);
        // Entries lapse once the map around them changed.
        self.blacklist.forget_changed(req.grid);
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
                    && !self.blacklist.contains(req.grid.geometry().cell_center(c))
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
