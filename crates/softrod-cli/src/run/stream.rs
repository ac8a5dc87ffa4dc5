//! The observer of `softrod run`: each sample recorded by the facade's
//! [`Recorder`], written as rows, kept for the figures; the progress bar,
//! the running summary and the signals that stop a run.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use indicatif::ProgressBar;
use softrod::dynamics::Model;
use softrod::integrate::Stats;
use softrod::record::{Recorder, RodSampling};
use softrod::{Flow, Observer, Sample};

use super::rows::RowWriter;
use super::summary::Summary;
use crate::common::CliError;
use crate::plots::{Series, Snapshot};
use crate::signals;

/// Longest wall time between two writes of the running summary, s.
pub const SUMMARY_EVERY: f64 = 0.5;

/// Where the run is, shared with the signal watchdog
/// ([`signals::watchdog`]): it is updated under the lock together with
/// each row written, so the watchdog, which takes the lock and never
/// releases it, writes a summary that matches the files.
pub struct Progress {
    /// The running summary (the run's fixed facts).
    pub summary: Summary,
    pub rows: usize,
    pub expected: usize,
    /// The last row's time, s.
    pub t: f64,
    pub stats: Stats,
    pub start: Instant,
    /// The run has stopped integrating (ended, failed or acted on the
    /// signal): the outputs are being closed.
    pub closing: bool,
    /// The final summary and its status, once written: the figures and
    /// the 3-D view follow.
    pub finished: Option<(Summary, String)>,
}

impl Progress {
    /// The lock, also if a panicking holder poisoned it (the counters stay
    /// consistent: each is a plain store).
    pub fn lock(p: &Mutex<Progress>) -> MutexGuard<'_, Progress> {
        p.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// What the watchdog writes when the run did not stop within the
    /// grace after signal `sig`: the summary that matches the files now.
    pub fn expire(&self, sig: &str) -> String {
        let wall = self.start.elapsed().as_secs_f64();
        let grace = signals::GRACE.as_secs_f64();
        if let Some((summary, status)) = &self.finished {
            let note = format!(
                "interrupted by {sig} while drawing the figures and the 3-D view (not \
                 finished {grace} s after the signal: some are missing)"
            );
            let status = if status == "ok" {
                format!("error: {note}")
            } else {
                format!("{status}; {note}")
            };
            let _ = summary.write(&self.stats, wall, self.t, &status, self.rows);
            return status;
        }
        let (rows, expected, t) = (self.rows, self.expected, self.t);
        let when = if self.closing {
            "while closing the outputs"
        } else {
            "inside a long computation (no step ended"
        };
        let status = format!(
            "error: interrupted by {sig} at t = {t} ({rows} of {expected} output rows \
             written) {when}{} within {grace} s of the signal): the figures, the 3-D view \
             and trajectory.npz were not made",
            if self.closing { " (not finished" } else { "" }
        );
        let _ = self.summary.write(&self.stats, wall, t, &status, rows);
        status
    }
}

/// Records, writes and keeps output rows as the integration produces them.
pub struct Streamer {
    recorder: Recorder,
    rows: RowWriter,
    progress: Arc<Mutex<Progress>>,
    start: Instant,
    summary_written: Option<Instant>,
    /// The signal that ended the run, if one did.
    pub interrupted: Option<&'static str>,
    expected: usize,
    next: usize,
    snapshot_at: Vec<usize>,
    /// The last row's snapshot, kept so the figures end where the run did.
    last_snapshot: Option<Snapshot>,
    pub series: Series,
    pub error: Option<String>,
    pub last_stats: Stats,
    pub last_t: f64,
    pub bar: Option<ProgressBar>,
    duration: f64,
}

/// The output rows nearest the times `chosen` (s, each finite and within
/// `[0, duration]`; exit 2 otherwise), or six spread evenly when none are.
pub fn chosen_rows(times: &[f64], chosen: Option<&[f64]>) -> Result<Vec<usize>, CliError> {
    let Some(chosen) = chosen else {
        return Ok(snapshot_rows(times.len()));
    };
    let end = times.last().copied().unwrap_or(0.0);
    let mut rows = Vec::with_capacity(chosen.len());
    for &t in chosen {
        if !(t.is_finite() && (0.0..=end).contains(&t)) {
            return Err(CliError::Input(format!(
                "--snapshots: {t} is not a time of the run (0 to {end} s)"
            )));
        }
        let k = times.partition_point(|x| *x < t);
        let nearest = if k == 0 {
            0
        } else if k == times.len() || t - times[k - 1] <= times[k] - t {
            k - 1
        } else {
            k
        };
        rows.push(nearest);
    }
    rows.sort_unstable();
    rows.dedup();
    Ok(rows)
}

/// Rows (indices into the output times) whose shapes and strains are drawn
/// by default: six spread evenly, first and last included.
fn snapshot_rows(m: usize) -> Vec<usize> {
    let snaps = 6.min(m);
    let mut v: Vec<usize> = (0..snaps)
        .map(|k| {
            if snaps == 1 {
                0
            } else {
                k * (m - 1) / (snaps - 1)
            }
        })
        .collect();
    v.dedup();
    v
}

