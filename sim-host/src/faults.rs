//! Fault injection for `papillon-sim serve`: what can go wrong between the robot's PC and its
//! hardware, each fault seeded so a run with faults replays.
//!
//! The `--faults` specification is a comma-separated list of `name=value` items:
//!
//! | item | meaning |
//! |---|---|
//! | `corrupt=P` | each byte the microcontroller sends has one bit flipped with probability P |
//! | `drop=P` | each byte the microcontroller sends is lost with probability P |
//! | `latency=MS` | the microcontroller's bytes leave MS milliseconds late |
//! | `jitter=MS` | plus a uniform extra delay of up to MS milliseconds (order is kept) |
//! | `cut=T+D` | the ARCOS link is cut from T s after start for D s: no byte passes either way, and a TCP client is disconnected (repeatable) |
//! | `laser-drop=T+D` | the laser sends no scan from T s for D s (repeatable) |
//! | `slip=F` | the random part of `serve --slip`'s model multiplied by F (1 = as is, the default `thesis`'s slide; 0 = none; `realistic`'s wheel errors are not scaled) |
//! | `estop=T+D` | the e-stop is pressed from T s for D s (repeatable) |
//! | `drain=V` | the battery drains V volts per minute while powered |
//!
//! Limits: [`MAX_DELAY_MS`], [`MAX_WINDOW_S`], [`MAX_SLIP_FACTOR`], [`MAX_DRAIN_V_PER_MIN`];
//! each fault but the windows at most once, no empty item (an empty specification is no
//! fault).
//!
//! Byte faults (`corrupt`, `drop`, `latency`, `jitter`) apply to the microcontroller's output
//! (robot to PC), where a noisy serial line hurts the onboard binary's decoder.

use std::collections::VecDeque;

use papillon::random::{self, ProjectRng};

/// A span of simulated time, `[start_s, start_s + duration_s)` \[s\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// Start, seconds after the simulation started \[s\].
    pub start_s: f64,
    /// Length \[s\].
    pub duration_s: f64,
}

impl Window {
    /// Whether `t_s` falls inside.
    pub fn contains(&self, t_s: f64) -> bool {
        t_s >= self.start_s && t_s < self.start_s + self.duration_s
    }
}

/// Every fault of one `serve` run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Faults {
    /// Probability that a byte has one bit flipped.
    pub corrupt: f32,
    /// Probability that a byte is lost.
    pub drop: f32,
    /// Added delay of the microcontroller's bytes \[ms\].
    pub latency_ms: u32,
    /// Largest extra random delay \[ms\].
    pub jitter_ms: u32,
    /// When the ARCOS link is cut.
    pub cuts: Vec<Window>,
    /// When the laser is silent.
    pub laser_dropouts: Vec<Window>,
    /// Factor on the wheel slip (`None`: the simulator's default).
    pub slip: Option<f32>,
    /// When the e-stop is pressed.
    pub estops: Vec<Window>,
    /// Battery drain while powered \[V/min\] (`None`: the simulator's default).
    pub drain_v_per_min: Option<f32>,
}

/// A `--faults` specification that cannot be read.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum FaultSpecError {
    /// An item that is not `name=value`, or an unknown name.
    UnknownItem {
        /// The item seen.
        item: String,
    },
    /// A value that is not a probability in [0, 1].
    BadProbability {
        /// The item seen.
        item: String,
    },
    /// A value that is not a non-negative number.
    BadNumber {
        /// The item seen.
        item: String,
    },
    /// A window that is not `T+D` with non-negative seconds.
    BadWindow {
        /// The item seen.
        item: String,
    },
    /// A latency or jitter longer than [`MAX_DELAY_MS`].
    TooLong {
        /// The item seen.
        item: String,
    },
    /// A fault that takes one value given twice.
    Repeated {
        /// The second item.
        item: String,
    },
    /// A slip factor above [`MAX_SLIP_FACTOR`] or a drain above [`MAX_DRAIN_V_PER_MIN`].
    TooLarge {
        /// The item seen.
        item: String,
        /// The largest value accepted.
        max: u32,
    },
}

