//! P3-DX body physics: differential drive with acceleration limits, disc collisions, odometry
//! with seeded slip, encoders, bumpers, stall, e-stop and battery.
//!
//! Kinematics: the unicycle model of a differential drive (Siegwart, Nourbakhsh & Scaramuzza,
//! *Introduction to Autonomous Mobile Robots*, 2nd ed., 2011, §3.2), integrated at a fixed step
//! ([`BodyConfig::step_s`]) with the midpoint heading. Commanded translational speed \[mm/s\] and
//! turn rate \[deg/s\] are reached through acceleration and deceleration limits, as the ARCOS
//! firmware does (SETA / SETRA). Wheel speeds follow from the track width:
//! `left = v - ω·track/2`, `right = v + ω·track/2`; the default track (0.357 m) is the one
//! implied by ARIA's `DiffConvFactor` 0.0056 for the P3-DX.
//!
//! Collisions: against walls, the robot's body is its outline ([`BodyConfig::body`]): a
//! rectangle with rounded ends, as the P3-DX's (0.381 m wide, 0.455 m long, axle 0.21 m behind
//! the front), modelled as a capsule (the rectangle's width as its diameter) and tested as four
//! discs along its axis, so that a door the body fits through straight lets it through and a
//! turn in place against a wall does not; between robots and against people, each robot is the
//! disc of [`BodyConfig::radius_m`] (0.25 m). Blocked cells are axis-aligned squares. A step
//! (translation and rotation) that would push the body deeper into an obstacle is cut at the
//! contact point (bisection), both
//! velocities drop to zero, and the stall flag and a bumper flag are set (front when the robot
//! was moving forward, rear when backward). Moves that do not go deeper are allowed, so a robot
//! can always back away, even if a door closed on it. The flags clear at the next free
//! translation.
//!
//! Odometry: the encoders measure the commanded wheel motion exactly; the true motion differs
//! by slip ([`SlipConfig`]): Gaussian errors whose variance grows with distance and rotation
//! (a random walk, independent of the step size), plus a slide when a move ends (the thesis,
//! Bendahmane 2023, saw 1–2 cm at the end of each move). So the odometry pose drifts from the
//! true pose, as on the real robot. All draws come from the body's own seeded RNG.

use core::f32::consts::PI;

use papillon::geometry::{Point2, Pose2, normalize_angle};
use papillon::math;
use papillon::random::{self, ProjectRng};
use papillon::units::{deg_to_rad, m_to_mm, rad_to_arcos_angle, rad_to_deg};

use crate::odometry_error::{DrawnWheels, WheelErrors};
use crate::world::World;

/// A disc obstacle in the map frame: another robot or a person.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disc {
    /// Centre \[m\].
    pub center: Point2,
    /// Radius \[m\].
    pub radius_m: f32,
}

impl Disc {
    /// A disc of `radius_m` at `center`.
    pub const fn new(center: Point2, radius_m: f32) -> Self {
        Self { center, radius_m }
    }
}

/// Odometry slip: how the true motion departs from what the encoders measure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlipConfig {
    /// Variance of the distance error per metre travelled \[m²/m\].
    pub distance_var_m2_per_m: f32,
    /// Variance of the heading error per radian turned \[rad²/rad\].
    pub rotation_var_rad2_per_rad: f32,
    /// Variance of the heading error per metre travelled \[rad²/m\].
    pub drift_var_rad2_per_m: f32,
    /// Standard deviation of the slide along the heading when a move ends \[m\].
    pub end_of_move_m: f32,
    /// Standard deviation of the heading slip when a move ends \[rad\].
    pub end_of_move_rad: f32,
    /// Systematic wheel errors and fast-turn slip ([`crate::odometry_error`]).
    pub wheels: WheelErrors,
}

impl SlipConfig {
    /// No slip: odometry equals the true motion.
    pub const fn none() -> Self {
        Self {
            distance_var_m2_per_m: 0.0,
            rotation_var_rad2_per_rad: 0.0,
            drift_var_rad2_per_m: 0.0,
            end_of_move_m: 0.0,
            end_of_move_rad: 0.0,
            wheels: WheelErrors::none(),
        }
    }

    /// What the thesis saw (Bendahmane 2023): a slide of 1–2 cm along the heading at the end
    /// of each move (σ = 1.5 cm, mean 1.2 cm), and nothing else.
    pub const fn thesis() -> Self {
        Self {
            end_of_move_m: 0.015,
            ..Self::none()
        }
    }
}

impl SlipConfig {
    /// The realistic model: [`WheelErrors::realistic`] systematic errors and fast-turn slip,
    /// the default random walks (about 1 cm per metre and 1° per quarter turn, 1 σ) and the
    /// thesis's end-of-move slide with 0.5° of heading.
    pub fn realistic() -> Self {
        Self {
            wheels: WheelErrors::realistic(),
            ..Self::default()
        }
    }

    /// The model named `name` on the command line: `realistic`, `thesis`, `full` (the random
    /// walks and the slide, no systematic error) or `none`.
    pub fn named(name: &str) -> Option<Self> {
        match name {
            "realistic" => Some(Self::realistic()),
            "thesis" => Some(Self::thesis()),
            "full" => Some(Self::default()),
            "none" => Some(Self::none()),
            _ => None,
        }
    }
}

impl Default for SlipConfig {
    /// About 1 cm per metre and 1° per quarter turn (1 σ), and a 1.5 cm, 0.5° slide at the
    /// end of each move.
    fn default() -> Self {
        Self {
            distance_var_m2_per_m: 1e-4,
            rotation_var_rad2_per_rad: 2e-4,
            drift_var_rad2_per_m: 1e-4,
            end_of_move_m: 0.015,
            end_of_move_rad: 0.5 * PI / 180.0,
            wheels: WheelErrors::none(),
        }
    }
}

