//! Progress bars on standard error and the Ctrl-C handler: the terminal side of the
//! observer and stop flag that `sepg-runs` takes.

use std::io::IsTerminal;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

use indicatif::{ProgressBar, ProgressStyle};
use sepg_runs::run::RunObserver;

/// Raised by SIGINT or SIGTERM (what cluster schedulers send before killing a job): every
/// running loop stops, within its current chunk of trajectories or step of a dynamic
/// programme, and checkpoints the last completed iteration.
pub static STOP: AtomicBool = AtomicBool::new(false);

/// Exit status after a second SIGINT or SIGTERM (128 + SIGINT, as shells report Ctrl-C).
pub const EXIT_INTERRUPTED: i32 = 130;

/// Installs the SIGINT and SIGTERM handler (once per process). The first signal raises
/// [`STOP`] and the cancellation request of the rollouts and dynamic programmes
/// ([`sepg_mdp::cancel`]); a second one ends the process at once with status
/// [`EXIT_INTERRUPTED`]. Every file of a run folder is replaced atomically and the partial log
/// is cut back to its checkpoint on resume, so the folder stays resumable either way.
pub fn install_interrupt_handler() {
    static ONCE: OnceLock<()> = OnceLock::new();
    ONCE.get_or_init(|| {
        // Without a handler (e.g. one is already installed) the signals keep their default
        // action; the checkpoints still leave the folder consistent.
        let _ = ctrlc::set_handler(|| {
            if STOP.swap(true, Ordering::SeqCst) {
                std::process::exit(EXIT_INTERRUPTED);
            }
            sepg_mdp::cancel::request();
        });
    });
}

/// A progress bar on standard error, shown only when asked for and standard error is a
/// terminal.
pub struct Bar(ProgressBar);

impl Bar {
    /// A bar counting iterations of one run.
    pub fn iterations(show: bool) -> Bar {
        Bar::new(show, "{bar:40} {pos}/{len} it  {per_sec}  eta {eta}")
    }

    /// A bar counting the runs of a sweep.
    pub fn runs(show: bool) -> Bar {
        Bar::new(show, "{bar:40} {pos}/{len} runs  eta {eta}")
    }

    fn new(show: bool, template: &str) -> Bar {
        if !(show && std::io::stderr().is_terminal()) {
            return Bar(ProgressBar::hidden());
        }
        let pb = ProgressBar::new(0);
        if let Ok(style) = ProgressStyle::with_template(template) {
            pb.set_style(style);
        }
        Bar(pb)
    }
}

impl RunObserver for Bar {
    fn begin(&self, done: u64, total: u64) {
        self.0.set_length(total);
        self.0.set_position(done);
    }

    fn advance(&self, done: u64) {
        self.0.set_position(done);
    }

    fn end(&self) {
        self.0.finish_and_clear();
    }
}
