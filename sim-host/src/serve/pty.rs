//! Pseudo-terminals for the serial endpoints: a raw, non-blocking master the server reads, and
//! a symlink to the slave device that clients open as their serial port.

use std::io;
use std::os::fd::{FromRawFd, OwnedFd};
use std::path::{Path, PathBuf};

/// Opens a pseudo-terminal pair in raw mode: the master (non-blocking), the slave's device
/// path and the slave itself.
pub(super) fn open_pty() -> io::Result<(OwnedFd, PathBuf, OwnedFd)> {
    let mut master: libc::c_int = -1;
    let mut slave: libc::c_int = -1;
    // SAFETY: openpty writes two descriptors; the name, termios and winsize pointers may be
    // null.
    let rc = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    if rc != 0 {
        return Err(io::Error::last_os_error());
    }
    // SAFETY: both descriptors were just opened by openpty and are owned by nobody else.
    let (master, slave) = unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) };
    use std::os::fd::AsRawFd;
    // SAFETY: plain termios/fcntl calls on descriptors we own, with a zeroed termios that
    // tcgetattr fills.
    unsafe {
        let mut t: libc::termios = std::mem::zeroed();
        if libc::tcgetattr(slave.as_raw_fd(), &mut t) == 0 {
            libc::cfmakeraw(&mut t);
            libc::tcsetattr(slave.as_raw_fd(), libc::TCSANOW, &t);
        }
        let flags = libc::fcntl(master.as_raw_fd(), libc::F_GETFL);
        libc::fcntl(master.as_raw_fd(), libc::F_SETFL, flags | libc::O_NONBLOCK);
    }
    let path = std::fs::read_link(format!("/proc/self/fd/{}", slave.as_raw_fd()))?;
    Ok((master, path, slave))
}

/// The speed the client set on the slave of the pty whose master is `master` \[baud\]: on
/// Linux a master's termios requests act on its slave, and `TCGETS2` gives the speed as a
/// number (also one set with `BOTHER`). `None` where this is not available.
pub(super) fn slave_baud(master: &std::fs::File) -> Option<u32> {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        // SAFETY: TCGETS2 fills a termios2 we own, on a descriptor we own.
        unsafe {
            let mut t: libc::termios2 = std::mem::zeroed();
            if libc::ioctl(master.as_raw_fd(), libc::TCGETS2, &mut t) == 0 {
                return Some(t.c_ospeed);
            }
        }
        None
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = master;
        None
    }
}

/// Makes `link` a symlink to `target`, replacing an older symlink (never a regular file).
pub(super) fn make_symlink(link: &Path, target: &Path) -> Result<(), String> {
    if let Ok(meta) = std::fs::symlink_metadata(link) {
        if meta.file_type().is_symlink() {
            let _ = std::fs::remove_file(link);
        } else {
            return Err(format!(
                "{} exists and is not a symlink; not replacing it",
                link.display()
            ));
        }
    }
    std::os::unix::fs::symlink(target, link)
        .map_err(|e| format!("cannot create symlink {}: {e}", link.display()))
}
