//! Progress reporting for long stages: bars on stderr, hidden when stderr is not a terminal or
//! when the user asked for quiet; or, for a caller that installed a [`ProgressSink`] (the Python
//! package's progress callback), rate-limited reports to that sink instead. A sink may also
//! cancel the run ([`ProgressSink::cancelled`]): the long loops ask their [`Progress`] at each row,
//! band or tile and skip the rest of their work, and the stage then returns
//! [`Error::Cancelled`]. Without a sink (the CLI) nothing is ever cancelled.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::error::{Error, Result};

/// Receives the progress of every stage started while it is installed ([`with_sink`]).
/// `update` may be called from any worker thread, never more often than every
/// [`SINK_INTERVAL`] per stage, and once more when the stage finishes.
pub trait ProgressSink: Send + Sync {
    /// `stage` (e.g. "display image LA", "ground truth Pin") has done `done` of `total` steps.
    fn update(&self, stage: &str, done: u64, total: u64);

    /// Whether the caller wants the run stopped (e.g. Python's Ctrl-C). Asked by worker threads
    /// at every row, band or tile of the long loops, so it must be cheap (an atomic load); once
    /// it is true it should stay true. By default never.
    fn cancelled(&self) -> bool {
        false
    }
}

/// The least time between two reports of one stage to a [`ProgressSink`].
pub const SINK_INTERVAL: Duration = Duration::from_millis(100);

thread_local! {
    static SINK: RefCell<Option<Arc<dyn ProgressSink>>> = const { RefCell::new(None) };
}

/// Runs `f` with `sink` receiving the progress of every [`Progress`] created on this thread
/// meanwhile (quiet or not), then restores what was installed before.
pub fn with_sink<T>(sink: Arc<dyn ProgressSink>, f: impl FnOnce() -> T) -> T {
    struct Restore(Option<Arc<dyn ProgressSink>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            SINK.with(|s| *s.borrow_mut() = previous);
        }
    }
    let _restore = Restore(SINK.with(|s| s.borrow_mut().replace(sink)));
    f()
}

/// The [`ProgressSink`] installed on this thread, to install with [`with_installed`] on the
/// threads that work is handed to (file writes run on rayon's workers).
pub fn installed() -> Option<Arc<dyn ProgressSink>> {
    SINK.with(|s| s.borrow().clone())
}

/// [`with_sink`] when `sink` is given, else `f` alone.
pub fn with_installed<T>(sink: Option<Arc<dyn ProgressSink>>, f: impl FnOnce() -> T) -> T {
    match sink {
        Some(sink) => with_sink(sink, f),
        None => f(),
    }
}

/// Whether the [`ProgressSink`] installed on this thread cancelled the run (never without one).
pub fn cancelled() -> bool {
    SINK.with(|s| s.borrow().as_ref().is_some_and(|s| s.cancelled()))
}

/// [`Error::Cancelled`] when the [`ProgressSink`] installed on this thread cancelled the run: the
/// check between stages, on the thread that installed the sink.
pub fn check_cancelled() -> Result<()> {
    if cancelled() {
        return Err(Error::Cancelled);
    }
    Ok(())
}

/// A stage reporting to a sink: counts steps atomically, reports at most every
/// [`SINK_INTERVAL`].
struct SinkStage {
    sink: Arc<dyn ProgressSink>,
    stage: String,
    total: u64,
    done: AtomicU64,
    last: Mutex<Instant>,
}

impl SinkStage {
    fn inc(&self, n: u64) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        // Whoever holds the lock reports; the others go on working.
        if let Ok(mut last) = self.last.try_lock() {
            if last.elapsed() >= SINK_INTERVAL {
                *last = Instant::now();
                drop(last);
                self.sink.update(&self.stage, done, self.total);
            }
        }
    }

    fn finish(&self) {
        self.sink.update(&self.stage, self.done.load(Ordering::Relaxed), self.total);
    }
}

/// A progress bar that may be hidden. Cheap to clone and `Sync` (increments are atomic).
#[derive(Clone, Default)]
pub struct Progress {
    bar: Option<ProgressBar>,
    sink: Option<Arc<SinkStage>>,
}

impl Progress {
    /// No output at all.
    pub fn hidden() -> Self {
        Self { bar: None, sink: None }
    }