/// Longest `latency` or `jitter` \[ms\]: a link silent for longer is a cut (`cut=T+D`), and
/// the firmware's watchdog (2 s) has long stopped the robot.
pub const MAX_DELAY_MS: u32 = 10_000;
/// Latest start and longest duration of a `cut`, `laser-drop` or `estop` window \[s\]: a day,
/// far beyond any mission `serve` hosts.
pub const MAX_WINDOW_S: f64 = 86_400.0;
/// Largest `slip` factor: 100 times the thesis's slip is 1.5 m per move.
pub const MAX_SLIP_FACTOR: f32 = 100.0;
/// Largest `drain` \[V/min\]: more empties a 12 V battery in a few seconds.
pub const MAX_DRAIN_V_PER_MIN: f32 = 100.0;

impl std::fmt::Display for FaultSpecError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FaultSpecError::UnknownItem { item } => write!(
                f,
                "unknown fault {item:?}: expected corrupt=P, drop=P, latency=MS, jitter=MS, \
                 cut=T+D, laser-drop=T+D, slip=F, estop=T+D or drain=V"
            ),
            FaultSpecError::BadProbability { item } => {
                write!(f, "in {item:?}: expected a probability between 0 and 1")
            }
            FaultSpecError::BadNumber { item } => {
                write!(f, "in {item:?}: expected a non-negative number")
            }
            FaultSpecError::TooLong { item } => write!(
                f,
                "in {item:?}: expected at most {MAX_DELAY_MS} ms (a longer silence is a cut: cut=T+D)"
            ),
            FaultSpecError::BadWindow { item } => write!(
                f,
                "in {item:?}: expected START+DURATION in seconds, each at most {MAX_WINDOW_S} \
                 (a day), e.g. 10+3"
            ),
            FaultSpecError::Repeated { item } => {
                write!(f, "in {item:?}: this fault is already given")
            }
            FaultSpecError::TooLarge { item, max } => {
                write!(f, "in {item:?}: expected a number from 0 to {max}")
            }
        }
    }
}

impl std::error::Error for FaultSpecError {}

impl std::str::FromStr for Faults {
    type Err = FaultSpecError;

    fn from_str(spec: &str) -> Result<Self, Self::Err> {
        let mut faults = Faults::default();
        let mut seen: Vec<&str> = Vec::new();
        if spec.trim().is_empty() {
            return Ok(faults);
        }
        for item in spec.split(',').map(str::trim) {
            let owned = || item.to_string();
            let (name, value) = item
                .split_once('=')
                .ok_or_else(|| FaultSpecError::UnknownItem { item: owned() })?;
            // The windows repeat; any other fault given twice would be one value silently lost.
            let name = name.trim();
            if !matches!(name, "cut" | "laser-drop" | "estop") {
                if seen.contains(&name) {
                    return Err(FaultSpecError::Repeated { item: owned() });
                }
                seen.push(name);
            }
            let value = value.trim();
            let number = || {
                value
                    .parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite() && *v >= 0.0)
                    .ok_or_else(|| FaultSpecError::BadNumber { item: owned() })
            };
            // A delay longer than a few seconds is a cut (`cut=T+D`), not a latency.
            let delay_ms = || {
                number().and_then(|v| {
                    if v <= MAX_DELAY_MS as f32 {
                        Ok(v.round() as u32)
                    } else {
                        Err(FaultSpecError::TooLong { item: owned() })
                    }
                })
            };
            let at_most = |v: f32, max: f32| {
                if v <= max {
                    Ok(v)
                } else {
                    Err(FaultSpecError::TooLarge {
                        item: owned(),
                        max: max as u32,
                    })
                }
            };
            let probability = || {
                value
                    .parse::<f32>()
                    .ok()
                    .filter(|p| (0.0..=1.0).contains(p))
                    .ok_or_else(|| FaultSpecError::BadProbability { item: owned() })
            };
            let window = || -> Result<Window, FaultSpecError> {
                let bad = || FaultSpecError::BadWindow { item: owned() };
                let (start, duration) = value.split_once('+').ok_or_else(bad)?;
                let secs = |s: &str| {
                    s.trim()
                        .parse::<f64>()
                        .ok()
                        .filter(|v| (0.0..=MAX_WINDOW_S).contains(v))
                };
                Ok(Window {
                    start_s: secs(start).ok_or_else(bad)?,
                    duration_s: secs(duration).ok_or_else(bad)?,
                })
            };
            match name {
                "corrupt" => faults.corrupt = probability()?,
                "drop" => faults.drop = probability()?,
                "latency" => faults.latency_ms = delay_ms()?,
                "jitter" => faults.jitter_ms = delay_ms()?,
                "cut" => faults.cuts.push(window()?),
                "laser-drop" => faults.laser_dropouts.push(window()?),
                "slip" => faults.slip = Some(at_most(number()?, MAX_SLIP_FACTOR)?),
                "estop" => faults.estops.push(window()?),
                "drain" => faults.drain_v_per_min = Some(at_most(number()?, MAX_DRAIN_V_PER_MIN)?),
                _ => return Err(FaultSpecError::UnknownItem { item: owned() }),
            }
        }
        Ok(faults)
    }
}

