//! Mouths of passages shut on the map: where to look again when no frontier is reachable.
//!
//! A passage can be free in truth, and seen through, yet shut in the planning layer: a door's
//! jamb mapped a cell too wide by range noise, a wall mapped thick and offset by odometry
//! drift, one return's evidence at the log-odds bound in a door's edge cell. The room behind
//! is then partly known (its Free cells were seen through the passage) and its frontier is
//! *cut*: passable cells next to it that the robot's distance field does not reach. Nothing
//! the robot could choose reaches it, and a frontier rule would end the mission "nothing
//! reachable" with unknown space it can drive to (issue 17, the *cut* clusters of
//! `coverage_gaps`).
//!
//! What opens such a passage is a look from close by: the laser's range noise grows with the
//! range (5 % of it by default), so returns from a door 0.5 m away land within a few
//! centimetres of the jambs, and the beams through the door clear the cells that far-away
//! returns marked in it (Thrun, Burgard & Fox, *Probabilistic Robotics*, 2005, §9.2: every
//! cell a beam passes before its return gets Free evidence). [`MouthSearch::find`] finds
//! where to look from: a breadth-first flood (4-connected, so it does not leak through the
//! diagonal steps of a mapped wall) over **Free** cells from the cut frontier's passable cells,
//! which crosses a passage that is open in Free cells however narrow the planning layer makes
//! it, and stops at the first cell the robot's distance field reaches: the mouth of the
//! passage on the robot's side. The target is the nearest cell there where the robot can turn
//! in place (so that it can face the passage and leave again).
//!
//! A look alone does not open a passage the odometry's drift shut: a wall seen from the far
//! side at one drift and from the near side at another is drawn twice, a cell or two apart,
//! and each copy is saturated at the log-odds bound by dozens of returns, more Free evidence
//! than one look through the passage gives. Before the look, [`doubt_walls`] therefore lowers
//! the Occupied cells around the mouth to one return's evidence: they still block (the
//! planning layer and the safety monitor's remembered obstacles see them as before), but the
//! look's own returns and misses decide them again, so the passage is drawn as the robot sees
//! it now, in the frame of its current pose estimate. This is the clearing recovery of ROS's
//! navigation stack (`move_base`'s `clear_costmap_recovery`: Marder-Eppstein, Berger, Foote,
//! Gerkey & Konolige, "The Office Marathon: robust navigation in an indoor office
//! environment", ICRA 2010: when no plan is found, obstacles around the robot are cleared and
//! re-sensed), here weakened rather than erased, and only around a passage open in Free cells.
//!
//! Mouths already looked from are remembered by the caller (at most [`MAX_MOUTHS`]); the flood
//! does not pass within [`MOUTH_MEMORY_M`] of one, so a passage a look did not open is not
//! looked at again and again, and the next search finds the next passage, or none: the robot
//! then really has nothing left it can reach. Frontier cells in the wall band (a wall's
//! unknown interior behind its Free face) are not cut: their Free neighbours are not passable,
//! and a look at a wall opens nothing.

use crate::geometry::Point2;
use crate::grid::{Cell, CellClass, OccupancyGrid};
use crate::planner::{DistanceField, Traversability};

/// Most mouths a mission remembers having looked from.
pub const MAX_MOUTHS: usize = 16;
/// The flood does not pass within this distance of a mouth looked from \[m\]: a 0.5–0.9 m
/// door's whole mouth, and the wall band beside it.
pub const MOUTH_MEMORY_M: f32 = 1.0;
/// The target is the nearest turnable reached cell within this distance of the mouth \[m\].
pub const MOUTH_STAND_M: f32 = 0.6;
/// [`doubt_walls`] lowers the Occupied cells within this distance of the mouth \[m\]: the
/// memory's radius, so that the doubted walls are those of the passage looked at, and no
/// other look doubts them again.
pub const DOUBT_RADIUS_M: f32 = MOUTH_MEMORY_M;

/// A passage shut on the map: where the robot stands to look, and the mouth (the first cell
/// on the robot's side that the flood over Free cells from the cut frontier reached).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShutMouth {
    /// The reached cell nearest the mouth where the robot can turn in place.
    pub stand: Cell,
    /// The mouth.
    pub mouth: Cell,
}

/// The flood's working memory: a queue and a mark per cell (about 5 bytes per cell).
#[derive(bytemuck::Zeroable)]
pub struct MouthSearch<const N: usize> {
    queue: [u32; N],
    seen: [u8; N],
}

impl<const N: usize> Default for MouthSearch<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> core::fmt::Debug for MouthSearch<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("MouthSearch")
            .field("capacity", &N)
            .finish_non_exhaustive()
    }
}

impl<const N: usize> MouthSearch<N> {
    /// Empty working memory (built on the stack or in a `static`).
    pub const fn new() -> Self {
        Self {
            queue: [0; N],
            seen: [0; N],
        }
    }

