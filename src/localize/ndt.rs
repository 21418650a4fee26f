//! Point-to-line refinement of a scan's pose against the per-cell return statistics of the map
//! ([`super::hits::HitMap::surface_at`]).
//!
//! The map is a normal distributions transform (Biber & Straßer, *The normal distributions
//! transform: a new approach to laser scan matching*, IROS 2003): per cell the mean and spread of
//! the returns written there. Each return of the scan, placed at the current pose, is paired with
//! the surface of the block of cells around it, and its residual is its distance to the line
//! through the block's mean along its major axis, `r = n · (q - μ)`: the point-to-line metric of
//! Censi's PLICP (*An ICP variant using a point-to-line metric*, ICRA 2008), which is as precise
//! as the mean, a fraction of the range noise, whatever the cell size and wherever a wall lies
//! against the cells (a bilinear field on 10 cm cells was flat over a cell on every wall,
//! docs/experiments.md, fourth measurement).
//!
//! Each residual is weighted by the inverse of its variance (the return's range noise, the
//! block's thickness net of noise, and the uncertainty of the block's mean), with Huber's robust
//! kernel (Huber, *Robust estimation of a location parameter*, 1964) and a hard gate for the
//! returns that land on no known surface or on the wrong one. Each iteration re-pairs the
//! returns and solves the weighted least squares for `(x, y, θ)`, stepping only along the
//! eigen-directions of the information the scan constrains (Zhang, Kaess & Singh, *On
//! degeneracy of optimization-based state estimation problems*, ICRA 2016; [`Constraint`]).
//! The information at the end, `H = Σ w Jᵀ J` in `1/m²`, is the inverse covariance of the fit.

use nalgebra::{Matrix3, Vector3};

use crate::geometry::{Point2, Pose2};
use crate::math;

use super::constraint::Constraint;
use super::hits::{HitMap, Surface};

/// Settings of the refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NdtConfig {
    /// Half-width of the block of cells a return is paired with \[cells\] (2: 5 x 5).
    pub block_half_cells: i32,
    /// A block weighing less than this (a return with 1 cm of noise weighs 1) is no surface.
    pub min_block_weight: f32,
    /// A block whose spread across is more than this fraction of its spread along is no line
    /// (a corner, a clutter of returns).
    pub max_thickness_ratio: f32,
    /// A return's range noise counts as at least this \[m\] in its weight (the block's mean
    /// keeps the returns layer's own floor, [`super::hits::SIGMA_FLOOR_M`]). At the default
    /// 1 cm a precise laser's near returns (0.3 % of 3 m is 9 mm) all weigh alike; 1 mm
    /// weighs them by their noise (docs/experiments.md, ninth measurement: better with exact
    /// odometry, worse with the realistic one; not the default).
    pub sigma_floor_m: f32,
    /// Range noise as a fraction of the range (the laser's).
    pub noise_fraction: f32,
    /// Huber's threshold on the normalised residual.
    pub huber_k: f32,
    /// Returns whose normalised residual is beyond this are left out.
    pub gate: f32,
    /// Iterations at most.
    pub iterations: u32,
    /// Length that turns a rotation into a distance \[m\].
    pub length_scale_m: f32,
    /// A direction is constrained when the fit pins it to this standard deviation or better
    /// \[m\] ...
    pub max_sigma_m: f32,
    /// ... and its information is at least this fraction of the strongest direction's. 1 %:
    /// at 2 % a direction a house's walls pin to a few millimetres, beside a heading held by
    /// walls 3–4 m away, was left to the odometry (docs/experiments.md, "seed 34's turned
    /// map"); on the house's 200 seeds with the realistic odometry 1 % took the maps at 97 %
    /// accuracy from 157 to 175 and the missions at 99 % coverage from 183 to 196
    /// ("Issue 18: the information ratio at 1 %").
    pub min_information_ratio: f32,
    /// The information a surface's normal, tilted by this many of its standard deviations
    /// ([`super::hits::Surface::normal_var_rad2`]), would fake along the surface is taken
    /// off each return's.
    pub normal_sigmas: f32,
    /// A block whose normal is known worse than this is no line \[rad\] (a block seen by a
    /// few far returns: taking off what its normal could fake would leave less than nothing).
    pub max_normal_sigma_rad: f32,
    /// The gate starts this wide \[m\] and halves every iteration down to
    /// [`Self::gate`] standard deviations (0: no annealing). A prediction a degree off puts
    /// the far returns of a precise laser centimetres off their walls, beyond a 4 σ gate,
    /// and the fit from the near returns alone then pins the heading poorly; a wide gate at
    /// first lets every return pull (with Huber's weight) toward the basin, the narrow one
    /// at the end keeps the result precise (the graduated gates of robust ICP: Zhang,
    /// *Iterative point matching for registration of free-form curves*, IJCV 1994). An
    /// experiment, off: measured no better (docs/experiments.md, seventh measurement).
    pub anneal_gate_m: f32,
}

