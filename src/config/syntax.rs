//! The syntax and shape check of a board file, before `serde-json-core` reads it: a small
//! scanner that reports the line and column of a syntax error, rejects keys the schema does not
//! know and duplicate keys, checks each value against its field's kind (object, string of at
//! most N bytes, whole number in the field's range, number) so that a wrong one is reported
//! with its JSON path, and records which known keys were present.

use super::*;

/// What a key's value must be.
#[derive(Clone, Copy, Debug)]
pub(super) enum Kind {
    /// An object (its keys have their own entries).
    Object,
    /// A string of at most this many bytes.
    Str(usize),
    /// A whole number from 0 to this.
    Whole(u64),
    /// Any number.
    Number,
    /// `true` or `false`.
    Bool,
    /// `null` or the inner kind.
    Optional(&'static Kind),
}

/// Every key a board file may hold, as a JSON path, whether it is required, and what its value
/// must be (the field types of [`BoardConfig`]: `Name` 32 bytes, `Address` 64, `u16`, `u32`,
/// `u64`, `f32`).
pub(super) const SCHEMA: &[(&str, bool, Kind)] = &[
    ("$.robot", true, Kind::Object),
    ("$.robot.name", true, Kind::Str(32)),
    ("$.robot.subclass", true, Kind::Str(32)),
    ("$.robot.radius_m", true, Kind::Number),
    ("$.robot.max_speed_mm_s", true, Kind::Number),
    ("$.robot.max_turn_rate_deg_s", true, Kind::Number),
    ("$.robot.accel_mm_s2", true, Kind::Number),
    ("$.robot.decel_mm_s2", true, Kind::Number),
    ("$.robot.rot_accel_deg_s2", true, Kind::Number),
    (
        "$.robot.wheel_diameter_ratio",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.robot.wheelbase_ratio",
        false,
        Kind::Optional(&Kind::Number),
    ),
    ("$.robot.wheelbase_m", false, Kind::Optional(&Kind::Number)),
    ("$.robot.footprint", false, Kind::Object),
    (
        "$.robot.footprint.width_m",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.robot.footprint.front_m",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.robot.footprint.rear_m",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.robot.footprint.swing_radius_m",
        false,
        Kind::Optional(&Kind::Number),
    ),
    ("$.link", true, Kind::Object),
    ("$.link.port", true, Kind::Str(64)),
    ("$.link.tcp", false, Kind::Optional(&Kind::Str(64))),
    ("$.link.baud", true, Kind::Whole(u32::MAX as u64)),
    ("$.link.switch_to_baud", true, Kind::Whole(u32::MAX as u64)),
    ("$.laser", true, Kind::Object),
    ("$.laser.model", true, Kind::Str(32)),
    ("$.laser.address", false, Kind::Optional(&Kind::Str(64))),
    ("$.laser.port", false, Kind::Optional(&Kind::Str(64))),
    (
        "$.laser.baud",
        false,
        Kind::Optional(&Kind::Whole(u32::MAX as u64)),
    ),
    ("$.laser.beam_count", true, Kind::Whole(u16::MAX as u64)),
    ("$.laser.first_angle_deg", true, Kind::Number),
    ("$.laser.step_deg", true, Kind::Number),
    ("$.laser.max_range_m", true, Kind::Number),
    ("$.laser.min_range_m", true, Kind::Number),
    ("$.laser.noise_fraction", true, Kind::Number),
    ("$.laser.rate_hz", true, Kind::Number),
    ("$.laser.mount", true, Kind::Object),
    ("$.laser.mount.x_m", true, Kind::Number),
    ("$.laser.mount.y_m", true, Kind::Number),
    ("$.laser.mount.theta_deg", true, Kind::Number),
    ("$.grid", true, Kind::Object),
    ("$.grid.width_m", true, Kind::Number),
    ("$.grid.height_m", true, Kind::Number),
    ("$.grid.resolution_m", true, Kind::Number),
    ("$.grid.origin_x_m", true, Kind::Number),
    ("$.grid.origin_y_m", true, Kind::Number),
    ("$.mission", true, Kind::Object),
    ("$.mission.method", true, Kind::Str(32)),
    ("$.mission.population", true, Kind::Whole(u16::MAX as u64)),
    ("$.mission.generations", true, Kind::Whole(u16::MAX as u64)),
    ("$.mission.strategy", true, Kind::Str(32)),
    ("$.mission.objective", false, Kind::Optional(&Kind::Str(32))),
    ("$.mission.preset", false, Kind::Optional(&Kind::Str(32))),
    ("$.mission.targets", true, Kind::Whole(u16::MAX as u64)),
    ("$.mission.battery_steps", true, Kind::Number),
    ("$.mission.reserve_steps", true, Kind::Number),
    ("$.mission.coverage_target", true, Kind::Number),
    ("$.mission.seed", true, Kind::Whole(u64::MAX)),
    (
        "$.mission.low_voltage_v",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.mission.low_voltage_hold_s",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.mission.return_to_start",
        false,
        Kind::Optional(&Kind::Bool),
    ),
    ("$.pid", true, Kind::Object),
    ("$.pid.heading_kp", true, Kind::Number),
    ("$.pid.heading_ki", true, Kind::Number),
    ("$.pid.heading_kd", true, Kind::Number),
    ("$.pid.distance_kp", true, Kind::Number),
    ("$.pid.distance_ki", true, Kind::Number),
    ("$.pid.distance_kd", true, Kind::Number),
    ("$.safety", true, Kind::Object),
    ("$.safety.obstacle_stop_m", true, Kind::Number),
    ("$.safety.stale_timeout_s", true, Kind::Number),
    ("$.safety.back_off_m", true, Kind::Number),
    ("$.persistence", true, Kind::Object),
    ("$.persistence.save_every_s", true, Kind::Number),
    ("$.localize", false, Kind::Object),
    ("$.localize.enabled", false, Kind::Optional(&Kind::Bool)),
    (
        "$.localize.every_n_scans",
        false,
        Kind::Optional(&Kind::Whole(u16::MAX as u64)),
    ),
    (
        "$.localize.min_travel_m",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.localize.min_turn_deg",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.localize.search_xy_m",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.localize.search_theta_deg",
        false,
        Kind::Optional(&Kind::Number),
    ),
    ("$.localize.pose_graph", false, Kind::Optional(&Kind::Bool)),
    (
        "$.localize.self_calibration",
        false,
        Kind::Optional(&Kind::Bool),
    ),
    ("$.mapping", false, Kind::Object),
    (
        "$.mapping.motion_filter",
        false,
        Kind::Optional(&Kind::Bool),
    ),
    (
        "$.mapping.min_travel_m",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.mapping.min_turn_deg",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.mapping.max_interval_s",
        false,
        Kind::Optional(&Kind::Number),
    ),
    (
        "$.mapping.occupied_thresh",
        false,
        Kind::Optional(&Kind::Number),
    ),
    ("$.planning", false, Kind::Object),
    (
        "$.planning.clearance_m",
        false,
        Kind::Optional(&Kind::Number),
    ),
];

// The seen-set is a `u128`.
const _: () = assert!(SCHEMA.len() <= 128);

/// A strict JSON syntax check (RFC 8259) that locates the first error, because
/// `serde-json-core` reports what went wrong but not where. It also checks every key against
/// [`SCHEMA`] and returns the set of schema entries seen (bit `i` for entry `i`).
pub(super) fn check_syntax(json: &[u8]) -> Result<u128, ConfigError> {
    let mut s = Scanner {
        json,
        pos: 0,
        path: heapless::String::new(),
        seen: 0,
        unknown: None,
    };
    s.ws();
    s.value(0)?;
    s.ws();
    if s.pos < json.len() {
        return Err(s.error("end of input after the top-level value"));
    }
    if let Some(e) = s.unknown {
        return Err(e);
    }
    Ok(s.seen)
}

/// Nesting depth the syntax check accepts.
const MAX_DEPTH: usize = 32;

struct Scanner<'a> {
    json: &'a [u8],
    pos: usize,
    /// JSON path of the object being scanned (`$` at the top level; empty inside arrays).
    path: heapless::String<96>,
    /// Schema entries seen so far.
    seen: u128,
    /// The first unknown or duplicate key, or value of the wrong kind, in document order
    /// (reported once the whole text is known to be well-formed).
    unknown: Option<ConfigError>,
}

