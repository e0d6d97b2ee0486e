//! Ctrl-C and SIGTERM: a flag that the run loops read at every step end, so
//! an interrupted run stops between steps and writes consistent files
//! (summary.json with `stop.reason = "interrupted"`).

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Installs the handler (once per process; later calls do nothing). A second
/// signal while the first is pending ends the process at once.
pub fn install() {
    static INSTALLED: std::sync::Once = std::sync::Once::new();
    INSTALLED.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            if REQUESTED.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
        });
    });
}

/// True once Ctrl-C or SIGTERM was received.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