impl Faults {
    /// Whether the ARCOS link is cut at `t_s`.
    pub fn link_cut(&self, t_s: f64) -> bool {
        self.cuts.iter().any(|w| w.contains(t_s))
    }

    /// Whether the laser is silent at `t_s`.
    pub fn laser_silent(&self, t_s: f64) -> bool {
        self.laser_dropouts.iter().any(|w| w.contains(t_s))
    }

    /// Applies a laser dropout to a laser's output at `t_s`: `out` holds `replies` bytes of
    /// replies to the client's requests, then the scans the laser streamed on its own. While
    /// the laser is silent the replies still go out and the streamed scans do not.
    pub fn silence_laser(&self, t_s: f64, out: &mut Vec<u8>, replies: usize) {
        if self.laser_silent(t_s) {
            out.truncate(replies);
        }
    }

    /// Whether the e-stop is pressed at `t_s`.
    pub fn estop_pressed(&self, t_s: f64) -> bool {
        self.estops.iter().any(|w| w.contains(t_s))
    }

    /// Whether any byte fault is configured.
    fn has_byte_faults(&self) -> bool {
        self.corrupt > 0.0 || self.drop > 0.0
    }

    /// Drops and corrupts bytes of `data` in place.
    pub fn damage(&self, rng: &mut ProjectRng, data: &mut Vec<u8>) {
        if !self.has_byte_faults() {
            return;
        }
        data.retain(|_| !random::chance(rng, self.drop));
        for byte in data.iter_mut() {
            if random::chance(rng, self.corrupt) {
                *byte ^= 1 << random::below(rng, 8);
            }
        }
    }

    /// Applies the wheel-slip and battery faults to a body configuration.
    pub fn apply_to_body(&self, config: &mut crate::physics::BodyConfig) {
        if let Some(f) = self.slip {
            let s = &mut config.slip;
            s.distance_var_m2_per_m *= f * f;
            s.rotation_var_rad2_per_rad *= f * f;
            s.drift_var_rad2_per_m *= f * f;
            s.end_of_move_m *= f;
            s.end_of_move_rad *= f;
        }
        if let Some(v) = self.drain_v_per_min {
            config.battery_drain_v_per_s = v / 60.0;
        }
    }
}

/// Bytes on their way out of the microcontroller, held back by latency and jitter; the order
/// of bytes is kept (a chunk never leaves before the one sent earlier).
#[derive(Debug, Default)]
pub struct DelayLine {
    queue: VecDeque<(f64, Vec<u8>)>,
    last_release_s: f64,
}

