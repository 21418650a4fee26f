//! Robot commands in ARCOS units, and the board's motion limits.
//!
//! The path follower proposes a [`MotionCommand`] (translational velocity [mm/s], rotational
//! velocity [deg/s], counter-clockwise positive), the safety monitor turns it into a
//! [`RobotCommand`]. A velocity command can only be built through [`Limits::clamp`], so every
//! [`RobotCommand::Velocity`] in existence is within the limits it was built with; and
//! [`Limits`] itself cannot exceed the P3-DX's absolute maxima (2200 mm/s, 500 deg/s,
//! docs/protocols.md §1.9). The wire layer maps the variants to ARCOS commands: `Velocity` to
//! VEL (11) + RVEL (21), `Stop` to STOP (29), `EnableMotors` to ENABLE (4), `KeepAlive` to
//! PULSE (0), `EmergencyStop` to E_STOP (55), `SetLimits` to SETV (6), SETRV (10), SETA (5)
//! and SETRA (23).

/// P3-DX absolute maximum translational velocity [mm/s] (MaxVelocity, docs/protocols.md §1.9).
pub const P3DX_ABSOLUTE_MAX_SPEED_MM_S: u16 = 2200;
/// P3-DX absolute maximum rotational velocity [deg/s] (MaxRVelocity, docs/protocols.md §1.9).
pub const P3DX_ABSOLUTE_MAX_TURN_RATE_DEG_S: u16 = 500;

/// A velocity the path follower asks for, before safety and limits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct MotionCommand {
    /// Translational velocity [mm/s], forward positive.
    pub speed_mm_s: i16,
    /// Rotational velocity [deg/s], counter-clockwise positive.
    pub turn_rate_deg_s: i16,
}

impl MotionCommand {
    /// Standing still.
    pub const ZERO: MotionCommand = MotionCommand {
        speed_mm_s: 0,
        turn_rate_deg_s: 0,
    };

    /// Whether this asks for any motion.
    pub fn is_zero(&self) -> bool {
        self.speed_mm_s == 0 && self.turn_rate_deg_s == 0
    }

    /// From SI values \[m/s, rad/s\], rounded and saturated to `i16`.
    pub fn from_si(speed_m_s: f32, turn_rate_rad_s: f32) -> Self {
        Self {
            speed_mm_s: saturating_i16(crate::units::m_to_mm(speed_m_s)),
            turn_rate_deg_s: saturating_i16(crate::units::rad_to_deg(turn_rate_rad_s)),
        }
    }
}

/// Rounds to the nearest `i16`, saturating; NaN gives 0.
pub fn saturating_i16(v: f32) -> i16 {
    // `as` saturates and maps NaN to 0.
    crate::math::round(v) as i16
}

/// Motion limits of the board, in ARCOS units.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Limits {
    max_speed_mm_s: u16,
    max_turn_rate_deg_s: u16,
    accel_mm_s2: u16,
    decel_mm_s2: u16,
    turn_accel_deg_s2: u16,
    turn_decel_deg_s2: u16,
}

impl Limits {
    /// Limits for exploration on a P3-DX: 400 mm/s and 60 deg/s (well under the absolute
    /// 2200 mm/s and 500 deg/s, as suits a robot driving among unknown obstacles), 300 mm/s²
    /// translational and 100 deg/s² rotational (de)acceleration (the usual P3-DX parameter
    /// file values; the real ones come in the CONFIG packet, fields 27-28 and 32-33, see
    /// [`Limits::from_board`]).
    pub const fn p3dx_exploration() -> Self {
        Self {
            max_speed_mm_s: 400,
            max_turn_rate_deg_s: 60,
            accel_mm_s2: 300,
            decel_mm_s2: 300,
            turn_accel_deg_s2: 100,
            turn_decel_deg_s2: 100,
        }
    }

    /// Limits with the given values; speeds are capped at the P3-DX absolute maxima.
    pub fn new(
        max_speed_mm_s: u16,
        max_turn_rate_deg_s: u16,
        accel_mm_s2: u16,
        decel_mm_s2: u16,
        turn_accel_deg_s2: u16,
        turn_decel_deg_s2: u16,
    ) -> Self {
        Self {
            max_speed_mm_s: max_speed_mm_s.min(P3DX_ABSOLUTE_MAX_SPEED_MM_S),
            max_turn_rate_deg_s: max_turn_rate_deg_s.min(P3DX_ABSOLUTE_MAX_TURN_RATE_DEG_S),
            accel_mm_s2,
            decel_mm_s2,
            turn_accel_deg_s2,
            turn_decel_deg_s2,
        }
    }

