//! Where several robots start in one world: robot 0 at the given start, each further robot at
//! the nearest free, reachable place around it. The fast runner ([`crate::runner`]) and the
//! emulator server ([`crate::serve`]) place their robots with [`start_poses`].

use std::fmt;

use papillon::geometry::{Point2, Pose2};

use crate::world::World;

/// No free place was found for robot `robot` near the start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NoRoom {
    /// Which robot.
    pub robot: usize,
}

impl fmt::Display for NoRoom {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "no free start pose for robot {} near the start",
            self.robot
        )
    }
}

impl std::error::Error for NoRoom {}

/// Start poses for `n` robots: the first at `start`, each next one at the nearest free place
/// (searched on rings 0.8 m apart around `start`, from the start heading on,
/// counter-clockwise) whose disc of `radius_m` plus 0.1 m is clear of walls and at least
/// 0.8 m from every robot placed before, and which lies in the start's free component (so it
/// is reachable). All robots keep the start heading.
pub fn start_poses(
    world: &World,
    start: Pose2,
    n: usize,
    radius_m: f32,
) -> Result<Vec<Pose2>, NoRoom> {
    let clearance = radius_m + 0.1;
    let spacing = (2.0 * radius_m + 0.3).max(0.8);
    let truth = world.truth();
    let mut poses = vec![start];
    'robots: for robot in 1..n {
        for ring in 1..=30 {
            let r = spacing * ring as f32;
            let count = (2.0 * core::f32::consts::PI * r / spacing).floor().max(6.0) as usize;
            for k in 0..count {
                let a = start.theta + 2.0 * core::f32::consts::PI * k as f32 / count as f32;
                let p = Point2::new(start.x + r * a.cos(), start.y + r * a.sin());
                if world.disc_hits_blocked(p, clearance)
                    || poses.iter().any(|q| q.position().distance(p) < spacing)
                {
                    continue;
                }
                // Reachable from the start: in the start's free component.
                let reachable = world
                    .geometry()
                    .cell_at(p)
                    .and_then(|c| world.geometry().index(c))
                    .is_some_and(|i| truth.mask()[i]);
                if reachable {
                    poses.push(Pose2::new(p.x, p.y, start.theta));
                    continue 'robots;
                }
            }
        }
        return Err(NoRoom { robot });
    }
    Ok(poses)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::builtin;

    #[test]
    fn extra_robots_start_clear_of_walls_and_each_other() {
        let w = builtin::house(0.1).unwrap();
        let poses = start_poses(&w, w.start(), 4, 0.25).unwrap();
        assert_eq!(poses.len(), 4);
        assert_eq!(poses[0], w.start());
        for (i, p) in poses.iter().enumerate() {
            assert!(!w.disc_hits_blocked(p.position(), 0.35), "{p:?}");
            for q in &poses[..i] {
                assert!(p.position().distance(q.position()) >= 0.8 - 1e-4);
            }
        }
    }
}
