//! The map scans are matched to: where laser returns landed, accumulated over the scans
//! integrated so far, on the occupancy grid's cells.
//!
//! The occupancy grid is the wrong reference for a matcher. Its inverse sensor model marks the
//! cells a beam crosses free, so with noisy ranges the cells just before a surface are cleared
//! by the longer returns of neighbouring beams and the occupied band recedes behind the
//! surface by a part of the range noise (at 3 m with 5 % noise, about a cell); and a wall seen
//! at a grazing angle is cleared by the beams that pass along it, leaving occupied spots whose
//! pattern along the wall pulls a match sideways. Both are biases, not noise: matched and
//! integrated scan after scan, they turn a robot standing still (measured: 20-30 cm and
//! several degrees in a few seconds, `examples/localize_turn.rs` in the simulator).
//!
//! Olson (*Real-time correlative scan matching*, ICRA 2009, §III) rasterises the *points* of
//! the reference scans instead, and that is what this layer keeps: every return adds one unit
//! of weight, split bilinearly among the four cell centres around it, so the weighted mean of
//! the cell centres is the return itself (no half-cell bias from which side of a cell border
//! a surface lies on). Returns are spread symmetrically about the surface by the range noise,
//! so the ridge of their density is on it. [`super::likelihood`] blurs this layer into the
//! field a scan is scored against.
//!
//! One `f32` per grid cell (metres of surface, see [`HitMap::add_scan`]). No allocation.

use crate::geometry::{Point2, Pose2};
use crate::grid::GridGeometry;
use crate::math;
use crate::sensor::{LaserConfig, Scan};

/// Surface one return stands for at most \[m\] (a return beside a gap in the scan).
pub const MAX_FOOTPRINT_M: f32 = 0.2;

/// Where returns landed, per grid cell.
#[derive(bytemuck::Zeroable)]
pub struct HitMap<const N: usize> {
    geometry: GridGeometry,
    weights: [f32; N],
}

impl<const N: usize> core::fmt::Debug for HitMap<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("HitMap")
            .field("geometry", &self.geometry)
            .finish_non_exhaustive()
    }
}

impl<const N: usize> HitMap<N> {
    /// An empty layer over `geometry` (which must have at most `N` cells; the caller's grid
    /// checked it). Use on the stack only for small `N`.
    pub fn new(geometry: GridGeometry) -> Self {
        Self {
            geometry,
            weights: [0.0; N],
        }
    }

    /// Sets up a zeroed layer (built by [`bytemuck::Zeroable`] on the heap) over `geometry`.
    pub fn set_up_zeroed(&mut self, geometry: GridGeometry) {
        self.geometry = geometry;
    }

    /// The grid geometry.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// Forgets every return (a pose graph draws the layer again from its keyframes).
    pub fn clear(&mut self) {
        let n = self.geometry.cell_count().min(N);
        self.weights[..n].fill(0.0);
    }

    /// Weight at a flat cell index (0 outside the grid) \[m of surface\].
    #[inline]
    pub fn weight_at(&self, index: usize) -> f32 {
        if index < self.geometry.cell_count().min(N) {
            self.weights[index]
        } else {
            0.0
        }
    }

    /// Adds a return at map point `p` standing for `weight` (bilinearly among the four
    /// nearest cell centres; parts off the grid are dropped).
    pub fn add_point(&mut self, p: Point2, weight: f32) {
        let g = self.geometry;
        let u = (p.x - g.origin.x) / g.resolution_m - 0.5;
        let v = (p.y - g.origin.y) / g.resolution_m - 0.5;
        if !(u.is_finite() && v.is_finite()) {
            return;
        }
        let (fu, fv) = (math::floor(u), math::floor(v));
        let (du, dv) = (u - fu, v - fv);
        let (c0, r0) = (fu as i64, fv as i64);
        for (dc, dr, w) in [
            (0, 0, (1.0 - du) * (1.0 - dv)),
            (1, 0, du * (1.0 - dv)),
            (0, 1, (1.0 - du) * dv),
            (1, 1, du * dv),
        ] {
            let (c, r) = (c0 + dc, r0 + dr);
            if c < 0 || r < 0 || c as usize >= g.width || r as usize >= g.height {
                continue;
            }
            let i = r as usize * g.width + c as usize;
            if i >= N {
                continue;
            }
            self.weights[i] += w * weight;
        }
    }

