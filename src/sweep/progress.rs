//! Progress of a sweep on stderr: an indicatif bar when stderr is a
//! terminal, plain lines otherwise.
//!
//! indicatif draws nothing when stderr is not a terminal (a pipe, a CI
//! log, `2> file`), which left a five-minute sweep silent. There a
//! [`Progress`] prints one line whenever another 5 % of the runs are done
//! ([`LINE_PERCENT`]) or [`LINE_INTERVAL_S`] seconds have passed since the
//! last line, whichever comes first, and one when the phase ends:
//!
//! ```text
//! sweep S01: 124/248 runs, 61 s
//! ```

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// A plain line is printed at least every this many percent of the runs.
pub const LINE_PERCENT: usize = 5;
/// A plain line is printed at least this often (seconds) while runs finish.
pub const LINE_INTERVAL_S: f64 = 10.0;

/// The progress of one phase of a sweep (`total` runs).
pub struct Progress {
    bar: ProgressBar,
    lines: Option<Mutex<Lines>>,
}

/// State of the plain-line reporter.
struct Lines {
    label: String,
    total: usize,
    done: usize,
    start: Instant,
    last: Instant,
    /// Runs done at the last line.
    last_done: usize,
}

/// One plain progress line: `sweep S01: 124/248 runs, 61 s`.
///
/// ```
/// use dae::sweep::progress::line;
///
/// assert_eq!(line("sweep S01", 124, 248, 61.4), "sweep S01: 124/248 runs, 61 s");
/// ```
pub fn line(label: &str, done: usize, total: usize, elapsed_s: f64) -> String {
    format!("{label}: {done}/{total} runs, {elapsed_s:.0} s")
}

/// Whether a plain line is due after `done` of `total` runs: another
/// [`LINE_PERCENT`] % of them finished since the line at `last_done`, or
/// [`LINE_INTERVAL_S`] passed since it (`since_last_s`), or the phase is
/// complete.
///
/// ```
/// use dae::sweep::progress::line_due;
///
/// assert!(!line_due(3, 0, 248, 1.0)); // 1.2 %, 1 s
/// assert!(line_due(13, 0, 248, 1.0)); // 5.2 %
/// assert!(line_due(4, 3, 248, 10.5)); // 10 s since the last line
/// assert!(line_due(248, 240, 248, 0.1)); // the end
/// ```
pub fn line_due(done: usize, last_done: usize, total: usize, since_last_s: f64) -> bool {
    done >= total
        || (done - last_done.min(done)) * 100 >= LINE_PERCENT * total.max(1)
        || since_last_s >= LINE_INTERVAL_S
}

impl Progress {
    /// A reporter for `total` runs labelled `label` (`sweep S01`); silent
    /// when `show` is false.
    pub fn new(label: &str, total: usize, show: bool) -> Self {
        let terminal = std::io::stderr().is_terminal();
        Self::with_terminal(label, total, show, terminal)
    }

    /// [`Progress::new`] with the terminal test given: a bar when
    /// `terminal`, plain lines otherwise.
    pub fn with_terminal(label: &str, total: usize, show: bool, terminal: bool) -> Self {
        let target = if show && terminal {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let bar = ProgressBar::with_draw_target(Some(total as u64), target);
        let style = ProgressStyle::with_template(
            "{prefix:>9} [{bar:32.cyan/blue}] {pos}/{len} {elapsed:>4} {wide_msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
        bar.set_style(style);
        bar.set_prefix(label.to_string());
        if show && terminal {
            bar.enable_steady_tick(Duration::from_millis(200));
        }
        let now = Instant::now();
        let lines = (show && !terminal && total > 0).then(|| {
            Mutex::new(Lines {
                label: label.to_string(),
                total,
                done: 0,
                start: now,
                last: now,
                last_done: 0,
            })
        });
        Progress { bar, lines }
    }

    /// The run being integrated (shown beside the bar).
    pub fn set_message(&self, msg: String) {
        self.bar.set_message(msg);
    }

    /// One more run done.
    pub fn inc(&self) {
        self.bar.inc(1);
        let Some(lines) = &self.lines else { return };
        let Ok(mut l) = lines.lock() else { return };
        l.done += 1;
        let now = Instant::now();
        if line_due(
            l.done,
            l.last_done,
            l.total,
            now.duration_since(l.last).as_secs_f64(),
        ) {
            let text = line(
                &l.label,
                l.done,
                l.total,
                now.duration_since(l.start).as_secs_f64(),
            );
            // Progress is a courtesy: a closed stderr does not stop a sweep.
            let _ = writeln!(std::io::stderr().lock(), "{text}");
            l.last = now;
            l.last_done = l.done;
        }
    }

    /// The phase is over: clear the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
