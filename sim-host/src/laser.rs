//! Laser rangefinder simulation by ray casting against the true world.
//!
//! Each beam is traced cell by cell with the exact grid traversal of Amanatides & Woo ("A Fast
//! Voxel Traversal Algorithm for Ray Tracing", Eurographics 1987): the ray visits every cell it
//! crosses, in order, and the range is the distance to where it enters the first blocked cell
//! (cells outside the grid count as blocked, so the world's edge is a wall). Other robots and
//! people are discs, hit by ray–circle intersection; a disc that contains the laser is ignored,
//! so passing every robot including the scanning one is harmless.
//!
//! The beam layout, usable range, blind zone, mount offset and noise come from a
//! [`LaserConfig`]. A return beyond `max_range_m` is no return (`None`). A return closer than
//! the blind zone is reported as measured: the consumer ignores readings below `min_range_m`,
//! as it must with a real laser. With noise on, each range gets Gaussian noise of standard
//! deviation `noise_fraction · range` (the thesis's 5 %), from the simulator's own seeded RNG;
//! [`LaserSim::with_range_sigma_m`] adds a part that does not grow with the range, in
//! quadrature: `σ = √((noise_fraction · range)² + range_sigma_m²)`. A real time-of-flight laser's
//! statistical error is mostly that constant part (SICK gives a typical 12 mm, 1 σ, for the
//! LMS1xx over its whole range: SICK support, "Measurement Errors LMSxxx"), where the
//! fraction alone makes a laser precise near and noisy far.

use papillon::geometry::{Point2, Pose2};
use papillon::grid::Cell;
use papillon::math;
use papillon::random::{self, ProjectRng};
use papillon::sensor::{Beam, LaserConfig, Scan, ScanError};

use crate::physics::Disc;
use crate::world::World;
use crate::world::clearance::Clearance;

/// Distance \[m\] from `origin` along the unit direction `(cos, sin)` of `angle_rad` to the first
/// blocked cell, if within `max_range_m`. A ray starting in a blocked cell returns 0.
pub fn cast_ray(world: &World, origin: Point2, angle_rad: f32, max_range_m: f32) -> Option<f32> {
    let (dx, dy) = (math::cos(angle_rad), math::sin(angle_rad));
    cast_ray_along(world, origin, dx, dy, max_range_m)
}

/// [`cast_ray`] along the unit direction `(dx, dy)` = `(cos, sin)` of the beam's angle.
fn cast_ray_along(
    world: &World,
    origin: Point2,
    dx: f32,
    dy: f32,
    max_range_m: f32,
) -> Option<f32> {
    let g = world.geometry();
    let r = g.resolution_m;
    // Work in cell units from the grid origin.
    let (px, py) = ((origin.x - g.origin.x) / r, (origin.y - g.origin.y) / r);
    let cell = Cell::new(math::floor(px) as i32, math::floor(py) as i32);
    if world.is_blocked(cell) {
        return Some(0.0);
    }
    let max_t = max_range_m / r;
    let (step_x, step_y) = (if dx > 0.0 { 1 } else { -1 }, if dy > 0.0 { 1 } else { -1 });
    let next_boundary = |p: f32, d: f32, c: i32| {
        if d > 0.0 {
            ((c + 1) as f32 - p) / d
        } else if d < 0.0 {
            (c as f32 - p) / d
        } else {
            f32::INFINITY
        }
    };
    let t_max_x = next_boundary(px, dx, cell.col);
    let t_max_y = next_boundary(py, dy, cell.row);
    let t_delta_x = if dx != 0.0 {
        1.0 / dx.abs()
    } else {
        f32::INFINITY
    };
    let t_delta_y = if dy != 0.0 {
        1.0 / dy.abs()
    } else {
        f32::INFINITY
    };
    // The walk keeps the cell's flat index along (the start cell is inside the grid, or it
    // would have counted as blocked); a cell outside the grid is blocked.
    let (width, height) = (g.width as i64, g.height as i64);
    let (col, row) = (cell.col as i64, cell.row as i64);
    // The k-th step along an axis happens at t >= k - 1 (a step takes at least one cell of
    // travel), so within the range the walk stays less than max_t + 2 cells from the start
    // cell along each axis: when that square lies inside the grid, no bounds check is needed.
    let reach = max_t.ceil() as i64 + 2;
    let inside = max_t.is_finite()
        && col - reach >= 0
        && col + reach < width
        && row - reach >= 0
        && row + reach < height;
    let walk = Walk {
        clearance: world.clearance(),
        width,
        height,
        step_x: step_x as i64,
        step_y: step_y as i64,
        t_delta_x,
        t_delta_y,
        max_t,
    };
    // The start cell is free: the walk first jumps over the open space around it. (Jumping
    // again from cells met along the way saved instructions but cost time: the extra branch
    // and the column and row it keeps in the loop; see docs/benchmarks.md.)
    let c = world.clearance().at_index((row * width + col) as usize);
    let (col, row, t_max_x, t_max_y) = walk.skip_open((col, row), c, 0.0, t_max_x, t_max_y);
    let t = if inside {
        walk.run::<false>(col, row, t_max_x, t_max_y)
    } else {
        walk.run::<true>(col, row, t_max_x, t_max_y)
    };
    t.map(|t| t * r)
}

