//! The semantic checks of a board file: each problem reported with its JSON path.

use core::fmt::Write as _;

use super::*;
use crate::capacity::MAX_CELLS;

/// Largest body dimension a board may give \[m\].
const MAX_BODY_M: f32 = 1.0;

impl BoardConfig {
    /// Checks every semantic constraint and calls `report(path, problem)` once per problem,
    /// with `path` a JSON path such as `$.mission.population`. Returns the number of problems.
    pub fn validate(&self, mut report: impl FnMut(&str, &str)) -> usize {
        let mut count = 0usize;
        let mut r = |path: &str, problem: &str| {
            count += 1;
            report(path, problem);
        };
        self.validate_robot(&mut r);
        self.validate_link(&mut r);
        self.validate_laser(&mut r);
        let grid_fine = self.validate_grid(&mut r);
        self.validate_mission(&mut r);
        self.validate_pid(&mut r);
        self.validate_safety(&mut r);
        self.validate_localize(&mut r);
        self.validate_mapping(&mut r);
        self.validate_planning(grid_fine, &mut r);
        if !positive(self.persistence.save_every_s) {
            r(
                "$.persistence.save_every_s",
                "must be a positive number of seconds",
            );
        }
        count
    }

    fn validate_robot(&self, r: &mut impl FnMut(&str, &str)) {
        let robot = &self.robot;
        if robot.name.is_empty() {
            r("$.robot.name", "must not be empty");
        }
        if !KNOWN_SUBCLASSES
            .iter()
            .any(|k| k.eq_ignore_ascii_case(&robot.subclass))
        {
            r(
                "$.robot.subclass",
                "unknown P3-DX subclass; expected one of p3dx, p3dx-sh, p3dx-sh-lms1xx, p3dx-sh-lms500",
            );
        }
        if !(positive(robot.radius_m) && robot.radius_m <= 1.0) {
            r("$.robot.radius_m", "must be in (0, 1] m");
        }
        if !(positive(robot.max_speed_mm_s) && robot.max_speed_mm_s <= P3DX_MAX_SPEED_MM_S) {
            r(
                "$.robot.max_speed_mm_s",
                "must be in (0, 2200] mm/s (the P3-DX absolute limit)",
            );
        }
        if !(positive(robot.max_turn_rate_deg_s)
            && robot.max_turn_rate_deg_s <= P3DX_MAX_TURN_RATE_DEG_S)
        {
            r(
                "$.robot.max_turn_rate_deg_s",
                "must be in (0, 500] deg/s (the P3-DX absolute limit)",
            );
        }
        for (path, v) in [
            ("$.robot.accel_mm_s2", robot.accel_mm_s2),
            ("$.robot.decel_mm_s2", robot.decel_mm_s2),
            ("$.robot.rot_accel_deg_s2", robot.rot_accel_deg_s2),
        ] {
            if !(positive(v) && v <= i16::MAX as f32) {
                r(path, "must be in (0, 32767] (an ARCOS integer argument)");
            }
        }
        for (path, v) in [
            ("$.robot.wheel_diameter_ratio", robot.wheel_diameter_ratio),
            ("$.robot.wheelbase_ratio", robot.wheelbase_ratio),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && (MIN_ODOMETRY_RATIO..=MAX_ODOMETRY_RATIO).contains(&v))
            {
                r(
                    path,
                    "must be a ratio from 0.8 to 1.2 (a correction of a few percent at most; see papillon calibrate)",
                );
            }
        }
        if let Some(b) = robot.wheelbase_m
            && !(b.is_finite() && (0.1..=1.0).contains(&b))
        {
            r("$.robot.wheelbase_m", "must be from 0.1 to 1 m");
        }
    }

    fn validate_link(&self, r: &mut impl FnMut(&str, &str)) {
        let link = &self.link;
        match &link.tcp {
            Some(tcp) => {
                if !is_host_port(tcp) {
                    r("$.link.tcp", "must be host:port with a port in 1..=65535");
                }
            }
            None => {
                if link.port.is_empty() {
                    r(
                        "$.link.port",
                        "must name a serial device when no tcp is given",
                    );
                }
            }
        }
        if !ARCOS_BAUD_RATES.contains(&link.baud) {
            r(
                "$.link.baud",
                "must be one of 9600, 19200, 38400, 57600, 115200",
            );
        }
        if !ARCOS_BAUD_RATES.contains(&link.switch_to_baud) {
            r(
                "$.link.switch_to_baud",
                "must be one of 9600, 19200, 38400, 57600, 115200",
            );
        }
    }

    fn validate_laser(&self, r: &mut impl FnMut(&str, &str)) {
        let laser = &self.laser;
        match LaserModel::from_name(&laser.model) {
            None => r("$.laser.model", "must be \"lms1xx\" or \"lms200\""),
            Some(LaserModel::Lms1xx) => match &laser.address {
                Some(a) if is_host_port(a) => {}
                Some(_) => r(
                    "$.laser.address",
                    "must be host:port with a port in 1..=65535",
                ),
                None => r("$.laser.address", "an lms1xx needs a TCP address host:port"),
            },
            Some(LaserModel::Lms200) => {
                match &laser.port {
                    Some(p) if !p.is_empty() => {}
                    _ => r("$.laser.port", "an lms200 needs a serial device"),
                }
                if let Some(b) = laser.baud
                    && !LMS200_BAUD_RATES.contains(&b)
                {
                    r("$.laser.baud", "must be one of 9600, 19200, 38400");
                }
            }
        }
        let count_ok = laser.beam_count >= 2 && laser.beam_count as usize <= MAX_BEAMS;
        if !count_ok {
            r("$.laser.beam_count", "must be in 2..=1081 beams");
        }
        if !(laser.first_angle_deg.is_finite() && math::abs(laser.first_angle_deg) <= 180.0) {
            r("$.laser.first_angle_deg", "must be in [-180, 180] deg");
        }
        if !positive(laser.step_deg) {
            r("$.laser.step_deg", "must be a positive angle in degrees");
        } else if count_ok && (laser.beam_count - 1) as f32 * laser.step_deg > 360.0 {
            r(
                "$.laser.step_deg",
                "beam_count and step_deg span more than 360 deg",
            );
        }
        if !(laser.min_range_m.is_finite() && laser.min_range_m >= 0.0) {
            r("$.laser.min_range_m", "must be zero or positive [m]");
        }
        if !positive(laser.max_range_m) {
            r("$.laser.max_range_m", "must be a positive range [m]");
        } else if laser.min_range_m >= laser.max_range_m {
            r("$.laser.max_range_m", "must be larger than min_range_m");
        }
        if !(laser.noise_fraction.is_finite()
            && laser.noise_fraction >= 0.0
            && laser.noise_fraction < 1.0)
        {
            r("$.laser.noise_fraction", "must be in [0, 1)");
        }
        if !positive(laser.rate_hz) {
            r("$.laser.rate_hz", "must be a positive rate [Hz]");
        }
        let m = &laser.mount;
        for (path, v) in [("$.laser.mount.x_m", m.x_m), ("$.laser.mount.y_m", m.y_m)] {
            if !(v.is_finite() && math::abs(v) <= 1.0) {
                r(path, "must be within 1 m of the robot's centre");
            }
        }
        if !(m.theta_deg.is_finite() && math::abs(m.theta_deg) <= 180.0) {
            r("$.laser.mount.theta_deg", "must be in [-180, 180] deg");
        }
    }

    /// Returns whether the grid's sizes and cell count are usable (the tests that need a grid
    /// skip theirs otherwise).
    fn validate_grid(&self, r: &mut impl FnMut(&str, &str)) -> bool {
        let g = &self.grid;
        let mut sizes_ok = true;
        for (path, v) in [
            ("$.grid.width_m", g.width_m),
            ("$.grid.height_m", g.height_m),
        ] {
            if !positive(v) {
                r(path, "must be a positive size [m]");
                sizes_ok = false;
            }
        }
        if !positive(g.resolution_m) {
            r("$.grid.resolution_m", "must be a positive cell size [m]");
            sizes_ok = false;
        }
        let mut usable = sizes_ok;
        if sizes_ok {
            let (cols, rows) = g.size_cells();
            if cols.saturating_mul(rows) > MAX_CELLS {
                usable = false;
                let mut problem = heapless::String::<160>::new();
                let _ = write!(
                    problem,
                    "width_m x height_m at resolution_m needs {cols} x {rows} cells, more than the {MAX_CELLS} the grid holds"
                );
                r("$.grid", &problem);
            }
            if positive(self.robot.radius_m) && g.resolution_m > self.robot.radius_m {
                r(
                    "$.grid.resolution_m",
                    "cells larger than the robot's radius cannot represent passages",
                );
            }
        }
        for (path, v) in [
            ("$.grid.origin_x_m", g.origin_x_m),
            ("$.grid.origin_y_m", g.origin_y_m),
        ] {
            if !v.is_finite() {
                r(path, "must be a finite coordinate [m]");
            }
        }
        if sizes_ok
            && g.origin_x_m.is_finite()
            && g.origin_y_m.is_finite()
            && !(g.origin_x_m <= 0.0
                && g.origin_y_m <= 0.0
                && g.origin_x_m + g.width_m > 0.0
                && g.origin_y_m + g.height_m > 0.0)
        {
            r(
                "$.grid",
                "the start pose (0, 0) must lie inside the grid: origin must be <= 0 and origin + size > 0",
            );
        }
        usable
    }

    fn validate_mission(&self, r: &mut impl FnMut(&str, &str)) {
        let m = &self.mission;
        if !KNOWN_METHODS.contains(&m.method.as_str()) {
            r(
                "$.mission.method",
                "unknown method; expected one of xboa, boa, mboa, aboa, saboa, ga, pso, gwo, abc, cmaes, nearest-frontier, frontier-utility",
            );
        }
        if !(2..=MAX_POPULATION).contains(&m.population) {
            let mut problem = heapless::String::<48>::new();
            let _ = write!(problem, "must be in 2..={MAX_POPULATION}");
            r("$.mission.population", &problem);
        }
        if m.generations == 0 {
            r("$.mission.generations", "must be at least 1");
        }
        if Strategy::from_name(&m.strategy).is_none() {
            r("$.mission.strategy", "must be \"short\" or \"long\"");
        }
        if self.objective().is_none() {
            r("$.mission.objective", "must be \"efficient\" or \"thesis\"");
        }
        if self.preset().is_none() {
            r("$.mission.preset", "must be \"standard\" or \"thesis\"");
        }
        if m.targets == 0 {
            r("$.mission.targets", "must be at least 1");
        } else if Strategy::from_name(&m.strategy) == Some(Strategy::Long)
            && usize::from(m.targets) > crate::explore::MAX_TARGETS
        {
            r(
                "$.mission.targets",
                "must be at most 8 with the long strategy (targets per decision)",
            );
        }
        if !positive(m.battery_steps) {
            r(
                "$.mission.battery_steps",
                "must be a positive energy [steps]",
            );
        }
        if !(m.reserve_steps.is_finite() && m.reserve_steps >= 0.0) {
            r(
                "$.mission.reserve_steps",
                "must be zero or positive [steps]",
            );
        } else if positive(m.battery_steps) && m.reserve_steps >= m.battery_steps {
            r("$.mission.reserve_steps", "must be less than battery_steps");
        }
        if !(positive(m.coverage_target) && m.coverage_target <= 1.0) {
            r("$.mission.coverage_target", "must be a fraction in (0, 1]");
        }
        if let Some(v) = m.low_voltage_v
            && !(v == 0.0
                || (v.is_finite() && (MIN_LOW_VOLTAGE_V..=MAX_LOW_VOLTAGE_V).contains(&v)))
        {
            r(
                "$.mission.low_voltage_v",
                "must be 0 (off) or a voltage from 6 to 30 [V] (a P3-DX runs on 12 V)",
            );
        }
        if let Some(s) = m.low_voltage_hold_s
            && !(s.is_finite() && (0.0..=MAX_LOW_VOLTAGE_HOLD_S).contains(&s))
        {
            r("$.mission.low_voltage_hold_s", "must be from 0 to 600 [s]");
        }
    }

    fn validate_mapping(&self, r: &mut impl FnMut(&str, &str)) {
        let m = &self.mapping;
        for (path, value, max, problem) in [
            (
                "$.mapping.min_travel_m",
                m.min_travel_m,
                10.0,
                "must be from 0 to 10 [m]",
            ),
            (
                "$.mapping.min_turn_deg",
                m.min_turn_deg,
                180.0,
                "must be from 0 to 180 [deg]",
            ),
            (
                "$.mapping.max_interval_s",
                m.max_interval_s,
                600.0,
                "must be from 0 to 600 [s]",
            ),
        ] {
            if let Some(v) = value
                && !(v.is_finite() && (0.0..=max).contains(&v))
            {
                r(path, problem);
            }
        }
        if self.grid_bounds().is_none() {
            let mut problem = heapless::String::<72>::new();
            let _ = write!(
                problem,
                "must be {}",
                crate::grid::LogOddsBounds::default().occupied_thresh_range()
            );
            r("$.mapping.occupied_thresh", &problem);
        }
    }

    /// The body's outline and the clearance, and that the planning layer they make can be
    /// built at the grid's cell size (tested only on a usable grid, `grid_fine`: a grid
    /// refused for its size is reported as such, not as a body too big for it).
    fn validate_planning(&self, grid_fine: bool, r: &mut impl FnMut(&str, &str)) {
        let f = &self.robot.footprint;
        let mut fine = true;
        for (path, value) in [
            ("$.robot.footprint.width_m", f.width_m),
            ("$.robot.footprint.front_m", f.front_m),
            ("$.robot.footprint.rear_m", f.rear_m),
            ("$.robot.footprint.swing_radius_m", f.swing_radius_m),
        ] {
            if let Some(v) = value
                && !(positive(v) && v <= MAX_BODY_M)
            {
                r(path, "must be in (0, 1] m");
                fine = false;
            }
        }
        let body = self.footprint();
        if fine && body.radius_m < 0.5 * body.width_m {
            // Named where the board wrote the conflict: the swing radius if it gave one.
            if f.swing_radius_m.is_some() {
                r(
                    "$.robot.footprint.swing_radius_m",
                    "is less than half the width: the body's sides lie outside the circle it sweeps turning in place",
                );
            } else {
                r(
                    "$.robot.footprint.width_m",
                    "is more than twice the swing radius (the P3-DX's 0.267 m, as swing_radius_m is not given): the body's sides would lie outside the circle it sweeps turning in place",
                );
            }
            fine = false;
        }
        if let Some(c) = self.planning.clearance_m
            && !crate::mission::footprint::is_valid_clearance(c)
        {
            let mut problem = heapless::String::<48>::new();
            let _ = write!(
                problem,
                "must be from 0 to {} [m]",
                crate::mission::footprint::MAX_CLEARANCE_M
            );
            r("$.planning.clearance_m", &problem);
            fine = false;
        }
        if fine && grid_fine && self.planning_layer().check(self.grid.resolution_m).is_err() {
            r(
                "$.robot.footprint",
                "the body, its clearance and its turning margin span more cells of $.grid.resolution_m than the planning layer holds; use a coarser grid",
            );
        }
    }

    fn validate_localize(&self, r: &mut impl FnMut(&str, &str)) {
        let l = &self.localize;
        if let Some(n) = l.every_n_scans
            && !(1..=1000).contains(&n)
        {
            r("$.localize.every_n_scans", "must be from 1 to 1000 scans");
        }
        if let Some(v) = l.min_travel_m
            && !(v.is_finite() && (0.0..=10.0).contains(&v))
        {
            r("$.localize.min_travel_m", "must be from 0 to 10 [m]");
        }
        if let Some(v) = l.min_turn_deg
            && !(v.is_finite() && (0.0..=180.0).contains(&v))
        {
            r("$.localize.min_turn_deg", "must be from 0 to 180 [deg]");
        }
        if let Some(v) = l.search_xy_m
            && !(positive(v) && v <= 1.0)
        {
            r("$.localize.search_xy_m", "must be in (0, 1] m");
        }
        if let Some(v) = l.search_theta_deg
            && !(positive(v) && v <= 45.0)
        {
            r("$.localize.search_theta_deg", "must be in (0, 45] deg");
        }
        // What sits behind the matcher, asked for without it.
        for (path, on) in [
            ("$.localize.pose_graph", l.pose_graph),
            ("$.localize.self_calibration", l.self_calibration),
        ] {
            if on == Some(true) && l.enabled != Some(true) {
                r(path, "needs the scan matcher: $.localize.enabled true");
            }
        }
        // The matcher's window must hold a whole scan with the search around it, or every
        // match would be refused and the map drawn at the odometry pose without a word.
        let laser = &self.laser;
        let reach_m = laser.max_range_m + math::hypot(laser.mount.x_m, laser.mount.y_m);
        if l.enabled == Some(true) && positive(reach_m) && positive(self.grid.resolution_m) {
            let config = self.localize_config();
            let side = crate::localize::window_side_cells(
                reach_m,
                self.grid.resolution_m,
                &config.matcher,
            );
            if side.saturating_mul(side) > crate::localize::WINDOW_CELLS {
                let mut problem = heapless::String::<200>::new();
                let _ = write!(
                    problem,
                    "the matcher needs a {side} x {side}-cell window for laser.max_range_m at grid.resolution_m with this search, more than the {} cells it holds; use a coarser $.grid.resolution_m or a smaller search",
                    crate::localize::WINDOW_CELLS
                );
                r("$.localize.enabled", &problem);
            }
        }
    }

    fn validate_pid(&self, r: &mut impl FnMut(&str, &str)) {
        let p = &self.pid;
        for (path, v) in [
            ("$.pid.heading_kp", p.heading_kp),
            ("$.pid.distance_kp", p.distance_kp),
        ] {
            if !(positive(v) && v <= MAX_GAIN) {
                r(path, "must be a positive gain of at most 1000");
            }
        }
        for (path, v) in [
            ("$.pid.heading_ki", p.heading_ki),
            ("$.pid.heading_kd", p.heading_kd),
            ("$.pid.distance_ki", p.distance_ki),
            ("$.pid.distance_kd", p.distance_kd),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                r(path, "must be zero or a positive gain");
            }
        }
    }

    fn validate_safety(&self, r: &mut impl FnMut(&str, &str)) {
        let s = &self.safety;
        if !positive(s.obstacle_stop_m) {
            r(
                "$.safety.obstacle_stop_m",
                "must be a positive distance [m]",
            );
        } else if positive(self.robot.radius_m)
            && self.laser.min_range_m.is_finite()
            && s.obstacle_stop_m < self.laser.min_range_m - self.robot.radius_m
        {
            r(
                "$.safety.obstacle_stop_m",
                "is inside the laser's blind zone, so it can never trigger",
            );
        }
        if !(positive(s.stale_timeout_s) && s.stale_timeout_s < ARCOS_WATCHDOG_S) {
            r(
                "$.safety.stale_timeout_s",
                "must be in (0, 2) s (below the ARCOS firmware watchdog)",
            );
        }
        if !(s.back_off_m.is_finite() && s.back_off_m >= 0.0 && s.back_off_m <= 1.0) {
            r("$.safety.back_off_m", "must be in [0, 1] m");
        }
    }
}

/// Largest PID gain: the gains act on metres and radians, where 1000 already saturates the
/// motors at a millimetre's error.
const MAX_GAIN: f32 = 1000.0;

/// Range of `$.mission.low_voltage_v` when not 0 \[V\].
const MIN_LOW_VOLTAGE_V: f32 = 6.0;
const MAX_LOW_VOLTAGE_V: f32 = 30.0;
/// Longest `$.mission.low_voltage_hold_s` \[s\].
const MAX_LOW_VOLTAGE_HOLD_S: f32 = 600.0;
/// Range of the odometry corrections `$.robot.wheel_diameter_ratio` and `wheelbase_ratio`.
const MIN_ODOMETRY_RATIO: f32 = 0.8;
const MAX_ODOMETRY_RATIO: f32 = 1.2;

fn positive(v: f32) -> bool {
    v.is_finite() && v > 0.0
}