/// The robot's outline for wall contacts: a capsule along the robot's heading, relative to
/// the centre of rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyOutline {
    /// Width \[m\] (the capsule's diameter).
    pub width_m: f32,
    /// From the centre of rotation to the front edge \[m\] (at least half the width).
    pub front_m: f32,
    /// From the centre of rotation to the rear edge \[m\] (at least half the width).
    pub rear_m: f32,
}

impl BodyOutline {
    /// The P3-DX body: 0.381 m wide, 0.21 m ahead of the axle and 0.245 m behind it (its
    /// datasheet, as [`papillon::control::safety::RobotFootprint::p3dx`]).
    pub const fn p3dx() -> Self {
        Self {
            width_m: 0.381,
            front_m: 0.210,
            rear_m: 0.245,
        }
    }

    /// The centres (in the robot frame, along x) and the radius of the four discs that make
    /// up the capsule: evenly spaced from the rear cap's centre to the front cap's. Between
    /// two discs the union dips below the capsule's side by less than half a millimetre.
    fn discs(&self) -> ([f32; 4], f32) {
        let r = 0.5 * self.width_m;
        let front = (self.front_m - r).max(0.0);
        let rear = -(self.rear_m - r).max(0.0);
        let step = (front - rear) / 3.0;
        ([rear, rear + step, rear + 2.0 * step, front], r)
    }
}

/// Physical parameters of the simulated robot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyConfig {
    /// Radius of the robot's disc as other robots and people meet it \[m\].
    pub radius_m: f32,
    /// The outline that meets walls.
    pub body: BodyOutline,
    /// Distance between the wheels \[m\].
    pub track_m: f32,
    /// Largest translational speed \[mm/s\].
    pub max_speed_mm_s: f32,
    /// Largest turn rate \[deg/s\].
    pub max_turn_deg_s: f32,
    /// Translational acceleration \[mm/s²\].
    pub accel_mm_s2: f32,
    /// Translational deceleration \[mm/s²\].
    pub decel_mm_s2: f32,
    /// Rotational acceleration \[deg/s²\].
    pub turn_accel_deg_s2: f32,
    /// Rotational deceleration \[deg/s²\].
    pub turn_decel_deg_s2: f32,
    /// Integration step \[s\] (a step that is not a positive number is replaced by 0.01 s).
    pub step_s: f32,
    /// Encoder ticks per millimetre of wheel travel.
    pub ticks_per_mm: f32,
    /// Battery voltage when fully charged \[V\].
    pub battery_full_v: f32,
    /// Battery drain while powered \[V/s\].
    pub battery_drain_v_per_s: f32,
    /// Extra battery drain per metre travelled \[V/m\].
    pub battery_drain_v_per_m: f32,
    /// Odometry slip.
    pub slip: SlipConfig,
}

impl Default for BodyConfig {
    /// A P3-DX: its body outline, a 0.25 m disc for other robots, track 0.357 m, 1200 mm/s
    /// and 300 deg/s at most, 300 mm/s² and 100 deg/s² (ARCOS defaults), 10 ms steps, 128
    /// ticks/mm, 13.0 V battery.
    fn default() -> Self {
        Self {
            radius_m: 0.25,
            body: BodyOutline::p3dx(),
            track_m: 0.357,
            max_speed_mm_s: 1200.0,
            max_turn_deg_s: 300.0,
            accel_mm_s2: 300.0,
            decel_mm_s2: 300.0,
            turn_accel_deg_s2: 100.0,
            turn_decel_deg_s2: 100.0,
            step_s: 0.01,
            ticks_per_mm: 128.0,
            battery_full_v: 13.0,
            battery_drain_v_per_s: 1e-4,
            battery_drain_v_per_m: 5e-4,
            slip: SlipConfig::default(),
        }
    }
}

/// How deep a body of outline `body` at `pose` reaches into the world's walls, or a disc of
/// `radius_m` at its centre into the `discs` \[m\].
pub fn body_penetration(
    world: &World,
    discs: &[Disc],
    pose: Pose2,
    body: &BodyOutline,
    radius_m: f32,
) -> f32 {
    let (xs, r) = body.discs();
    let (sin, cos) = (math::sin(pose.theta), math::cos(pose.theta));
    let mut depth = f32::NEG_INFINITY;
    for x in xs {
        let c = Point2::new(pose.x + x * cos, pose.y + x * sin);
        depth = depth.max(world.wall_penetration(c, r));
    }
    let p = pose.position();
    for d in discs {
        depth = depth.max(radius_m + d.radius_m - p.distance(d.center));
    }
    depth
}

/// How deep a disc at `p` of `radius_m` reaches into the world and the `discs` \[m\].
pub fn penetration(world: &World, discs: &[Disc], p: Point2, radius_m: f32) -> f32 {
    let mut depth = world.wall_penetration(p, radius_m);
    for d in discs {
        depth = depth.max(radius_m + d.radius_m - p.distance(d.center));
    }
    depth
}

/// The simulated robot: true state, odometry, encoders and status flags.
#[derive(Clone, Debug)]
pub struct RobotBody {
    config: BodyConfig,
    rng: ProjectRng,
    true_pose: Pose2,
    start_pose: Pose2,
    odom_pose: Pose2,
    speed_mm_s: f32,
    turn_deg_s: f32,
    cmd_speed_mm_s: f32,
    cmd_turn_deg_s: f32,
    left_ticks: f64,
    right_ticks: f64,
    stall: bool,
    front_bumper: bool,
    rear_bumper: bool,
    motors_enabled: bool,
    e_stop: bool,
    battery_v: f32,
    distance_m: f64,
    rotation_rad: f64,
    time_s: f64,
    pending_s: f32,
    moving: bool,
    wheels: DrawnWheels,
    /// The discs a step can touch ([`discs_within`]), reused from step to step.
    near: Vec<Disc>,
}