    /// Adds the returns of `scan`, taken by `laser` at robot pose `pose` (map frame), each
    /// weighted by the length of surface it stands for: half the distance to each neighbouring
    /// return, at most [`MAX_FOOTPRINT_M`] a side. A wall seen close or head-on holds many
    /// returns per metre and one seen far or at a grazing angle few; weighted so, every metre
    /// of wall a scan sees weighs the same, and the field does not pull returns along a wall
    /// toward where it was seen densest.
    pub fn add_scan(&mut self, scan: &Scan, laser: &LaserConfig, pose: Pose2) {
        let at = pose.compose(laser.mount);
        let point = |i: usize| -> Option<Point2> {
            let b = scan.beams().get(i)?;
            let r = b
                .range_m
                .filter(|r| r.is_finite() && *r >= laser.min_range_m && *r < laser.max_range_m)?;
            if !b.angle_rad.is_finite() {
                return None;
            }
            let a = at.theta + b.angle_rad;
            Some(Point2::new(
                at.x + r * math::cos(a),
                at.y + r * math::sin(a),
            ))
        };
        let n = scan.beams().len();
        let mut prev: Option<Point2> = None;
        let mut here = point(0);
        for i in 0..n {
            let next = point(i + 1);
            if let Some(p) = here {
                let side = |q: Option<Point2>| {
                    q.map_or(0.0, |q| (0.5 * q.distance(p)).min(MAX_FOOTPRINT_M))
                };
                let (a, b) = (side(prev), side(next));
                // A return without one neighbour stands for as much on that side as on the
                // other.
                let w = match (prev.is_some(), next.is_some()) {
                    (true, true) => a + b,
                    (true, false) => 2.0 * a,
                    (false, true) => 2.0 * b,
                    (false, false) => 0.0,
                };
                if w > 0.0 {
                    self.add_point(p, w);
                }
            }
            prev = here;
            here = next;
        }
    }

    /// Forgets every return within `radius_m` of `centre` (cell centres), e.g. where a robot
    /// stood that another robot's laser saw.
    pub fn clear_disc(&mut self, centre: Point2, radius_m: f32) {
        let g = self.geometry;
        let c = g.cell_at_unchecked(centre);
        let span = math::ceil(radius_m / g.resolution_m) as i32 + 1;
        for row in c.row - span..=c.row + span {
            for col in c.col - span..=c.col + span {
                let cell = crate::grid::Cell::new(col, row);
                if let Some(i) = g.index(cell).filter(|&i| i < N)
                    && g.cell_center(cell).distance(centre) <= radius_m
                {
                    self.weights[i] = 0.0;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_return_on_a_cell_border_splits_evenly_and_keeps_its_mean() {
        let g = GridGeometry::new(10, 10, 0.1, Point2::new(0.0, 0.0)).unwrap();
        let mut h = HitMap::<100>::new(g);
        // On the border between columns 4 and 5, at the centre of row 3.
        h.add_point(Point2::new(0.5, 0.35), 1.0);
        assert!((h.weight_at(3 * 10 + 4) - 0.5).abs() < 1e-6);
        assert!((h.weight_at(3 * 10 + 5) - 0.5).abs() < 1e-6);
        assert_eq!(h.weight_at(4 * 10 + 4), 0.0);
        // A return at a cell centre stays in its cell.
        h.add_point(Point2::new(0.75, 0.75), 1.0);
        assert!((h.weight_at(7 * 10 + 7) - 1.0).abs() < 1e-6);
        h.clear_disc(Point2::new(0.75, 0.75), 0.05);
        assert_eq!(h.weight_at(7 * 10 + 7), 0.0);
        assert!((h.weight_at(3 * 10 + 4) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn a_wall_weighs_its_length_however_densely_it_was_sampled() {
        use crate::sensor::{Beam, LaserConfig, Scan};
        // A wall 1 m ahead across the laser's view: beams at 1° put returns 1.7 cm apart
        // near its foot, farther apart away from it; the weight on the wall's cells is its
        // length seen either way.
        let g = GridGeometry::new(40, 40, 0.1, Point2::new(-2.0, -2.0)).unwrap();
        let mut h = HitMap::<1600>::new(g);
        let laser = LaserConfig::thesis();
        let mut scan = Scan::new();
        for i in 0..laser.beam_count as usize {
            let a = laser.beam_angle(i);
            let r = 1.0 / math::cos(a);
            scan.push(Beam {
                angle_rad: a,
                range_m: (math::cos(a) > 0.3).then_some(r),
            })
            .unwrap();
        }
        h.add_scan(&scan, &laser, Pose2::new(0.0, 0.0, 0.0));
        let total: f32 = (0..1600).map(|i| h.weight_at(i)).sum();
        // The wall seen spans y = ±tan(acos 0.3) = ±3.18 m, cut by the grid at ±2 m.
        let seen = 2.0 * (1.0f32 - 0.09).sqrt() / 0.3;
        assert!(total > 3.8 && total < seen + 0.1, "{total} m");
        // Near the foot and 1.5 m along: the same weight per cell of wall.
        let foot = h.weight_at(20 * 40 + 29) + h.weight_at(20 * 40 + 30);
        let along = h.weight_at(35 * 40 + 29) + h.weight_at(35 * 40 + 30);
        assert!((foot - along).abs() < 0.02, "{foot} vs {along}");
    }
}