    /// These limits, tightened to what the board reports: its current TransVelMax and
    /// RotVelMax (CONFIG fields 26 and 25) and its (de)accelerations (fields 32, 33, 27, 28).
    /// A zero from the board (field absent) leaves the value unchanged.
    pub fn from_board(
        self,
        trans_vel_max_mm_s: u16,
        rot_vel_max_deg_s: u16,
        trans_accel_mm_s2: u16,
        trans_decel_mm_s2: u16,
        rot_accel_deg_s2: u16,
        rot_decel_deg_s2: u16,
    ) -> Self {
        let tighten = |ours: u16, board: u16| if board == 0 { ours } else { ours.min(board) };
        Self::new(
            tighten(self.max_speed_mm_s, trans_vel_max_mm_s),
            tighten(self.max_turn_rate_deg_s, rot_vel_max_deg_s),
            tighten(self.accel_mm_s2, trans_accel_mm_s2),
            tighten(self.decel_mm_s2, trans_decel_mm_s2),
            tighten(self.turn_accel_deg_s2, rot_accel_deg_s2),
            tighten(self.turn_decel_deg_s2, rot_decel_deg_s2),
        )
    }

    /// Maximum translational speed [mm/s].
    pub fn max_speed_mm_s(&self) -> u16 {
        self.max_speed_mm_s
    }
    /// Maximum rotational speed [deg/s].
    pub fn max_turn_rate_deg_s(&self) -> u16 {
        self.max_turn_rate_deg_s
    }
    /// Translational acceleration [mm/s²].
    pub fn accel_mm_s2(&self) -> u16 {
        self.accel_mm_s2
    }
    /// Translational deceleration [mm/s²].
    pub fn decel_mm_s2(&self) -> u16 {
        self.decel_mm_s2
    }
    /// Rotational acceleration [deg/s²].
    pub fn turn_accel_deg_s2(&self) -> u16 {
        self.turn_accel_deg_s2
    }
    /// Rotational deceleration [deg/s²].
    pub fn turn_decel_deg_s2(&self) -> u16 {
        self.turn_decel_deg_s2
    }

    /// `proposed` clamped to these limits.
    pub fn clamp(&self, proposed: MotionCommand) -> Velocity {
        let clamp = |v: i16, max: u16| -> i16 {
            // max <= 2200 fits i16.
            let m = max as i16;
            v.clamp(-m, m)
        };
        Velocity {
            speed_mm_s: clamp(proposed.speed_mm_s, self.max_speed_mm_s),
            turn_rate_deg_s: clamp(proposed.turn_rate_deg_s, self.max_turn_rate_deg_s),
        }
    }

    /// The command for `proposed` clamped to these limits.
    pub fn velocity_command(&self, proposed: MotionCommand) -> RobotCommand {
        RobotCommand::Velocity(self.clamp(proposed))
    }

    /// Whether a velocity is within these limits.
    pub fn allows(&self, v: Velocity) -> bool {
        v.speed_mm_s.unsigned_abs() <= self.max_speed_mm_s
            && v.turn_rate_deg_s.unsigned_abs() <= self.max_turn_rate_deg_s
    }
}

impl Default for Limits {
    fn default() -> Self {
        Self::p3dx_exploration()
    }
}

/// A velocity already clamped to a [`Limits`]; built only by [`Limits::clamp`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Velocity {
    speed_mm_s: i16,
    turn_rate_deg_s: i16,
}

impl Velocity {
    /// Standing still.
    pub const ZERO: Velocity = Velocity {
        speed_mm_s: 0,
        turn_rate_deg_s: 0,
    };

    /// Translational velocity [mm/s] (VEL argument).
    pub fn speed_mm_s(&self) -> i16 {
        self.speed_mm_s
    }

    /// Rotational velocity [deg/s], counter-clockwise positive (RVEL argument).
    pub fn turn_rate_deg_s(&self) -> i16 {
        self.turn_rate_deg_s
    }

    /// The same velocity as an unclamped [`MotionCommand`].
    pub fn as_motion(&self) -> MotionCommand {
        MotionCommand {
            speed_mm_s: self.speed_mm_s,
            turn_rate_deg_s: self.turn_rate_deg_s,
        }
    }
}

/// A command to the robot, in ARCOS units.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum RobotCommand {
    /// Translational and rotational velocity (VEL + RVEL), within the limits.
    Velocity(Velocity),
    /// Stop translation and rotation with the board's deceleration (STOP).
    Stop,
    /// Enable (`true`) or disable the motors (ENABLE 1/0).
    EnableMotors(bool),
    /// Keep the firmware watchdog from stopping the robot (PULSE).
    KeepAlive,
    /// Emergency stop, overriding the deceleration (E_STOP).
    EmergencyStop,
    /// Send the limits to the board (SETV, SETRV, SETA, SETRA).
    SetLimits(Limits),
}