impl RobotBody {
    /// A robot at rest at `pose` (map frame), motors enabled, odometry at zero, slip drawn from
    /// a generator seeded with `seed`.
    pub fn new(mut config: BodyConfig, pose: Pose2, seed: u64) -> Self {
        if !(config.step_s.is_finite() && config.step_s > 0.0) {
            config.step_s = 0.01;
        }
        let mut rng = random::seeded(seed);
        let wheels = config.slip.wheels.draw(&mut rng);
        Self {
            config,
            rng,
            true_pose: pose,
            start_pose: pose,
            odom_pose: Pose2::default(),
            speed_mm_s: 0.0,
            turn_deg_s: 0.0,
            cmd_speed_mm_s: 0.0,
            cmd_turn_deg_s: 0.0,
            left_ticks: 0.0,
            right_ticks: 0.0,
            stall: false,
            front_bumper: false,
            rear_bumper: false,
            motors_enabled: true,
            e_stop: false,
            battery_v: config.battery_full_v,
            distance_m: 0.0,
            rotation_rad: 0.0,
            time_s: 0.0,
            pending_s: 0.0,
            near: Vec::new(),
            moving: false,
            wheels,
        }
    }

    /// The parameters.
    pub fn config(&self) -> &BodyConfig {
        &self.config
    }

    /// This robot's systematic wheel errors, drawn at creation.
    pub fn wheels(&self) -> &DrawnWheels {
        &self.wheels
    }

    /// Replaces the drawn systematic wheel errors (`papillon-sim serve --wheel-errors`).
    pub fn set_wheels(&mut self, wheels: DrawnWheels) {
        self.wheels = wheels;
    }

    /// Commands a translational speed \[mm/s\] (positive forward) and a turn rate \[deg/s\]
    /// (positive counter-clockwise), clamped to the limits; reached under the acceleration
    /// limits.
    pub fn command(&mut self, speed_mm_s: f32, turn_deg_s: f32) {
        let finite = |v: f32| if v.is_finite() { v } else { 0.0 };
        let c = &self.config;
        self.cmd_speed_mm_s = finite(speed_mm_s).clamp(-c.max_speed_mm_s, c.max_speed_mm_s);
        self.cmd_turn_deg_s = finite(turn_deg_s).clamp(-c.max_turn_deg_s, c.max_turn_deg_s);
    }

    /// Sets the translational acceleration and deceleration \[mm/s²\] and the rotational
    /// acceleration and deceleration \[deg/s²\] the wheels ramp with (the firmware's SETA and
    /// SETRA); values that are not positive numbers keep the current ones.
    pub fn set_accelerations(
        &mut self,
        accel_mm_s2: f32,
        decel_mm_s2: f32,
        turn_accel_deg_s2: f32,
        turn_decel_deg_s2: f32,
    ) {
        let keep = |v: f32, old: f32| if v.is_finite() && v > 0.0 { v } else { old };
        let c = &mut self.config;
        c.accel_mm_s2 = keep(accel_mm_s2, c.accel_mm_s2);
        c.decel_mm_s2 = keep(decel_mm_s2, c.decel_mm_s2);
        c.turn_accel_deg_s2 = keep(turn_accel_deg_s2, c.turn_accel_deg_s2);
        c.turn_decel_deg_s2 = keep(turn_decel_deg_s2, c.turn_decel_deg_s2);
    }

    /// Commands zero speed and turn rate (a normal, decelerated stop).
    pub fn stop(&mut self) {
        self.command(0.0, 0.0);
    }

    /// Enables or disables the motors; disabled motors stop the wheels at once.
    pub fn set_motors_enabled(&mut self, enabled: bool) {
        self.motors_enabled = enabled;
    }

    /// Presses (`true`) or releases the emergency stop: pressed, the wheels stop at once and
    /// commands are ignored.
    pub fn set_e_stop(&mut self, pressed: bool) {
        self.e_stop = pressed;
    }

    /// Moves the robot without physics (and without touching odometry or encoders).
    pub fn teleport(&mut self, pose: Pose2) {
        self.true_pose = pose;
    }

    /// True pose in the map frame \[m, rad\].
    pub fn true_pose(&self) -> Pose2 {
        self.true_pose
    }

    /// The robot's disc at its true position.
    pub fn disc(&self) -> Disc {
        Disc::new(self.true_pose.position(), self.config.radius_m)
    }

    /// Odometry pose in the odometry frame (zero where the robot was created) \[m, rad\].
    pub fn odometry_pose(&self) -> Pose2 {
        self.odom_pose
    }

    /// Odometry pose expressed in the map frame (the odometry frame anchored at the start
    /// pose): differs from [`Self::true_pose`] by the accumulated slip.
    pub fn odometry_in_map(&self) -> Pose2 {
        self.start_pose.compose(self.odom_pose)
    }

    /// ARCOS XPOS: odometry x \[mm\] modulo 0x8000.
    pub fn arcos_x(&self) -> u16 {
        arcos_position(self.odom_pose.x)
    }

    /// ARCOS YPOS: odometry y \[mm\] modulo 0x8000.
    pub fn arcos_y(&self) -> u16 {
        arcos_position(self.odom_pose.y)
    }

    /// ARCOS THPOS: odometry heading in 2π/4096 units, in (-2048, 2048].
    pub fn arcos_heading(&self) -> i16 {
        let u = rad_to_arcos_angle(normalize_angle(self.odom_pose.theta)).round() as i32;
        (if u <= -2048 { u + 4096 } else { u }) as i16
    }

