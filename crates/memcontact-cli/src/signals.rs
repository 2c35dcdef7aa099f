//! Ctrl-C: the first SIGINT asks the run to stop (the library's cancellation token: the
//! solve stops within its iteration, a result set being written is not committed and its
//! staging directory is removed, so an earlier result stays as it was); the tool then
//! exits with status 130. A second SIGINT ends the process at once.

use memcontact::Cancel;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// The token the handler sets.
static TOKEN: OnceLock<Cancel> = OnceLock::new();
/// Its flag, for the handler (which may only store into it).
static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();

extern "C" fn on_sigint(_: libc::c_int) {
    if let Some(flag) = FLAG.get() {
        flag.store(true, Ordering::SeqCst);
    }
    // SAFETY: `signal` is async-signal-safe; the next SIGINT gets the default action.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
    }
}

/// Installs the handler (once).
pub fn install() {
    let token = TOKEN.get_or_init(Cancel::new);
    let _ = FLAG.set(token.flag());
    // SAFETY: the handler only stores into an atomic and resets the disposition.
    unsafe {
        libc::signal(
            libc::SIGINT,
            on_sigint as extern "C" fn(libc::c_int) as libc::sighandler_t,
        );
    }
}

/// The token Ctrl-C sets (a fresh one when no handler is installed).
pub fn token() -> Cancel {
    TOKEN.get_or_init(Cancel::new).clone()
}
