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
//! One `f32` per grid cell (metres of surface, see [`HitMap::add_scan`]) for the coarse search's
//! field.
//!
//! Beside it, every cell keeps the statistics of the returns that landed in it, as the normal
//! distributions transform does (Biber & Straßer, *The normal distributions transform: a new
//! approach to laser scan matching*, IROS 2003): the weight, the weighted sums of the return
//! positions (relative to the cell centre, so `f32` keeps sub-millimetre precision) and of their
//! products. [`HitMap::surface_at`] adds up the cells of a block and returns the mean and the
//! principal axes of the returns there: where they lie on a wall, the mean is on the wall to a
//! fraction of the range noise and the minor axis is its normal, however the wall lies against
//! the cells ([`super::ndt`] fits scans to these lines).
//!
//! Each return is weighted by the inverse of its range variance (`σ = noise_fraction · range`,
//! at least [`SIGMA_FLOOR_M`]), so the mean leans on the precise returns; and its expected noise
//! scatter (`σ² u uᵀ` along its beam `u`) is taken off the second moments, so a wall seen from
//! afar (its returns scattered along the beams more than along the wall) still shows the wall's
//! direction and not the beams'. No allocation.

use crate::geometry::{Point2, Pose2};
use crate::grid::GridGeometry;
use crate::math;
use crate::sensor::{LaserConfig, Scan};

/// Surface one return stands for at most \[m\] (a return beside a gap in the scan).
pub const MAX_FOOTPRINT_M: f32 = 0.2;

/// A return's range noise counts as at least this in its weight \[m\]: a return with this
/// noise or less weighs 1, one with `σ` weighs `(SIGMA_FLOOR_M / σ)²`.
pub const SIGMA_FLOOR_M: f32 = 0.01;

/// The returns of a block of cells: where they lie and how they spread.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Weighted mean of the returns (map frame) \[m\].
    pub mean: Point2,
    /// Unit normal: the minor axis of their spread.
    pub normal: Point2,
    /// Their spread along the normal, net of the range noise (at least 0) \[m²\].
    pub across_var_m2: f32,
    /// Their spread along the major axis \[m²\].
    pub along_var_m2: f32,
    /// Total weight (a return with [`SIGMA_FLOOR_M`] of noise weighs 1).
    pub weight: f32,
    /// Variance of the normal's angle \[rad²\]: how far the minor axis may be off the
    /// surface's true normal ([`HitMap::surface_at`] says why).
    pub normal_var_rad2: f32,
}

