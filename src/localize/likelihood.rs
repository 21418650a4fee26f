//! The smoothed likelihood field a scan is scored against: a local window of the returns
//! the map holds ([`super::hits`]), where each cell holds how likely a laser return is to land
//! there.
//!
//! Olson (*Real-time correlative scan matching*, ICRA 2009, §III) scores a pose by looking up
//! each projected return in a rasterised, blurred copy of the reference points: blurring by
//! the sensor's uncertainty turns "did a return land in this cell" into "how close is this
//! cell to where returns land", so a return a few centimetres off still scores, and the score
//! falls smoothly with the offset. Here the value of a cell is
//! `max over cells c' within 2σ of  s(c') · exp(-d(c, c')² / 2σ²)`, with `s(c')` the weight of
//! the returns in `c'` (the metres of surface they stand for, [`super::hits`]) divided by
//! [`WALL_FRACTION`] of the largest weight within the same reach (at least
//! [`FLOOR_M_PER_CELL`]), capped at 1. The range noise spreads a wall's returns over a band
//! across it; every cell of the band at half its height or more is a wall cell (`s = 1`),
//! however often it was seen, and the cells on the band's edges count in proportion (so the
//! ridge keeps sub-cell position). Where all of `s` is 0 or 1 this is the likelihood-field
//! model of Thrun, Burgard & Fox (*Probabilistic Robotics*, 2005, §6.4),
//! `exp(-d²/2σ²)` of the distance `d` to the nearest wall cell (the Gaussian max-convolution
//! of a binary image is that distance transform, bounded at 2σ).
//!
//! The cap matters: the weight itself (first version: the weight over the local largest,
//! uncapped) varies along a wall with how many scans saw each part of it, and that slope
//! along the wall pulled a robot driving a corridor back toward where it had been
//! (`sim-host/tests/localize_corridor.rs`: 5.6 m behind after 40 m, now within the
//! odometry's own error). A maximum, as Olson's, not a sum: a sum fades at the end of a wall
//! seen so far and pulls the returns near it inward. Both passes
//! are separable: one along the rows, one along the columns, each with a short line buffer.
//!
//! Two variants are kept for experiments (docs/experiments.md, fourth measurement), neither used
//! by default: a Gaussian *sum* blur of the returns before the normalisation (`smooth`, a
//! density whose ridge is the surface's mean line) and cubic interpolation
//! ([`LikelihoodField::sample_cubic`]), which keeps the maximum of a ridge lying on a cell
//! border where bilinear interpolation leaves a plateau a cell wide.
//!
//! The same field, read with bilinear interpolation between cell centres
//! ([`LikelihoodField::sample`]), is the continuous map function Hector's Gauss-Newton step
//! differentiates (Kohlbrecher et al., SSRR 2011, §IV.A).
//!
//! Only the window around the scan is built (sized to the capacity `T` cells), at every match:
//! the map changes with every scan of every robot, and a window of 100 x 100 cells costs tens
//! of microseconds.

use crate::geometry::Point2;
use crate::grid::GridGeometry;
use crate::math;

use super::hits::HitMap;

/// Longest row or column of a window \[cells\] (the line buffer of the separable pass).
pub const MAX_LINE: usize = 512;

/// A cell's weight is normalised by at least this many metres of surface per cell side: a
/// wall seen once by a scan (one metre of surface per metre, half of it in each of two cells
/// when it runs along a cell border) reaches 1, a few stray returns stay faint.
pub const FLOOR_M_PER_CELL: f32 = 0.5;

/// A cell is a wall (scores 1) when its weight is at least this fraction of the largest
/// within the kernel's reach (the band of a wall's returns at half its height); below it
/// scores in proportion.
pub const WALL_FRACTION: f32 = 0.5;

/// Kernel half-width limit \[cells\].
const MAX_KERNEL: usize = 8;