    /// Where to look from at the nearest passage that is open in Free cells but shut in
    /// the planning layer `trav`, from the robot's distance field `field`; `None` if there is
    /// none (or none farther than [`MOUTH_MEMORY_M`] from every point of `looked`). A grid of
    /// more cells than the memory holds has no answer.
    pub fn find(
        &mut self,
        grid: &OccupancyGrid<N>,
        trav: &Traversability<N>,
        field: &DistanceField<N>,
        looked: &[Point2],
    ) -> Option<ShutMouth> {
        let geom = *grid.geometry();
        let cells = grid.cell_count();
        if cells > N || trav.geometry() != grid.geometry() {
            return None;
        }
        self.seen[..cells].fill(0);
        let remembered = |c: Cell| -> bool {
            looked
                .iter()
                .any(|m| m.distance(geom.cell_center(c)) < MOUTH_MEMORY_M)
        };
        let (mut head, mut tail) = (0usize, 0usize);
        // Seeds: the passable Free 4-neighbours of frontier cells that the robot cannot reach.
        let area = crate::frontier::frontier_box(grid);
        for row in area.row_min..area.row_end {
            for col in area.col_min..area.col_end {
                let i = row * geom.width + col;
                if !crate::frontier::is_frontier_cell(grid, i) {
                    continue;
                }
                let c = geom.cell(i);
                for (dc, dr) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                    let n = Cell::new(c.col + dc, c.row + dr);
                    let Some(j) = geom.index(n) else { continue };
                    if self.seen[j] != 0
                        || grid.class(j) != CellClass::Free
                        || !trav.is_passable(n)
                        || field.is_reachable(n)
                        || remembered(n)
                    {
                        continue;
                    }
                    self.seen[j] = 1;
                    self.queue[tail] = j as u32;
                    tail += 1;
                }
            }
        }
        // The flood over Free cells, nearest the cut frontier first.
        while head < tail {
            let c = geom.cell(self.queue[head] as usize);
            head += 1;
            for (dc, dr) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                let n = Cell::new(c.col + dc, c.row + dr);
                let Some(j) = geom.index(n) else { continue };
                if self.seen[j] != 0 {
                    continue;
                }
                self.seen[j] = 1;
                if grid.class(j) != CellClass::Free || remembered(n) {
                    continue;
                }
                if field.is_reachable(n) {
                    // The robot's side of the passage: stand near it where it can turn.
                    if let Some(stand) = stand_near(trav, field, n, &remembered) {
                        return Some(ShutMouth { stand, mouth: n });
                    }
                    continue;
                }
                self.queue[tail] = j as u32;
                tail += 1;
            }
        }
        None
    }
}

/// The reached cell nearest `mouth` (within [`MOUTH_STAND_M`]) where the robot can turn in
/// place, not near a mouth looked from.
fn stand_near<const N: usize>(
    trav: &Traversability<N>,
    field: &DistanceField<N>,
    mouth: Cell,
    remembered: &impl Fn(Cell) -> bool,
) -> Option<Cell> {
    let geom = trav.geometry();
    let span = (MOUTH_STAND_M / geom.resolution_m) as i32;
    let mut best: Option<(i32, Cell)> = None;
    for dr in -span..=span {
        for dc in -span..=span {
            let d2 = dc * dc + dr * dr;
            if d2 > span * span || best.is_some_and(|(b, _)| d2 >= b) {
                continue;
            }
            let c = Cell::new(mouth.col + dc, mouth.row + dr);
            if trav.can_turn(c) && field.is_reachable(c) && !remembered(c) {
                best = Some((d2, c));
            }
        }
    }
    best.map(|(_, c)| c)
}