    /// Current translational speed \[mm/s\].
    pub fn speed_mm_s(&self) -> f32 {
        self.speed_mm_s
    }

    /// Current turn rate \[deg/s\].
    pub fn turn_deg_s(&self) -> f32 {
        self.turn_deg_s
    }

    /// Wheel speeds (left, right) \[mm/s\].
    pub fn wheel_speeds_mm_s(&self) -> (f32, f32) {
        let half = m_to_mm(self.config.track_m) / 2.0 * deg_to_rad(self.turn_deg_s);
        (self.speed_mm_s - half, self.speed_mm_s + half)
    }

    /// Accumulated encoder counts (left, right), wrapping like a 32-bit counter.
    pub fn encoder_ticks(&self) -> (i32, i32) {
        let wrap = |t: f64| (t.round() as i64) as i32;
        (wrap(self.left_ticks), wrap(self.right_ticks))
    }

    /// Whether the last motion was blocked (the wheels stalled).
    pub fn stalled(&self) -> bool {
        self.stall
    }

    /// Whether the front bumper is pressed.
    pub fn front_bumper(&self) -> bool {
        self.front_bumper
    }

    /// Whether the rear bumper is pressed.
    pub fn rear_bumper(&self) -> bool {
        self.rear_bumper
    }

    /// ARCOS STALL AND BUMPERS word: bits 0 and 8 wheel stalls, bits 1-7 rear bumper
    /// segments, bits 9-15 front bumper segments (all segments on contact).
    pub fn arcos_stall_bumpers(&self) -> u16 {
        let mut w = 0u16;
        if self.stall {
            w |= 0x0101;
        }
        if self.rear_bumper {
            w |= 0x00FE;
        }
        if self.front_bumper {
            w |= 0xFE00;
        }
        w
    }

    /// Whether the motors are enabled.
    pub fn motors_enabled(&self) -> bool {
        self.motors_enabled
    }

    /// Whether the emergency stop is pressed.
    pub fn e_stop(&self) -> bool {
        self.e_stop
    }

    /// Battery voltage \[V\].
    pub fn battery_v(&self) -> f32 {
        self.battery_v
    }

    /// True distance travelled \[m\].
    pub fn distance_m(&self) -> f64 {
        self.distance_m
    }

    /// True rotation, absolute, summed \[rad\].
    pub fn rotation_rad(&self) -> f64 {
        self.rotation_rad
    }

