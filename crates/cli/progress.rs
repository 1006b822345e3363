//! A progress line on standard error for long runs (`calibrate`): a spinner with what is being
//! done and the time spent, drawn only when standard error is a terminal and only once the run
//! has taken a second, cleared when the work ends; `--quiet` turns it off. Reports, warnings
//! and errors never go through it, so pipes, logs and snapshots see none of it.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Runs shorter than this draw nothing.
pub const SHOW_AFTER: Duration = Duration::from_secs(1);

/// A spinner that appears after [`SHOW_AFTER`]; dropping it clears it.
pub struct Progress {
    bar: ProgressBar,
    done: Arc<AtomicBool>,
    waiter: Option<std::thread::JoinHandle<()>>,
}

impl Progress {
    /// Starts the spinner for `what` ("calibrating robot.urdf against d.csv"), unless `quiet`.
    pub fn start(what: &str, quiet: bool) -> Option<Self> {
        if quiet {
            return None;
        }
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        let style = ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
            .unwrap_or_else(|_| ProgressStyle::default_spinner());
        bar.set_style(style);
        bar.set_message(crate::guard::escape(what).into_owned());
        let done = Arc::new(AtomicBool::new(false));
        let (shown, flag) = (bar.clone(), Arc::clone(&done));
        let waiter = std::thread::spawn(move || {
            let until = Instant::now() + SHOW_AFTER;
            // Parked until the deadline or until the work ends (no lock held while drawing).
            while !flag.load(Ordering::Acquire) {
                let now = Instant::now();
                if now >= until {
                    // `stderr()` draws only on a terminal.
                    shown.set_draw_target(ProgressDrawTarget::stderr());
                    shown.enable_steady_tick(Duration::from_millis(120));
                    return;
                }
                std::thread::park_timeout(until - now);
            }
        });
        Some(Self {
            bar,
            done,
            waiter: Some(waiter),
        })
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.done.store(true, Ordering::Release);
        if let Some(w) = self.waiter.take() {
            w.thread().unpark();
            let _ = w.join();
        }
        self.bar.finish_and_clear();
    }
}