/// Lowers every Occupied cell of `grid` within `radius_m` of `centre` to at most
/// `occupied_log_odds` (one return's evidence, the sensor model's increment), reporting the
/// class changes to `observer` (none: a lowered cell stays Occupied). Returns how many cells
/// it lowered. See the module's notes: the next scans decide these cells again.
pub fn doubt_walls<const N: usize>(
    grid: &mut OccupancyGrid<N>,
    centre: Point2,
    radius_m: f32,
    occupied_log_odds: f32,
    observer: &mut impl crate::grid::CellObserver,
) -> usize {
    let geom = *grid.geometry();
    if !(geom.contains_point(centre) && radius_m >= 0.0 && occupied_log_odds > 0.0) {
        return 0;
    }
    let mut lowered = 0;
    for i in geom.indices_within(centre, radius_m) {
        if grid.log_odds_at(i) > occupied_log_odds {
            grid.set_log_odds(i, occupied_log_odds, observer);
            lowered += 1;
        }
    }
    lowered
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{GridGeometry, LogOddsBounds};
    use crate::sensor::{Beam, LaserConfig, Scan, SensorModel, integrate_scan};

    /// A 3 m x 3 m map of 0.1 m cells: a wall along row 15 (y 1.5-1.6 m) with a 0.5 m door
    /// (columns 13..=17) and, a cell further north, a copy of the wall drawn at another drift
    /// with its door two cells east (columns 15..=19), every wall cell saturated.
    fn drifted_door() -> OccupancyGrid<900> {
        let geom = GridGeometry::new(30, 30, 0.1, Point2::new(0.0, 0.0)).unwrap();
        let mut g = OccupancyGrid::<900>::new(geom, LogOddsBounds::default()).unwrap();
        let max = g.bounds().max;
        let min = g.bounds().min;
        for row in 0..30 {
            for col in 0..30 {
                let i = row * 30 + col;
                let wall = (row == 15 && !(13..=17).contains(&col))
                    || (row == 16 && !(15..=19).contains(&col));
                g.set_log_odds(i, if wall { max } else { min }, &mut ());
            }
        }
        g
    }

    /// A 180° scan of 361 beams from `pose` of the true world: the wall of row 15 only, its
    /// door at columns 13..=17, nothing else within 4 m.
    fn look(pose: crate::geometry::Pose2) -> Scan {
        let mut scan = Scan::new();
        for k in 0..361 {
            let a = -core::f32::consts::FRAC_PI_2 + k as f32 * core::f32::consts::PI / 360.0;
            let (dx, dy) = (libm::cosf(pose.theta + a), libm::sinf(pose.theta + a));
            // The wall's south face, y = 1.5 m; the door, x in 1.3..1.8 m.
            let mut range = None;
            if dy > 1e-3 {
                let t = (1.5 - pose.y) / dy;
                let x = pose.x + t * dx;
                if !(1.3..1.8).contains(&x) && t <= 4.0 {
                    range = Some(t);
                }
            }
            let _ = scan.push(Beam {
                angle_rad: a,
                range_m: range,
            });
        }
        scan
    }

    fn passable_column(g: &OccupancyGrid<900>, col: usize) -> bool {
        (14..=17).all(|row| g.class(row * 30 + col) == crate::grid::CellClass::Free)
    }

    /// Scans (at most 20) from `pose` until the door's five columns are Free from row 14 to
    /// row 17 in `g`; `None` if they never are.
    fn looks_to_open(g: &mut OccupancyGrid<900>, pose: crate::geometry::Pose2) -> Option<usize> {
        let laser = LaserConfig {
            noise_fraction: 0.0,
            ..LaserConfig::thesis()
        };
        let scan = look(pose);
        (1..=20).find(|_| {
            integrate_scan(g, &scan, pose, &laser, &SensorModel::thesis(), &mut ()).unwrap();
            (13..=17).all(|c| passable_column(g, c))
        })
    }

    #[test]
    fn a_doubted_door_opens_with_fewer_looks_and_its_walls_stay() {
        let occupied = SensorModel::thesis().occupied_log_odds;
        // Looks from 1.5 m south of the door's middle (x 1.55 m), facing north.
        let pose = crate::geometry::Pose2::new(1.55, 0.05, core::f32::consts::FRAC_PI_2);
        let mut plain = drifted_door();
        let mut doubted = drifted_door();
        let lowered = doubt_walls(
            &mut doubted,
            Point2::new(1.55, 1.45),
            DOUBT_RADIUS_M,
            occupied,
            &mut (),
        );
        assert!(lowered > 20, "{lowered} cells lowered");
        let plain_looks = looks_to_open(&mut plain, pose);
        let doubted_looks = looks_to_open(&mut doubted, pose);
        // The copy's cells in the true door (row 16, columns 13 and 14) are free in truth:
        // saturated, they take more of the look's misses than doubted ones.
        let doubted_looks = doubted_looks.expect("the doubted door opens");
        assert!(
            plain_looks.is_none_or(|p| doubted_looks < p),
            "doubted {doubted_looks} looks, saturated {plain_looks:?}"
        );
        // The true wall beside the door is still Occupied, and saturated again where seen.
        for col in [10, 11, 12, 18, 19, 20] {
            assert_eq!(
                doubted.class(15 * 30 + col),
                crate::grid::CellClass::Occupied,
                "wall cell at column {col}"
            );
        }
        assert!(doubted.log_odds_at(15 * 30 + 12) > occupied);
    }

    #[test]
    fn doubt_lowers_only_occupied_cells_within_the_radius() {
        let mut g = drifted_door();
        let before: heapless::Vec<f32, 900> = g.log_odds().iter().copied().collect();
        let centre = Point2::new(1.55, 1.45);
        let n = doubt_walls(&mut g, centre, 0.5, 0.847, &mut ());
        let geom = *g.geometry();
        let mut expected = 0;
        for (i, (&a, &b)) in before.iter().zip(g.log_odds()).enumerate() {
            let near = geom.cell_center(geom.cell(i)).distance(centre) <= 0.5;
            if near && a > 0.847 {
                expected += 1;
                assert_eq!(b, 0.847, "cell {i}");
            } else {
                assert_eq!(a, b, "cell {i} changed");
            }
        }
        assert_eq!(n, expected);
        assert!(n > 0);
        // Bad input changes nothing.
        assert_eq!(doubt_walls(&mut g, centre, -1.0, 0.847, &mut ()), 0);
        assert_eq!(
            doubt_walls(&mut g, Point2::new(-5.0, 0.0), 1.0, 0.847, &mut ()),
            0
        );
    }
}
