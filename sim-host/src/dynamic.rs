//! Dynamic obstacles: doors that open and close on a schedule, and people walking paths.
//!
//! A [`Door`] is a set of cells of the world that are blocked while it is closed and free while
//! it is open; its schedule lists the times \[s\] at which it changes. [`Dynamics::update`] writes
//! the doors' current states into the [`World`], so physics and the laser see them with no
//! extra work. A door never closes on something: while a robot or a person overlaps its cells,
//! closing waits.
//!
//! A [`Person`] walks a polyline at a constant speed, back and forth (or round a loop), and is a
//! [`Disc`]: pass [`Dynamics::people_discs`] to the physics (as obstacles) and to the laser
//! (as returns). People do not avoid robots; a robot never moves deeper into a person, so it is
//! pushed aside only in the sense that it stops.

use papillon::geometry::Point2;
use papillon::grid::Cell;

use crate::physics::Disc;
use crate::world::World;

/// Whether a door is open or closed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DoorState {
    /// Its cells are free.
    Open,
    /// Its cells are blocked.
    Closed,
}

/// A door: cells toggled between free and blocked at scheduled times.
#[derive(Clone, Debug, PartialEq)]
pub struct Door {
    cells: Vec<Cell>,
    initial: DoorState,
    /// (time \[s\], state from then on), sorted by time.
    schedule: Vec<(f64, DoorState)>,
    applied: Option<DoorState>,
}

impl Door {
    /// A door over the cells whose centres lie in `[x0, x1) x [y0, y1)` \[m\] of `world`, in
    /// state `initial` until the first scheduled change.
    pub fn new(world: &World, x0: f32, y0: f32, x1: f32, y1: f32, initial: DoorState) -> Self {
        Self::from_cells(world.cells_in_rect(x0, y0, x1, y1), initial)
    }

    /// A door over the given cells.
    pub fn from_cells(cells: Vec<Cell>, initial: DoorState) -> Self {
        Self {
            cells,
            initial,
            schedule: Vec::new(),
            applied: None,
        }
    }

    /// Adds a change to `state` at `time_s` \[s\] (builder style; changes may be given in any
    /// order).
    pub fn at(mut self, time_s: f64, state: DoorState) -> Self {
        self.schedule.push((time_s, state));
        self.schedule.sort_by(|a, b| a.0.total_cmp(&b.0));
        self
    }

    /// Adds changes that alternate the state every `period_s` \[s\] from `first_s` up to
    /// `until_s`, starting with the opposite of the initial state.
    pub fn alternating(mut self, first_s: f64, period_s: f64, until_s: f64) -> Self {
        let mut state = self.initial;
        let mut t = first_s;
        while period_s > 0.0 && t <= until_s {
            state = flip(state);
            self = self.at(t, state);
            t += period_s;
        }
        self
    }

    /// The cells.
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// The scheduled state at `time_s` \[s\] (what the schedule asks, before any wait for the
    /// doorway to clear).
    pub fn scheduled_state(&self, time_s: f64) -> DoorState {
        self.schedule
            .iter()
            .take_while(|(t, _)| *t <= time_s)
            .last()
            .map_or(self.initial, |&(_, s)| s)
    }

    /// The state last written to the world (`None` before the first update).
    pub fn state(&self) -> Option<DoorState> {
        self.applied
    }

    fn obstructed(&self, world: &World, discs: &[Disc]) -> bool {
        let g = world.geometry();
        let half = g.resolution_m / 2.0;
        self.cells.iter().any(|&c| {
            let p = g.cell_center(c);
            discs.iter().any(|d| {
                let dx = ((p.x - d.center.x).abs() - half).max(0.0);
                let dy = ((p.y - d.center.y).abs() - half).max(0.0);
                dx * dx + dy * dy < d.radius_m * d.radius_m
            })
        })
    }
}

fn flip(s: DoorState) -> DoorState {
    match s {
        DoorState::Open => DoorState::Closed,
        DoorState::Closed => DoorState::Open,
    }
}

/// A person walking a path at constant speed.
#[derive(Clone, Debug, PartialEq)]
pub struct Person {
    path: Vec<Point2>,
    speed_m_s: f32,
    radius_m: f32,
    looped: bool,
    start_s: f64,
    length_m: f32,
}

impl Person {
    /// A person of `radius_m` walking `path` \[m\] at `speed_m_s` from time `start_s` \[s\] (standing
    /// at the first point before), back and forth along it, or round it if `looped` (the last
    /// point joins the first). An empty path puts the person at the origin.
    pub fn new(
        path: Vec<Point2>,
        speed_m_s: f32,
        radius_m: f32,
        looped: bool,
        start_s: f64,
    ) -> Self {
        let mut length_m = path.windows(2).map(|w| w[0].distance(w[1])).sum::<f32>();
        if looped && path.len() > 1 {
            length_m += path[path.len() - 1].distance(path[0]);
        }
        Self {
            path,
            speed_m_s: speed_m_s.max(0.0),
            radius_m,
            looped,
            start_s,
            length_m,
        }
    }