impl Default for NdtConfig {
    /// Blocks of 5 x 5 cells weighing at least 0.1 (their mean known to 3 cm) and at most 10 %
    /// as thick as long, noise at
    /// least 1 cm (the laser's fraction set by the matcher), Huber at 2 σ, gate at 4 σ,
    /// 12 iterations, L = 1 m; a direction pinned to 10 cm or better and at least 1 % of the
    /// strongest is constrained; blocks whose normal is known to worse than 0.2 rad left
    /// out, and the information a normal tilted by 2 σ would fake taken off.
    fn default() -> Self {
        Self {
            block_half_cells: 2,
            min_block_weight: 0.1,
            max_thickness_ratio: 0.1,
            sigma_floor_m: super::hits::SIGMA_FLOOR_M,
            noise_fraction: 0.0,
            huber_k: 2.0,
            gate: 4.0,
            iterations: 12,
            length_scale_m: 1.0,
            max_sigma_m: 0.1,
            min_information_ratio: 0.01,
            normal_sigmas: 2.0,
            max_normal_sigma_rad: 0.2,
            anneal_gate_m: 0.0,
        }
    }
}

/// The refined pose and what the fit knows about it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fitted {
    /// The pose \[m, rad\].
    pub pose: Pose2,
    /// `Σ w Jᵀ J` at the pose in `(x, y, θ·L)` \[1/m²\], net of what the normals'
    /// uncertainty fakes.
    pub information: Matrix3<f64>,
    /// The position block a position direction is judged by ([`Constraint::analyse`]): the
    /// information net of what normals tilted by [`NdtConfig::normal_sigmas`] would fake.
    pub position_test: Matrix3<f64>,
    /// Returns paired with a surface within the gate at the pose.
    pub inliers: u32,
    /// Iterations run.
    pub iterations: u32,
}

/// `H - (k² - 1) F` in `(x, y, θ·L)`: the information net of `k` standard deviations of
/// tilt (`H` is already net of one).
fn position_test(lin: &Linearised, scale: &Matrix3<f64>, config: &NdtConfig) -> Matrix3<f64> {
    let k2 = (config.normal_sigmas * config.normal_sigmas) as f64;
    scale * (lin.h - (k2 - 1.0).max(0.0) * lin.fake) * scale
}

/// Largest translation of one step \[m\] and largest rotation \[rad\].
const MAX_STEP_M: f32 = 0.1;
const MAX_STEP_RAD: f32 = 0.05;

