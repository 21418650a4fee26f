//! SICK LMS1xx CoLa-A over TCP (port 2111), both directions (fact sheet section 2).
//!
//! A telegram is `STX (0x02)`, ASCII tokens separated by single spaces, `ETX (0x03)`, no
//! checksum. Numbers are hex without sign (`1388`, `FFF92230`) or decimal with an explicit
//! sign (`+5000`, `-450000`); the parsers accept both forms everywhere.
//!
//! - [`framing`]: [`ColaDecoder`], the STX/ETX streaming decoder, and [`framing::emit_frame`].
//! - [`command`]: [`Request`]s of both client connect sequences (the clearpath LMS1xx driver
//!   and ARIA), the laser's [`Reply`]s, and [`command::check_reply`] which turns an unexpected
//!   or refusing reply into an error.
//! - [`scandata`]: the `LMDscandata` telegram ([`ScanTelegram`]), values as the laser sends
//!   them (the sensor layer (`sensor::telegram`) turns one into a scan).

pub mod command;
pub mod framing;
pub mod scandata;

pub use command::{Dialect, Reply, ReplyError, Request, ScanConfig, ScanDataConfig};
pub use framing::{ColaDecoder, ColaStats};
pub use scandata::ScanTelegram;

use core::fmt;

/// TCP port of the LMS1xx.
pub const TCP_PORT: u16 = 2111;
/// Start of a telegram.
pub const STX: u8 = 0x02;
/// End of a telegram.
pub const ETX: u8 = 0x03;

/// A short copy of a token, for error messages.
pub type TokenText = heapless::String<24>;

fn token_text(t: &[u8]) -> TokenText {
    let mut s = TokenText::new();
    for &b in t.iter().take(24) {
        let c = if b.is_ascii_graphic() { b as char } else { '?' };
        if s.push(c).is_err() {
            break;
        }
    }
    s
}

/// Errors parsing a CoLa-A telegram.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ParseError {
    /// The telegram has no tokens.
    Empty,
    /// A message kind and name this parser does not know.
    UnknownMessage {
        /// The first tokens seen.
        got: TokenText,
    },
    /// A token missing at the end of the telegram.
    MissingToken {
        /// The field expected.
        field: &'static str,
        /// Index of the token (0 = message kind).
        index: usize,
    },
    /// A token that is not a number of the expected range.
    BadNumber {
        /// The field.
        field: &'static str,
        /// Index of the token.
        index: usize,
        /// The token.
        got: TokenText,
    },
    /// More items than the capacity.
    TooMany {
        /// The field.
        field: &'static str,
        /// The count announced.
        count: u32,
        /// The capacity.
        capacity: usize,
    },
    /// A text token longer than its capacity or not ASCII.
    BadText {
        /// The field.
        field: &'static str,
        /// Index of the token.
        index: usize,
    },
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParseError::Empty => write!(f, "empty telegram"),
            ParseError::UnknownMessage { got } => write!(f, "unknown message '{got}'"),
            ParseError::MissingToken { field, index } => {
                write!(f, "telegram ends before {field} (token {index})")
            }
            ParseError::BadNumber { field, index, got } => {
                write!(f, "{field} (token {index}): '{got}' is not a valid number")
            }
            ParseError::TooMany {
                field,
                count,
                capacity,
            } => write!(f, "{field}: {count} announced, capacity {capacity}"),
            ParseError::BadText { field, index } => {
                write!(f, "{field} (token {index}): text too long or not ASCII")
            }
        }
    }
}

impl core::error::Error for ParseError {}

/// Errors encoding a CoLa-A telegram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum EmitError {
    /// The output buffer is too small.
    BufferTooSmall {
        /// Bytes available.
        capacity: usize,
    },
    /// More values than a channel holds.
    TooManyValues {
        /// Values given.
        count: usize,
        /// The capacity.
        capacity: usize,
    },
}

impl fmt::Display for EmitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EmitError::BufferTooSmall { capacity } => {
                write!(f, "telegram does not fit in {capacity} bytes")
            }
            EmitError::TooManyValues { count, capacity } => {
                write!(f, "{count} values, a channel holds at most {capacity}")
            }
        }
    }
}

impl core::error::Error for EmitError {}

