//! Ctrl-C and SIGTERM: a flag that the run loops read at every step end, so
//! an interrupted run stops between steps and writes consistent files
//! (summary.json with `stop.reason = "interrupted"`).

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Exit code of a run ended at once by a second signal (130 is the clean
/// stop at a step end, with summary.json).
pub const SECOND_SIGNAL: i32 = 131;

/// Installs the handler (once per process; later calls do nothing). A second
/// signal while the first is pending ends the process at once.
pub fn install() {
    static INSTALLED: std::sync::Once = std::sync::Once::new();
    INSTALLED.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            if REQUESTED.swap(true, Ordering::SeqCst) {
                // Review 23: the same 130 as a clean stop, with no
                // summary.json and no word, misled scripts (Slurm may
                // signal twice).
                eprintln!(
                    "second interrupt: stopped at once, without summary.json (exit {SECOND_SIGNAL}); history.csv and steps.csv hold the steps so far, and `anm run --resume DIR` continues from the last checkpoint"
                );
                crate::output::lock::remove_held();
                std::process::exit(SECOND_SIGNAL);
            }
        });
    });
}

/// True once Ctrl-C or SIGTERM was received.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