impl RobotCommand {
    /// Whether this command can make the robot move.
    pub fn commands_motion(&self) -> bool {
        match self {
            RobotCommand::Velocity(v) => *v != Velocity::ZERO,
            RobotCommand::EnableMotors(on) => *on,
            _ => false,
        }
    }

    /// The commanded velocity: zero for `Stop` and `EmergencyStop`, `None` for commands
    /// that leave the velocity as it was.
    pub fn velocity(&self) -> Option<Velocity> {
        match self {
            RobotCommand::Velocity(v) => Some(*v),
            RobotCommand::Stop | RobotCommand::EmergencyStop => Some(Velocity::ZERO),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{below, seeded};

    #[test]
    fn exploration_defaults_are_400_mm_s_and_60_deg_s() {
        let l = Limits::default();
        assert_eq!((l.max_speed_mm_s(), l.max_turn_rate_deg_s()), (400, 60));
        let v = l.clamp(MotionCommand {
            speed_mm_s: 1000,
            turn_rate_deg_s: -200,
        });
        assert_eq!((v.speed_mm_s(), v.turn_rate_deg_s()), (400, -60));
    }

    #[test]
    fn limits_never_exceed_the_p3dx_absolute_maxima() {
        let l = Limits::new(u16::MAX, u16::MAX, 1, 1, 1, 1);
        assert_eq!(l.max_speed_mm_s(), 2200);
        assert_eq!(l.max_turn_rate_deg_s(), 500);
        let v = l.clamp(MotionCommand {
            speed_mm_s: i16::MIN,
            turn_rate_deg_s: i16::MAX,
        });
        assert_eq!((v.speed_mm_s(), v.turn_rate_deg_s()), (-2200, 500));
    }

    #[test]
    fn board_values_only_tighten() {
        let l = Limits::default().from_board(300, 100, 0, 200, 0, 0);
        assert_eq!(l.max_speed_mm_s(), 300);
        assert_eq!(l.max_turn_rate_deg_s(), 60);
        assert_eq!((l.accel_mm_s2(), l.decel_mm_s2()), (300, 200));
    }

    #[test]
    fn si_conversion_rounds_and_saturates() {
        let m = MotionCommand::from_si(0.2504, -0.5);
        assert_eq!(m.speed_mm_s, 250);
        assert_eq!(m.turn_rate_deg_s, -29);
        let m = MotionCommand::from_si(f32::NAN, 1e9);
        assert_eq!((m.speed_mm_s, m.turn_rate_deg_s), (0, i16::MAX));
    }

    /// Property: for random limits and random proposals, no command ever exceeds the limits.
    #[test]
    fn no_command_ever_exceeds_the_limits() {
        let mut rng = seeded(0x4c494d);
        let any_i16 = |rng: &mut crate::random::ProjectRng| -> i16 {
            match below(rng, 4) {
                0 => [i16::MIN, i16::MAX, 0, -1][below(rng, 4)],
                _ => rng_i16(rng),
            }
        };
        for _ in 0..20_000 {
            let limits = Limits::new(
                below(&mut rng, 3000) as u16,
                below(&mut rng, 700) as u16,
                300,
                300,
                100,
                100,
            );
            let proposed = MotionCommand {
                speed_mm_s: any_i16(&mut rng),
                turn_rate_deg_s: any_i16(&mut rng),
            };
            let cmd = limits.velocity_command(proposed);
            let v = cmd.velocity().unwrap();
            assert!(limits.allows(v), "{v:?} beyond {limits:?}");
            assert!(v.speed_mm_s().unsigned_abs() <= P3DX_ABSOLUTE_MAX_SPEED_MM_S);
            assert!(v.turn_rate_deg_s().unsigned_abs() <= P3DX_ABSOLUTE_MAX_TURN_RATE_DEG_S);
            // Within the limits, the proposal passes unchanged.
            if limits.allows(Velocity {
                speed_mm_s: proposed.speed_mm_s,
                turn_rate_deg_s: proposed.turn_rate_deg_s,
            }) {
                assert_eq!(v.as_motion(), proposed);
            }
        }
    }

    fn rng_i16(rng: &mut crate::random::ProjectRng) -> i16 {
        use rand_core::Rng;
        rng.next_u32() as u16 as i16
    }
}