/// A ray's walk through the world's cells, from one cell to the next across whichever grid
/// line the ray meets first.
struct Walk<'a> {
    /// Per cell, the chessboard distance to the nearest blocked cell or the grid's edge (0:
    /// blocked).
    clearance: &'a Clearance,
    width: i64,
    height: i64,
    step_x: i64,
    step_y: i64,
    /// Ray parameter \[cells\] between two vertical (horizontal) grid lines.
    t_delta_x: f32,
    t_delta_y: f32,
    /// The range \[cells\].
    max_t: f32,
}

/// Open space worth skipping: a cell at least this many cells from every blocked cell.
const SKIP_CLEARANCE: u8 = 5;

impl Walk<'_> {
    /// Jumps over the open space around the cell `(col, row)` the walk entered at ray
    /// parameter `t_entry` \[cells\] (0 for the start cell): when the cell's clearance `c` is
    /// large, every crossing up to `t_entry + c - 3` (and the range) leads into a free cell
    /// (a point within `c - 3` cells of the cell's entry point lies in a cell within `c - 2`
    /// cells of it, one cell kept for rounding), so the walk's state after them is known
    /// without looking at the cells: the crossings along each axis are counted up to there,
    /// added one by one exactly as [`Walk::run`] adds them. The walk processes crossings in
    /// increasing order whatever the other axis does, so the counts fix its cell; the result
    /// is the state [`Walk::run`] would reach, bit for bit. Returns the new cell and the next
    /// crossings along each axis.
    #[inline(always)]
    fn skip_open(
        &self,
        (col, row): (i64, i64),
        c: u8,
        t_entry: f32,
        mut t_max_x: f32,
        mut t_max_y: f32,
    ) -> (i64, i64, f32, f32) {
        if c < SKIP_CLEARANCE {
            return (col, row, t_max_x, t_max_y);
        }
        let until = (t_entry + f32::from(c - 3)).min(self.max_t);
        let (mut steps_x, mut steps_y) = (0i64, 0i64);
        while t_max_x <= until {
            t_max_x += self.t_delta_x;
            steps_x += 1;
        }
        while t_max_y <= until {
            t_max_y += self.t_delta_y;
            steps_y += 1;
        }
        (
            col + steps_x * self.step_x,
            row + steps_y * self.step_y,
            t_max_x,
            t_max_y,
        )
    }

    /// Ray parameter \[cells\] at which the walk from `(col, row)` enters the first blocked
    /// cell, or `None` past the range; `t_max_x` (`t_max_y`) is where it crosses the next
    /// vertical (horizontal) grid line. `CHECKED`: the walk may leave the grid, and leaving it
    /// counts as entering a blocked cell; each step checks only the axis it moved along.
    #[inline(always)]
    fn run<const CHECKED: bool>(
        &self,
        mut col: i64,
        mut row: i64,
        mut t_max_x: f32,
        mut t_max_y: f32,
    ) -> Option<f32> {
        let mut index = row * self.width + col;
        let index_step_y = self.step_y * self.width;
        // Each branch finishes its own step (rather than sharing the test of the new cell), so
        // the crossing times stay in their registers.
        loop {
            if t_max_x < t_max_y {
                let t = t_max_x;
                if t > self.max_t {
                    return None;
                }
                col += self.step_x;
                index += self.step_x;
                if CHECKED && !(0..self.width).contains(&col) {
                    return Some(t);
                }
                let c = self.clearance.at_index(index as usize);
                if c == 0 {
                    return Some(t);
                }
                t_max_x += self.t_delta_x;
            } else {
                let t = t_max_y;
                if t > self.max_t {
                    return None;
                }
                row += self.step_y;
                index += index_step_y;
                if CHECKED && !(0..self.height).contains(&row) {
                    return Some(t);
                }
                let c = self.clearance.at_index(index as usize);
                if c == 0 {
                    return Some(t);
                }
                t_max_y += self.t_delta_y;
            }
        }
    }
}

