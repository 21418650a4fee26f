//! Waiting for SIGINT or SIGTERM, the way `papillon-sim serve` is stopped.

use std::sync::atomic::{AtomicBool, Ordering};
use std::thread;
use std::time::Duration;

static SIGNALLED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_signal: libc::c_int) {
    SIGNALLED.store(true, Ordering::SeqCst);
}

/// Installs handlers for SIGINT and SIGTERM that [`wait`] watches (instead of the default,
/// which ends the process at once).
pub fn install_handlers() {
    let handler = on_signal as extern "C" fn(libc::c_int);
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, handler as libc::sighandler_t);
        libc::signal(libc::SIGTERM, handler as libc::sighandler_t);
    }
}

/// Returns once SIGINT or SIGTERM has arrived since [`install_handlers`] (checking every
/// 20 ms).
pub fn wait() {
    while !SIGNALLED.load(Ordering::SeqCst) {
        thread::sleep(Duration::from_millis(20));
    }
}
