//! Progress of long jobs on stderr: a bar on a terminal, a line every few seconds in a log.
//!
//! Input: the work's name and unit, its total, and counts as items finish (from any thread).
//! Output: on a terminal, an indicatif bar with the count, the rate and the time left; when
//! stderr is not a terminal (a log file, a CI job), one line at the start, one every
//! [`LOG_EVERY_S`] seconds (`VOCC_PROGRESS_SECONDS` overrides it) and one at the end.
//! Invariant: reporting only; it never changes what the work computes.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Seconds between progress lines when stderr is not a terminal.
pub const LOG_EVERY_S: f64 = 5.0;

pub struct Progress {
    what: String,
    /// The unit counted, singular and plural ("cell", "cells").
    unit: (String, String),
    total: AtomicU64,
    done: AtomicU64,
    start: Instant,
    bar: Option<indicatif::ProgressBar>,
    /// Log mode: when the last line was printed.
    last: Mutex<Instant>,
    every: Duration,
}

fn secs(s: f64) -> String {
    if s < 90.0 {
        format!("{s:.0} s")
    } else if s < 5400.0 {
        format!("{:.0} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

impl Progress {
    /// `what` is the activity ("baking"), `unit` what is counted, singular and plural
    /// (`("cell", "cells")`).
    pub fn new(what: &str, unit: (&str, &str), total: u64) -> Progress {
        let (one, many) = unit;
        let bar = std::io::stderr().is_terminal().then(|| {
            let b = indicatif::ProgressBar::new(total);
            b.set_style(
                indicatif::ProgressStyle::with_template(&format!(
                    "{what} {{bar:40}} {{pos}}/{{len}} {many}, {{per_sec}}, {{elapsed}} elapsed, about {{eta}} left"
                ))
                .expect("a valid template"),
            );
            b
        });
        let every = std::env::var("VOCC_PROGRESS_SECONDS")
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|v| v.is_finite() && *v >= 0.0)
            .unwrap_or(LOG_EVERY_S);
        Progress {
            what: what.to_string(),
            unit: (one.to_string(), many.to_string()),
            total: AtomicU64::new(total),
            done: AtomicU64::new(0),
            start: Instant::now(),
            bar,
            last: Mutex::new(Instant::now()),
            every: Duration::from_secs_f64(every),
        }
    }

    /// Sets the total (when it is known only once the work starts) and, in a log, prints the
    /// first line.
    pub fn start(&self, total: u64) {
        self.total.store(total, Ordering::Relaxed);
        match &self.bar {
            Some(b) => b.set_length(total),
            None => eprintln!("{}: {}", self.what, self.count(total)),
        }
    }

    /// One more item done.
    pub fn inc(&self) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        match &self.bar {
            Some(b) => b.inc(1),
            None => {
                let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
                if last.elapsed() >= self.every {
                    *last = Instant::now();
                    eprintln!("{}", self.line(done));
                }
            }
        }
    }

    /// "228 cells", "1 cell".
    fn count(&self, n: u64) -> String {
        format!("{n} {}", if n == 1 { &self.unit.0 } else { &self.unit.1 })
    }

    /// "baking: 120/228 cells (53%), 12.3 cells/s, 10 s elapsed, about 9 s left".
    fn line(&self, done: u64) -> String {
        let total = self.total.load(Ordering::Relaxed);
        let t = self.start.elapsed().as_secs_f64();
        let rate = done as f64 / t.max(1e-9);
        let left = total.saturating_sub(done) as f64 / rate.max(1e-9);
        // A slow job's rate per minute ("1.2 cells/min", not "0.0 cells/s").
        let rate = if rate < 0.1 {
            format!("{:.1} {}/min", 60.0 * rate, self.unit.1)
        } else {
            format!("{rate:.1} {}/s", self.unit.1)
        };
        format!(
            "{}: {done}/{} ({:.0}%), {rate}, {} elapsed, about {} left",
            self.what,
            self.count(total),
            100.0 * done as f64 / total.max(1) as f64,
            secs(t),
            secs(left)
        )
    }

    /// Clears the bar, or prints the last line of a log.
    pub fn finish(&self) {
        match &self.bar {
            Some(b) => b.finish_and_clear(),
            None => {
                let done = self.done.load(Ordering::Relaxed);
                eprintln!(
                    "{}: {done}/{} done in {}",
                    self.what,
                    self.count(self.total.load(Ordering::Relaxed)),
                    secs(self.start.elapsed().as_secs_f64())
                );
            }
        }
    }
}