/// Parses a CoLa-A number: signed decimal if it starts with `+` or `-`, else unsigned hex
/// (at most 8 digits). `None` for anything else.
pub fn parse_number(tok: &[u8]) -> Option<i64> {
    let (&first, rest) = tok.split_first()?;
    match first {
        b'+' | b'-' => {
            if rest.is_empty() || rest.len() > 10 {
                return None;
            }
            let mut v: i64 = 0;
            for &c in rest {
                if !c.is_ascii_digit() {
                    return None;
                }
                v = v * 10 + (c - b'0') as i64;
            }
            Some(if first == b'-' { -v } else { v })
        }
        _ => {
            if tok.len() > 8 {
                return None;
            }
            let mut v: i64 = 0;
            for &c in tok {
                let d = (c as char).to_digit(16)?;
                v = v * 16 + d as i64;
            }
            Some(v)
        }
    }
}

/// Token cursor over a telegram's payload.
#[derive(Clone, Debug)]
pub(crate) struct Tokens<'a> {
    rest: &'a [u8],
    index: usize,
}

impl<'a> Tokens<'a> {
    pub(crate) fn new(payload: &'a [u8]) -> Self {
        Self {
            rest: payload,
            index: 0,
        }
    }

    pub(crate) fn next_token(&mut self) -> Option<&'a [u8]> {
        let start = self.rest.iter().position(|&b| b != b' ')?;
        let rest = self.rest.get(start..)?;
        let end = rest.iter().position(|&b| b == b' ').unwrap_or(rest.len());
        let (tok, tail) = rest.split_at(end);
        self.rest = tail;
        self.index += 1;
        Some(tok)
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.rest.iter().all(|&b| b == b' ')
    }

    pub(crate) fn token(&mut self, field: &'static str) -> Result<&'a [u8], ParseError> {
        let index = self.index;
        self.next_token()
            .ok_or(ParseError::MissingToken { field, index })
    }

    fn number(&mut self, field: &'static str) -> Result<(i64, usize, &'a [u8]), ParseError> {
        let t = self.token(field)?;
        let index = self.index - 1;
        let v = parse_number(t).ok_or_else(|| ParseError::BadNumber {
            field,
            index,
            got: token_text(t),
        })?;
        Ok((v, index, t))
    }

    /// An unsigned value up to `max`.
    pub(crate) fn uint(&mut self, field: &'static str, max: u32) -> Result<u32, ParseError> {
        let (v, index, t) = self.number(field)?;
        if (0..=max as i64).contains(&v) {
            Ok(v as u32)
        } else {
            Err(ParseError::BadNumber {
                field,
                index,
                got: token_text(t),
            })
        }
    }

    /// A signed 32-bit value: decimal in range, or hex as two's complement.
    pub(crate) fn int32(&mut self, field: &'static str) -> Result<i32, ParseError> {
        let (v, index, t) = self.number(field)?;
        let signed = t.first().is_some_and(|&c| c == b'+' || c == b'-');
        if signed {
            i32::try_from(v).map_err(|_| ParseError::BadNumber {
                field,
                index,
                got: token_text(t),
            })
        } else {
            Ok(v as u32 as i32)
        }
    }

    /// An IEEE-754 float: 8 hex digits are its bit pattern, a signed decimal its value.
    pub(crate) fn float(&mut self, field: &'static str) -> Result<f32, ParseError> {
        let (v, _, t) = self.number(field)?;
        let signed = t.first().is_some_and(|&c| c == b'+' || c == b'-');
        Ok(if signed {
            v as f32
        } else {
            f32::from_bits(v as u32)
        })
    }

    pub(crate) fn flag(&mut self, field: &'static str) -> Result<bool, ParseError> {
        Ok(self.uint(field, u32::MAX)? != 0)
    }

    pub(crate) fn text<const N: usize>(
        &mut self,
        field: &'static str,
    ) -> Result<heapless::String<N>, ParseError> {
        let t = self.token(field)?;
        let index = self.index - 1;
        let s = core::str::from_utf8(t)
            .ok()
            .filter(|s| s.is_ascii())
            .ok_or(ParseError::BadText { field, index })?;
        heapless::String::try_from(s).map_err(|_| ParseError::BadText { field, index })
    }
}