/// Distance \[m\] along the unit direction `(dx, dy)` from `origin` to the disc's boundary, if the
/// ray hits it ahead; `None` when it misses or when the origin is inside the disc.
pub fn ray_disc(origin: Point2, dx: f32, dy: f32, disc: &Disc) -> Option<f32> {
    let (ox, oy) = (origin.x - disc.center.x, origin.y - disc.center.y);
    let c = ox * ox + oy * oy - disc.radius_m * disc.radius_m;
    if c <= 0.0 {
        return None;
    }
    let b = ox * dx + oy * dy;
    if b >= 0.0 {
        return None;
    }
    let disc2 = b * b - c;
    if disc2 < 0.0 {
        return None;
    }
    Some(-b - disc2.sqrt())
}

/// A simulated laser rangefinder with its own seeded noise generator.
#[derive(Clone, Debug)]
pub struct LaserSim {
    config: LaserConfig,
    rng: ProjectRng,
    noise: bool,
    /// The range noise's part that does not grow with the range \[m\] (1 σ): see
    /// [`Self::with_range_sigma_m`].
    range_sigma_m: f32,
    /// How far the beams reach \[m\] (at least `config.max_range_m`): see
    /// [`Self::with_reach_m`].
    reach_m: f32,
    /// Each beam's direction and nearest return of the scan in progress (kept between scans
    /// so that a scan does not allocate).
    beams: Vec<BeamWork>,
}

/// One beam of the scan in progress: its unit direction and its nearest return so far.
#[derive(Clone, Copy, Debug)]
struct BeamWork {
    dx: f32,
    dy: f32,
    range: Option<f32>,
}

/// Pad \[rad\] on the half-angle a disc subtends when choosing the beams to test against it:
/// far more than the rounding of the beams' angles and directions (about 1e-6 rad), so no beam
/// that hits is left out; a beam let in that misses is rejected by [`ray_disc`].
const DISC_ANGLE_PAD_RAD: f32 = 1e-3;

/// The beams (indices into `0..count`) whose direction can meet `disc`, seen from `origin`
/// by a fan whose beam `i` points at `first_rad + i * step_rad`: up to three runs (the fan may
/// come round to the disc's bearing again), possibly overlapping; all beams when the disc is
/// close (it subtends more than a right angle) or any input is not finite. Every beam that
/// [`ray_disc`] finds a hit for is in a run (it meets the disc within its subtended angle).
fn beams_toward(
    origin: Point2,
    disc: &Disc,
    first_rad: f32,
    step_rad: f32,
    count: usize,
) -> [core::ops::Range<usize>; 3] {
    let all = [0..count, 0..0, 0..0];
    let (ox, oy) = (disc.center.x - origin.x, disc.center.y - origin.y);
    let dist = (ox * ox + oy * oy).sqrt();
    let sin_half = disc.radius_m / dist;
    let usable = sin_half.is_finite()
        && sin_half < core::f32::consts::FRAC_1_SQRT_2
        && step_rad.is_finite()
        && step_rad > 0.0
        && first_rad.abs() <= 64.0;
    if !usable {
        return all;
    }
    let half = sin_half.asin() + DISC_ANGLE_PAD_RAD;
    let tau = core::f32::consts::TAU;
    let v = (oy.atan2(ox) - first_rad).rem_euclid(tau);
    if !v.is_finite() {
        return all;
    }
    [-tau, 0.0, tau].map(|shift| {
        let (lo, hi) = ((v + shift - half) / step_rad, (v + shift + half) / step_rad);
        if hi < 0.0 || lo >= count as f32 {
            return 0..0;
        }
        let lo = lo.max(0.0).ceil() as usize;
        let hi = (hi.floor() as usize).min(count.saturating_sub(1));
        lo..(hi + 1).max(lo)
    })
}

