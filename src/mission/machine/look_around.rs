//! The look-around at the start of a mission: before its first decision the robot turns in
//! place, slowly enough for every scan to be mapped, by the laser's blind sector (the part of
//! the circle its field of view leaves out, plus a margin), so that the first decision sees
//! the space behind the start pose instead of the Unknown a 270° or 180° laser leaves there.
//!
//! Source: the 360° sensor sweep of frontier-based exploration (B. Yamauchi, "A
//! frontier-based approach for autonomous exploration", IEEE CIRA 1997, section 3); turning
//! only by the blind sector is that sweep cut to what the laser has not seen yet.
//!
//! Only for the optimizers on the efficient objective ([`MissionConfig::look_around`]): the
//! thesis objective keeps the thesis's decisions, and the frontier rules theirs. Every command
//! still goes through the safety monitor; a turn it refuses (the swing circle does not fit)
//! ends the look-around and the mission decides from where it stands.

use core::f32::consts::TAU;

use crate::control::Time;
use crate::control::command::MotionCommand;
use crate::control::safety::SafetyState;
use crate::explore::ObjectiveKind;
use crate::geometry::normalize_angle;
use crate::math;
use crate::units::deg_to_rad;

use super::super::{MissionConfig, SelectorKind};
use super::{Mission, Phase, secs};

/// Turn rate of the look-around \[deg/s\]: under the 20 deg/s above which the runner's and
/// the binary's pumps leave a scan unmapped (`sim-host` `PumpModel::onboard`,
/// `onboard::mission::MAX_MAPPING_TURN_RAD` per 0.1 s), so every scan of the turn is mapped.
const LOOK_TURN_DEG_S: i16 = 15;
/// Turned beyond the blind sector, so that its edges are seen by more than one beam \[deg\].
const LOOK_MARGIN_DEG: f32 = 10.0;

/// A turn in place at the start of the mission.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct LookAround {
    command: MotionCommand,
    /// Angle turned so far \[rad\].
    turned_rad: f32,
    /// Angle to turn \[rad\].
    target_rad: f32,
    /// Heading (odometry) at the last period \[rad\].
    last_theta: f32,
    /// Given up at this time (a turn the base does not follow).
    until: Time,
}

/// The angle a look-around turns with `config` \[rad\]; `None` when the mission makes none
/// (off, not the efficient objective's optimizer, or a laser that sees all around).
pub(super) fn look_around_rad(config: &MissionConfig) -> Option<f32> {
    let efficient = matches!(config.selector, SelectorKind::Optimized(_))
        && config.explore.objective == ObjectiveKind::Efficient;
    if !(config.look_around && efficient) {
        return None;
    }
    let laser = &config.laser;
    let fov_rad = f32::from(laser.beam_count.saturating_sub(1)) * laser.step_rad;
    let blind_rad = TAU - fov_rad;
    if !(blind_rad.is_finite() && blind_rad > 0.0) {
        return None;
    }
    Some((blind_rad + deg_to_rad(LOOK_MARGIN_DEG)).min(TAU))
}

impl<const N: usize> Mission<N> {
    /// The phase after Starting: a look-around when the configuration asks for one and the
    /// safety monitor lets the robot turn (left, or else right) on the latest scan;
    /// otherwise Deciding.
    pub(super) fn after_start(&self, now: Time) -> Phase {
        let Some(target_rad) = look_around_rad(&self.config) else {
            return Phase::Deciding;
        };
        let senses = &self.senses;
        if senses.scan_time.is_none() {
            return Phase::Deciding;
        }
        let limits = *self.monitor.limits();
        let turn = |turn_rate_deg_s: i16| MotionCommand {
            speed_mm_s: 0,
            turn_rate_deg_s,
        };
        let Some(command) = [turn(LOOK_TURN_DEG_S), turn(-LOOK_TURN_DEG_S)]
            .into_iter()
            .find(|&c| {
                self.monitor
                    .obstacle_in_path(limits.clamp(c), &senses.scan, &self.config.laser)
                    .is_none()
            })
        else {
            return Phase::Deciding;
        };
        // Twice the time the turn takes at its rate, and a few seconds to get going.
        let rate_rad_s = deg_to_rad(f32::from(LOOK_TURN_DEG_S));
        let until = now + secs(2.0 * target_rad / rate_rad_s + 5.0);
        Phase::LookingAround(LookAround {
            command,
            turned_rad: 0.0,
            target_rad,
            last_theta: senses.pose_odom.theta,
            until,
        })
    }

    /// One period of look-around `l`; `None` once it is over (the mission then decides).
    pub(super) fn look_around_step(
        &mut self,
        now: Time,
        mut l: LookAround,
    ) -> Option<MotionCommand> {
        let theta = self.senses.pose_odom.theta;
        l.turned_rad += math::abs(normalize_angle(theta - l.last_theta));
        l.last_theta = theta;
        let backing_off = matches!(self.monitor.state(), SafetyState::BackingOff { .. });
        if l.turned_rad >= l.target_rad || now >= l.until || backing_off {
            self.phase = Phase::Deciding;
            return None;
        }
        // The turn is a fresh decision of its own: the monitor holds at the start until one.
        let _ = self.monitor.acknowledge_replan();
        self.watch.ack_pending = false;
        self.phase = Phase::LookingAround(l);
        Some(l.command)
    }
}
