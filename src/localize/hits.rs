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
//! Weights are fixed-point `u16` ([`UNIT`] per return, saturating), one per grid cell: half
//! the memory of the grid's `f32` log-odds. No allocation.

use crate::geometry::{Point2, Pose2};
use crate::grid::GridGeometry;
use crate::math;
use crate::sensor::{LaserConfig, Scan};

/// Weight of one return (split among four cells).
pub const UNIT: u16 = 64;

/// Where returns landed, per grid cell.
#[derive(bytemuck::Zeroable)]
pub struct HitMap<const N: usize> {
    geometry: GridGeometry,
    weights: [u16; N],
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
            weights: [0; N],
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

    /// Weight at a flat cell index (0 outside the grid) \[1/[`UNIT`] returns\].
    #[inline]
    pub fn weight_at(&self, index: usize) -> u16 {
        if index < self.geometry.cell_count().min(N) {
            self.weights[index]
        } else {
            0
        }
    }

    /// Adds one return at map point `p` (bilinearly among the four nearest cell centres;
    /// parts off the grid are dropped).
    pub fn add_point(&mut self, p: Point2) {
        let g = self.geometry;
        let u = (p.x - g.origin.x) / g.resolution_m - 0.5;
        let v = (p.y - g.origin.y) / g.resolution_m - 0.5;
        if !(u.is_finite() && v.is_finite()) {
            return;
        }
        let (fu, fv) = (math::floor(u), math::floor(v));
        let (du, dv) = (u - fu, v - fv);
        let (c0, r0) = (fu as i64, fv as i64);
        let unit = UNIT as f32;
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
            let add = math::floor(w * unit + 0.5) as u16;
            self.weights[i] = self.weights[i].saturating_add(add);
        }
    }

    /// Adds the returns of `scan`, taken by `laser` at robot pose `pose` (map frame).
    pub fn add_scan(&mut self, scan: &Scan, laser: &LaserConfig, pose: Pose2) {
        let at = pose.compose(laser.mount);
        for b in scan.beams() {
            let Some(r) = b.range_m.filter(|r| {
                r.is_finite() && *r >= laser.min_range_m && *r < laser.max_range_m
            }) else {
                continue;
            };
            if !b.angle_rad.is_finite() {
                continue;
            }
            let a = at.theta + b.angle_rad;
            self.add_point(Point2::new(
                at.x + r * math::cos(a),
                at.y + r * math::sin(a),
            ));
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
                    self.weights[i] = 0;
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
        h.add_point(Point2::new(0.5, 0.35));
        assert_eq!(h.weight_at(3 * 10 + 4), UNIT / 2);
        assert_eq!(h.weight_at(3 * 10 + 5), UNIT / 2);
        assert_eq!(h.weight_at(4 * 10 + 4), 0);
        // A return at a cell centre stays in its cell.
        h.add_point(Point2::new(0.75, 0.75));
        assert_eq!(h.weight_at(7 * 10 + 7), UNIT);
        h.clear_disc(Point2::new(0.75, 0.75), 0.05);
        assert_eq!(h.weight_at(7 * 10 + 7), 0);
        assert_eq!(h.weight_at(3 * 10 + 4), UNIT / 2);
    }
}
