//! SIGINT / SIGTERM during `softrod run`: the first one is noted (the run
//! finishes the current output row, writes a true summary and the figures
//! of what exists, and exits 1); a second one ends the process at once
//! with the signal's default action. SIGKILL cannot be handled: such a run
//! leaves `"status": "running"` in `summary.json`
//! (docs/scene-format-extensions.md says how to tell). The handlers are
//! `signal-hook`'s async-signal-safe atomic stores.
//!
//! The run looks at the flag between steps and rows; a single step can
//! take much longer (one dense factorization of thousands of coordinates).
//! [`watchdog`] bounds that: if the process is still alive [`GRACE`] after
//! the first signal, a thread of its own writes what is true of the files
//! and ends the process.

use std::sync::Arc;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// How long after the first signal the run may take to stop by itself
/// before [`watchdog`] ends it (the contract: within a second or two).
pub const GRACE: Duration = Duration::from_secs(1);

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

/// Starts a thread that, once a signal has been received ([`received`])
/// and the process is still running [`GRACE`] later, calls
/// `on_expiry(signal name)` and exits the process with status 1. The
/// callback writes what is true of the outputs at that moment (it must not
/// wait on the main thread, which is busy). Detached: a process that ends
/// first ends it.
pub fn watchdog(on_expiry: impl FnOnce(&'static str) + Send + 'static) {
    let spawned = std::thread::Builder::new()
        .name("softrod-signal-watchdog".into())
        .spawn(move || {
            let mut first: Option<Instant> = None;
            loop {
                std::thread::sleep(Duration::from_millis(20));
                let Some(sig) = received() else { continue };
                let since = *first.get_or_insert_with(Instant::now);
                if since.elapsed() >= GRACE {
                    on_expiry(sig);
                    std::process::exit(1);
                }
            }
        });
    // Without the thread a signal still stops the run at its next step.
    let _ = spawned;
}
