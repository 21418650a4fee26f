//! Bounded reads of input files (host only).
//!
//! Every file either binary reads (board, saved mission, map files) goes through
//! [`read_limited`]: a wrong path (`/dev/zero`, a disk image, a log) gives an error after at
//! most `limit + 1` bytes instead of an endless read or an exhausted memory.

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// Largest board file \[bytes\]: a board is about 1.3 kB.
pub const BOARD_MAX_BYTES: u64 = 64 << 10;
/// Largest YAML map description or other small text file \[bytes\].
pub const TEXT_MAX_BYTES: u64 = 1 << 20;
/// Largest map image, CSV or Moving AI map, saved state \[bytes\]: a 4096 x 4096 PGM with
/// 16-bit pixels is 32 MiB.
pub const MAP_MAX_BYTES: u64 = 64 << 20;

/// Reads the whole of `path` if it has at most `limit` bytes. A larger file (or one that never
/// ends, such as a character device) is an [`io::ErrorKind::InvalidData`] error saying so; the
/// caller names the file.
pub fn read_limited(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let file = File::open(path)?;
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(limit));
    }
    Ok(bytes)
}

/// [`read_limited`] for a UTF-8 text file.
pub fn read_limited_to_string(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_limited(path, limit)?)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, format!("not UTF-8 text: {e}")))
}

fn too_large(limit: u64) -> io::Error {
    let size = if limit >= 1 << 20 && limit % (1 << 20) == 0 {
        format!("{} MiB", limit >> 20)
    } else if limit >= 1 << 10 && limit % (1 << 10) == 0 {
        format!("{} KiB", limit >> 10)
    } else {
        format!("{limit} bytes")
    };
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!("larger than {size}, more than such a file can be (is it the right file?)"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_within_the_limit_is_read_whole_and_a_larger_one_refused() {
        let p = std::env::temp_dir().join(format!("papillon-files-{}", std::process::id()));
        std::fs::write(&p, b"0123456789").unwrap();
        assert_eq!(read_limited(&p, 10).unwrap(), b"0123456789");
        let e = read_limited(&p, 9).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        assert!(e.to_string().contains("larger than 9 bytes"), "{e}");
        std::fs::remove_file(&p).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_device_that_never_ends_is_refused() {
        let e = read_limited(Path::new("/dev/zero"), BOARD_MAX_BYTES).unwrap_err();
        assert!(e.to_string().contains("larger than 64 KiB"), "{e}");
    }
}
