//! The map made consistent afterwards: keyframes ([`super::keyframes`]) become the nodes of a
//! pose graph ([`super::pose_graph`]) linked by the tracker's corrected motion between them;
//! when the robot comes back to a place, a loop closure ([`super::loop_closure`]) adds an edge
//! to the old keyframe, the graph is optimised, and when that moved the keyframes the
//! matcher's reference (the returns layer) and the occupancy grid are drawn again from the
//! keyframes at their corrected poses, and the robot's estimate moves with its last keyframe.
//!
//! This is the graph-based SLAM back end of Lu & Milios (*Globally consistent range scan
//! alignment for environment mapping*, Autonomous Robots 4, 1997) as Karto and slam_toolbox
//! run it behind a scan matcher (Konolige et al., IROS 2010; Macenski & Jambrecic, JOSS 2021).
//! One robot per map. Off by default ([`GraphConfig::enabled`]). No allocation: the stores
//! have fixed capacities; a full store stops the graph (counted), it never panics.

use crate::geometry::{Point2, Pose2};
use crate::grid::{CellClass, LogOddsBounds, OccupancyGrid};
use crate::sensor::{IntegrationError, LaserConfig, Scan, SensorModel, integrate_scan_banded};

use super::keyframes::{KeyframeStore, is_keyframe};
use super::loop_closure::{ClosureConfig, LOCAL_CELLS, LocalMap, Refusal, candidate};
use super::path_uncertainty::PathUncertainty;
use super::pose_graph::{Edge, PoseGraph};
use super::{HitMap, MatchConfig, ScanMatcher, WINDOW_CELLS};

/// Keyframes a mission's graph holds: one each 0.2 m or 0.2 rad, about 40 minutes of a house
/// mission (4.5 MB of scans; with the graph and the closure map about 7 MB, boxed with the map,
/// zeroed and left untouched while the graph is off).
pub const GRAPH_KEYFRAMES: usize = 4096;
/// Edges: one per keyframe and as many closures.
pub const GRAPH_EDGES: usize = 2 * GRAPH_KEYFRAMES;

/// Settings of the pose graph.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GraphConfig {
    /// Keep keyframes, close loops and redraw the map (off: the tracker alone).
    pub enabled: bool,
    /// A keyframe once the corrected pose has moved this far \[m\] ...
    pub keyframe_travel_m: f32,
    /// ... or turned this much \[rad\] since the last.
    pub keyframe_turn_rad: f32,
    /// Variance of the tracker's motion between keyframes per metre \[m²/m\] ...
    pub step_var_m2_per_m: f32,
    /// ... of its heading per radian turned \[rad²/rad\] ...
    pub step_var_rad2_per_rad: f32,
    /// ... and per metre driven \[rad²/m\].
    pub step_var_rad2_per_m: f32,
    /// Standard deviation of any step at least \[m\] ...
    pub step_floor_m: f32,
    /// ... and \[rad\].
    pub step_floor_rad: f32,
    /// Loop closures.
    pub closure: ClosureConfig,
    /// Path between two closure attempts after an accepted closure \[m\].
    pub closure_every_m: f32,
    /// Redraw the map when an optimisation moved a keyframe more than this \[m\] ...
    pub redraw_move_m: f32,
    /// ... or turned one more than this \[rad\].
    pub redraw_turn_rad: f32,
    /// Only keyframes are written into the matcher's reference (the returns layer), at their
    /// corrected pose, as the redraw does; the scans between go to the grid only (Karto and
    /// slam_toolbox match against their keyframes' scans only). Off: measured worse.
    pub reference_keyframes_only: bool,
    /// A redraw keeps what no keyframe sees again: a cell that was Free or Occupied before
    /// and is Unknown after the keyframes are drawn (the scans between keyframes alone saw
    /// it) gets one observation's evidence of its old class ([`SensorModel`]'s
    /// `free_log_odds` or `occupied_log_odds`), so the next scan there decides. Off, a redraw
    /// forgets it: 300 to 630 known cells of a house mission (1 % of the house, the margin
    /// of a 99 % coverage), which come back as frontiers in explored ground and send the
    /// robot back (docs/experiments.md, "Issue 26: what a redraw forgets").
    pub redraw_keeps_unseen: bool,
    /// Gauss-Newton iterations per optimisation.
    pub iterations: u32,
    /// Conjugate-gradient steps per iteration at most.
    pub cg_steps: u32,
}

