//! A progress line on standard error for long runs (`calibrate`): a spinner with what is being
//! done and the time spent, drawn only when standard error is a terminal and only once the run
//! has taken a second, cleared when the work ends; `--quiet` turns it off. Reports, warnings
//! and errors never go through it, so pipes, logs and snapshots see none of it.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use dh_workflows::fit::Plan;
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

/// The pipeline's progress ([`dh_workflows::fit::Progress`]) on a terminal: when the fit
/// starts, a notice on standard error for a long run (`notice`, `None` for none) and the
/// spinner of [`Progress`] (`label`); cleared when the fit is over, or when this is dropped.
pub struct PipelineProgress<'a> {
    err: &'a mut dyn std::io::Write,
    quiet: bool,
    notice: &'a dyn Fn(&Plan) -> Option<String>,
    label: &'a dyn Fn(&Plan) -> String,
    line: Option<Progress>,
    failed: Option<std::io::Error>,
}

impl<'a> PipelineProgress<'a> {
    /// Progress written to `err` (the notice) and drawn on the terminal (the spinner, unless
    /// `quiet`).
    pub fn new(
        err: &'a mut dyn std::io::Write,
        quiet: bool,
        notice: &'a dyn Fn(&Plan) -> Option<String>,
        label: &'a dyn Fn(&Plan) -> String,
    ) -> Self {
        Self {
            err,
            quiet,
            notice,
            label,
            line: None,
            failed: None,
        }
    }

    /// The first failure to write the notice, if any.
    ///
    /// # Errors
    /// That failure.
    pub fn check(&mut self) -> std::io::Result<()> {
        self.failed.take().map_or(Ok(()), Err)
    }
}

impl dh_workflows::fit::Progress for PipelineProgress<'_> {
    fn started(&mut self, plan: &Plan) {
        if let Some(n) = (self.notice)(plan) {
            if let Err(e) = writeln!(self.err, "{n}") {
                self.failed.get_or_insert(e);
            }
        }
        self.line = Progress::start(&(self.label)(plan), self.quiet);
    }

    fn finished(&mut self) {
        self.line = None;
    }
}