impl Scanner<'_> {
    fn line_column(&self, pos: usize) -> (usize, usize) {
        let upto = &self.json[..pos.min(self.json.len())];
        let line = 1 + upto.iter().filter(|&&b| b == b'\n').count();
        let line_start = upto.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        (line, pos - line_start + 1)
    }

    fn error(&self, expected: &'static str) -> ConfigError {
        let (line, column) = self.line_column(self.pos);
        ConfigError::Syntax {
            offset: self.pos,
            line,
            column,
            expected,
        }
    }

    /// Records the key spanning `start..end` (quotes included) of the current object; returns
    /// the path length to restore afterwards and the key's schema entry, if it has one.
    fn key(&mut self, start: usize, end: usize) -> (usize, Option<usize>) {
        let restore = self.path.len();
        let key = core::str::from_utf8(&self.json[start + 1..end - 1]).unwrap_or("?");
        let fits = self.path.push('.').is_ok() && self.path.push_str(key).is_ok();
        if !fits {
            // Deeper than any schema path: unknown for sure; keep the prefix readable.
            self.path.truncate(restore);
        }
        let entry = SCHEMA
            .iter()
            .position(|(p, ..)| fits && *p == self.path.as_str());
        match entry {
            Some(i) if self.seen & (1u128 << i) != 0 && self.unknown.is_none() => {
                let (line, column) = self.line_column(start);
                self.unknown = Some(ConfigError::DuplicateKey {
                    path: SCHEMA[i].0,
                    line,
                    column,
                });
            }
            Some(i) if self.seen & (1u128 << i) != 0 => {}
            Some(i) => self.seen |= 1u128 << i,
            None if self.unknown.is_none() => {
                let (line, column) = self.line_column(start);
                let mut path = self.path.clone();
                if !fits {
                    let _ = path.push_str(".?");
                }
                self.unknown = Some(ConfigError::UnknownKey { path, line, column });
            }
            None => {}
        }
        (restore, entry)
    }

    /// Checks the value spanning `start..self.pos` against the schema entry `entry`; the
    /// first mismatch is kept for the end of the scan.
    fn check_kind(&mut self, entry: usize, start: usize) {
        if self.unknown.is_some() {
            return;
        }
        let (path, _, kind) = SCHEMA[entry];
        let token = &self.json[start..self.pos];
        if let Some(mismatch) = mismatch(kind, token) {
            let (line, column) = self.line_column(start);
            let mut found = heapless::String::new();
            let (expected, _) = match mismatch {
                Expected::Length { found: n, max } => (
                    if max <= 32 {
                        "a string of at most 32 bytes"
                    } else {
                        "a string of at most 64 bytes"
                    },
                    fmt::write(&mut found, format_args!("{n}")),
                ),
                Expected::Kind(what) => {
                    let cut = token.len().min(FOUND_SHOWN);
                    let shown = core::str::from_utf8(&token[..cut]).unwrap_or("?");
                    let more = if token.len() > cut { "…" } else { "" };
                    (what, fmt::write(&mut found, format_args!("{shown}{more}")))
                }
            };
            self.unknown = Some(ConfigError::Value {
                path,
                line,
                column,
                expected,
                found,
            });
        }
    }

    fn peek(&self) -> Option<u8> {
        self.json.get(self.pos).copied()
    }

    fn ws(&mut self) {
        while let Some(b' ' | b'\t' | b'\n' | b'\r') = self.peek() {
            self.pos += 1;
        }
    }

    fn value(&mut self, depth: usize) -> Result<(), ConfigError> {
        if depth == 0 {
            self.path.clear();
            let _ = self.path.push('$');
        }
        if depth > MAX_DEPTH {
            return Err(self.error("less deeply nested values"));
        }
        match self.peek() {
            Some(b'{') => self.object(depth),
            Some(b'[') => self.array(depth),
            Some(b'"') => self.string(),
            Some(b'-' | b'0'..=b'9') => self.number(),
            Some(b't') => self.literal(b"true"),
            Some(b'f') => self.literal(b"false"),
            Some(b'n') => self.literal(b"null"),
            _ => Err(self.error("a value (object, array, string, number, true, false or null)")),
        }
    }

    fn literal(&mut self, word: &[u8]) -> Result<(), ConfigError> {
        for &b in word {
            if self.peek() != Some(b) {
                return Err(self.error("true, false or null"));
            }
            self.pos += 1;
        }
        Ok(())
    }

    fn object(&mut self, depth: usize) -> Result<(), ConfigError> {
        self.pos += 1;
        self.ws();
        if self.peek() == Some(b'}') {
            self.pos += 1;
            return Ok(());
        }
        loop {
            self.ws();
            if self.peek() != Some(b'"') {
                return Err(self.error("a quoted key"));
            }
            let start = self.pos;
            self.string()?;
            let (restore, entry) = self.key(start, self.pos);
            self.ws();
            if self.peek() != Some(b':') {
                return Err(self.error("':' after the key"));
            }
            self.pos += 1;
            self.ws();
            let value_start = self.pos;
            self.value(depth + 1)?;
            if let Some(entry) = entry {
                self.check_kind(entry, value_start);
            }
            self.path.truncate(restore);
            self.ws();
            match self.peek() {
                Some(b',') => self.pos += 1,
                Some(b'}') => {
                    self.pos += 1;
                    return Ok(());
                }
                _ => return Err(self.error("',' or '}'")),
            }
        }
    }

    fn array(&mut self, depth: usize) -> Result<(), ConfigError> {
        self.pos += 1;
        self.ws();
        if self.peek() == Some(b']') {
            self.pos += 1;
            return Ok(());
        }
        let restore = self.path.len();
        let _ = self.path.push_str("[]");
        loop {
            self.ws();
            self.value(depth + 1)?;
            self.ws();
            match self.peek() {
                Some(b',') => self.pos += 1,
                Some(b']') => {
                    self.pos += 1;
                    self.path.truncate(restore);
                    return Ok(());
                }
                _ => return Err(self.error("',' or ']'")),
            }
        }
    }

    /// The four hex digits after `\u`, as a UTF-16 code unit.
    fn hex4(&mut self) -> Result<u16, ConfigError> {
        let mut unit = 0u16;
        for _ in 0..4 {
            let digit = self
                .peek()
                .and_then(|b| (b as char).to_digit(16))
                .ok_or_else(|| self.error("four hex digits after \\u"))?;
            unit = unit * 16 + digit as u16;
            self.pos += 1;
        }
        Ok(unit)
    }

    fn string(&mut self) -> Result<(), ConfigError> {
        self.pos += 1;
        loop {
            match self.peek() {
                None => return Err(self.error("a closing '\"'")),
                Some(b'"') => {
                    self.pos += 1;
                    return Ok(());
                }
                Some(b'\\') => {
                    self.pos += 1;
                    match self.peek() {
                        Some(b'"' | b'\\' | b'/' | b'b' | b'f' | b'n' | b'r' | b't') => {
                            self.pos += 1
                        }
                        Some(b'u') => {
                            self.pos += 1;
                            let unit = self.hex4()?;
                            // A UTF-16 surrogate is only half a character: a high one must be
                            // followed by a low one, and a low one cannot stand alone.
                            if (0xDC00..=0xDFFF).contains(&unit) {
                                return Err(self.error("a character, not half of a \\u pair"));
                            }
                            if (0xD800..=0xDBFF).contains(&unit) {
                                if self.json.get(self.pos..self.pos + 2) != Some(&b"\\u"[..]) {
                                    return Err(self.error("the second half of a \\u pair"));
                                }
                                self.pos += 2;
                                if !(0xDC00..=0xDFFF).contains(&self.hex4()?) {
                                    return Err(self.error("the second half of a \\u pair"));
                                }
                            }
                        }
                        _ => return Err(self.error("a valid escape after '\\'")),
                    }
                }
                Some(0..=0x1F) => return Err(self.error("no control characters inside a string")),
                Some(_) => self.pos += 1,
            }
        }
    }

    fn digits(&mut self) -> usize {
        let start = self.pos;
        while self.peek().is_some_and(|b| b.is_ascii_digit()) {
            self.pos += 1;
        }
        self.pos - start
    }

    fn number(&mut self) -> Result<(), ConfigError> {
        if self.peek() == Some(b'-') {
            self.pos += 1;
        }
        match self.peek() {
            Some(b'0') => self.pos += 1,
            Some(b'1'..=b'9') => {
                self.digits();
            }
            _ => return Err(self.error("a digit")),
        }
        if self.peek() == Some(b'.') {
            self.pos += 1;
            if self.digits() == 0 {
                return Err(self.error("a digit after '.'"));
            }
        }
        if let Some(b'e' | b'E') = self.peek() {
            self.pos += 1;
            if let Some(b'+' | b'-') = self.peek() {
                self.pos += 1;
            }
            if self.digits() == 0 {
                return Err(self.error("a digit in the exponent"));
            }
        }
        Ok(())
    }
}