    /// Simulated time this body has been stepped \[s\].
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Advances by `dt_s` seconds in whole fixed steps (a remainder is carried to the next
    /// call), against the world's blocked cells and the given discs.
    pub fn advance(&mut self, dt_s: f32, world: &World, discs: &[Disc]) {
        self.pending_s += dt_s.max(0.0);
        while self.pending_s >= self.config.step_s * 0.999 {
            self.pending_s -= self.config.step_s;
            self.step(world, discs);
        }
    }

    /// One fixed integration step.
    pub fn step(&mut self, world: &World, discs: &[Disc]) {
        self.step_among(world, discs, None);
    }

    /// [`Self::step`] against `discs` except the one at index `skip` (the body's own, when
    /// `discs` holds every body). Only the discs the step can reach are tested
    /// ([`discs_within`]): the same motion, bit for bit, as against all of them.
    fn step_among(&mut self, world: &World, discs: &[Disc], skip: Option<usize>) {
        let mut near = core::mem::take(&mut self.near);
        self.step_near(world, discs, skip, &mut near);
        self.near = near;
    }

    fn step_near(
        &mut self,
        world: &World,
        all_discs: &[Disc],
        skip: Option<usize>,
        near: &mut Vec<Disc>,
    ) {
        let c = self.config;
        let dt = c.step_s;
        self.time_s += dt as f64;
        self.battery_v = (self.battery_v - c.battery_drain_v_per_s * dt).max(0.0);
        let halted = self.e_stop || !self.motors_enabled;
        if halted {
            self.speed_mm_s = 0.0;
            self.turn_deg_s = 0.0;
        } else {
            self.speed_mm_s = ramp(
                self.speed_mm_s,
                self.cmd_speed_mm_s,
                c.accel_mm_s2,
                c.decel_mm_s2,
                dt,
            );
            self.turn_deg_s = ramp(
                self.turn_deg_s,
                self.cmd_turn_deg_s,
                c.turn_accel_deg_s2,
                c.turn_decel_deg_s2,
                dt,
            );
        }
        let d = self.speed_mm_s * 0.001 * dt;
        let dth = deg_to_rad(self.turn_deg_s) * dt;
        if d == 0.0 && dth == 0.0 {
            if self.moving {
                self.moving = false;
                self.end_of_move_slip(world, all_discs, skip, near);
            }
            return;
        }
        self.moving = true;
        // True motion = measured motion + slip.
        let s = c.slip;
        let (d_sys, dth_sys) = self.wheels.true_motion(d, dth, c.track_m);
        let d_true = d_sys + gauss(&mut self.rng, s.distance_var_m2_per_m * d.abs());
        let dth_true = dth_sys
            + gauss(
                &mut self.rng,
                s.rotation_var_rad2_per_rad * dth.abs()
                    + s.drift_var_rad2_per_m * d.abs()
                    + self.wheels.fast_turn_var(dth, self.turn_deg_s),
            );
        let from = self.true_pose;
        // Every pose the step tests lies within |d_true| of `from`.
        discs_within(
            all_discs,
            skip,
            from.position(),
            c.radius_m + d_true.abs(),
            near,
        );
        let discs: &[Disc] = near;
        let mid = from.theta + dth_true / 2.0;
        let to = Point2::new(
            from.x + d_true * math::cos(mid),
            from.y + d_true * math::sin(mid),
        );
        let pose_at = |m: f32| {
            let p = lerp(from.position(), to, m);
            Pose2::new(p.x, p.y, from.theta + dth_true * m)
        };
        let depth_of = |pose: Pose2| body_penetration(world, discs, pose, &c.body, c.radius_m);
        let depth_from = depth_of(from).max(0.0);
        let depth_to = depth_of(pose_at(1.0));
        let mut fraction = 1.0f32;
        if depth_to > depth_from {
            // Cut the step at the contact point.
            let (mut lo, mut hi) = (0.0f32, 1.0f32);
            for _ in 0..10 {
                let m = 0.5 * (lo + hi);
                if depth_of(pose_at(m)) > depth_from {
                    hi = m;
                } else {
                    lo = m;
                }
            }
            fraction = lo;
            self.stall = true;
            if d > 0.0 {
                self.front_bumper = true;
            } else if d < 0.0 {
                self.rear_bumper = true;
            }
            self.speed_mm_s = 0.0;
            self.turn_deg_s = 0.0;
        } else if d != 0.0 {
            self.stall = false;
            self.front_bumper = false;
            self.rear_bumper = false;
        }
        let p = lerp(from.position(), to, fraction);
        self.true_pose = Pose2::new(p.x, p.y, from.theta + dth_true * fraction);
        self.distance_m += (d_true.abs() * fraction) as f64;
        self.rotation_rad += (dth_true.abs() * fraction) as f64;
        self.battery_v =
            (self.battery_v - c.battery_drain_v_per_m * d_true.abs() * fraction).max(0.0);
        // The encoders see the measured wheel motion up to the contact.
        let (dm, dthm) = (d * fraction, dth * fraction);
        let half = c.track_m / 2.0 * dthm;
        self.left_ticks += ((dm - half) * 1000.0 * c.ticks_per_mm) as f64;
        self.right_ticks += ((dm + half) * 1000.0 * c.ticks_per_mm) as f64;
        let o = self.odom_pose;
        let omid = o.theta + dthm / 2.0;
        self.odom_pose = Pose2::new(
            o.x + dm * math::cos(omid),
            o.y + dm * math::sin(omid),
            o.theta + dthm,
        );
    }

    fn end_of_move_slip(
        &mut self,
        world: &World,
        all_discs: &[Disc],
        skip: Option<usize>,
        near: &mut Vec<Disc>,
    ) {
        let s = self.config.slip;
        if s.end_of_move_m == 0.0 && s.end_of_move_rad == 0.0 {
            return;
        }
        let along = s.end_of_move_m * random::gaussian(&mut self.rng);
        let turn = s.end_of_move_rad * random::gaussian(&mut self.rng);
        let from = self.true_pose;
        // The slide ends within |along| of `from`.
        discs_within(
            all_discs,
            skip,
            from.position(),
            self.config.radius_m + along.abs(),
            near,
        );
        let discs: &[Disc] = near;
        let to = Point2::new(
            from.x + along * math::cos(from.theta),
            from.y + along * math::sin(from.theta),
        );
        let to = Pose2::new(to.x, to.y, from.theta + turn);
        let (body, r) = (&self.config.body, self.config.radius_m);
        if body_penetration(world, discs, to, body, r)
            > body_penetration(world, discs, from, body, r).max(0.0)
        {
            return;
        }
        self.true_pose = to;
    }
}

/// The discs of `discs` (but the one at index `skip`) that a body of radius `reach_m` about
/// `p` can overlap: whose boundary is within `reach_m` of `p`, with a centimetre to spare,
/// into `out` in their order. A disc farther away adds a negative depth to
/// [`body_penetration`] at every pose within that reach, and a step only compares depths
/// above zero, so testing these is testing all of them; the filter costs one squared
/// distance per disc instead of a distance per disc at each of the step's 2 to 12 tested
/// poses.
fn discs_within(discs: &[Disc], skip: Option<usize>, p: Point2, reach_m: f32, out: &mut Vec<Disc>) {
    out.clear();
    for (j, d) in discs.iter().enumerate() {
        if Some(j) == skip {
            continue;
        }
        let r = reach_m + d.radius_m + 0.01;
        let (dx, dy) = (d.center.x - p.x, d.center.y - p.y);
        // NaN keeps the disc (no ordering).
        if (dx * dx + dy * dy).partial_cmp(&(r * r)) != Some(core::cmp::Ordering::Greater) {
            out.push(*d);
        }
    }
}

/// Advances several robots together by `dt_s`, step by step, each seeing the others (and
/// `extra` discs such as people) as obstacles. Robots are stepped in slice order: a robot
/// sees where the robots before it have already stepped to.
pub fn advance_all(bodies: &mut [RobotBody], dt_s: f32, world: &World, extra: &[Disc]) {
    for b in bodies.iter_mut() {
        b.pending_s += dt_s.max(0.0);
    }
    // Every body's disc, kept current as the bodies step, then the extra discs (the order
    // does not matter: a step takes the deepest overlap).
    let mut discs: Vec<Disc> = bodies.iter().map(RobotBody::disc).collect();
    discs.extend(extra.iter().copied());
    loop {
        let mut any = false;
        for i in 0..bodies.len() {
            if bodies[i].pending_s < bodies[i].config.step_s * 0.999 {
                continue;
            }
            let b = &mut bodies[i];
            b.pending_s -= b.config.step_s;
            b.step_among(world, &discs, Some(i));
            discs[i] = b.disc();
            any = true;
        }
        if !any {
            break;
        }
    }
}

fn arcos_position(m: f32) -> u16 {
    (m_to_mm(m).round() as i64).rem_euclid(0x8000) as u16
}

fn lerp(a: Point2, b: Point2, t: f32) -> Point2 {
    Point2::new(a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t)
}

/// A zero-mean Gaussian draw of variance `var` (no draw is consumed when `var` is 0, so turning
/// slip off does not shift other random streams).
fn gauss(rng: &mut ProjectRng, var: f32) -> f32 {
    if var > 0.0 {
        var.sqrt() * random::gaussian(rng)
    } else {
        0.0
    }
}

/// Moves `v` toward `target` by at most `accel·dt` when speeding up (same sign, larger
/// magnitude) and `decel·dt` otherwise.
fn ramp(v: f32, target: f32, accel: f32, decel: f32, dt: f32) -> f32 {
    let speeding_up = v * target >= 0.0 && target.abs() > v.abs();
    let limit = if speeding_up { accel } else { decel } * dt;
    v + (target - v).clamp(-limit, limit)
}

/// Turn rate \[deg/s\] from a wheel speed difference, for callers converting VEL2-style
/// commands: `ω = (right - left) / track`.
pub fn turn_rate_from_wheels(left_mm_s: f32, right_mm_s: f32, track_m: f32) -> f32 {
    rad_to_deg((right_mm_s - left_mm_s) / m_to_mm(track_m))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::builtin;

    /// `advance_all` as it was before the reach filter: each body stepped against a fresh
    /// list of every other body's disc and the extra discs.
    fn advance_all_against_every_disc(
        bodies: &mut [RobotBody],
        dt_s: f32,
        world: &World,
        extra: &[Disc],
    ) {
        for b in bodies.iter_mut() {
            b.pending_s += dt_s.max(0.0);
        }
        loop {
            let mut any = false;
            for i in 0..bodies.len() {
                if bodies[i].pending_s < bodies[i].config.step_s * 0.999 {
                    continue;
                }
                let mut discs: Vec<Disc> = extra.to_vec();
                discs.extend(
                    bodies
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != i)
                        .map(|(_, b)| b.disc()),
                );
                let b = &mut bodies[i];
                b.pending_s -= b.config.step_s;
                b.step(world, &discs);
                any = true;
            }
            if !any {
                break;
            }
        }
    }