/// A local, blurred copy of the returns the map holds.
#[derive(bytemuck::Zeroable)]
pub struct LikelihoodField<const T: usize> {
    /// Grid column and row of the window's cell (0, 0).
    col0: i32,
    row0: i32,
    width: usize,
    height: usize,
    resolution_m: f32,
    /// Map-frame position of the centre of the window's cell (0, 0) \[m\].
    first_center: Point2,
    values: [f32; T],
    /// The largest density within the kernel's reach of each cell (normalisation).
    peak: [f32; T],
    line: [f32; MAX_LINE],
}

impl<const T: usize> core::fmt::Debug for LikelihoodField<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("LikelihoodField")
            .field("col0", &self.col0)
            .field("row0", &self.row0)
            .field("width", &self.width)
            .field("height", &self.height)
            .finish_non_exhaustive()
    }
}

impl<const T: usize> Default for LikelihoodField<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const T: usize> LikelihoodField<T> {
    /// An empty field (build it with [`Self::build`]).
    pub const fn new() -> Self {
        Self {
            col0: 0,
            row0: 0,
            width: 0,
            height: 0,
            resolution_m: 1.0,
            first_center: Point2::new(0.0, 0.0),
            values: [0.0; T],
            peak: [0.0; T],
            line: [0.0; MAX_LINE],
        }
    }

    /// Columns of the window.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows of the window.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Cell side \[m\].
    pub fn resolution_m(&self) -> f32 {
        self.resolution_m
    }

    /// The values, row-major, row 0 south.
    pub fn values(&self) -> &[f32] {
        &self.values[..self.width * self.height]
    }

    /// The columns and rows of a window over the cells covering `lo..=hi` (map frame \[m\])
    /// of `geom`, or `None` when [`Self::build`] would refuse it: no cell, more than `T`
    /// cells or a line longer than [`MAX_LINE`].
    pub fn window_size(geom: &GridGeometry, lo: Point2, hi: Point2) -> Option<(usize, usize)> {
        let a = geom.cell_at_unchecked(lo);
        let b = geom.cell_at_unchecked(hi);
        let width = (b.col - a.col + 1).max(0) as usize;
        let height = (b.row - a.row + 1).max(0) as usize;
        (width != 0 && height != 0 && width * height <= T && width.max(height) <= MAX_LINE)
            .then_some((width, height))
    }