    /// Radius \[m\].
    pub fn radius_m(&self) -> f32 {
        self.radius_m
    }

    /// Position at `time_s` \[s\].
    pub fn position_at(&self, time_s: f64) -> Point2 {
        let Some(&first) = self.path.first() else {
            return Point2::default();
        };
        if self.length_m <= 0.0 || time_s <= self.start_s {
            return first;
        }
        let walked = ((time_s - self.start_s) * self.speed_m_s as f64) as f32;
        let mut s = if self.looped {
            walked.rem_euclid(self.length_m)
        } else {
            let s = walked.rem_euclid(2.0 * self.length_m);
            if s > self.length_m {
                2.0 * self.length_m - s
            } else {
                s
            }
        };
        let n = self.path.len();
        let segments = if self.looped { n } else { n - 1 };
        for k in 0..segments {
            let (a, b) = (self.path[k], self.path[(k + 1) % n]);
            let l = a.distance(b);
            if s <= l {
                let f = if l > 0.0 { s / l } else { 0.0 };
                return Point2::new(a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f);
            }
            s -= l;
        }
        if self.looped { first } else { self.path[n - 1] }
    }

    /// The person's disc at `time_s` \[s\].
    pub fn disc_at(&self, time_s: f64) -> Disc {
        Disc::new(self.position_at(time_s), self.radius_m)
    }
}

/// The dynamic obstacles of a world.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dynamics {
    doors: Vec<Door>,
    people: Vec<Person>,
}

impl Dynamics {
    /// No doors, no people.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a door (builder style).
    pub fn with_door(mut self, door: Door) -> Self {
        self.doors.push(door);
        self
    }

    /// Adds a person (builder style).
    pub fn with_person(mut self, person: Person) -> Self {
        self.people.push(person);
        self
    }

    /// The doors.
    pub fn doors(&self) -> &[Door] {
        &self.doors
    }

    /// The people.
    pub fn people(&self) -> &[Person] {
        &self.people
    }

    /// Whether there is nothing dynamic.
    pub fn is_empty(&self) -> bool {
        self.doors.is_empty() && self.people.is_empty()
    }

    /// The people's discs at `time_s` \[s\].
    pub fn people_discs(&self, time_s: f64) -> Vec<Disc> {
        self.people.iter().map(|p| p.disc_at(time_s)).collect()
    }