impl LaserSim {
    /// A laser described by `config`, with range noise (if `config.noise_fraction > 0`) drawn
    /// from a generator seeded with `seed`.
    pub fn new(config: LaserConfig, seed: u64) -> Self {
        Self {
            config,
            rng: random::seeded(seed),
            noise: config.noise_fraction > 0.0,
            range_sigma_m: 0.0,
            reach_m: config.max_range_m,
            beams: Vec::new(),
        }
    }

    /// The laser's beams reach `reach_m` (if more than the configuration's usable range), and
    /// a reading beyond the usable range is no return, as a consumer of a longer-range laser
    /// sees it: `papillon run` keeps the readings of `papillon-sim serve`'s 20 m LMS1xx up to
    /// its board's `max_range_m`. With noise, a surface a little beyond the usable range then
    /// reads within it, as it does on a real laser (a wall at 4.2 m reads under 4 m once in
    /// six at 5 % noise); a laser that reaches only its usable range never shows it.
    pub fn with_reach_m(mut self, reach_m: f32) -> Self {
        self.reach_m = reach_m.max(self.config.max_range_m);
        self
    }

    /// Each range's noise gets a part of standard deviation `range_sigma_m` \[m\] that does not
    /// grow with the range, added in quadrature to the configuration's `noise_fraction · range`
    /// (noise turns on if it is positive). A value that is not finite or not positive adds
    /// nothing.
    pub fn with_range_sigma_m(mut self, range_sigma_m: f32) -> Self {
        if range_sigma_m.is_finite() && range_sigma_m > 0.0 {
            self.range_sigma_m = range_sigma_m;
            self.noise = true;
        }
        self
    }

    /// The configuration.
    pub fn config(&self) -> &LaserConfig {
        &self.config
    }

    /// Turns range noise on or off.
    pub fn set_noise(&mut self, on: bool) {
        self.noise = on;
    }

    /// Whether range noise is on.
    pub fn noise(&self) -> bool {
        self.noise
    }

    /// A scan from a robot at `robot_pose` (map frame, true pose) in `world`, seeing `discs`
    /// (other robots, people).
    pub fn scan(&mut self, world: &World, robot_pose: Pose2, discs: &[Disc]) -> Scan {
        let mut scan = Scan::new();
        // A config with more beams than a scan holds keeps the first MAX_BEAMS.
        let _ = self.scan_into(world, robot_pose, discs, &mut scan);
        scan
    }