    /// Builds the field over the cells covering `lo..=hi` (map frame \[m\]) from the returns
    /// in `hits`, blurred by `sigma_m`, wall cells at `wall_fraction` of the local peak
    /// ([`WALL_FRACTION`]), by a sum before the normalisation when `smooth` (else by a maximum
    /// after). Cells outside the grid hold nothing. Returns `false`, leaving the field
    /// empty, when the window needs more than `T` cells or a line longer than [`MAX_LINE`].
    pub fn build<const N: usize>(
        &mut self,
        hits: &HitMap<N>,
        lo: Point2,
        hi: Point2,
        sigma_m: f32,
        wall_fraction: f32,
        smooth: bool,
    ) -> bool {
        let geom = *hits.geometry();
        self.width = 0;
        self.height = 0;
        let Some((width, height)) = Self::window_size(&geom, lo, hi) else {
            return false;
        };
        let a = geom.cell_at_unchecked(lo);
        self.col0 = a.col;
        self.row0 = a.row;
        self.width = width;
        self.height = height;
        self.resolution_m = geom.resolution_m;
        self.first_center = geom.cell_center(a);

        // Weight of returns in every window cell.
        for r in 0..height {
            let row = a.row + r as i32;
            let out = &mut self.values[r * width..(r + 1) * width];
            if row < 0 || row as usize >= geom.height {
                out.fill(0.0);
                continue;
            }
            for (c, v) in out.iter_mut().enumerate() {
                let col = a.col + c as i32;
                *v = if col < 0 || col as usize >= geom.width {
                    0.0
                } else {
                    hits.weight_at(row as usize * geom.width + col as usize)
                };
            }
        }

        let reach =
            (math::ceil(2.0 * sigma_m / geom.resolution_m).max(0.0) as usize).min(MAX_KERNEL);
        let mut kernel = [0.0f32; MAX_KERNEL + 1];
        for (k, w) in kernel.iter_mut().enumerate().take(reach + 1) {
            let d = k as f32 * geom.resolution_m;
            *w = math::exp(-d * d / (2.0 * sigma_m * sigma_m));
        }
        let kernel = &kernel[..=reach];
        let flat = [1.0f32; MAX_KERNEL + 1];
        let flat = &flat[..=reach];
        let mut floor = FLOOR_M_PER_CELL * geom.resolution_m;

        if smooth {
            // The density of returns: a Gaussian sum-blur (a kernel density estimate), whose
            // ridge is smooth and sits on the wall's mean line.
            let total: f32 = kernel[0] + 2.0 * kernel[1..].iter().sum::<f32>();
            let mut unit = [0.0f32; MAX_KERNEL + 1];
            for (u, k) in unit.iter_mut().zip(kernel) {
                *u = k / total;
            }
            let unit = &unit[..=reach];
            floor *= unit[0];
            for r in 0..height {
                let span = r * width..(r + 1) * width;
                sum_filter(&self.values[span.clone()], &mut self.peak[span], 1, unit);
            }
            for c in 0..width {
                for r in 0..height {
                    self.line[r] = self.peak[r * width + c];
                }
                sum_filter(&self.line[..height], &mut self.values[c..], width, unit);
            }
        }

        // Each cell's weight relative to the largest within the reach, capped: 1 over
        // a wall's band of returns however often each part of it was seen (no slope along
        // the wall), less on the band's edges.
        for r in 0..height {
            let span = r * width..(r + 1) * width;
            max_filter(&self.values[span.clone()], &mut self.peak[span], 1, flat);
        }
        for c in 0..width {
            for r in 0..height {
                self.line[r] = self.peak[r * width + c];
            }
            max_filter(&self.line[..height], &mut self.peak[c..], width, flat);
        }
        for (v, &p) in self.values[..width * height]
            .iter_mut()
            .zip(&self.peak[..width * height])
        {
            *v = (*v / (wall_fraction * p.max(floor))).min(1.0);
        }
        if smooth {
            return true;
        }

        // The separable max-convolution with a Gaussian of σ, cut at 2σ.
        for r in 0..height {
            let row = &mut self.values[r * width..(r + 1) * width];
            self.line[..width].copy_from_slice(row);
            max_filter(&self.line[..width], row, 1, kernel);
        }
        for c in 0..width {
            for r in 0..height {
                self.line[r] = self.values[r * width + c];
            }
            max_filter(&self.line[..height], &mut self.values[c..], width, kernel);
        }
        true
    }

    /// Window coordinates of a map point, in cells, with cell centres at whole numbers.
    #[inline]
    pub fn to_window(&self, p: Point2) -> (f32, f32) {
        let inv = 1.0 / self.resolution_m;
        (
            (p.x - self.first_center.x) * inv,
            (p.y - self.first_center.y) * inv,
        )
    }

    /// The bilinearly interpolated value at a map point and its gradient \[1/m\]; zero outside
    /// the window.
    #[inline]
    pub fn sample(&self, p: Point2) -> (f32, f32, f32) {
        let (u, v) = self.to_window(p);
        let (fu, fv) = (math::floor(u), math::floor(v));
        let (iu, iv) = (fu as i32, fv as i32);
        if iu < 0 || iv < 0 || iu as usize + 1 >= self.width || iv as usize + 1 >= self.height {
            return (0.0, 0.0, 0.0);
        }
        let (du, dv) = (u - fu, v - fv);
        let i = iv as usize * self.width + iu as usize;
        let (m00, m10) = (self.values[i], self.values[i + 1]);
        let (m01, m11) = (self.values[i + self.width], self.values[i + self.width + 1]);
        let value = (1.0 - dv) * ((1.0 - du) * m00 + du * m10) + dv * ((1.0 - du) * m01 + du * m11);
        let inv = 1.0 / self.resolution_m;
        let gx = ((1.0 - dv) * (m10 - m00) + dv * (m11 - m01)) * inv;
        let gy = ((1.0 - du) * (m01 - m00) + du * (m11 - m10)) * inv;
        (value, gx, gy)
    }