    /// A bar of `len` steps on stderr (indicatif draws nothing when stderr is not a terminal),
    /// or reports to the [`ProgressSink`] installed on this thread, if any.
    pub fn new(len: u64, message: &str, quiet: bool) -> Self {
        if let Some(sink) = SINK.with(|s| s.borrow().clone()) {
            let stage = SinkStage {
                sink,
                stage: message.to_string(),
                total: len,
                done: AtomicU64::new(0),
                // The first report comes one interval after the start.
                last: Mutex::new(Instant::now()),
            };
            return Self { bar: None, sink: Some(Arc::new(stage)) };
        }
        if quiet {
            return Self::hidden();
        }
        let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template("{msg:32} [{bar:40}] {percent:>3}% {elapsed_precise}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_message(message.to_string());
        Self { bar: Some(bar), sink: None }
    }

    /// Advances the bar (and the sink, if any) by `n` units.
    #[inline]
    pub fn inc(&self, n: u64) {
        if let Some(b) = &self.bar {
            b.inc(n);
        }
        if let Some(s) = &self.sink {
            s.inc(n);
        }
    }

    /// Whether the run was cancelled ([`ProgressSink::cancelled`] of the sink this stage reports
    /// to; never for a bar or a hidden stage). The long loops ask at each row, band or tile and
    /// skip the rest of their work once it is true.
    #[inline]
    pub fn cancelled(&self) -> bool {
        self.sink.as_ref().is_some_and(|s| s.sink.cancelled())
    }

    /// [`Error::Cancelled`] when the run was cancelled: asked after a loop that may have skipped
    /// work, so that no partial result is used.
    pub fn check(&self) -> Result<()> {
        if self.cancelled() {
            return Err(Error::Cancelled);
        }
        Ok(())
    }

    /// Finishes and clears the bar.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
        if let Some(s) = &self.sink {
            s.finish();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Default)]
    struct Record(Mutex<Vec<(String, u64, u64)>>);

    impl ProgressSink for Record {
        fn update(&self, stage: &str, done: u64, total: u64) {
            self.0.lock().unwrap().push((stage.to_string(), done, total));
        }
    }

    #[test]
    fn a_sink_sees_the_final_count_and_is_uninstalled_afterwards() {
        let record = Arc::new(Record::default());
        let sink: Arc<dyn ProgressSink> = record.clone();
        with_sink(sink, || {
            let p = Progress::new(10, "stage A", true);
            for _ in 0..10 {
                p.inc(1);
            }
            p.finish();
        });
        // Quick increments are rate-limited: only the final report (10 of 10) arrives.
        assert_eq!(*record.0.lock().unwrap(), vec![("stage A".to_string(), 10, 10)]);
        // Outside `with_sink`, nothing reaches the sink.
        let p = Progress::new(5, "stage B", true);
        p.inc(5);
        p.finish();
        assert_eq!(record.0.lock().unwrap().len(), 1);
    }

    /// A sink that cancels once asked `after` times.
    struct CancelAfter(AtomicU64, u64);

    impl ProgressSink for CancelAfter {
        fn update(&self, _: &str, _: u64, _: u64) {}
        fn cancelled(&self) -> bool {
            self.0.fetch_add(1, Ordering::Relaxed) >= self.1
        }
    }

    #[test]
    fn a_sink_cancels_the_stages_and_the_checks_between_them_only_while_installed() {
        let sink: Arc<dyn ProgressSink> = Arc::new(CancelAfter(AtomicU64::new(0), 2));
        with_sink(sink, || {
            let p = Progress::new(10, "stage", true);
            assert!(!p.cancelled() && p.check().is_ok());
            assert!(p.cancelled() && matches!(p.check(), Err(Error::Cancelled)));
            assert!(matches!(check_cancelled(), Err(Error::Cancelled)));
        });
        // Without a sink (the CLI), and for a bar or a hidden stage, nothing is ever cancelled.
        assert!(!cancelled() && check_cancelled().is_ok());
        assert!(!Progress::new(10, "stage", true).cancelled() && !Progress::hidden().cancelled());
    }

    #[test]
    fn reports_are_at_least_an_interval_apart() {
        let record = Arc::new(Record::default());
        let sink: Arc<dyn ProgressSink> = record.clone();
        with_sink(sink, || {
            let p = Progress::new(3, "slow", true);
            for _ in 0..3 {
                std::thread::sleep(SINK_INTERVAL + Duration::from_millis(20));
                p.inc(1);
            }
            p.finish();
        });
        let r = record.0.lock().unwrap();
        let done: Vec<u64> = r.iter().map(|x| x.1).collect();
        assert_eq!(done, vec![1, 2, 3, 3]);
    }
}