    #[test]
    fn a_crowd_moves_as_if_every_disc_were_tested() {
        // Forty robots packed 0.6 m apart, driving and turning at random with the default
        // slip, bumping into each other, the walls and two people: the reach filter must give
        // the same poses, bit for bit, as testing every disc.
        let w = builtin::empty(0.1).unwrap();
        let mut rng = random::seeded(7);
        let mut a = Vec::new();
        for k in 0..40 {
            let pose = Pose2::new(
                1.0 + 0.6 * (k % 8) as f32,
                1.0 + 0.6 * (k / 8) as f32,
                random::range_f32(&mut rng, -3.0, 3.0),
            );
            a.push(RobotBody::new(BodyConfig::default(), pose, 100 + k as u64));
        }
        let mut b = a.clone();
        let people = [
            Disc::new(Point2::new(2.5, 2.5), 0.25),
            Disc::new(Point2::new(4.0, 1.5), 0.25),
        ];
        let mut contacts = 0;
        for period in 0..300 {
            if period % 10 == 0 {
                for (x, y) in a.iter_mut().zip(b.iter_mut()) {
                    let v = random::range_f32(&mut rng, -300.0, 600.0);
                    let t = random::range_f32(&mut rng, -60.0, 60.0);
                    x.command(v, t);
                    y.command(v, t);
                }
            }
            advance_all(&mut a, 0.1, &w, &people);
            advance_all_against_every_disc(&mut b, 0.1, &w, &people);
            for (x, y) in a.iter().zip(&b) {
                let (p, q) = (x.true_pose(), y.true_pose());
                assert_eq!(
                    (p.x.to_bits(), p.y.to_bits(), p.theta.to_bits()),
                    (q.x.to_bits(), q.y.to_bits(), q.theta.to_bits()),
                    "period {period}"
                );
                assert_eq!(x.stalled(), y.stalled());
                contacts += x.stalled() as usize;
            }
        }
        assert!(
            contacts > 50,
            "the crowd must bump: {contacts} stalled body-periods"
        );
    }

    fn no_slip() -> BodyConfig {
        BodyConfig {
            slip: SlipConfig::none(),
            ..BodyConfig::default()
        }
    }

    fn run(b: &mut RobotBody, world: &World, seconds: f32) {
        b.advance(seconds, world, &[]);
    }

    #[test]
    fn speed_ramps_under_the_acceleration_limit() {
        let w = builtin::empty(0.1).unwrap();
        let mut b = RobotBody::new(no_slip(), Pose2::new(5.0, 5.0, 0.0), 1);
        b.command(600.0, 0.0);
        run(&mut b, &w, 1.0);
        assert!((b.speed_mm_s() - 300.0).abs() < 1.0, "{}", b.speed_mm_s());
        run(&mut b, &w, 2.0);
        assert!((b.speed_mm_s() - 600.0).abs() < 1e-3);
        // 0.5·300·1² + 300·1 + 600·... : distance after 3 s = 0.6 m + 1.2 m... check x.
        // Ramp 0→600 over 2 s covers 0.6 m, then 1 s at 600 mm/s covers 0.6 m.
        assert!((b.true_pose().x - 6.2).abs() < 0.01, "{:?}", b.true_pose());
        b.stop();
        run(&mut b, &w, 3.0);
        assert_eq!(b.speed_mm_s(), 0.0);
        // Decelerating from 600 at 300 mm/s² covers 0.6 m more.
        assert!((b.true_pose().x - 6.8).abs() < 0.01, "{:?}", b.true_pose());
        let (l, r) = b.encoder_ticks();
        assert!((l as f32 - 1800.0 * 128.0).abs() < 200.0, "{l}");
        assert_eq!(l, r);
    }

