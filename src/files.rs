//! Bounded reads of input files and careful creation of output files (host only).
//!
//! Every file either binary reads (board, saved mission, map files) goes through
//! [`read_limited`]: a wrong path (`/dev/zero`, a disk image, a log) gives an error after at
//! most `limit + 1` bytes instead of an endless read or an exhausted memory.
//!
//! Files written in a directory another user may write to never follow a symbolic link
//! planted in their place: a temporary file is created exclusively ([`create_temporary`]), a
//! log is opened by [`open_log`], which refuses a link and checks that the file it opened is
//! the one at the path.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Read};
use std::path::Path;
use std::time::Duration;

/// Largest board file \[bytes\]: a board is about 1.3 kB.
pub const BOARD_MAX_BYTES: u64 = 64 << 10;
/// Largest YAML map description or other small text file \[bytes\].
pub const TEXT_MAX_BYTES: u64 = 1 << 20;
/// Largest map image, CSV or Moving AI map, saved state \[bytes\]: a 4096 x 4096 PGM with
/// 16-bit pixels is 32 MiB.
pub const MAP_MAX_BYTES: u64 = 64 << 20;
/// How long [`read_limited`] waits for a program to open a named pipe for writing.
pub const PIPE_WRITER_WAIT: Duration = Duration::from_secs(5);

/// Reads the whole of `path` if it has at most `limit` bytes. A larger file (or one that never
/// ends, such as a character device) is an [`io::ErrorKind::InvalidData`] error saying so; the
/// caller names the file. A named pipe that no program opens for writing within
/// [`PIPE_WRITER_WAIT`] is an [`io::ErrorKind::TimedOut`] error (opening it would block for
/// ever); once a writer has it open, the pipe is read to its end as any file.
pub fn read_limited(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let file = open_to_read(path)?;
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(limit));
    }
    Ok(bytes)
}

/// Opens `path` for reading; a named pipe is opened on a thread of its own, given up after
/// [`PIPE_WRITER_WAIT`] (the thread stays blocked until a writer comes or the program ends).
fn open_to_read(path: &Path) -> io::Result<File> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if fs::metadata(path)?.file_type().is_fifo() {
            let (sender, receiver) = std::sync::mpsc::channel();
            let pipe = path.to_path_buf();
            std::thread::spawn(move || {
                let _ = sender.send(File::open(pipe));
            });
            return receiver.recv_timeout(PIPE_WRITER_WAIT).unwrap_or_else(|_| {
                Err(io::Error::new(
                    io::ErrorKind::TimedOut,
                    format!(
                        "a named pipe that no program opened for writing within {} s",
                        PIPE_WRITER_WAIT.as_secs()
                    ),
                ))
            });
        }
    }
    File::open(path)
}

/// [`read_limited`] for a UTF-8 text file.
pub fn read_limited_to_string(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_limited(path, limit)?)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, format!("not UTF-8 text: {e}")))
}

/// Creates `path` afresh for writing (a temporary file next to the file it will replace):
/// whatever is at the path (a stale temporary file, a planted symbolic link) is removed first
/// (the link itself, never what it points to), and the file is created exclusively, so that
/// a link planted in between makes this fail rather than be followed.
pub fn create_temporary(path: &Path) -> io::Result<File> {
    match fs::remove_file(path) {
        Err(e) if e.kind() != io::ErrorKind::NotFound => return Err(e),
        _ => {}
    }
    OpenOptions::new().write(true).create_new(true).open(path)
}

/// How [`open_log`] treats a log that exists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Existing {
    /// Append to it.
    Append,
    /// Empty it first.
    Truncate,
}

