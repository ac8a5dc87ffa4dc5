//! SIGINT / SIGTERM during `softrod run`: the first one is noted (the run
//! finishes the current output row, writes a true summary and the figures
//! of what exists, and exits 1); a second one ends the process at once
//! with the signal's default action. SIGKILL cannot be handled: such a run
//! leaves `"status": "running"` in `summary.json`
//! (docs/scene-format-extensions.md says how to tell). The handlers are
//! `signal-hook`'s async-signal-safe atomic stores.

use std::sync::Arc;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The signal received (0 for none) and whether one was.
struct Flags {
    which: Arc<AtomicUsize>,
    any: Arc<AtomicBool>,
}

static FLAGS: OnceLock<Flags> = OnceLock::new();

/// Installs the handlers for SIGINT and SIGTERM (once; later calls do
/// nothing).
pub fn install() {
    #[cfg(unix)]
    FLAGS.get_or_init(|| {
        use signal_hook::consts::{SIGINT, SIGTERM};
        use signal_hook::flag;
        let flags = Flags {
            which: Arc::new(AtomicUsize::new(0)),
            any: Arc::new(AtomicBool::new(false)),
        };
        for sig in [SIGINT, SIGTERM] {
            // Registered first, so it sees the flag as the previous signal
            // left it: a second signal takes the default action.
            let ok = flag::register_conditional_default(sig, Arc::clone(&flags.any)).is_ok()
                && flag::register_usize(sig, Arc::clone(&flags.which), sig as usize).is_ok()
                && flag::register(sig, Arc::clone(&flags.any)).is_ok();
            // Without a handler a signal just ends the run as before.
            let _ = ok;
        }
        flags
    });
}

/// The name of the signal received since [`install`], if any.
pub fn received() -> Option<&'static str> {
    let sig = FLAGS.get()?.which.load(Ordering::SeqCst);
    match sig {
        0 => None,
        #[cfg(unix)]
        s if s == signal_hook::consts::SIGINT as usize => Some("SIGINT"),
        #[cfg(unix)]
        s if s == signal_hook::consts::SIGTERM as usize => Some("SIGTERM"),
        _ => Some("a signal"),
    }
}