/// Where returns landed, per grid cell.
#[derive(bytemuck::Zeroable)]
pub struct HitMap<const N: usize> {
    geometry: GridGeometry,
    weights: [f32; N],
    /// Per cell: weight, `Σ w dx`, `Σ w dy`, `Σ w (dx² - σ²uₓ²)`, `Σ w (dx dy - σ²uₓu_y)`,
    /// `Σ w (dy² - σ²u_y²)`, `Σ w σ²uₓ²`, `Σ w σ²uₓu_y`, `Σ w σ²u_y²`, with `d` the return's
    /// offset from the cell centre and `σ` its range noise along its beam `u`.
    stats: [[f32; 9]; N],
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
            stats: [[0.0; 9]; N],
        }
    }

    /// An empty layer over `geometry`, built on the heap whatever `N`.
    #[cfg(feature = "std")]
    pub fn new_boxed(geometry: GridGeometry) -> std::boxed::Box<Self> {
        let mut h = crate::heap::boxed_zeroed::<Self>();
        h.set_up_zeroed(geometry);
        h
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
        // The per-cell statistics too: the point-to-line refinement reads them
        // ([`Self::surface_at`]), and a layer drawn again would otherwise keep the old returns.
        self.stats[..n].fill([0.0; 9]);
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
        self.add_scan_capped(scan, laser, pose, f32::INFINITY);
    }

    /// [`Self::add_scan`], leaving out the returns that land in a cell whose statistics
    /// already weigh `max_cell_weight` or more: a wall the map knows well stays where the
    /// first scans put it, and a pose that drifts later does not drag it along (scan after
    /// scan, the matcher would otherwise fit the newest returns, drawn at the newest poses,
    /// and the pose would random-walk with the map).
    pub fn add_scan_capped(
        &mut self,
        scan: &Scan,
        laser: &LaserConfig,
        pose: Pose2,
        max_cell_weight: f32,
    ) {
        let at = pose.compose(laser.mount);
        // A usable return: its point and the beam's unit direction (map frame).
        let point = |i: usize| -> Option<(Point2, Point2)> {
            let b = scan.beams().get(i)?;
            let r = b
                .range_m
                .filter(|r| r.is_finite() && *r >= laser.min_range_m && *r < laser.max_range_m)?;
            if !b.angle_rad.is_finite() {
                return None;
            }
            let (sin, cos) = math::sin_cos(at.theta + b.angle_rad);
            Some((
                Point2::new(at.x + r * cos, at.y + r * sin),
                Point2::new(cos, sin),
            ))
        };
        let n = scan.beams().len();
        let mut prev: Option<Point2> = None;
        let mut here_beam = point(0);
        for i in 0..n {
            let next_beam = point(i + 1);
            let (here, next) = (here_beam.map(|(p, _)| p), next_beam.map(|(p, _)| p));
            let full = here.is_some_and(|p| self.cell_weight(p) >= max_cell_weight);
            if let Some(p) = here.filter(|_| !full) {
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
                if let (Some(r), Some((_, u))) = (scan.beams()[i].range_m, here_beam) {
                    let sigma = laser.noise_fraction.max(0.0) * r;
                    self.add_return(p, u, sigma);
                }
            }
            prev = here;
            here_beam = next_beam;
        }
    }

    /// Weight of the statistics of the cell holding `p` (0 off the grid).
    fn cell_weight(&self, p: Point2) -> f32 {
        let g = self.geometry;
        g.cell_at(p)
            .and_then(|c| g.index(c))
            .filter(|&i| i < N)
            .map_or(0.0, |i| self.stats[i][0])
    }

    /// Adds one return at map point `p`, seen along the unit beam direction `u` with range
    /// noise `sigma_m`, to the statistics of the cell it lands in.
    pub fn add_return(&mut self, p: Point2, u: Point2, sigma_m: f32) {
        let g = self.geometry;
        let Some(i) = g.cell_at(p).and_then(|c| g.index(c)).filter(|&i| i < N) else {
            return;
        };
        if !(sigma_m.is_finite() && u.x.is_finite() && u.y.is_finite()) {
            return;
        }
        let c = g.cell_center(g.cell_at_unchecked(p));
        let (dx, dy) = (p.x - c.x, p.y - c.y);
        let s = sigma_m.max(SIGMA_FLOOR_M);
        let w = (SIGMA_FLOOR_M / s) * (SIGMA_FLOOR_M / s);
        let n2 = sigma_m * sigma_m;
        let st = &mut self.stats[i];
        st[0] += w;
        st[1] += w * dx;
        st[2] += w * dy;
        st[3] += w * (dx * dx - n2 * u.x * u.x);
        st[4] += w * (dx * dy - n2 * u.x * u.y);
        st[5] += w * (dy * dy - n2 * u.y * u.y);
        st[6] += w * n2 * u.x * u.x;
        st[7] += w * n2 * u.x * u.y;
        st[8] += w * n2 * u.y * u.y;
    }

    /// The returns of the `(2 half + 1)²` cells centred on the cell holding `p`: their mean
    /// and principal axes ([`Surface`]), or `None` when they weigh less than `min_weight`
    /// or `p` is off the grid.
    pub fn surface_at(&self, p: Point2, half: i32, min_weight: f32) -> Option<Surface> {
        let g = self.geometry;
        let centre = g.cell_at(p)?;
        let res = g.resolution_m;
        let (mut w, mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0.0f32, 0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut nxx, mut nxy, mut nyy) = (0.0f32, 0.0f32, 0.0f32);
        for dr in -half..=half {
            let row = centre.row + dr;
            if row < 0 || row as usize >= g.height {
                continue;
            }
            let oy = dr as f32 * res;
            for dc in -half..=half {
                let col = centre.col + dc;
                if col < 0 || col as usize >= g.width {
                    continue;
                }
                let i = row as usize * g.width + col as usize;
                if i >= N {
                    continue;
                }
                let st = &self.stats[i];
                if st[0] <= 0.0 {
                    continue;
                }
                let ox = dc as f32 * res;
                w += st[0];
                sx += st[1] + st[0] * ox;
                sy += st[2] + st[0] * oy;
                sxx += st[3] + 2.0 * ox * st[1] + st[0] * ox * ox;
                sxy += st[4] + ox * st[2] + oy * st[1] + st[0] * ox * oy;
                syy += st[5] + 2.0 * oy * st[2] + st[0] * oy * oy;
                nxx += st[6];
                nxy += st[7];
                nyy += st[8];
            }
        }
        if w < min_weight.max(f32::MIN_POSITIVE) {
            return None;
        }
        let (mx, my) = (sx / w, sy / w);
        let cxx = sxx / w - mx * mx;
        let cxy = sxy / w - mx * my;
        let cyy = syy / w - my * my;
        // Eigen-decomposition of the symmetric 2 x 2 spread.
        let half_tr = 0.5 * (cxx + cyy);
        let disc = math::sqrt((0.5 * (cxx - cyy)) * (0.5 * (cxx - cyy)) + cxy * cxy);
        let (major, minor) = (half_tr + disc, half_tr - disc);
        // The major axis is the angle of the eigenvector of `major`.
        let angle = 0.5 * math::atan2(2.0 * cxy, cxx - cyy);
        let c = g.cell_center(centre);
        // The normal's angle is the ratio of the spread's off-diagonal (in the surface's
        // frame) to the spread along, `S`. Two things move that off-diagonal. Sampling: the
        // mean's own variance, `σ_floor² / W`, over `S`. And the range noise, whose expected
        // part is taken off above but which, where beams meet the surface at a slant, also
        // carries returns across the block's ends along their beams: a fraction `σₜ / L` of
        // the returns (`σₜ`, `σₙ` the noise along and across the surface, `L` the block's
        // length) cross an end, each at `L / 2` from the mean and `σₙ` off the surface, and
        // those entering at one end lie deeper than those leaving at the other; a tilt of
        // `σₜ σₙ / (2 S)`, the noise's weighted mean `|tᵀ Σ w σ² u uᵀ n| / W` over `2 S`,
        // that the subtraction cannot see (zero for returns seen head-on or along the
        // surface; measured: 5 % range noise seen from behind tilts a corridor's walls 6°;
        // docs/experiments.md, sixth measurement).
        let along = (major - minor.max(0.0)).max(f32::MIN_POSITIVE);
        let floor2 = SIGMA_FLOOR_M * SIGMA_FLOOR_M;
        let (ca, sa) = (math::cos(angle), math::sin(angle));
        // t = (cos, sin), n = (-sin, cos): tᵀ N n.
        let tn = -ca * sa * nxx + (ca * ca - sa * sa) * nxy + sa * ca * nyy;
        let tilt = math::abs(tn) / w / (2.0 * along);
        let normal_var_rad2 = floor2 / w / along + tilt * tilt;
        Some(Surface {
            mean: Point2::new(c.x + mx, c.y + my),
            normal: Point2::new(-math::sin(angle), math::cos(angle)),
            across_var_m2: minor.max(0.0),
            along_var_m2: major.max(0.0),
            weight: w,
            normal_var_rad2,
        })
    }

    /// Forgets every return within `radius_m` of `centre` (cell centres), e.g. where a robot
    /// stood that another robot's laser saw.
    pub fn clear_disc(&mut self, centre: Point2, radius_m: f32) {
        for i in self.geometry.indices_within(centre, radius_m) {
            if i < N {
                self.weights[i] = 0.0;
                self.stats[i] = [0.0; 9];
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
    #[test]
    fn a_capped_cell_takes_no_more_returns() {
        use crate::sensor::{Beam, LaserConfig, Scan};
        // The same wall 1 m ahead, added ten times: without a cap the cell's statistics
        // grow with every scan; capped at 3.5 scans' weight they stop within the fourth.
        let g = GridGeometry::new(40, 40, 0.1, Point2::new(-2.0, -2.0)).unwrap();
        let laser = LaserConfig::thesis();
        let mut scan = Scan::new();
        for i in 0..laser.beam_count as usize {
            let a = laser.beam_angle(i);
            scan.push(Beam {
                angle_rad: a,
                range_m: (math::cos(a) > 0.3).then_some(1.0 / math::cos(a)),
            })
            .unwrap();
        }
        let pose = Pose2::new(0.0, 0.0, 0.0);
        let foot = Point2::new(1.0, 0.0);
        let once = {
            let mut h = HitMap::<1600>::new(g);
            h.add_scan(&scan, &laser, pose);
            h.cell_weight(foot)
        };
        assert!(once > 0.0, "one scan: {once}");
        let mut free = HitMap::<1600>::new(g);
        let mut capped = HitMap::<1600>::new(g);
        for _ in 0..10 {
            free.add_scan(&scan, &laser, pose);
            capped.add_scan_capped(&scan, &laser, pose, 3.5 * once);
        }
        let (wf, wc) = (free.cell_weight(foot), capped.cell_weight(foot));
        assert!(
            (wf - 10.0 * once).abs() < 1e-3 * wf,
            "uncapped: {wf} (one scan {once})"
        );
        // The fourth scan's returns stop as soon as the cell reaches the cap.
        assert!(
            wc >= 3.5 * once && wc <= 4.0 * once * 1.001,
            "capped: {wc} (one scan {once})"
        );
    }
}