/// Opens a log file for writing: created if absent (exclusively), else appended to or
/// emptied. A symbolic link or anything but a regular file at `path` is refused with an error
/// naming it, before anything is written or truncated.
pub fn open_log(path: &Path, existing: Existing) -> io::Result<File> {
    let refuse = |what: &str| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "{}: {what}; refusing to write through it (remove it or choose another path)",
                path.display()
            ),
        )
    };
    let before = match fs::symlink_metadata(path) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            // O_CREAT | O_EXCL: fails on anything created meanwhile, a link included.
            return OpenOptions::new()
                .write(true)
                .append(existing == Existing::Append)
                .create_new(true)
                .open(path)
                .map_err(|e| io::Error::new(e.kind(), format!("{}: {e}", path.display())));
        }
        Err(e) => return Err(io::Error::new(e.kind(), format!("{}: {e}", path.display()))),
        Ok(m) if m.file_type().is_symlink() => return Err(refuse("a symbolic link")),
        Ok(m) if !m.is_file() => return Err(refuse("not a regular file")),
        Ok(m) => m,
    };
    let file = OpenOptions::new()
        .write(true)
        .append(existing == Existing::Append)
        .open(path)
        .map_err(|e| io::Error::new(e.kind(), format!("{}: {e}", path.display())))?;
    // A link swapped in between the check and the open: the opened file is another one.
    if !same_file(&before, &file.metadata()?) {
        return Err(refuse("replaced while being opened"));
    }
    if existing == Existing::Truncate {
        file.set_len(0)?;
    }
    Ok(file)
}

#[cfg(unix)]
fn same_file(a: &fs::Metadata, b: &fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    a.dev() == b.dev() && a.ino() == b.ino()
}

#[cfg(not(unix))]
fn same_file(a: &fs::Metadata, b: &fs::Metadata) -> bool {
    a.len() == b.len() && a.modified().ok() == b.modified().ok()
}

fn too_large(limit: u64) -> io::Error {
    let size = if limit >= 1 << 20 && limit.is_multiple_of(1 << 20) {
        format!("{} MiB", limit >> 20)
    } else if limit >= 1 << 10 && limit.is_multiple_of(1 << 10) {
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
    fn planted_links_are_never_followed() {
        let dir = std::env::temp_dir().join(format!("papillon-links-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let victim = dir.join("victim");
        fs::write(&victim, b"precious").unwrap();
        let tmp = dir.join(".x.tmp");
        std::os::unix::fs::symlink(&victim, &tmp).unwrap();
        use std::io::Write;
        create_temporary(&tmp).unwrap().write_all(b"new").unwrap();
        assert_eq!(fs::read(&victim).unwrap(), b"precious");
        assert_eq!(fs::read(&tmp).unwrap(), b"new");
        let log = dir.join("log");
        std::os::unix::fs::symlink(&victim, &log).unwrap();
        for existing in [Existing::Append, Existing::Truncate] {
            let e = open_log(&log, existing).unwrap_err();
            assert!(e.to_string().contains("symbolic link"), "{e}");
        }
        assert_eq!(fs::read(&victim).unwrap(), b"precious");
        let e = open_log(&dir, Existing::Append).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        let plain = dir.join("plain");
        open_log(&plain, Existing::Append)
            .unwrap()
            .write_all(b"a")
            .unwrap();
        open_log(&plain, Existing::Append)
            .unwrap()
            .write_all(b"b")
            .unwrap();
        assert_eq!(fs::read(&plain).unwrap(), b"ab");
        open_log(&plain, Existing::Truncate)
            .unwrap()
            .write_all(b"c")
            .unwrap();
        assert_eq!(fs::read(&plain).unwrap(), b"c");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_named_pipe_without_a_writer_is_given_up_and_one_with_a_writer_is_read() {
        let dir = std::env::temp_dir().join(format!("papillon-fifo-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("board.json");
        // Two pipes: the thread left blocked on the first one must not take the second's data.
        let other = dir.join("other.json");
        let made = std::process::Command::new("mkfifo")
            .args([&fifo, &other])
            .status();
        if !made.is_ok_and(|s| s.success()) {
            eprintln!("skipped: no mkfifo");
            return;
        }
        let e = read_limited(&fifo, BOARD_MAX_BYTES).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::TimedOut, "{e}");
        assert!(e.to_string().contains("named pipe"), "{e}");
        let writer = {
            let other = other.clone();
            std::thread::spawn(move || {
                use std::io::Write;
                OpenOptions::new()
                    .write(true)
                    .open(other)
                    .unwrap()
                    .write_all(b"{}")
                    .unwrap();
            })
        };
        assert_eq!(read_limited(&other, BOARD_MAX_BYTES).unwrap(), b"{}");
        writer.join().unwrap();
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_device_that_never_ends_is_refused() {
        let e = read_limited(Path::new("/dev/zero"), BOARD_MAX_BYTES).unwrap_err();
        assert!(e.to_string().contains("larger than 64 KiB"), "{e}");
    }
}
