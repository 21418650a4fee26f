//! Nearest-frontier exploration (Yamauchi, "A Frontier-Based Approach for Autonomous
//! Exploration", IEEE CIRA 1997): go to the frontier cell with the shortest **path** distance
//! from the robot, read from the decision's distance field.
//!
//! A frontier cell the robot cannot stand on (Unknown cells in strict mode) is approached
//! through its reachable Free 4-neighbour; one near a place the robot failed to reach
//! ([`NearestFrontier::blacklist`]) is skipped. The plan, predicted gain and energy come from the
//! same [`ExploreObjective`] as the optimized selector, so decisions compare like for like.

use crate::frontier::{FrontierConfig, FrontierWorkspace, find_frontiers};
use crate::grid::Cell;
use crate::planner::{AStar, Planner};

use super::objective::ExploreObjective;
use super::{
    Blacklist, DecideError, DecisionRequest, ExploreConfig, Outcome, TargetSelector,
    reach_frontier_cell,
};

/// Yamauchi's nearest-frontier rule.
pub struct NearestFrontier<
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
    /// Places the robot failed to reach: frontier cells near them are skipped (empty by
    /// default).
    pub blacklist: Blacklist,
    objective: &'o mut ExploreObjective<'m, N, P>,
    workspace: &'w mut FrontierWorkspace<C, F>,
}

impl<const N: usize, const C: usize, const F: usize, P: Planner<N>> core::fmt::Debug
    for NearestFrontier<'_, '_, '_, N, C, F, P>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("NearestFrontier")
            .field("config", &self.config)
            .field("frontier", &self.frontier)
            .finish_non_exhaustive()
    }
}

impl<'o, 'm, 'w, const N: usize, const C: usize, const F: usize, P: Planner<N>>
    NearestFrontier<'o, 'm, 'w, N, C, F, P>
{
    /// A selector using `objective` for planning and `workspace` for the frontier search.
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
            blacklist: Blacklist::default(),
            objective,
            workspace,
        }
    }
}

impl<const N: usize, const C: usize, const F: usize, P: Planner<N>> TargetSelector<N>
    for NearestFrontier<'_, '_, '_, N, C, F, P>
{
    fn decide<R: rand_core::Rng>(
        &mut self,
        req: &DecisionRequest<'_, N>,
        _rng: &mut R,
    ) -> Result<Outcome, DecideError> {
        // Entries lapse once the map around them changed.
        self.blacklist.forget_changed(req.grid);
        // The frontier rules plan to the cells they chose: no snapping, no set-back...
        let plan_only = ExploreConfig {
            objective: super::ObjectiveKind::Thesis,
            ..self.config
        };
        self.objective.prepare(req, &plan_only)?;
        // ... but end where the robot can turn for the next plan's first turn.
        self.objective.end_where_turnable(true);
        find_frontiers(
            req.grid,
            req.pose.position(),
            &self.frontier,
            self.workspace,
        )
        .map_err(DecideError::Frontier)?;
        let ws = &*self.workspace;
        let geom = req.grid.geometry();
        let mut best: Option<(Cell, f32)> = None;
        let mut reachable = false;
        let mut evaluations = 0u32;
        for fr in ws.frontiers() {
            for &i in ws.cells_of(fr) {
                evaluations += 1;
                if let Some((c, d)) =
                    reach_frontier_cell(req.grid, self.objective.field(), i as usize)
                {
                    reachable = true;
                    if best.is_none_or(|(_, b)| d < b)
                        && !self.blacklist.contains(geom.cell_center(c))
                    {
                        best = Some((c, d));
                    }
                }
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