/// Refines `start` for `points` (robot frame \[m\]; the laser at `origin` in the robot frame)
/// against `hits`.
pub fn refine<const N: usize>(
    hits: &HitMap<N>,
    points: &[Point2],
    origin: Point2,
    start: Pose2,
    config: &NdtConfig,
) -> Fitted {
    let l = config.length_scale_m.max(1e-3) as f64;
    let scale = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 1.0 / l));
    let mut pose = start;
    let mut wide = config.anneal_gate_m.max(0.0);
    let mut memo = SurfaceMemo::new();
    let mut lin = linearise(hits, &mut memo, points, origin, pose, config, wide);
    let mut taken = 0;
    let min_eig = 1.0 / (config.max_sigma_m.max(1e-6) * config.max_sigma_m.max(1e-6));
    for _ in 0..config.iterations {
        let h = scale * lin.h * scale;
        let g = scale * lin.g;
        let c = Constraint::analyse(
            &h,
            &position_test(&lin, &scale, config),
            min_eig,
            config.min_information_ratio,
        );
        let mut step_scaled = Vector3::zeros();
        for k in 0..3 {
            if c.constrained[k] {
                let v = Vector3::from(c.directions[k]).cast::<f64>();
                step_scaled -= v * (v.dot(&g) / c.eigenvalues[k] as f64);
            }
        }
        if step_scaled == Vector3::zeros() {
            break;
        }
        let step = scale * step_scaled;
        let (mut dx, mut dy, mut dth) = (step[0] as f32, step[1] as f32, step[2] as f32);
        let t = math::hypot(dx, dy);
        if t > MAX_STEP_M {
            dx *= MAX_STEP_M / t;
            dy *= MAX_STEP_M / t;
        }
        dth = dth.clamp(-MAX_STEP_RAD, MAX_STEP_RAD);
        pose = Pose2::new(pose.x + dx, pose.y + dy, pose.theta + dth);
        taken += 1;
        wide *= 0.5;
        if wide < 0.01 {
            wide = 0.0;
        }
        lin = linearise(hits, &mut memo, points, origin, pose, config, wide);
        if wide == 0.0 && math::hypot(dx, dy) < 1e-4 && math::abs(dth) < 2e-5 {
            break;
        }
    }
    if wide > 0.0 {
        lin = linearise(hits, &mut memo, points, origin, pose, config, 0.0);
    }
    Fitted {
        pose,
        position_test: position_test(&lin, &scale, config),
        information: scale * lin.h * scale,
        inliers: lin.inliers,
        iterations: taken,
    }
}

struct Linearised {
    /// `Σ w (j jᵀ - σ_φ² jₜ jₜᵀ)`.
    h: Matrix3<f64>,
    /// `Σ w σ_φ² jₜ jₜᵀ`: the information one standard deviation of tilt fakes.
    fake: Matrix3<f64>,
    g: Vector3<f64>,
    inliers: u32,
}

/// `H = Σ w Jᵀ J` and `g = Σ w Jᵀ r` of the point-to-line residuals at `pose` (the rotation
/// about the robot's position).
fn linearise<const N: usize>(
    hits: &HitMap<N>,
    memo: &mut SurfaceMemo,
    points: &[Point2],
    origin: Point2,
    pose: Pose2,
    config: &NdtConfig,
    wide_gate_m: f32,
) -> Linearised {
    let (s, c) = (math::sin(pose.theta), math::cos(pose.theta));
    let (mut h00, mut h01, mut h02, mut h11, mut h12, mut h22) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut f00, mut f01, mut f02, mut f11, mut f12, mut f22) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut g0, mut g1, mut g2) = (0.0f64, 0.0f64, 0.0f64);
    let mut inliers = 0;
    for p in points {
        let (rx, ry) = (c * p.x - s * p.y, s * p.x + c * p.y);
        let q = Point2::new(pose.x + rx, pose.y + ry);
        let Some(surface) = memo.surface_at(hits, q, config) else {
            continue;
        };
        if surface.across_var_m2 > config.max_thickness_ratio * surface.along_var_m2
            || surface.normal_var_rad2 > config.max_normal_sigma_rad * config.max_normal_sigma_rad
        {
            continue;
        }
        let range = math::hypot(p.x - origin.x, p.y - origin.y);
        let sigma = (config.noise_fraction * range).max(config.sigma_floor_m);
        // The block's mean is known to `σ_floor / √W` (the layer's weights are
        // `(σ_floor / σ)²` with its own floor, whatever the fit's).
        let floor2 = super::hits::SIGMA_FLOOR_M * super::hits::SIGMA_FLOOR_M;
        let var = sigma * sigma + surface.across_var_m2 + floor2 / surface.weight;
        let n = surface.normal;
        let r = n.x * (q.x - surface.mean.x) + n.y * (q.y - surface.mean.y);
        let z = math::abs(r) / math::sqrt(var);
        if z.is_nan() || (z > config.gate && math::abs(r) > wide_gate_m) {
            continue;
        }
        inliers += 1;
        let robust = if z <= config.huber_k {
            1.0
        } else {
            config.huber_k / z
        };
        let w = (robust / var) as f64;
        let j = [n.x as f64, n.y as f64, (n.y * rx - n.x * ry) as f64];
        // The normal is known to `σ_φ` ([`super::hits::Surface::normal_var_rad2`]): tilted
        // by `δ`, the return's Jacobian gains `δ jₜ`, `jₜ` the Jacobian along the surface's
        // tangent, so `E[j jᵀ]` holds `σ_φ² jₜ jₜᵀ` of information along the surface that no
        // surface gives. It is taken off (the bias of a sample's second moment, removed as
        // the range noise is in the map's statistics): along a corridor the walls then give
        // none, and the axis stays with the odometry (Zhang, Kaess & Singh 2016: a direction
        // is constrained only by information the measurements really hold).
        let phi2 = (surface.normal_var_rad2 as f64).min(1.0);
        let (tx, ty) = (-n.y, n.x);
        let jt = [tx as f64, ty as f64, (ty * rx - tx * ry) as f64];
        let r = r as f64;
        h00 += w * j[0] * j[0];
        h01 += w * j[0] * j[1];
        h02 += w * j[0] * j[2];
        h11 += w * j[1] * j[1];
        h12 += w * j[1] * j[2];
        h22 += w * j[2] * j[2];
        let wf = w * phi2;
        f00 += wf * jt[0] * jt[0];
        f01 += wf * jt[0] * jt[1];
        f02 += wf * jt[0] * jt[2];
        f11 += wf * jt[1] * jt[1];
        f12 += wf * jt[1] * jt[2];
        f22 += wf * jt[2] * jt[2];
        g0 += w * j[0] * r;
        g1 += w * j[1] * r;
        g2 += w * j[2] * r;
    }
    let fake = Matrix3::new(f00, f01, f02, f01, f11, f12, f02, f12, f22);
    Linearised {
        h: Matrix3::new(h00, h01, h02, h01, h11, h12, h02, h12, h22) - fake,
        fake,
        g: Vector3::new(g0, g1, g2),
        inliers,
    }
}