impl Default for GraphConfig {
    /// Off; keyframes each 0.2 m or 0.2 rad; steps of (1 cm)² per metre, (0.6°)² per radian
    /// and (0.3°)² per metre, at least 5 mm and 0.1°; the default closures, attempted again
    /// 2 m of path after one is made; a redraw after a move of 1 cm or 0.1°; 10 iterations of
    /// at most 3000 steps; every scan into the reference (from keyframes only, two of 8 house
    /// seeds diverged with main's matcher: docs/experiments.md, "pose graph").
    fn default() -> Self {
        Self {
            enabled: false,
            keyframe_travel_m: 0.2,
            keyframe_turn_rad: 0.2,
            step_var_m2_per_m: 1e-4,
            step_var_rad2_per_rad: 1e-4,
            step_var_rad2_per_m: 2.5e-5,
            step_floor_m: 0.005,
            step_floor_rad: 0.002,
            closure: ClosureConfig::default(),
            closure_every_m: 2.0,
            redraw_move_m: 0.01,
            redraw_turn_rad: 0.002,
            reference_keyframes_only: false,
            redraw_keeps_unseen: true,
            iterations: 10,
            cg_steps: 3000,
        }
    }
}

impl GraphConfig {
    /// Variances of a step `z` between two keyframes along its `x`, `y` and heading
    /// \[m², m², rad²\]: growing with the distance driven and the angle turned, at least the
    /// floors.
    pub fn step_variances(&self, z: Pose2) -> [f32; 3] {
        let d = crate::math::hypot(z.x, z.y);
        let turn = crate::math::abs(z.theta);
        let var_m2 = (self.step_var_m2_per_m * d).max(self.step_floor_m * self.step_floor_m);
        let var_rad2 = (self.step_var_rad2_per_rad * turn + self.step_var_rad2_per_m * d)
            .max(self.step_floor_rad * self.step_floor_rad);
        [var_m2, var_m2, var_rad2]
    }
}

/// A cell's class before a redraw, one byte ([`KeyframeGraph::redraw`]).
const FREE: i8 = -1;
const OCCUPIED: i8 = 1;

fn class_code(class: CellClass) -> i8 {
    match class {
        CellClass::Free => FREE,
        CellClass::Unknown => 0,
        CellClass::Occupied => OCCUPIED,
    }
}

/// Counters of a mission's graph.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Zeroable)]
pub struct GraphStats {
    /// Keyframes kept.
    pub keyframes: u32,
    /// Closures looked for (a candidate was near).
    pub attempts: u32,
    /// Closures accepted (edges added).
    pub closures: u32,
    /// Optimisations that moved the keyframes enough to redraw the map.
    pub redraws: u32,
    /// Conjugate-gradient steps over all optimisations.
    pub cg_steps: u64,
    /// Largest keyframe move of an optimisation \[m\].
    pub max_move_m: f32,
    /// Whether a full store stopped the graph.
    pub full: bool,
    /// Closures refused: by the matcher's own checks, as unconstrained, for a low score, for
    /// little known ground, as inconsistent with the graph, as ambiguous, as seeing through
    /// walls.
    pub refused: [u32; 7],
}

impl GraphStats {
    fn refuse(&mut self, why: Refusal) {
        let k = match why {
            Refusal::Distrusted(_) | Refusal::NoMap => 0,
            Refusal::Unconstrained(_) => 1,
            Refusal::LowScore(_) => 2,
            Refusal::LittleKnown(_) => 3,
            Refusal::Inconsistent(_) => 4,
            Refusal::Ambiguous(_) => 5,
            Refusal::SeesThrough(_) => 6,
        };
        self.refused[k] += 1;
    }
}

/// What an optimisation did to the last keyframe: the robot's estimate moves with it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moved {
    /// The last keyframe's pose before ...
    pub before: Pose2,
    /// ... and after.
    pub after: Pose2,
}

impl Moved {
    /// `pose` (near the last keyframe) moved as the keyframe moved.
    pub fn apply(&self, pose: Pose2) -> Pose2 {
        self.after.compose(pose.in_frame_of(self.before))
    }
}

/// A mission's keyframes, pose graph and closure map.
#[derive(bytemuck::Zeroable)]
pub struct KeyframeGraph<const K: usize, const E: usize> {
    store: KeyframeStore<K>,
    graph: PoseGraph<K, E>,
    local: LocalMap<LOCAL_CELLS>,
    /// Corrected path driven \[m\] and the pose it was last measured at (once `started`).
    path_m: f32,
    last_pose: Pose2,
    started: bool,
    /// Path at which closures may be looked for again \[m\].
    next_closure_m: f32,
    stats: GraphStats,
}