    /// The value at a map point and its gradient \[1/m\], interpolated between cell centres
    /// by cubic convolution (Keys, *Cubic convolution interpolation for digital image
    /// processing*, IEEE Trans. ASSP 29(6), 1981, with a = -0.5, the Catmull-Rom spline);
    /// zero outside the window. Bilinear interpolation, as Hector's, is flat between two equal
    /// cells: the ridge of a wall lying on a cell border (every wall of a map drawn on the
    /// grid) would be a plateau a cell wide, and a scan could slide across it by ±half a cell.
    /// The cubic puts the ridge's maximum where the samples place it, with a continuous slope.
    /// (Measured with `examples/localize_open.rs`, not yet used by the matcher: see
    /// docs/experiments.md.)
    #[inline]
    pub fn sample_cubic(&self, p: Point2) -> (f32, f32, f32) {
        let (u, v) = self.to_window(p);
        let (fu, fv) = (math::floor(u), math::floor(v));
        let (iu, iv) = (fu as i32, fv as i32);
        if iu < 1 || iv < 1 || iu as usize + 2 >= self.width || iv as usize + 2 >= self.height {
            return (0.0, 0.0, 0.0);
        }
        let (wu, du) = cubic_weights(u - fu);
        let (wv, dv) = cubic_weights(v - fv);
        let (mut value, mut gx, mut gy) = (0.0f32, 0.0f32, 0.0f32);
        let base = (iv as usize - 1) * self.width + iu as usize - 1;
        for j in 0..4 {
            let row = &self.values[base + j * self.width..base + j * self.width + 4];
            let (mut r, mut dr) = (0.0f32, 0.0f32);
            for i in 0..4 {
                r += wu[i] * row[i];
                dr += du[i] * row[i];
            }
            value += wv[j] * r;
            gx += wv[j] * dr;
            gy += dv[j] * r;
        }
        let inv = 1.0 / self.resolution_m;
        (value, gx * inv, gy * inv)
    }
}

/// The four weights of Catmull-Rom cubic convolution at fraction `t` (0..1) past the second
/// sample, and their derivatives in `t`.
#[inline]
fn cubic_weights(t: f32) -> ([f32; 4], [f32; 4]) {
    let (t2, t3) = (t * t, t * t * t);
    (
        [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ],
        [
            0.5 * (-3.0 * t2 + 4.0 * t - 1.0),
            0.5 * (9.0 * t2 - 10.0 * t),
            0.5 * (-9.0 * t2 + 8.0 * t + 1.0),
            0.5 * (3.0 * t2 - 2.0 * t),
        ],
    )
}

/// `out[i·stride] = Σ_k src[i + k] · kernel[|k|]` for `|k| <= reach`, splatting the non-zero
/// source cells.
fn sum_filter(src: &[f32], out: &mut [f32], stride: usize, kernel: &[f32]) {
    let reach = kernel.len() - 1;
    let n = src.len();
    for i in 0..n {
        out[i * stride] = 0.0;
    }
    for (j, &s) in src.iter().enumerate() {
        if s <= 0.0 {
            continue;
        }
        let lo = j.saturating_sub(reach);
        let hi = (j + reach).min(n - 1);
        for i in lo..=hi {
            out[i * stride] += s * kernel[i.abs_diff(j)];
        }
    }
}