    /// Brings the doors to their scheduled states at `time_s` \[s\], writing them into `world`.
    /// A door due to close stays open while one of `robots` or a person overlaps it. Returns
    /// how many doors changed state.
    pub fn update(&mut self, time_s: f64, world: &mut World, robots: &[Disc]) -> usize {
        let mut occupants: Vec<Disc> = robots.to_vec();
        occupants.extend(self.people_discs(time_s));
        let mut changed = 0;
        for door in &mut self.doors {
            let want = door.scheduled_state(time_s);
            if door.applied == Some(want) {
                continue;
            }
            if want == DoorState::Closed && door.obstructed(world, &occupants) {
                continue;
            }
            for &c in &door.cells {
                world.set_blocked(c, want == DoorState::Closed);
            }
            if door.applied.is_some() {
                changed += 1;
            }
            door.applied = Some(want);
        }
        changed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::laser::{LaserSim, cast_ray};
    use crate::physics::{BodyConfig, RobotBody, SlipConfig, advance_all};
    use crate::world::builtin;
    use papillon::geometry::Pose2;
    use papillon::sensor::LaserConfig;

    /// The lab's door is the gap at x 3.9..4.1, y 4..5.
    fn lab_with_door() -> (World, Dynamics) {
        let w = builtin::lab(0.1).unwrap();
        let (x0, y0, x1, y1) = builtin::LAB_DOOR;
        let door = Door::new(&w, x0, y0, x1, y1, DoorState::Open).at(10.0, DoorState::Closed);
        (w, Dynamics::new().with_door(door))
    }

    #[test]
    fn a_door_closes_on_schedule_and_the_laser_sees_it() {
        let (mut w, mut dy) = lab_with_door();
        let eye = Point2::new(2.0, 4.5);
        assert_eq!(dy.update(0.0, &mut w, &[]), 0);
        let open = cast_ray(&w, eye, 0.0, 10.0).unwrap();
        assert!(
            (open - 5.7).abs() < 1e-3,
            "through the door to the east wall: {open}"
        );
        assert_eq!(dy.update(9.9, &mut w, &[]), 0);
        assert_eq!(dy.update(10.0, &mut w, &[]), 1);
        assert_eq!(dy.doors()[0].state(), Some(DoorState::Closed));
        let closed = cast_ray(&w, eye, 0.0, 10.0).unwrap();
        assert!((closed - 1.9).abs() < 1e-3, "{closed}");
    }

    #[test]
    fn a_closed_door_stops_a_robot() {
        let (mut w, mut dy) = lab_with_door();
        dy.update(10.0, &mut w, &[]);
        let cfg = BodyConfig {
            slip: SlipConfig::none(),
            ..BodyConfig::default()
        };
        let mut bodies = [RobotBody::new(cfg, Pose2::new(2.5, 4.5, 0.0), 1)];
        bodies[0].command(400.0, 0.0);
        for _ in 0..100 {
            advance_all(&mut bodies, 0.1, &w, &[]);
        }
        assert!(bodies[0].stalled() && bodies[0].front_bumper());
        // The front edge, 0.21 m ahead of the axle, stops at the door.
        assert!(bodies[0].true_pose().x <= 3.9 - 0.21 + 1e-3);
    }

    #[test]
    fn a_door_waits_for_the_doorway_to_clear() {
        let (mut w, mut dy) = lab_with_door();
        dy.update(0.0, &mut w, &[]);
        let robot = Disc::new(Point2::new(4.0, 4.5), 0.25);
        assert_eq!(dy.update(12.0, &mut w, &[robot]), 0);
        assert_eq!(dy.doors()[0].state(), Some(DoorState::Open));
        assert_eq!(dy.update(13.0, &mut w, &[]), 1);
        assert!(w.is_blocked_at(Point2::new(4.0, 4.5)));
    }

    #[test]
    fn alternating_schedule() {
        let w = builtin::lab(0.1).unwrap();
        let d = Door::new(&w, 3.9, 4.0, 4.1, 5.0, DoorState::Open).alternating(5.0, 5.0, 20.0);
        assert_eq!(d.scheduled_state(4.9), DoorState::Open);
        assert_eq!(d.scheduled_state(5.0), DoorState::Closed);
        assert_eq!(d.scheduled_state(12.0), DoorState::Open);
        assert_eq!(d.scheduled_state(19.0), DoorState::Closed);
        assert_eq!(d.scheduled_state(100.0), DoorState::Open);
        assert_eq!(d.cells().len(), 20);
    }

    #[test]
    fn a_person_walks_back_and_forth_and_round_loops() {
        let path = vec![
            Point2::new(1.0, 1.0),
            Point2::new(5.0, 1.0),
            Point2::new(5.0, 3.0),
        ];
        let p = Person::new(path.clone(), 1.0, 0.2, false, 2.0);
        assert_eq!(p.position_at(0.0), Point2::new(1.0, 1.0));
        assert_eq!(p.position_at(4.0), Point2::new(3.0, 1.0));
        assert_eq!(p.position_at(7.0), Point2::new(5.0, 2.0));
        assert_eq!(p.position_at(8.0), Point2::new(5.0, 3.0));
        assert_eq!(p.position_at(9.0), Point2::new(5.0, 2.0));
        assert_eq!(p.position_at(14.0), Point2::new(1.0, 1.0));
        let q = Person::new(path, 1.0, 0.2, true, 0.0);
        let perimeter = 4.0 + 2.0 + 20f32.sqrt();
        let back = q.position_at(perimeter as f64);
        assert!(back.distance(Point2::new(1.0, 1.0)) < 1e-3, "{back:?}");
    }

    #[test]
    fn a_person_is_seen_and_blocks_a_robot() {
        let w = builtin::empty(0.1).unwrap();
        let dy = Dynamics::new().with_person(Person::new(
            vec![Point2::new(8.0, 3.0), Point2::new(8.0, 9.0)],
            0.5,
            0.2,
            false,
            0.0,
        ));
        // At t = 4 s the person stands at (8, 5), right in front of a robot at (5, 5).
        let people = dy.people_discs(4.0);
        assert_eq!(people[0].center, Point2::new(8.0, 5.0));
        let cfg = LaserConfig {
            noise_fraction: 0.0,
            ..LaserConfig::thesis()
        };
        let scan = LaserSim::new(cfg, 1).scan(&w, Pose2::new(5.0, 5.0, 0.0), &people);
        assert!((scan.beams()[90].range_m.unwrap() - 2.8).abs() < 1e-3);
        // A robot driving east meets the (standing) person.
        let body_cfg = BodyConfig {
            slip: SlipConfig::none(),
            ..BodyConfig::default()
        };
        let mut bodies = [RobotBody::new(body_cfg, Pose2::new(5.0, 5.0, 0.0), 1)];
        bodies[0].command(500.0, 0.0);
        for _ in 0..100 {
            advance_all(&mut bodies, 0.1, &w, &people);
        }
        assert!(bodies[0].stalled());
        let gap = bodies[0]
            .true_pose()
            .position()
            .distance(Point2::new(8.0, 5.0));
        assert!((gap - 0.45).abs() < 2e-3, "{gap}");
    }
}