impl<const K: usize, const E: usize> core::fmt::Debug for KeyframeGraph<K, E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("KeyframeGraph")
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl<const K: usize, const E: usize> KeyframeGraph<K, E> {
    /// Counters.
    pub fn stats(&self) -> &GraphStats {
        &self.stats
    }

    /// The pose graph.
    pub fn graph(&self) -> &PoseGraph<K, E> {
        &self.graph
    }

    /// The keyframes.
    pub fn keyframes(&self) -> &KeyframeStore<K> {
        &self.store
    }

    /// A scan integrated at the corrected pose `pose`: kept as a keyframe when the pose moved
    /// enough since the last; then, when an old keyframe is near, a closure is looked for and,
    /// if made, the graph optimised. Returns how the last keyframe moved when the map must be
    /// redrawn ([`Self::redraw`]).
    #[allow(clippy::too_many_arguments)]
    pub fn on_scan(
        &mut self,
        config: &GraphConfig,
        tracker: &MatchConfig,
        scan: &Scan,
        laser: &LaserConfig,
        sensor: &SensorModel,
        bounds: LogOddsBounds,
        resolution_m: f32,
        pose: Pose2,
        matcher: &mut ScanMatcher<WINDOW_CELLS>,
    ) -> Option<Moved> {
        if !config.enabled || self.stats.full {
            return None;
        }
        if self.started {
            self.path_m += self.last_pose.position().distance(pose.position());
        }
        self.last_pose = pose;
        self.started = true;
        let n = self.graph.len();
        let prev = n.checked_sub(1).and_then(|i| self.graph.pose(i));
        if let Some(p) = prev
            && !is_keyframe(p, pose, config.keyframe_travel_m, config.keyframe_turn_rad)
        {
            return None;
        }
        // Keep the scan and the node; link it to the previous keyframe.
        let stored = self.store.push(scan, laser, self.path_m);
        let node = stored.ok().and_then(|_| self.graph.add_node(pose).ok());
        let Some(node) = node else {
            // Full (or a scan of another layout): the graph stops here.
            self.stats.full = true;
            return None;
        };
        if self.store.len() != self.graph.len() {
            self.stats.full = true;
            return None;
        }
        self.stats.keyframes += 1;
        if let Some(p) = prev {
            let z = pose.in_frame_of(p);
            let [var_m2, _, var_rad2] = config.step_variances(z);
            let edge = Edge {
                from: (node - 1) as u16,
                to: node as u16,
                measured: z,
                information: [1.0 / var_m2, 1.0 / var_m2, 1.0 / var_rad2],
            };
            if self.graph.add_edge(edge).is_err() {
                self.stats.full = true;
                return None;
            }
        }

        // A closure?
        if self.path_m < self.next_closure_m {
            return None;
        }
        let c = &config.closure;
        let graph = &self.graph;
        let old = candidate(&self.store, |i| graph.pose(i), pose, self.path_m, c)?;
        self.stats.attempts += 1;
        // The old keyframe and its neighbours along the path, none of them recent.
        let lo = old.saturating_sub(c.neighbours);
        let mut hi = (old + c.neighbours + 1).min(node);
        while hi > old + 1
            && self
                .store
                .get(hi - 1)
                .is_some_and(|k| k.path_m > self.path_m - c.min_path_m)
        {
            hi -= 1;
        }
        if let Err(why) = self.local.render(
            &self.store,
            |i| graph.pose(i),
            lo..hi,
            pose.position(),
            resolution_m,
            laser,
            sensor,
            bounds,
        ) {
            self.stats.refuse(why);
            return None;
        }
        let (verdict, _quality) = self.local.close(matcher, scan, laser, pose, tracker, c);
        let matched = match verdict {
            Ok(p) => p,
            Err(why) => {
                self.stats.refuse(why);
                return None;
            }
        };
        let old_pose = self.graph.pose(old)?;
        if c.gate_sigmas > 0.0 {
            // How far the graph may have drifted over the path between the two keyframes:
            // the steps' covariance compounded along it, each heading error swinging all
            // that follows it. The match is tested against the graph's prediction of the same
            // relative pose under that covariance and the closure's own.
            let mut path = PathUncertainty::new();
            let mut from = old_pose;
            for i in old + 1..=node {
                let Some(to) = self.graph.pose(i) else { break };
                let z = to.in_frame_of(from);
                path.push(z, config.step_variances(z));
                from = to;
            }
            let closure = [
                c.sigma_m * c.sigma_m,
                c.sigma_m * c.sigma_m,
                c.sigma_rad * c.sigma_rad,
            ];
            let d2 = path.mahalanobis2(
                matched.in_frame_of(old_pose),
                pose.in_frame_of(old_pose),
                closure,
            );
            if d2 > c.gate_sigmas * c.gate_sigmas {
                self.stats.refuse(Refusal::Inconsistent(d2));
                return None;
            }
        }
        let edge = Edge {
            from: old as u16,
            to: node as u16,
            measured: matched.in_frame_of(old_pose),
            information: [
                1.0 / (c.sigma_m * c.sigma_m),
                1.0 / (c.sigma_m * c.sigma_m),
                1.0 / (c.sigma_rad * c.sigma_rad),
            ],
        };
        if self.graph.add_edge(edge).is_err() {
            self.stats.full = true;
            return None;
        }
        self.stats.closures += 1;
        self.next_closure_m = self.path_m + config.closure_every_m;
        let before = self.graph.pose(node)?;
        let mut done = self.graph.optimise(config.iterations, config.cg_steps);
        self.stats.cg_steps += u64::from(done.cg_steps);
        // After the optimisation the closure must agree with the graph: a closure that the
        // rest of the graph holds far from its measurement (a residual beyond
        // `residual_sigmas` on the three axes together) is taken out again, and the graph
        // goes back to where it was (a consistency check of the kind of Olson's, RAS 2009).
        let last = self.graph.edge_count() - 1;
        let limit = f64::from(c.residual_sigmas * c.residual_sigmas) * 3.0;
        if c.residual_sigmas > 0.0 && self.graph.edge_error(last) > limit {
            let chi2 = self.graph.edge_error(last) as f32;
            self.graph.pop_edge();
            self.stats.closures -= 1;
            self.stats.refuse(Refusal::Inconsistent(chi2));
            done = self.graph.optimise(config.iterations, config.cg_steps);
            self.stats.cg_steps += u64::from(done.cg_steps);
            // Back at the optimum without it: what moved is measured from `before`.
            let after = self.graph.pose(node)?;
            done.max_move_m = after.position().distance(before.position());
            done.max_turn_rad =
                crate::math::abs(crate::geometry::normalize_angle(after.theta - before.theta));
        }
        self.stats.max_move_m = self.stats.max_move_m.max(done.max_move_m);
        if done.max_move_m <= config.redraw_move_m && done.max_turn_rad <= config.redraw_turn_rad {
            return None;
        }
        self.stats.redraws += 1;
        Some(Moved {
            before,
            after: self.graph.pose(node)?,
        })
    }

    /// Draws `grid` and `hits` again from the keyframes at their graph poses (everything else
    /// they held is forgotten), the grid with the wall band `band_m`
    /// ([`crate::sensor::integrate_scan_banded`]). With `keep_unseen` (one byte a cell, at
    /// least the grid's cells; [`GraphConfig::redraw_keeps_unseen`]), a cell known before
    /// and Unknown after keeps its old class at one observation's evidence; `None`, or a
    /// shorter slice, keeps nothing. No observer is told of the cells' changes: the caller
    /// rebuilds the traversability layer afterwards.
    pub fn redraw<const N: usize>(
        &mut self,
        grid: &mut OccupancyGrid<N>,
        hits: &mut HitMap<N>,
        band_m: f32,
        laser: &LaserConfig,
        sensor: &SensorModel,
        keep_unseen: Option<&mut [i8]>,
    ) -> Result<(), IntegrationError> {
        let geometry = *grid.geometry();
        let cells = grid.cell_count();
        let mut before = keep_unseen.and_then(|k| k.get_mut(..cells));
        let bounds = grid.bounds();
        if let Some(before) = before.as_deref_mut() {
            for (b, &l) in before.iter_mut().zip(grid.log_odds()) {
                *b = class_code(bounds.class_of(l));
            }
        }
        // The grid keeps its geometry, which fits.
        let _ = grid.reset(geometry);
        hits.clear();
        let mut scan = Scan::new();
        for i in 0..self.store.len() {
            let (Some(k), Some(pose)) = (self.store.get(i), self.graph.pose(i)) else {
                break;
            };
            k.scan_into(laser, &mut scan);
            integrate_scan_banded(grid, &scan, pose, band_m, laser, sensor, &mut ())?;
            hits.add_scan(&scan, laser, pose);
        }
        if let Some(before) = before {
            for (i, &b) in before.iter().enumerate() {
                let evidence = match b {
                    FREE => sensor.free_log_odds,
                    OCCUPIED => sensor.occupied_log_odds,
                    _ => continue,
                };
                if grid.class(i) == CellClass::Unknown {
                    grid.set_log_odds(i, evidence, &mut ());
                }
            }
        }
        Ok(())
    }

    /// The position of keyframe `i` (for pictures).
    pub fn keyframe_position(&self, i: usize) -> Option<Point2> {
        self.graph.pose(i).map(|p| p.position())
    }
}