/// `out[i·stride] = max_k src[i + k] · kernel[|k|]` for `|k| <= reach`, splatting each
/// non-zero source cell onto its neighbours (most of a window holds no return, so this costs
/// in proportion to the walls, not to the window).
fn max_filter(src: &[f32], out: &mut [f32], stride: usize, kernel: &[f32]) {
    let reach = kernel.len() - 1;
    let n = src.len();
    for i in 0..n {
        out[i * stride] = 0.0;
    }
    for (j, &s) in src.iter().enumerate() {
        if s <= 0.0 {
            continue;
        }
        let lo = j.saturating_sub(reach);
        let hi = (j + reach).min(n - 1);
        for i in lo..=hi {
            let v = s * kernel[i.abs_diff(j)];
            let o = &mut out[i * stride];
            if v > *o {
                *o = v;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridGeometry;

    #[test]
    fn a_single_return_blurs_into_a_peak_with_a_smooth_slope() {
        let geom = GridGeometry::new(20, 20, 0.1, Point2::new(0.0, 0.0)).unwrap();
        let mut hits = HitMap::<400>::new(geom);
        hits.add_point(Point2::new(1.05, 1.05), 0.3);
        let mut f = LikelihoodField::<400>::new();
        assert!(f.build(
            &hits,
            Point2::new(0.0, 0.0),
            Point2::new(1.99, 1.99),
            0.1,
            WALL_FRACTION,
            false
        ));
        let centre = Point2::new(1.05, 1.05);
        let (v, _, _) = f.sample(centre);
        assert!((v - 1.0).abs() < 1e-6);
        // One cell away: exp(-0.5).
        let (v1, gx1, _) = f.sample(Point2::new(1.15, 1.05));
        assert!((v1 - (-0.5f32).exp()).abs() < 1e-4, "{v1}");
        // Halfway between: interpolated, and the slope points back to the return.
        let (vh, gxh, _) = f.sample(Point2::new(1.10, 1.05));
        assert!(vh < 1.0 && vh > v1);
        assert!(gxh < 0.0 && gx1 < 0.0);
        // Three cells away: beyond 2σ.
        assert_eq!(f.sample(Point2::new(1.35, 1.05)).0, 0.0);
    }

    #[test]
    fn the_ridge_of_returns_on_a_cell_border_is_on_the_border() {
        // A wall along y = 1.0 (a border between rows 9 and 10), seen as returns on it: the
        // field is symmetric about it, so a point on it sits on the ridge.
        let geom = GridGeometry::new(20, 20, 0.1, Point2::new(0.0, 0.0)).unwrap();
        let mut hits = HitMap::<400>::new(geom);
        for k in 0..80 {
            hits.add_point(Point2::new(0.6 + 0.01 * k as f32, 1.0), 0.01);
        }
        let mut f = LikelihoodField::<400>::new();
        assert!(f.build(
            &hits,
            Point2::new(0.0, 0.0),
            Point2::new(1.99, 1.99),
            0.1,
            WALL_FRACTION,
            false
        ));
        let below = f.sample(Point2::new(1.0, 0.96)).0;
        let above = f.sample(Point2::new(1.0, 1.04)).0;
        assert!((below - above).abs() < 1e-4, "{below} vs {above}");
        assert!(f.sample(Point2::new(1.0, 1.0)).0 >= below);
    }

    #[test]
    fn a_window_larger_than_the_capacity_is_refused() {
        let geom = GridGeometry::new(20, 20, 0.1, Point2::new(0.0, 0.0)).unwrap();
        let hits = HitMap::<400>::new(geom);
        let mut f = LikelihoodField::<100>::new();
        assert!(!f.build(
            &hits,
            Point2::new(0.0, 0.0),
            Point2::new(1.99, 1.99),
            0.1,
            WALL_FRACTION,
            false
        ));
        assert_eq!(f.width(), 0);
    }
}