impl Streamer {
    /// A streamer of `model`'s run at `times`, its rods sampled at
    /// `sampling`, its rows written by `rows`, shapes drawn at the rows
    /// `snapshot_at`.
    pub fn new(
        model: &Model,
        times: &[f64],
        sampling: Vec<RodSampling>,
        mut rows: RowWriter,
        snapshot_at: Vec<usize>,
        progress: Arc<Mutex<Progress>>,
        bar: Option<ProgressBar>,
    ) -> Self {
        rows.collect_view(model, sampling.iter().map(|r| r.s.clone()).collect());
        Self {
            recorder: Recorder::with_sampling(model, sampling),
            rows,
            progress,
            start: Instant::now(),
            summary_written: None,
            interrupted: None,
            next: 0,
            snapshot_at,
            last_snapshot: None,
            series: Series::new(model.rods().len(), model.n_cables()),
            error: None,
            last_stats: Stats::default(),
            last_t: 0.0,
            duration: times.last().copied().unwrap_or(0.0),
            expected: times.len(),
            bar,
        }
    }

    pub fn rows_written(&self) -> usize {
        self.next
    }

    pub fn rows_expected(&self) -> usize {
        self.expected
    }

    /// The largest closure residual over the rows written \[m\] (0 without
    /// closures).
    pub fn closure_residual_max(&self) -> f64 {
        self.recorder.closure_residual_max()
    }

    /// The largest penetration over the rows written \[m\] (0 without
    /// contact).
    pub fn max_penetration(&self) -> f64 {
        self.recorder.max_penetration()
    }

    /// [`softrod::record::Recorder::penetration_warning`] of the rows so far.
    pub fn penetration_warning(&self, model: &softrod::dynamics::Model) -> Option<String> {
        self.recorder.penetration_warning(model)
    }

    /// The most contacts active at one row.
    pub fn max_contacts(&self) -> usize {
        self.recorder.max_contacts()
    }

    /// The file writer (for `trajectory.npz` at the end).
    pub fn rows(&self) -> &RowWriter {
        &self.rows
    }

    /// The frames of the 3-D view kept from the rows written.
    pub fn take_view(&mut self) -> Option<softrod_viz::collect::FrameCollector> {
        self.rows.take_view()
    }

    /// The series for the figures; a run that stopped early gets its last
    /// row as the final snapshot, so it is drawn up to where it stopped.
    pub fn finish_series(&mut self) -> &Series {
        self.series.finish();
        let stopped_early = self.next < self.expected;
        if let Some(last) = self.last_snapshot.take().filter(|_| stopped_early) {
            if self.series.snapshots.last().is_none_or(|s| s.t < last.t) {
                self.series.snapshots.push(last);
            }
        }
        &self.series
    }

    fn write_row(&mut self, s: Sample<'_>) -> Result<(), String> {
        let rec = self
            .recorder
            .record(s.model, s.data, s.t, s.q, s.qd)
            .map_err(|e| softrod::report(&e))?;
        self.rows.write(rec)?;
        self.series.push(rec);
        let snapshot = Snapshot::of(rec);
        if self.snapshot_at.contains(&self.next) {
            self.series.snapshots.push(snapshot);
            self.last_snapshot = None;
        } else {
            self.last_snapshot = Some(snapshot);
        }
        Ok(())
    }
}

impl Observer for Streamer {
    /// One output row: the integrator's dense output at the next output time.
    fn sample(&mut self, s: Sample<'_>) -> Result<Flow, String> {
        let t = s.t;
        // Held while the row is written and counted: the watchdog then
        // sees whole rows only.
        let progress = Arc::clone(&self.progress);
        let mut p = Progress::lock(&progress);
        if let Err(e) = self.write_row(s) {
            self.error = Some(e.clone());
            return Err(e);
        }
        self.next += 1;
        self.last_t = t;
        (p.rows, p.t) = (self.next, t);
        // Keep summary.json current, so a run killed with SIGKILL still
        // says how far it got (its status stays "running").
        if self
            .summary_written
            .is_none_or(|w| w.elapsed().as_secs_f64() >= SUMMARY_EVERY)
        {
            let wall = self.start.elapsed().as_secs_f64();
            if let Err(e) = p
                .summary
                .write(&self.last_stats, wall, t, "running", self.next)
            {
                let e = e.to_string();
                self.error = Some(e.clone());
                return Err(e);
            }
            self.summary_written = Some(Instant::now());
        }
        if let Some(sig) = signals::received() {
            self.interrupted = Some(sig);
            p.closing = true;
            return Ok(Flow::Stop);
        }
        Ok(Flow::Continue)
    }

    fn stop_requested(&mut self) -> bool {
        // A signal stops the run at the step it arrives in, not at the next
        // output time (which may be far off).
        match signals::received() {
            Some(sig) => {
                self.interrupted = Some(sig);
                Progress::lock(&self.progress).closing = true;
                true
            }
            None => false,
        }
    }

    fn step(&mut self, t: f64, stats: &Stats) {
        self.last_stats = *stats;
        Progress::lock(&self.progress).stats = *stats;
        if let Some(b) = &self.bar {
            b.set_position((t / self.duration * 1000.0) as u64);
            b.set_message(format!("{t:.4}"));
        }
    }
}