    #[test]
    fn turning_follows_the_rate_and_wheels_differ() {
        let w = builtin::empty(0.1).unwrap();
        let mut b = RobotBody::new(no_slip(), Pose2::new(5.0, 5.0, 0.0), 1);
        b.command(0.0, 90.0);
        run(&mut b, &w, 0.5);
        let (l, r) = b.wheel_speeds_mm_s();
        assert!((b.turn_deg_s() - 50.0).abs() < 0.5);
        assert!((r + l).abs() < 1e-3 && r > 0.0);
        assert!((turn_rate_from_wheels(l, r, 0.357) - b.turn_deg_s()).abs() < 0.01);
        b.stop();
        run(&mut b, &w, 2.0);
        // Up 0.5 s (12.5°), down 0.5 s (12.5°): 25°.
        assert!((rad_to_deg(b.true_pose().theta) - 25.0).abs() < 0.5);
        assert_eq!(b.true_pose().position(), Point2::new(5.0, 5.0));
    }

    #[test]
    fn walls_stop_the_robot_and_set_the_front_bumper() {
        let w = builtin::empty(0.1).unwrap();
        // Facing the east wall (inner face at x = 23.5 m): the front edge, 0.21 m ahead of the
        // axle, stops at the face.
        let mut b = RobotBody::new(no_slip(), Pose2::new(22.0, 5.0, 0.0), 3);
        b.command(500.0, 0.0);
        run(&mut b, &w, 10.0);
        let x = b.true_pose().x;
        assert!(x <= 23.29 + 1e-3 && x > 23.24, "stopped at {x}");
        assert!(b.stalled() && b.front_bumper() && !b.rear_bumper());
        assert_eq!(b.arcos_stall_bumpers(), 0xFF01);
        let body = BodyOutline::p3dx();
        assert!(body_penetration(&w, &[], b.true_pose(), &body, 0.25) <= 0.0);
        // Backing off frees it and sets nothing.
        b.command(-200.0, 0.0);
        run(&mut b, &w, 2.0);
        assert!(!b.stalled() && !b.front_bumper());
        assert!(b.true_pose().x < x);
    }

    #[test]
    fn backing_into_a_wall_sets_the_rear_bumper() {
        let w = builtin::empty(0.1).unwrap();
        let mut b = RobotBody::new(no_slip(), Pose2::new(1.0, 5.0, 0.0), 3);
        b.command(-300.0, 0.0);
        run(&mut b, &w, 5.0);
        assert!(b.stalled() && b.rear_bumper() && !b.front_bumper());
        // The rear edge, 0.245 m behind the axle, stops at the west wall's face (x = 0.5 m).
        assert!(b.true_pose().x >= 0.745 - 1e-3);
    }

    #[test]
    fn the_body_passes_a_half_metre_door_straight_but_not_a_narrower_one_than_itself() {
        // 0.381 m wide: through 0.5 m and (barely) 0.4 m, not through 0.3 m.
        for (door_m, passes) in [(0.5, true), (0.4, true), (0.3, false)] {
            let mut w = builtin::empty(0.1).unwrap();
            // A wall across x = 10 m with a door centred on y = 5 m.
            w.fill_rect(10.0, 0.5, 10.1, 5.0 - door_m / 2.0, true);
            w.fill_rect(10.0, 5.0 + door_m / 2.0, 10.1, 23.5, true);
            let mut b = RobotBody::new(no_slip(), Pose2::new(8.0, 5.0, 0.0), 3);
            b.command(200.0, 0.0);
            run(&mut b, &w, 20.0);
            let x = b.true_pose().x;
            assert_eq!(x > 11.0, passes, "door {door_m} m: stopped at {x}");
            assert_eq!(b.stalled(), !passes);
        }
    }

    #[test]
    fn turning_in_place_against_a_wall_is_stopped() {
        let w = builtin::empty(0.1).unwrap();
        // The rear 0.2 m from the west wall's face: the rear corners hit it when turning.
        let mut b = RobotBody::new(no_slip(), Pose2::new(0.5 + 0.2 + 0.05, 5.0, 0.0), 3);
        b.command(0.0, 30.0);
        run(&mut b, &w, 3.0);
        // Free of the wall, a turn in place goes round.
        let mut free = RobotBody::new(no_slip(), Pose2::new(5.0, 5.0, 0.0), 3);
        free.command(0.0, 30.0);
        run(&mut free, &w, 3.0);
        assert!(free.true_pose().theta.abs() > 0.5);
        assert!(!free.stalled());
        let _ = b;
    }

    #[test]
    fn robots_do_not_pass_through_each_other() {
        let w = builtin::empty(0.1).unwrap();
        let mut bodies = vec![
            RobotBody::new(no_slip(), Pose2::new(5.0, 5.0, 0.0), 1),
            RobotBody::new(no_slip(), Pose2::new(8.0, 5.0, PI), 2),
        ];
        bodies[0].command(400.0, 0.0);
        bodies[1].command(400.0, 0.0);
        for _ in 0..100 {
            advance_all(&mut bodies, 0.1, &w, &[]);
        }
        let gap = bodies[0]
            .true_pose()
            .position()
            .distance(bodies[1].true_pose().position());
        assert!((0.5 - 1e-3..0.52).contains(&gap), "gap {gap}");
        assert!(bodies.iter().all(|b| b.stalled() && b.front_bumper()));
    }

