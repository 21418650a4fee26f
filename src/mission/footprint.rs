//! The planning layer a robot's body asks for: which cells it may enter, where it may turn,
//! and where it should rather not drive.
//!
//! A differential-drive robot that turns only in place needs two things of the map (the
//! inscribed and circumscribed radii of a costmap's inflation layer, Lu, Hershberger & Smart,
//! "Layered costmaps for context-sensitive navigation", IROS 2014):
//! - **fit**: driving straight, its body fits where the walls are farther than half its width
//!   plus the clearance from the path. Cells closer than that to an Occupied cell are blocked.
//!   The map only knows walls to the cell, so the distance is counted between cell centres and
//!   half a cell is added: a wall's face lies at most half a cell from the centre of the cell
//!   its return fell in. At 0.1 m cells a P3-DX (0.381 m) with 5 cm of clearance is blocked
//!   within 0.29 m of a wall's cell: a 0.5 m opening aligned with the cells leaves its middle
//!   column free (0.3 m from both sides), a 0.4 m opening never does.
//! - **turn**: turning in place sweeps the swing circle, so within its radius plus the safety
//!   monitor's turning margin (and half a cell) of a wall the robot may pass but not turn
//!   ([`crate::planner::WallBands::no_turn_radius_m`]); waypoints avoid those cells.
//!
//! A band beyond it costs a little more, so that paths keep to the middle where there is room.

use crate::control::safety::SafetyConfig;
use crate::planner::{TraversabilityConfig, UnknownPolicy, WallBands};

/// Default clearance between the body's side and a wall on a planned path \[m\].
pub const DEFAULT_CLEARANCE_M: f32 = 0.05;
/// Largest clearance a board or the simulator accepts \[m\]: more would shut every ordinary
/// door to a P3-DX.
pub const MAX_CLEARANCE_M: f32 = 0.3;

/// Whether `clearance_m` is one a board or the simulator accepts (0 to [`MAX_CLEARANCE_M`]).
pub fn is_valid_clearance(clearance_m: f32) -> bool {
    clearance_m.is_finite() && (0.0..=MAX_CLEARANCE_M).contains(&clearance_m)
}

/// Width of the near-wall band beyond the no-turn band \[m\].
pub const NEAR_BAND_WIDTH_M: f32 = 0.15;
/// Cost factor of a no-turn cell: crossing a door costs a little, so paths do not run along
/// walls, but never so much that a detour of metres beats a door.
pub const NO_TURN_COST_FACTOR: f32 = 2.0;
/// Cost factor of a near-wall cell.
pub const NEAR_COST_FACTOR: f32 = 1.3;

/// The planning layer for the body described by `safety` (its footprint and turning margin),
/// `clearance_m` on each side, cells of `resolution_m`, and Unknown cells as `unknown_policy`
/// says.
pub fn planning_layer(
    safety: &SafetyConfig,
    clearance_m: f32,
    resolution_m: f32,
    unknown_policy: UnknownPolicy,
) -> TraversabilityConfig {
    let fp = safety.footprint;
    let half_cell = 0.5 * resolution_m;
    let no_turn = fp.radius_m + safety.turn_margin_m + half_cell;
    TraversabilityConfig {
        robot_radius_m: 0.5 * fp.width_m + clearance_m + half_cell,
        unknown_policy,
        bands: WallBands {
            no_turn_radius_m: no_turn,
            no_turn_cost_factor: NO_TURN_COST_FACTOR,
            near_radius_m: no_turn + NEAR_BAND_WIDTH_M,
            near_cost_factor: NEAR_COST_FACTOR,
        },
    }
}

/// The narrowest opening in a wall, aligned with the cells of `resolution_m`, that the layer
/// `planning_layer` made lets the robot through \[m\]: an opening of `n` free cells between
/// two Occupied ones leaves its middle cell `⌊(n + 1) / 2⌋` cells from the nearer jamb's
/// centre, which must not be closer than the blocking radius. An opening off the cells' lines
/// may need one cell more. `None` for a bad cell size.
pub fn narrowest_opening_m(layer: &TraversabilityConfig, resolution_m: f32) -> Option<f32> {
    if !(resolution_m.is_finite() && resolution_m > 0.0) {
        return None;
    }
    let r2 = (layer.robot_radius_m / resolution_m) * (layer.robot_radius_m / resolution_m);
    // The least half-width k (in cells) with k² not below the radius², as the layer's own
    // stencil test (`d² < r²` blocks) counts it.
    let mut k = 1u32;
    while ((k * k) as f32) < r2 {
        k += 1;
    }
    Some((2 * k - 1) as f32 * resolution_m)
}

/// Most map obstacles passed to the safety monitor in one period.
pub const MAX_REMEMBERED: usize = 128;

