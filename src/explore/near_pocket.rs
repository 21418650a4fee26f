//! Small unknown pockets cleared before the robot moves away from them (efficient objective).
//!
//! The efficient objective scores one decision at a time (`gain · exp(-lambda · steps)`): next
//! to a large unknown area, a pocket of a few dozen cells that an obstacle hid (the strip behind
//! a pillar, a corner a wall's end shadowed) scores far lower and is left behind. It is still
//! reachable Unknown space, so the mission comes back for it at the end, from wherever the
//! robot then is: on the lab (two 4 m rooms) that return is a 7 m trip for 20–25 cells, a
//! quarter more steps on the whole mission, taken or not depending on whether the laser's noise
//! hid the pocket ("one trip more or not", docs/user-guide.md, issue 26).
//!
//! The rule: after the optimizer has chosen its plan, a **small pocket** whose frontier
//! viewpoint is **nearer the robot (path distance) than the plan's first target** is visited
//! first. Going there now costs the detour `d(r, p) + d(p, t) - d(r, t)`; coming back for it
//! after reaching the target costs at least `d(t, p)`; by the triangle inequality the detour is
//! the smaller exactly when `d(r, p) < d(r, t)`, so the rule needs no tuned weight. This is the
//! distance utility of Kulich, Faigl & Přeučil ("On distance utility in the exploration task",
//! ICRA 2011: a goal's cost is the length of the tour through it and the other goals, not the
//! distance to it alone) restricted to the one kind of goal a greedy choice strands, and the
//! remedy Holz, Basilico, Amigoni & Behnke ("Evaluating the efficiency of frontier-based
//! exploration strategies", ISR/ROBOTIK 2010) give for the revisits they measured: finish the
//! local frontiers before leaving.
//!
//! The plan to the pocket (driven up to the viewpoint: the objective's set-back would stop it
//! before the pocket is in view) replaces the optimizer's only if it is predicted to see at
//! least [`worth_cells`] Unknown cells, the robot's own footprint (a disc of its radius): an
//! unknown patch smaller than the robot hides no passage and no room; it is left to the end of
//! the mission as before.
//!
//! **Off by default** ([`super::ExploreConfig::near_pockets_first`]): in the runner with the
//! board's pump it did not remove the lab's two modes (seed 1 better, seed 3 worse over 12
//! noise draws), and on it the mission's escape test fails on one corner start (8 escapes
//! against 6); figures and the variants tried in `docs/experiments.md` ("Issue 26: the lab's
//! one trip more or not").
//!
//! A **pocket** is a group of listed frontier viewpoints ([`ReachableViewpoints`]) whose blocks
//! touch (8-neighbours at the decision's block side) and whose frontier cells add up to at most
//! [`POCKET_GROUP_FRONTIER_CELLS`]; the viewpoint of the group nearest the robot is where it is
//! cleared from. The plan's target lying in the group, a pocket with a viewpoint at a blacklisted place, and
//! a viewpoint on the robot's own cell (its scans there did not clear the pocket, so going
//! there again would not either) leave the plan as the optimizer chose it. A viewpoint next
//! to the robot's cell is kept: the plan is then a turn in place, which at the start of a
//! mission looks into the laser's blind sector behind the robot.

use crate::grid::Cell;
use crate::planner::DistanceField;

use super::Blacklist;
use super::reachable::{MAX_VIEWPOINTS, POCKET_FRONTIER_CELLS, ReachableViewpoints};

/// Most frontier cells of a pocket (summed over its group of viewpoint blocks): three times
/// the one-block pocket of [`super::reachable::Viewpoint::pocket`], a strip of about 1 m along
/// both sides of a shadow at 0.1 m cells.
pub const POCKET_GROUP_FRONTIER_CELLS: u32 = 3 * POCKET_FRONTIER_CELLS as u32;

/// Fewest Unknown cells a plan to a pocket must be predicted to see to replace the optimizer's
/// plan: the robot's footprint, a disc of the traversability layer's robot radius, in cells of
/// the request's grid.
pub fn worth_cells<const N: usize>(req: &super::DecisionRequest<'_, N>) -> f32 {
    let r = req.trav.config().robot_radius_m;
    let cell = req.grid.geometry().resolution_m;
    core::f32::consts::PI * r * r / (cell * cell)
}

/// The viewpoint from which to clear the nearest small pocket that lies nearer the robot than
/// `target` (the plan's first target, a cell `field` reaches) and farther than `min_distance_m`
/// (nearer, the robot already stands there), or `None` (see the
/// [module documentation](self)). `blacklist` is checked at the cell's centre through
/// `centre`.
pub fn pocket_before<const N: usize>(
    viewpoints: &ReachableViewpoints,
    field: &DistanceField<N>,
    target: Cell,
    min_distance_m: f32,
    blacklist: &Blacklist,
    centre: impl Fn(Cell) -> crate::geometry::Point2,
) -> Option<Cell> {
    let list = viewpoints.as_slice();
    let n = list.len().min(MAX_VIEWPOINTS);
    let target_m = field.distance_to(target)?;
    let block = viewpoints.block_cells().max(1);
    let block_of = |c: Cell| (c.col.div_euclid(block), c.row.div_euclid(block));
    // Groups of touching blocks: union-find over the list's indices.
    let mut parent = [0u16; MAX_VIEWPOINTS];
    for (i, p) in parent[..n].iter_mut().enumerate() {
        *p = i as u16;
    }
    fn root(parent: &mut [u16], mut i: usize) -> usize {
        while parent[i] as usize != i {
            parent[i] = parent[parent[i] as usize];
            i = parent[i] as usize;
        }
        i
    }
    let list = &list[..n];
    for (i, vi) in list.iter().enumerate() {
        let a = block_of(vi.cell);
        for (j, vj) in list.iter().enumerate().skip(i + 1) {
            let b = block_of(vj.cell);
            if (a.0 - b.0).abs() <= 1 && (a.1 - b.1).abs() <= 1 {
                let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                if ri != rj {
                    parent[rj] = ri as u16;
                }
            }
        }
    }
    // Frontier cells per group (summed at its root); a group with a blacklisted viewpoint
    // counts as large (the robot failed to get there).
    let mut cells = [0u32; MAX_VIEWPOINTS];
    for (i, v) in list.iter().enumerate() {
        let r = root(&mut parent, i);
        cells[r] += u32::from(v.frontier_cells);
        if blacklist.contains(centre(v.cell)) {
            cells[r] = u32::MAX / 2;
        }
    }
    let target_block = block_of(target);
    let mut target_group = None;
    for (i, v) in list.iter().enumerate() {
        if block_of(v.cell) == target_block {
            target_group = Some(root(&mut parent, i));
        }
    }
    let mut best: Option<(f32, Cell)> = None;
    for (i, &v) in list.iter().enumerate() {
        let r = root(&mut parent, i);
        if cells[r] > POCKET_GROUP_FRONTIER_CELLS
            || Some(r) == target_group
            || v.distance_m >= target_m
            || v.distance_m <= min_distance_m
        {
            continue;
        }
        if best.is_none_or(|(d, _)| v.distance_m < d) {
            best = Some((v.distance_m, v.cell));
        }
    }
    best.map(|(_, c)| c)
}