impl DelayLine {
    /// Queues `data`, sent at `now_s`, to leave after the configured delay.
    pub fn push(&mut self, faults: &Faults, rng: &mut ProjectRng, now_s: f64, data: Vec<u8>) {
        if data.is_empty() {
            return;
        }
        let jitter = if faults.jitter_ms > 0 {
            random::unit_f32(rng) as f64 * faults.jitter_ms as f64
        } else {
            0.0
        };
        let release = (now_s + (faults.latency_ms as f64 + jitter) * 1e-3).max(self.last_release_s);
        self.last_release_s = release;
        self.queue.push_back((release, data));
    }

    /// Appends to `out` every chunk due by `now_s`.
    pub fn due(&mut self, now_s: f64, out: &mut Vec<u8>) {
        while let Some((t, _)) = self.queue.front() {
            if *t > now_s {
                break;
            }
            if let Some((_, data)) = self.queue.pop_front() {
                out.extend_from_slice(&data);
            }
        }
    }

    /// Forgets everything queued (the link was cut).
    pub fn clear(&mut self) {
        self.queue.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_spec_parses() {
        let f: Faults = "corrupt=0.01, drop=0.002, latency=20, jitter=5, cut=10+3, cut=40+2, \
                         laser-drop=15+2, slip=2, estop=30+1.5, drain=0.5"
            .parse()
            .unwrap();
        assert_eq!(f.corrupt, 0.01);
        assert_eq!(f.drop, 0.002);
        assert_eq!((f.latency_ms, f.jitter_ms), (20, 5));
        assert_eq!(f.cuts.len(), 2);
        assert!(f.link_cut(10.0) && f.link_cut(12.9) && !f.link_cut(13.0) && !f.link_cut(9.9));
        assert!(f.link_cut(41.0));
        assert!(f.laser_silent(16.0) && !f.laser_silent(17.5));
        assert!(f.estop_pressed(31.0) && !f.estop_pressed(31.6));
        assert_eq!(f.slip, Some(2.0));
        assert_eq!(f.drain_v_per_min, Some(0.5));
    }

    #[test]
    fn bad_specs_name_the_item() {
        let e = "cut=10".parse::<Faults>().unwrap_err();
        assert_eq!(
            e,
            FaultSpecError::BadWindow {
                item: "cut=10".into()
            }
        );
        assert!(e.to_string().contains("START+DURATION"));
        assert!(matches!(
            "latency=-3".parse::<Faults>(),
            Err(FaultSpecError::BadNumber { .. })
        ));
        assert!(matches!(
            "drop=1.5".parse::<Faults>(),
            Err(FaultSpecError::BadProbability { .. })
        ));
        assert!(matches!(
            "gremlins=1".parse::<Faults>(),
            Err(FaultSpecError::UnknownItem { .. })
        ));
    }

    #[test]
    fn the_delay_line_keeps_order_and_releases_on_time() {
        let faults: Faults = "latency=50,jitter=30".parse().unwrap();
        let mut rng = random::seeded(3);
        let mut line = DelayLine::default();
        let mut out = Vec::new();
        for k in 0..20u8 {
            line.push(&faults, &mut rng, k as f64 * 0.01, vec![k]);
        }
        line.due(0.049, &mut out);
        assert!(out.is_empty(), "nothing leaves before the latency");
        line.due(1.0, &mut out);
        assert_eq!(out, (0..20).collect::<Vec<u8>>());
    }

    #[test]
    fn slip_and_drain_change_the_body() {
        let faults: Faults = "slip=0,drain=6".parse().unwrap();
        let mut config = crate::physics::BodyConfig::default();
        faults.apply_to_body(&mut config);
        assert_eq!(config.slip, crate::physics::SlipConfig::none());
        assert!((config.battery_drain_v_per_s - 0.1).abs() < 1e-6);
    }
}
