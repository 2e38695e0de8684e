//! Progress: a spinner for work whose length is not known in advance, and rows of reference
//! rays.

use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

pub(crate) fn spinner(msg: &str) -> ProgressBar {
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{elapsed}]").expect("valid template"),
    );
    pb.enable_steady_tick(Duration::from_millis(120));
    pb.set_message(msg.to_string());
    pb
}

/// A bar of `len` steps named `what` ("frames"), with the step's message and the time left.
pub(crate) fn bar(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template(&format!(
            "{{bar:30}} {{pos}}/{{len}} {what}, {{msg}} [{{elapsed}}, ~{{eta}} left]"
        ))
        .expect("valid template"),
    );
    pb
}

/// Progress of a reference traced row by row (`compare`): on a terminal a bar with the rays
/// so far (at most: pairs out of reach trace none), rays per second and the time left; where stderr is no terminal (a log) the same as
/// a line at every tenth of the rows.
pub(crate) struct RowProgress {
    bar: ProgressBar,
    plain: bool,
    rows: u64,
    rays_per_row: f64,
    what: String,
    started: std::time::Instant,
    /// Rows done: each tracing thread's row gets its own count (the bar's position may be
    /// read by two threads at once).
    done: std::sync::atomic::AtomicU64,
}

impl RowProgress {
    /// `rows` rows of about `rays_per_row` rays each, named `what` ("reference rays").
    pub(crate) fn new(
        multi: &indicatif::MultiProgress,
        rows: u64,
        rays_per_row: f64,
        what: &str,
    ) -> Self {
        let bar = multi.add(ProgressBar::new(rows));
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{{bar:30}} {{pos}}/{{len}} rows of {what}, {{msg}} [{{elapsed}}, ~{{eta}} left]"
            ))
            .expect("valid template"),
        );
        Self {
            bar,
            plain: !std::io::IsTerminal::is_terminal(&std::io::stderr()),
            rows,
            rays_per_row,
            what: what.to_string(),
            started: std::time::Instant::now(),
            done: std::sync::atomic::AtomicU64::new(0),
        }
    }

    /// One row done (called from the tracing threads).
    pub(crate) fn row(&self) {
        self.bar.inc(1);
        let done = self.done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        let secs = self.started.elapsed().as_secs_f64().max(1e-3);
        let rays = done as f64 * self.rays_per_row;
        // An upper bound: pixels out of a light's reach or facing away trace nothing.
        let status = format!(
            "≤ {} rays, ≤ {}/s",
            crate::progress::si(rays),
            crate::progress::si(rays / secs)
        );
        let step = (self.rows / 10).max(1);
        if self.plain && (done.is_multiple_of(step) || done == self.rows) {
            let left = secs * (self.rows - done) as f64 / done.max(1) as f64;
            eprintln!(
                "{}: {done}/{} rows, {status}, ~{left:.0} s left",
                self.what, self.rows
            );
        }
        self.bar.set_message(status);
    }

    /// Clears the bar.
    pub(crate) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// `1234567.0` as `1.2 M` (k, M, G).
pub(crate) fn si(x: f64) -> String {
    match x {
        x if x >= 1e9 => format!("{:.1} G", x / 1e9),
        x if x >= 1e6 => format!("{:.1} M", x / 1e6),
        x if x >= 1e3 => format!("{:.1} k", x / 1e3),
        x => format!("{x:.0}"),
    }
}