/// Speed while any part of the body is in the no-turn band (a door, a narrow aisle)
/// \[mm/s\]: slow enough that the safety monitor's corridor is only a little wider than the
/// body (its side margin grows with speed) and that path tracking stays within centimetres.
pub const NARROW_SPEED_MM_S: i16 = 150;

/// Speed a robot creeps at past what its safety monitor would stop it for at full speed
/// \[mm/s\]: the monitor's corridor is then 0.2205 m each side of a P3-DX's middle (3 cm
/// inside the frames of a 0.5 m door) and its stopping distance 0.12 m beyond the front.
pub const CREEP_SPEED_MM_S: i16 = 100;

/// `proposed`, slowed to [`CREEP_SPEED_MM_S`] when driving forward faster would make
/// `monitor` stop the robot for a return of `scan` and the creep speed would not: the
/// slow-down field in front of a safety scanner's protective field. The monitor still checks
/// the slowed command, and still stops the robot for what lies in the creep speed's corridor.
pub fn creep_near_obstacles(
    monitor: &crate::control::safety::SafetyMonitor,
    proposed: crate::control::command::MotionCommand,
    scan: &crate::sensor::Scan,
    laser: &crate::sensor::LaserConfig,
) -> crate::control::command::MotionCommand {
    if proposed.speed_mm_s <= CREEP_SPEED_MM_S {
        return proposed;
    }
    let limits = *monitor.limits();
    if monitor
        .obstacle_in_path(limits.clamp(proposed), scan, laser)
        .is_none()
    {
        return proposed;
    }
    let slow = crate::control::command::MotionCommand {
        speed_mm_s: CREEP_SPEED_MM_S,
        ..proposed
    };
    if monitor
        .obstacle_in_path(limits.clamp(slow), scan, laser)
        .is_none()
    {
        slow
    } else {
        proposed
    }
}

/// How far ahead of the robot a narrow place already slows it \[m\].
pub const NARROW_LOOKAHEAD_M: f32 = 0.4;

/// The Occupied cells of `grid` within `radius_m` of the robot at `pose`, as the point of
/// each cell nearest the robot, in the robot's frame, into `out` (ring by ring outward from
/// the robot's cell, so the nearest fill it first; the rest are dropped). What the laser cannot see (behind a 180° laser, inside its blind
/// zone) the map still knows: the safety monitor checks turns and back-offs against it.
pub fn remembered_obstacles<const N: usize>(
    grid: &crate::grid::OccupancyGrid<N>,
    pose: crate::geometry::Pose2,
    radius_m: f32,
    out: &mut heapless::Vec<crate::geometry::Point2, MAX_REMEMBERED>,
) {
    use crate::geometry::Point2;
    use crate::grid::{Cell, CellClass};
    out.clear();
    let g = *grid.geometry();
    let res = g.resolution_m;
    let reach = crate::math::ceil(radius_m / res) as i32 + 1;
    let Some(centre) = g.cell_at(pose.position()) else {
        return;
    };
    let (sin, cos) = (crate::math::sin(pose.theta), crate::math::cos(pose.theta));
    // Square rings of cells around the robot's cell, the nearest first.
    let ring = |k: i32| {
        (-k..=k).flat_map(move |dr| {
            let step = if dr.abs() == k {
                1
            } else {
                (2 * k).max(1) as usize
            };
            (-k..=k).step_by(step).map(move |dc| (dr, dc))
        })
    };
    for (dr, dc) in (0..=reach).flat_map(ring) {
        {
            let cell = Cell::new(centre.col + dc, centre.row + dr);
            let Some(i) = g.index(cell) else { continue };
            if grid.class(i) != CellClass::Occupied {
                continue;
            }
            // The nearest point of the cell's square to the robot.
            let c = g.cell_center(cell);
            let half = 0.5 * res;
            let near = Point2::new(
                pose.x.clamp(c.x - half, c.x + half),
                pose.y.clamp(c.y - half, c.y + half),
            );
            let (dx, dy) = (near.x - pose.x, near.y - pose.y);
            if dx * dx + dy * dy > radius_m * radius_m {
                continue;
            }
            let base = Point2::new(cos * dx + sin * dy, -sin * dx + cos * dy);
            if out.push(base).is_err() {
                return;
            }
        }
    }
}

