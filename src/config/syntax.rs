//! The syntax and shape check of a board file, before `serde-json-core` reads it: a small
//! scanner that reports the line and column of a syntax error, rejects keys the schema does not
//! know and duplicate keys, and records which known keys were present.

use super::*;

/// Every key a board file may hold, as a JSON path, and whether it is required.
pub(super) const SCHEMA: &[(&str, bool)] = &[
    ("$.robot", true),
    ("$.robot.name", true),
    ("$.robot.subclass", true),
    ("$.robot.radius_m", true),
    ("$.robot.max_speed_mm_s", true),
    ("$.robot.max_turn_rate_deg_s", true),
    ("$.robot.accel_mm_s2", true),
    ("$.robot.decel_mm_s2", true),
    ("$.robot.rot_accel_deg_s2", true),
    ("$.link", true),
    ("$.link.port", true),
    ("$.link.tcp", false),
    ("$.link.baud", true),
    ("$.link.switch_to_baud", true),
    ("$.laser", true),
    ("$.laser.model", true),
    ("$.laser.address", false),
    ("$.laser.port", false),
    ("$.laser.baud", false),
    ("$.laser.beam_count", true),
    ("$.laser.first_angle_deg", true),
    ("$.laser.step_deg", true),
    ("$.laser.max_range_m", true),
    ("$.laser.min_range_m", true),
    ("$.laser.noise_fraction", true),
    ("$.laser.rate_hz", true),
    ("$.laser.mount", true),
    ("$.laser.mount.x_m", true),
    ("$.laser.mount.y_m", true),
    ("$.laser.mount.theta_deg", true),
    ("$.grid", true),
    ("$.grid.width_m", true),
    ("$.grid.height_m", true),
    ("$.grid.resolution_m", true),
    ("$.grid.origin_x_m", true),
    ("$.grid.origin_y_m", true),
    ("$.mission", true),
    ("$.mission.method", true),
    ("$.mission.population", true),
    ("$.mission.generations", true),
    ("$.mission.strategy", true),
    ("$.mission.objective", false),
    ("$.mission.targets", true),
    ("$.mission.battery_steps", true),
    ("$.mission.reserve_steps", true),
    ("$.mission.coverage_target", true),
    ("$.mission.seed", true),
    ("$.pid", true),
    ("$.pid.heading_kp", true),
    ("$.pid.heading_ki", true),
    ("$.pid.heading_kd", true),
    ("$.pid.distance_kp", true),
    ("$.pid.distance_ki", true),
    ("$.pid.distance_kd", true),
    ("$.safety", true),
    ("$.safety.obstacle_stop_m", true),
    ("$.safety.stale_timeout_s", true),
    ("$.safety.back_off_m", true),
    ("$.persistence", true),
    ("$.persistence.save_every_s", true),
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
    /// The first unknown key.
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

    /// Records the key spanning `start..end` (quotes included) of the current object.
    fn key(&mut self, start: usize, end: usize) -> usize {
        let restore = self.path.len();
        let key = core::str::from_utf8(&self.json[start + 1..end - 1]).unwrap_or("?");
        let fits = self.path.push('.').is_ok() && self.path.push_str(key).is_ok();
        if !fits {
            // Deeper than any schema path: unknown for sure; keep the prefix readable.
            self.path.truncate(restore);
        }
        match SCHEMA
            .iter()
            .position(|(p, _)| fits && *p == self.path.as_str())
        {
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
        restore
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
            let restore = self.key(start, self.pos);
            self.ws();
            if self.peek() != Some(b':') {
                return Err(self.error("':' after the key"));
            }
            self.pos += 1;
            self.ws();
            self.value(depth + 1)?;
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
                            for _ in 0..4 {
                                if !self.peek().is_some_and(|b| b.is_ascii_hexdigit()) {
                                    return Err(self.error("four hex digits after \\u"));
                                }
                                self.pos += 1;
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