    /// Like [`Self::scan`], into a caller's scan (cleared first); errs if the configuration has
    /// more beams than a scan holds (the beams that fit are kept).
    pub fn scan_into(
        &mut self,
        world: &World,
        robot_pose: Pose2,
        discs: &[Disc],
        out: &mut Scan,
    ) -> Result<(), ScanError> {
        out.clear();
        let cfg = self.config;
        let laser = robot_pose.compose(cfg.mount);
        let origin = laser.position();
        let max = self.reach_m;
        let count = cfg.beam_count as usize;
        self.beams.clear();
        for i in 0..count {
            let a = laser.theta + cfg.beam_angle(i);
            let (dy, dx) = math::sin_cos(a);
            let range = cast_ray_along(world, origin, dx, dy, max);
            self.beams.push(BeamWork { dx, dy, range });
        }
        // Each disc against the beams that can meet it only; the nearest return of a beam
        // does not depend on the order its discs are tried in.
        let first_rad = laser.theta + cfg.first_angle_rad;
        for d in discs {
            for run in beams_toward(origin, d, first_rad, cfg.step_rad, count) {
                for b in &mut self.beams[run] {
                    if let Some(t) = ray_disc(origin, b.dx, b.dy, d)
                        && t <= max
                        && b.range.is_none_or(|r| t < r)
                    {
                        b.range = Some(t);
                    }
                }
            }
        }
        for (i, b) in self.beams.iter().enumerate() {
            let angle_rad = cfg.beam_angle(i);
            let range_m = b
                .range
                .map(|r| {
                    if self.noise {
                        let sigma = (cfg.noise_fraction * r).hypot(self.range_sigma_m);
                        (r + sigma * random::gaussian(&mut self.rng)).max(0.0)
                    } else {
                        r
                    }
                })
                .filter(|&r| max <= cfg.max_range_m || r <= cfg.max_range_m);
            out.push(Beam { angle_rad, range_m })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;
    use papillon::grid::GridGeometry;
    use papillon::units::deg_to_rad;

    /// A 6 m x 6 m room with walls 0.5 m thick: inner faces at 0.5 and 5.5 m.
    fn room() -> World {
        let g = GridGeometry::from_extent(6.0, 6.0, 0.1, Point2::default()).unwrap();
        let mut w = World::new("room", g);
        w.fill_rect(0.0, 0.0, 6.0, 0.5, true);
        w.fill_rect(0.0, 5.5, 6.0, 6.0, true);
        w.fill_rect(0.0, 0.0, 0.5, 6.0, true);
        w.fill_rect(5.5, 0.0, 6.0, 6.0, true);
        w
    }

    fn analytic(p: Point2, a: f32) -> f32 {
        let (c, s) = (a.cos(), a.sin());
        let tx = if c > 1e-9 {
            (5.5 - p.x) / c
        } else if c < -1e-9 {
            (0.5 - p.x) / c
        } else {
            f32::INFINITY
        };
        let ty = if s > 1e-9 {
            (5.5 - p.y) / s
        } else if s < -1e-9 {
            (0.5 - p.y) / s
        } else {
            f32::INFINITY
        };
        tx.min(ty)
    }

    fn full_circle(noise: f32) -> LaserConfig {
        LaserConfig {
            beam_count: 360,
            first_angle_rad: -PI,
            step_rad: deg_to_rad(1.0),
            max_range_m: 20.0,
            min_range_m: 0.0,
            noise_fraction: noise,
            ..LaserConfig::thesis()
        }
    }

    /// The walk checked cell by cell against the world (outside counts as blocked).
    fn cast_ray_checked(world: &World, origin: Point2, a: f32, max_range_m: f32) -> Option<f32> {
        let g = world.geometry();
        let r = g.resolution_m;
        let (dx, dy) = (math::cos(a), math::sin(a));
        let (px, py) = ((origin.x - g.origin.x) / r, (origin.y - g.origin.y) / r);
        let mut cell = Cell::new(px.floor() as i32, py.floor() as i32);
        if world.is_blocked(cell) {
            return Some(0.0);
        }
        let max_t = max_range_m / r;
        let (sx, sy) = (if dx > 0.0 { 1 } else { -1 }, if dy > 0.0 { 1 } else { -1 });
        let nb = |p: f32, d: f32, c: i32| {
            if d > 0.0 {
                ((c + 1) as f32 - p) / d
            } else if d < 0.0 {
                (c as f32 - p) / d
            } else {
                f32::INFINITY
            }
        };
        let (mut tx, mut ty) = (nb(px, dx, cell.col), nb(py, dy, cell.row));
        let tdx = if dx != 0.0 {
            1.0 / dx.abs()
        } else {
            f32::INFINITY
        };
        let tdy = if dy != 0.0 {
            1.0 / dy.abs()
        } else {
            f32::INFINITY
        };
        loop {
            let t;
            if tx < ty {
                cell.col += sx;
                t = tx;
                tx += tdx;
            } else {
                cell.row += sy;
                t = ty;
                ty += tdy;
            }
            if t > max_t {
                return None;
            }
            if world.is_blocked(cell) {
                return Some(t * r);
            }
        }
    }

    #[test]
    fn rays_far_from_the_edges_see_what_a_checked_walk_sees() {
        // An open 12 m x 12 m world with scattered blocks and no outer wall: rays from the
        // middle skip the bounds checks, rays near the edges leave the grid.
        // The sparse world with the long range has the open space the walk jumps over
        // ([`Walk::skip_open`]); every range must still be the checked walk's, bit for bit.
        for (blocks, range_m, seed) in [(40, 4.0, 6), (6, 20.0, 8)] {
            let g = GridGeometry::from_extent(12.0, 12.0, 0.1, Point2::default()).unwrap();
            let mut w = World::new("blocks", g);
            let mut rng = random::seeded(seed);
            for _ in 0..blocks {
                let (x, y) = (
                    12.0 * random::unit_f32(&mut rng),
                    12.0 * random::unit_f32(&mut rng),
                );
                w.fill_rect(x, y, x + 0.3, y + 0.3, true);
            }
            let mut returns = 0;
            for _ in 0..20_000 {
                let o = Point2::new(
                    12.0 * random::unit_f32(&mut rng),
                    12.0 * random::unit_f32(&mut rng),
                );
                let a = 2.0 * PI * random::unit_f32(&mut rng);
                let want = cast_ray_checked(&w, o, a, range_m);
                let got = cast_ray(&w, o, a, range_m);
                assert_eq!(
                    got.map(f32::to_bits),
                    want.map(f32::to_bits),
                    "{blocks} blocks: from {o:?} at {a}"
                );
                returns += got.is_some() as usize;
            }
            assert!(
                returns > 2_000 && returns <= 20_000,
                "{blocks} blocks: {returns} returns"
            );
        }
    }

    #[test]
    fn ranges_match_the_walls_without_noise() {
        let w = room();
        let mut rng = random::seeded(4);
        let mut laser = LaserSim::new(full_circle(0.05), 1);
        laser.set_noise(false);
        for _ in 0..50 {
            let pose = Pose2::new(
                random::range_f32(&mut rng, 0.8, 5.2),
                random::range_f32(&mut rng, 0.8, 5.2),
                random::range_f32(&mut rng, -PI, PI),
            );
            let scan = laser.scan(&w, pose, &[]);
            assert_eq!(scan.len(), 360);
            for b in scan.beams() {
                let want = analytic(pose.position(), pose.theta + b.angle_rad);
                let got = b.range_m.expect("a closed room always returns");
                assert!((got - want).abs() <= 0.1, "{pose:?} {b:?} want {want}");
                assert!(
                    (got - want).abs() <= 1e-3,
                    "exact traversal: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn nothing_returns_beyond_the_range() {
        let w = room();
        let cfg = LaserConfig {
            noise_fraction: 0.0,
            ..LaserConfig::thesis()
        };
        let mut laser = LaserSim::new(cfg, 1);
        // At (1, 3) facing east: east wall 4.5 m away, beyond the 4 m range; west wall 0.5 m
        // (behind, out of the 180° field); north and south walls 2.5 m.
        let scan = laser.scan(&w, Pose2::new(1.0, 3.0, 0.0), &[]);
        let mid = scan.beams()[90];
        assert!(mid.angle_rad.abs() < 1e-6);
        assert_eq!(mid.range_m, None);
        let left = scan.beams()[180];
        assert!((left.range_m.unwrap() - 2.5).abs() < 1e-3);
    }

    #[test]
    fn blind_zone_readings_are_reported_as_measured() {
        let w = room();
        let mut laser = LaserSim::new(
            LaserConfig {
                noise_fraction: 0.0,
                ..LaserConfig::thesis()
            },
            1,
        );
        let scan = laser.scan(&w, Pose2::new(5.3, 3.0, 0.0), &[]);
        assert!((scan.beams()[90].range_m.unwrap() - 0.2).abs() < 1e-3);
    }

    /// A wall 4.2 m ahead of a 4 m laser at 5 % noise: a laser that reaches only its usable
    /// range never returns from it; one that reaches 20 m reads it within 4 m now and then
    /// (about once in six) and reports nothing beyond 4 m.
    #[test]
    fn a_longer_reach_shows_a_wall_just_beyond_the_range_through_the_noise() {
        let w = room();
        let cfg = LaserConfig {
            max_range_m: 4.0,
            ..full_circle(0.05)
        };
        let pose = Pose2::new(1.3, 3.0, 0.0);
        let ahead = |laser: &mut LaserSim| {
            let scan = laser.scan(&w, pose, &[]);
            let beam = scan
                .beams()
                .iter()
                .find(|b| b.angle_rad.abs() < 1e-4)
                .copied()
                .unwrap();
            beam.range_m
        };
        let mut short = LaserSim::new(cfg, 3);
        let mut long = LaserSim::new(cfg, 3).with_reach_m(20.0);
        let (mut within, mut beyond) = (0, 0);
        for _ in 0..300 {
            assert_eq!(ahead(&mut short), None);
            match ahead(&mut long) {
                Some(r) if r <= 4.0 => within += 1,
                Some(_) => beyond += 1,
                None => {}
            }
        }
        assert_eq!(beyond, 0);
        assert!((20..=90).contains(&within), "{within} of 300");
    }

    /// Every beam against every disc, the nearest return kept: what the scan computed before
    /// it chose the beams to test per disc.
    fn scan_every_disc(
        cfg: &LaserConfig,
        w: &World,
        pose: Pose2,
        discs: &[Disc],
    ) -> Vec<Option<f32>> {
        let laser = pose.compose(cfg.mount);
        let origin = laser.position();
        (0..cfg.beam_count as usize)
            .map(|i| {
                let a = laser.theta + cfg.beam_angle(i);
                let (dx, dy) = (math::cos(a), math::sin(a));
                let mut range = cast_ray_along(w, origin, dx, dy, cfg.max_range_m);
                for d in discs {
                    if let Some(t) = ray_disc(origin, dx, dy, d)
                        && t <= cfg.max_range_m
                        && range.is_none_or(|r| t < r)
                    {
                        range = Some(t);
                    }
                }
                range
            })
            .collect()
    }

    #[test]
    fn a_crowd_of_discs_reads_as_when_every_beam_tests_every_disc() {
        // Discs everywhere around the laser, near and far, for the thesis's 180° fan and a
        // full circle (whose fan comes round past the bearing of a disc behind), at headings
        // beyond a turn either way: bit for bit the scan that tests every disc with every beam.
        let w = room();
        let mut rng = random::seeded(11);
        let mut hits = 0;
        for cfg in [
            LaserConfig {
                noise_fraction: 0.0,
                ..LaserConfig::thesis()
            },
            full_circle(0.0),
        ] {
            let mut laser = LaserSim::new(cfg, 1);
            for _ in 0..200 {
                let pose = Pose2::new(
                    random::range_f32(&mut rng, 0.8, 5.2),
                    random::range_f32(&mut rng, 0.8, 5.2),
                    random::range_f32(&mut rng, -9.0, 9.0),
                );
                let discs: Vec<Disc> = (0..30)
                    .map(|_| {
                        let centre = Point2::new(
                            random::range_f32(&mut rng, 0.0, 6.0),
                            random::range_f32(&mut rng, 0.0, 6.0),
                        );
                        Disc::new(centre, random::range_f32(&mut rng, 0.05, 0.6))
                    })
                    .collect();
                let want = scan_every_disc(&cfg, &w, pose, &discs);
                let walls = scan_every_disc(&cfg, &w, pose, &[]);
                let scan = laser.scan(&w, pose, &discs);
                for ((b, want), wall) in scan.beams().iter().zip(&want).zip(&walls) {
                    assert_eq!(
                        b.range_m.map(f32::to_bits),
                        want.map(f32::to_bits),
                        "pose {pose:?}, beam at {}",
                        b.angle_rad
                    );
                    hits += (want != wall) as usize;
                }
            }
        }
        // The discs are seen (the test can fail if the beams chosen per disc are wrong).
        assert!(hits > 10_000, "{hits} beams stopped by a disc");
    }

    #[test]
    fn other_robots_appear_as_discs() {
        let w = room();
        let mut laser = LaserSim::new(full_circle(0.0), 1);
        let me = Pose2::new(1.0, 3.0, 0.0);
        let other = Disc::new(Point2::new(3.0, 3.0), 0.25);
        let own = Disc::new(me.position(), 0.25);
        let scan = laser.scan(&w, me, &[other, own]);
        let ahead = scan
            .beams()
            .iter()
            .find(|b| b.angle_rad.abs() < 1e-4)
            .unwrap();
        assert!((ahead.range_m.unwrap() - 1.75).abs() < 1e-4, "{ahead:?}");
        let behind = scan.beams()[0];
        assert!(
            (behind.range_m.unwrap() - 0.5).abs() < 1e-3,
            "own disc ignored"
        );
        assert_eq!(ray_disc(Point2::new(0.0, 0.0), 0.0, 1.0, &other), None);
    }

    #[test]
    fn mount_offset_moves_the_origin() {
        let w = room();
        let cfg = LaserConfig {
            noise_fraction: 0.0,
            ..LaserConfig::lms1xx()
        };
        let mut laser = LaserSim::new(cfg, 1);
        let scan = laser.scan(&w, Pose2::new(3.0, 3.0, PI / 2.0), &[]);
        let ahead = scan
            .beams()
            .iter()
            .find(|b| b.angle_rad.abs() < 1e-4)
            .unwrap();
        assert!((ahead.range_m.unwrap() - (2.5 - 0.055)).abs() < 1e-3);
        assert_eq!(scan.len(), 541);
    }

    #[test]
    fn noise_is_five_percent_and_seeded() {
        let w = room();
        let cfg = LaserConfig {
            first_angle_rad: 0.0,
            step_rad: 0.0,
            beam_count: 1000,
            ..LaserConfig::thesis()
        };
        let pose = Pose2::new(2.5, 3.0, 0.0); // 3 m to the east wall.
        let a = LaserSim::new(cfg, 9).scan(&w, pose, &[]);
        let b = LaserSim::new(cfg, 9).scan(&w, pose, &[]);
        assert_eq!(a, b);
        let r: Vec<f32> = a.beams().iter().map(|b| b.range_m.unwrap()).collect();
        let mean = r.iter().sum::<f32>() / r.len() as f32;
        let sd = (r.iter().map(|x| (x - mean).powi(2)).sum::<f32>() / r.len() as f32).sqrt();
        assert!((mean - 3.0).abs() < 0.03, "mean {mean}");
        assert!((sd - 0.15).abs() < 0.02, "sd {sd}");
    }

    /// Mean and standard deviation of 1000 beams' ranges from `pose` with `laser`.
    fn spread(laser: &mut LaserSim, w: &World, pose: Pose2) -> (f32, f32) {
        let r: Vec<f32> = laser
            .scan(w, pose, &[])
            .beams()
            .iter()
            .map(|b| b.range_m.unwrap())
            .collect();
        let mean = r.iter().sum::<f32>() / r.len() as f32;
        let sd = (r.iter().map(|x| (x - mean).powi(2)).sum::<f32>() / r.len() as f32).sqrt();
        (mean, sd)
    }

    #[test]
    fn a_range_sigma_is_the_same_near_and_far_and_adds_in_quadrature() {
        let w = room();
        let one_way = LaserConfig {
            first_angle_rad: 0.0,
            step_rad: 0.0,
            beam_count: 1000,
            noise_fraction: 0.0,
            ..LaserConfig::thesis()
        };
        let near = Pose2::new(4.5, 3.0, 0.0); // 1 m to the east wall.
        let far = Pose2::new(2.5, 3.0, 0.0); // 3 m.
        let mut sick = LaserSim::new(one_way, 4).with_range_sigma_m(0.012);
        assert!(sick.noise());
        for (pose, range) in [(near, 1.0), (far, 3.0)] {
            let (mean, sd) = spread(&mut sick, &w, pose);
            assert!((mean - range).abs() < 0.003, "mean {mean} at {range} m");
            assert!((sd - 0.012).abs() < 0.0015, "sd {sd} at {range} m");
        }
        // 1 % of 3 m (3 cm) and 4 cm: 5 cm.
        let both = LaserConfig {
            noise_fraction: 0.01,
            ..one_way
        };
        let mut laser = LaserSim::new(both, 5).with_range_sigma_m(0.04);
        let (_, sd) = spread(&mut laser, &w, far);
        assert!((sd - 0.05).abs() < 0.005, "sd {sd}");
        // Not finite or not positive: nothing added, noise stays off.
        for bad in [0.0, -0.01, f32::NAN, f32::INFINITY] {
            let mut exact = LaserSim::new(one_way, 4).with_range_sigma_m(bad);
            assert!(!exact.noise());
            let (mean, sd) = spread(&mut exact, &w, far);
            assert!((mean - 3.0).abs() < 1e-4 && sd < 1e-4, "{bad}: {mean} {sd}");
        }
    }

    #[test]
    fn ray_from_inside_a_wall_is_zero_and_axis_rays_work() {
        let w = room();
        assert_eq!(cast_ray(&w, Point2::new(0.2, 3.0), 0.0, 4.0), Some(0.0));
        let up = cast_ray(&w, Point2::new(3.05, 3.0), PI / 2.0, 4.0).unwrap();
        assert!((up - 2.5).abs() < 1e-4);
        let west = cast_ray(&w, Point2::new(3.05, 3.0), PI, 4.0).unwrap();
        assert!((west - 2.55).abs() < 1e-4);
    }
}
