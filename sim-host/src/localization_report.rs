//! How far a robot's pose estimate is from the truth at the end of a run, beside how far its
//! raw odometry is: the drift and what scan matching corrected of it.

use papillon::geometry::{Pose2, normalize_angle};
use papillon::mission::Mission;

use crate::physics::RobotBody;

/// One robot's final pose errors and scan-matching counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LocalizationReport {
    /// True pose (physics) \[m, rad\].
    pub true_pose: [f32; 3],
    /// The mission's estimate (odometry corrected by scan matching when on) \[m, rad\].
    pub estimated_pose: [f32; 3],
    /// Raw odometry anchored at the start pose \[m, rad\].
    pub odometry_pose: [f32; 3],
    /// Distance from the estimate to the truth \[m\].
    pub position_error_m: f32,
    /// Heading error of the estimate, absolute \[rad\].
    pub heading_error_rad: f32,
    /// Distance from the raw odometry to the truth \[m\].
    pub odometry_position_error_m: f32,
    /// Heading error of the raw odometry, absolute \[rad\].
    pub odometry_heading_error_rad: f32,
    /// Scans matched.
    pub matches: u32,
    /// Matches trusted (at least partly applied).
    pub matches_trusted: u32,
}

impl LocalizationReport {
    /// The errors of `mission`'s robot, whose body is `body`.
    pub fn of<const N: usize>(body: &RobotBody, mission: &Mission<N>) -> Self {
        let truth = body.true_pose();
        let estimate = mission.pose_map();
        let odometry = body.odometry_in_map();
        let array = |p: Pose2| [p.x, p.y, p.theta];
        let heading = |p: Pose2| normalize_angle(p.theta - truth.theta).abs();
        Self {
            true_pose: array(truth),
            estimated_pose: array(estimate),
            odometry_pose: array(odometry),
            position_error_m: estimate.position().distance(truth.position()),
            heading_error_rad: heading(estimate),
            odometry_position_error_m: odometry.position().distance(truth.position()),
            odometry_heading_error_rad: heading(odometry),
            matches: mission.localizer().matches(),
            matches_trusted: mission.localizer().trusted(),
        }
    }
}