    #[test]
    fn e_stop_and_disabled_motors_hold_the_robot() {
        let w = builtin::empty(0.1).unwrap();
        let mut b = RobotBody::new(no_slip(), Pose2::new(5.0, 5.0, 0.0), 1);
        b.command(500.0, 0.0);
        b.set_e_stop(true);
        run(&mut b, &w, 1.0);
        assert_eq!(b.true_pose().position(), Point2::new(5.0, 5.0));
        assert!(b.e_stop());
        b.set_e_stop(false);
        b.set_motors_enabled(false);
        run(&mut b, &w, 1.0);
        assert_eq!(b.true_pose().position(), Point2::new(5.0, 5.0));
        b.set_motors_enabled(true);
        run(&mut b, &w, 1.0);
        assert!(b.true_pose().x > 5.1);
        assert!(b.battery_v() < 13.0 && b.battery_v() > 12.9);
    }

    #[test]
    fn slip_makes_odometry_drift_deterministically() {
        let w = builtin::empty(0.1).unwrap();
        let drive = |seed: u64| {
            let mut b = RobotBody::new(BodyConfig::default(), Pose2::new(5.0, 5.0, 0.0), seed);
            for _ in 0..4 {
                b.command(400.0, 0.0);
                b.advance(5.0, &w, &[]);
                b.stop();
                b.advance(2.0, &w, &[]);
                b.command(0.0, 45.0);
                b.advance(2.0, &w, &[]);
                b.stop();
                b.advance(2.0, &w, &[]);
            }
            b
        };
        let a = drive(7);
        let b = drive(7);
        assert_eq!(a.true_pose(), b.true_pose());
        assert_eq!(a.odometry_pose(), b.odometry_pose());
        let err = a
            .true_pose()
            .position()
            .distance(a.odometry_in_map().position());
        assert!(err > 0.002 && err < 0.5, "drift {err}");
        let c = drive(8);
        assert_ne!(a.true_pose(), c.true_pose());
        // Without slip, odometry is exact.
        let mut e = RobotBody::new(no_slip(), Pose2::new(5.0, 5.0, 0.3), 1);
        e.command(300.0, 20.0);
        e.advance(4.0, &w, &[]);
        let d = e
            .true_pose()
            .position()
            .distance(e.odometry_in_map().position());
        assert!(d < 1e-4, "{d}");
    }

    #[test]
    fn end_of_move_slip_is_about_a_centimetre_or_two() {
        let w = builtin::empty(0.1).unwrap();
        let mut total = 0.0;
        let n = 200;
        for seed in 0..n {
            let cfg = BodyConfig {
                slip: SlipConfig {
                    distance_var_m2_per_m: 0.0,
                    rotation_var_rad2_per_rad: 0.0,
                    drift_var_rad2_per_m: 0.0,
                    ..SlipConfig::default()
                },
                ..BodyConfig::default()
            };
            let mut b = RobotBody::new(cfg, Pose2::new(5.0, 5.0, 0.0), seed);
            b.command(300.0, 0.0);
            b.advance(2.0, &w, &[]);
            b.stop();
            b.advance(2.0, &w, &[]);
            total += b
                .true_pose()
                .position()
                .distance(b.odometry_in_map().position());
        }
        let mean = total / n as f32;
        // Mean of |N(0, 1.5 cm)| is 1.2 cm.
        assert!((0.008..0.016).contains(&mean), "mean slide {mean}");
    }

    #[test]
    fn a_bad_step_falls_back_to_ten_milliseconds() {
        let w = builtin::empty(0.1).unwrap();
        for step_s in [0.0, -1.0, f32::NAN] {
            let cfg = BodyConfig {
                step_s,
                ..no_slip()
            };
            let mut b = RobotBody::new(cfg, Pose2::new(5.0, 5.0, 0.0), 1);
            assert_eq!(b.config().step_s, 0.01);
            b.command(300.0, 0.0);
            b.advance(1.0, &w, &[]);
            assert!((b.time_s() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn arcos_fields_wrap() {
        let w = builtin::empty(0.1).unwrap();
        let mut b = RobotBody::new(no_slip(), Pose2::new(5.0, 5.0, 0.0), 1);
        assert_eq!((b.arcos_x(), b.arcos_y(), b.arcos_heading()), (0, 0, 0));
        b.command(-300.0, 0.0);
        b.advance(1.0, &w, &[]);
        // About 150 mm backwards: negative x wraps modulo 0x8000.
        let x_mm = (b.odometry_pose().x * 1000.0).round() as i32;
        assert!((-155..=-148).contains(&x_mm), "{x_mm}");
        assert_eq!(b.arcos_x() as i32, 0x8000 + x_mm);
        assert_eq!(arcos_position(40.0), (40_000 % 0x8000) as u16);
        let mut t = RobotBody::new(no_slip(), Pose2::new(5.0, 5.0, 0.0), 1);
        t.command(0.0, 90.0);
        t.advance(1.9, &w, &[]);
        t.stop();
        t.advance(2.0, &w, &[]);
        let want = rad_to_arcos_angle(normalize_angle(t.odometry_pose().theta)).round() as i16;
        assert_eq!(t.arcos_heading(), want);
        assert!(t.arcos_heading() > 0);
    }

    #[test]
    fn names_map_to_models() {
        assert_eq!(SlipConfig::named("thesis"), Some(SlipConfig::thesis()));
        assert_eq!(SlipConfig::named("none"), Some(SlipConfig::none()));
        assert_eq!(
            SlipConfig::named("realistic").unwrap().wheels,
            crate::odometry_error::WheelErrors::realistic()
        );
        assert_eq!(SlipConfig::named("lots"), None);
    }
}