/// Bytes of a wrong value shown in its error (its first ones).
const FOUND_SHOWN: usize = 40;

/// Why a value does not fit its schema entry.
enum Expected {
    /// Not of the kind: what was expected.
    Kind(&'static str),
    /// A string longer than the entry allows.
    Length {
        /// Its length \[bytes\].
        found: usize,
        /// The most the entry allows \[bytes\].
        max: usize,
    },
}

/// How `token` (a well-formed JSON value) fails to be of `kind`; `None` if it fits.
fn mismatch(kind: Kind, token: &[u8]) -> Option<Expected> {
    let text = core::str::from_utf8(token).unwrap_or("");
    match kind {
        Kind::Optional(_) if token == b"null" => None,
        Kind::Optional(inner) => mismatch(*inner, token),
        Kind::Object => (token.first() != Some(&b'{')).then_some(Expected::Kind("an object")),
        Kind::Str(max) => {
            if token.first() != Some(&b'"') {
                return Some(Expected::Kind("a string"));
            }
            if core::str::from_utf8(token).is_err() {
                return Some(Expected::Kind("a string of UTF-8 text"));
            }
            let n = unescaped_len(&token[1..token.len() - 1]);
            (n > max).then_some(Expected::Length { found: n, max })
        }
        Kind::Whole(max) => {
            let fits =
                token.iter().all(u8::is_ascii_digit) && text.parse::<u64>().is_ok_and(|v| v <= max);
            let what = match max {
                m if m == u64::from(u16::MAX) => "a whole number from 0 to 65535",
                m if m == u64::from(u32::MAX) => "a whole number from 0 to 4294967295",
                _ => "a whole number from 0 to 18446744073709551615",
            };
            (!fits).then_some(Expected::Kind(what))
        }
        Kind::Bool => {
            (token != b"true" && token != b"false").then_some(Expected::Kind("true or false"))
        }
        Kind::Number => {
            let fits = matches!(token.first(), Some(b'-' | b'0'..=b'9'))
                && text
                    .parse::<f64>()
                    .is_ok_and(|v| v.is_finite() && v.abs() <= f64::from(f32::MAX));
            (!fits).then_some(Expected::Kind(
                "a number (within ±3.4e38, the range of a 32-bit float)",
            ))
        }
    }
}

/// Bytes of a JSON string's contents (between the quotes, well-formed) once unescaped.
fn unescaped_len(raw: &[u8]) -> usize {
    let mut n = 0;
    let mut i = 0;
    while i < raw.len() {
        if raw[i] == b'\\' {
            if raw.get(i + 1) == Some(&b'u') {
                let hex = core::str::from_utf8(raw.get(i + 2..i + 6).unwrap_or(b""))
                    .ok()
                    .and_then(|h| u32::from_str_radix(h, 16).ok())
                    .unwrap_or(0);
                // A surrogate half: its pair makes 4 bytes in all.
                n += char::from_u32(hex).map_or(2, char::len_utf8);
                i += 6;
            } else {
                n += 1;
                i += 2;
            }
        } else {
            n += 1;
            i += 1;
        }
    }
    n
}