/// Slots of [`SurfaceMemo`]'s table: twice its entries, so that probes stay short.
const MEMO_SLOTS: usize = 1024;
/// Blocks [`SurfaceMemo`] remembers; past them it computes each block again.
const MEMO_ENTRIES: usize = MEMO_SLOTS / 2;

/// The blocks' surfaces of one fit, by the cell at their centre. A block's surface depends
/// only on that cell (and the fit's settings), and the map does not change during a fit,
/// while the fit pairs the scan's returns again at every iteration, mostly with the same
/// cells: each is worked out once (the same arithmetic, so the same surface to the bit).
/// Open addressing with linear probing, on the stack of the fit.
struct SurfaceMemo {
    /// Per slot, 1 + the index in `entries` of the block hashed there; 0: empty.
    slots: [u16; MEMO_SLOTS],
    /// The blocks met: the centre cell's flat index and its surface.
    entries: heapless::Vec<(usize, Option<Surface>), MEMO_ENTRIES>,
}

impl SurfaceMemo {
    fn new() -> Self {
        Self {
            slots: [0; MEMO_SLOTS],
            entries: heapless::Vec::new(),
        }
    }

    /// [`HitMap::surface_at`] for the block around the cell holding `q`, with `config`'s
    /// block size and weight.
    fn surface_at<const N: usize>(
        &mut self,
        hits: &HitMap<N>,
        q: Point2,
        config: &NdtConfig,
    ) -> Option<Surface> {
        let compute = || hits.surface_at(q, config.block_half_cells, config.min_block_weight);
        let g = hits.geometry();
        let Some(cell) = g.index(g.cell_at_unchecked(q)) else {
            // Off the grid: no surface, and nothing to remember.
            return compute();
        };
        // Fibonacci hashing (Knuth, TAOCP vol. 3, §6.4) of the flat index.
        let mut slot = (cell as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) as usize >> 54;
        for _ in 0..MEMO_SLOTS {
            match self.slots[slot] {
                0 => {
                    let surface = compute();
                    if self.entries.push((cell, surface)).is_ok() {
                        self.slots[slot] = self.entries.len() as u16;
                    }
                    return surface;
                }
                k => {
                    let (key, surface) = self.entries[usize::from(k) - 1];
                    if key == cell {
                        return surface;
                    }
                }
            }
            slot = (slot + 1) % MEMO_SLOTS;
        }
        compute()
    }
}