/// The speed cap where the body is, or is about to be, in the no-turn band of `trav`
/// (within [`NARROW_LOOKAHEAD_M`] ahead along the heading): [`NARROW_SPEED_MM_S`]; `None`
/// elsewhere.
pub fn narrow_speed_cap<const N: usize>(
    trav: &crate::planner::Traversability<N>,
    pose: crate::geometry::Pose2,
) -> Option<i16> {
    use crate::geometry::Point2;
    let g = trav.geometry();
    let steps = 4;
    for k in 0..=steps {
        let d = NARROW_LOOKAHEAD_M * k as f32 / steps as f32;
        let p = Point2::new(
            pose.x + d * crate::math::cos(pose.theta),
            pose.y + d * crate::math::sin(pose.theta),
        );
        let Some(cell) = g.cell_at(p) else { continue };
        if trav.wall_band(cell) == Some(crate::planner::traversability::BAND_NO_TURN) {
            return Some(NARROW_SPEED_MM_S);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_p3dx_plans_with_its_half_width_clearance_and_swing_circle() {
        let t = planning_layer(
            &SafetyConfig::default(),
            DEFAULT_CLEARANCE_M,
            0.1,
            UnknownPolicy::Blocked,
        );
        assert!((t.robot_radius_m - 0.2905).abs() < 1e-4);
        // Between the 0.2 m and 0.3 m cell-centre distances of a 0.4 m and a 0.5 m door.
        assert!(t.robot_radius_m > 0.2 && t.robot_radius_m < 0.3);
        assert!((t.bands.no_turn_radius_m - 0.347).abs() < 1e-4);
        assert!(t.bands.near_radius_m > t.bands.no_turn_radius_m);
    }

    /// Whether the middle column of a `door_cells`-cell opening (aligned with the cells) in a
    /// wall is passable for the layer `planning_layer` makes of `body` and `clearance_m`.
    fn passes_door(body: crate::control::safety::RobotFootprint, clearance_m: f32) -> bool {
        use crate::geometry::Point2;
        use crate::grid::{CellClass, GridGeometry, LogOddsBounds, OccupancyGrid};
        use crate::planner::Traversability;
        const CAP: usize = 32 * 24;
        let g = GridGeometry::new(32, 24, 0.1, Point2::new(0.0, 0.0)).unwrap();
        let mut grid = OccupancyGrid::<CAP>::new(g, LogOddsBounds::default()).unwrap();
        let safety = SafetyConfig {
            footprint: body,
            ..SafetyConfig::default()
        };
        let layer = planning_layer(&safety, clearance_m, 0.1, UnknownPolicy::Blocked);
        let mut trav = Traversability::<CAP>::new(g, layer).unwrap();
        for i in 0..g.cell_count() {
            let c = g.cell(i);
            let wall = c.row == 12 && !(14..19).contains(&c.col);
            let class = if wall {
                CellClass::Occupied
            } else {
                CellClass::Free
            };
            grid.set_class(i, class, &mut trav);
        }
        trav.is_passable(crate::grid::Cell::new(16, 12))
    }

    #[test]
    fn the_narrowest_opening_follows_the_body_the_clearance_and_the_cells() {
        use crate::control::safety::RobotFootprint;
        let opening = |body: RobotFootprint, clearance_m: f32, res: f32| {
            let safety = SafetyConfig {
                footprint: body,
                ..SafetyConfig::default()
            };
            let layer = planning_layer(&safety, clearance_m, res, UnknownPolicy::Blocked);
            narrowest_opening_m(&layer, res).unwrap()
        };
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
        let p3dx = RobotFootprint::p3dx();
        assert!(close(opening(p3dx, DEFAULT_CLEARANCE_M, 0.1), 0.5));
        // Finer cells cost the half-metre door: half a 5 cm cell of doubt is too much of
        // the 0.95 cm left each side.
        assert!(close(opening(p3dx, DEFAULT_CLEARANCE_M, 0.05), 0.55));
        assert!(close(opening(p3dx, 0.1, 0.1), 0.7));
        let bumpers = RobotFootprint::p3dx_with_bumpers();
        assert!(close(opening(bumpers, DEFAULT_CLEARANCE_M, 0.1), 0.7));
        // The figure agrees with the layer itself (the door test below).
        assert!(
            passes_door(p3dx, DEFAULT_CLEARANCE_M) && !passes_door(bumpers, DEFAULT_CLEARANCE_M)
        );
        assert_eq!(
            narrowest_opening_m(&TraversabilityConfig::default(), 0.0),
            None
        );
    }

    #[test]
    fn the_body_and_the_clearance_decide_a_half_metre_door() {
        use crate::control::safety::RobotFootprint;
        assert!(passes_door(RobotFootprint::p3dx(), DEFAULT_CLEARANCE_M));
        // No clearance at all still passes; 10 cm a side does not (0.381 + 0.2 > 0.5).
        assert!(passes_door(RobotFootprint::p3dx(), 0.0));
        assert!(!passes_door(RobotFootprint::p3dx(), 0.1));
        // With its bumper rings (0.425 m) a P3-DX no longer fits with 5 cm a side.
        assert!(!passes_door(
            RobotFootprint::p3dx_with_bumpers(),
            DEFAULT_CLEARANCE_M
        ));
        assert!(passes_door(RobotFootprint::p3dx_with_bumpers(), 0.0));
    }
}
