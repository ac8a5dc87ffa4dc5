//! The observer of `softrod run`: each sample recorded by the facade's
//! [`Recorder`], written as rows, kept for the figures; the progress bar,
//! the running summary and the signals that stop a run.

use std::sync::mpsc::{Receiver, SyncSender};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Instant;

use indicatif::ProgressBar;
use softrod::dynamics::Model;
use softrod::integrate::Stats;
use softrod::record::{Columns, Recorder, RodSampling};
use softrod::{Flow, Observer, Sample};

use super::rows::{RowData, RowWriter};
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

    /// Counts a row written at time `t` (s) and keeps summary.json current
    /// (at most every [`SUMMARY_EVERY`] s; `summary_at`: when it was last
    /// written), so that a run killed with SIGKILL still says how far it
    /// got (its status stays "running") with the rows the files hold.
    fn count_row(&mut self, t: f64, summary_at: &mut Option<Instant>) -> Result<(), String> {
        self.rows += 1;
        self.t = t;
        if summary_at.is_none_or(|w| w.elapsed().as_secs_f64() >= SUMMARY_EVERY) {
            let wall = self.start.elapsed().as_secs_f64();
            self.summary
                .write(&self.stats, wall, t, "running", self.rows)
                .map_err(|e| e.to_string())?;
            *summary_at = Some(Instant::now());
        }
        Ok(())
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

/// Batches of output times in flight between the integration and the
/// writer thread: enough that neither waits for the other's jitter, few
/// enough that a failed write stops the run soon after.
const BATCHES_IN_FLIGHT: usize = 4;
/// Output times per batch: the writer is woken once per batch, not once
/// per row (on a busy machine each wake-up is a switch between threads).
const BATCH_ROWS: usize = 16;
/// Batching is for rows that come fast: a row computed at least this long
/// after the last batch was sent goes at once (the first row too), and a
/// batch is sent at the end of the step in which its first row has waited
/// this long, s — a slow run's files follow it as before.
const BATCH_WAIT: f64 = 0.05;

/// One batch of output times.
type Batch = Vec<RowData>;

/// What the writer thread hands back: the files' writer, the rows it
/// wrote, the last one's time \[s\], and the error it stopped at.
type Written = (RowWriter, usize, f64, Option<String>);

/// Where the rows go: formatted and written on a thread of their own
/// while the integration goes on (the process is timed by its wall clock,
/// and the text of the rows costs about as much as the integration of a
/// short run: docs/performance.md, issue 30), or, if no thread can be
/// started, here.
// One per run: the variants' sizes do not matter.
#[allow(clippy::large_enum_variant)]
enum Sink {
    Thread {
        rows: SyncSender<Batch>,
        /// Batches written, for reuse.
        spent: Receiver<Batch>,
        /// The batch being filled, when its first row was computed, and
        /// when the last batch was sent.
        batch: Batch,
        since: Option<Instant>,
        sent: Option<Instant>,
        /// Row buffers for reuse.
        free: Vec<RowData>,
        /// The error the writer stopped at.
        failed: Arc<Mutex<Option<String>>>,
        writer: JoinHandle<Option<Written>>,
    },
    /// Written on the integration's thread; also the writer once the
    /// thread is joined.
    Here {
        rows: RowWriter,
        written: usize,
        last_t: f64,
        spare: RowData,
        /// When the running summary was last written.
        summary_at: Option<Instant>,
    },
    /// The writer thread panicked: no writer is left.
    Lost,
}

/// The writer thread: writes each time's rows as they come, counts them in
/// `progress` under its lock (so the signal watchdog sees whole rows only
/// and a summary that matches the files), and stops at the first error.
fn write_rows(
    mut rows: RowWriter,
    incoming: Receiver<Batch>,
    spent: SyncSender<Batch>,
    failed: Arc<Mutex<Option<String>>>,
    progress: Arc<Mutex<Progress>>,
) -> Written {
    let (mut written, mut last_t, mut summary_at) = (0, 0.0, None);
    for batch in incoming {
        for d in &batch {
            let mut p = Progress::lock(&progress);
            let done = rows
                .write(d)
                .and_then(|()| p.count_row(d.t, &mut summary_at));
            if let Err(e) = done {
                drop(p);
                *failed
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(e.clone());
                return (rows, written, last_t, Some(e));
            }
            written += 1;
            last_t = d.t;
        }
        // Full only if the integration has buffers enough: then dropped.
        let _ = spent.try_send(batch);
    }
    (rows, written, last_t, None)
}

impl Sink {
    /// The writer thread for `rows`, or `rows` here if no thread starts.
    fn start(rows: RowWriter, progress: &Arc<Mutex<Progress>>) -> Self {
        let (tx, incoming) = std::sync::mpsc::sync_channel(BATCHES_IN_FLIGHT);
        let (spent_tx, spent) = std::sync::mpsc::sync_channel(BATCHES_IN_FLIGHT + 2);
        let failed = Arc::new(Mutex::new(None));
        // Held in a slot so that it comes back if the thread cannot start.
        let slot = Arc::new(Mutex::new(Some(rows)));
        let (f, p, sl) = (Arc::clone(&failed), Arc::clone(progress), Arc::clone(&slot));
        let started = std::thread::Builder::new()
            .name("softrod-rows".into())
            .spawn(move || {
                let rows = sl
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner)
                    .take();
                // Always there: it leaves the slot here or, if the thread
                // never starts, below.
                rows.map(|rows| write_rows(rows, incoming, spent_tx, f, p))
            });
        match started {
            Ok(writer) => Sink::Thread {
                rows: tx,
                spent,
                batch: Vec::with_capacity(BATCH_ROWS),
                since: None,
                sent: None,
                free: Vec::new(),
                failed,
                writer,
            },
            Err(_) => match slot
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .take()
            {
                Some(rows) => Sink::Here {
                    rows,
                    written: 0,
                    last_t: 0.0,
                    spare: RowData::default(),
                    summary_at: None,
                },
                None => Sink::Lost,
            },
        }
    }

    /// Hands one time's rows (`fill` copies them into a buffer) to the
    /// writer; the error of a failed write, also of an earlier row on the
    /// thread.
    fn push(
        &mut self,
        progress: &Arc<Mutex<Progress>>,
        fill: impl FnOnce(&mut RowData),
    ) -> Result<(), String> {
        match self {
            Sink::Thread {
                failed,
                batch,
                since,
                sent,
                free,
                ..
            } => {
                if let Some(e) = failed
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner)
                    .clone()
                {
                    return Err(e);
                }
                let mut d = free.pop().unwrap_or_default();
                fill(&mut d);
                batch.push(d);
                since.get_or_insert_with(Instant::now);
                let sparse = sent.is_none_or(|w| w.elapsed().as_secs_f64() >= BATCH_WAIT);
                if batch.len() >= BATCH_ROWS || sparse {
                    self.send()
                } else {
                    Ok(())
                }
            }
            Sink::Here {
                rows,
                written,
                last_t,
                spare,
                summary_at,
            } => {
                fill(spare);
                let mut p = Progress::lock(progress);
                rows.write(spare)?;
                p.count_row(spare.t, summary_at)?;
                *written += 1;
                *last_t = spare.t;
                Ok(())
            }
            Sink::Lost => Err("writing the rows failed unexpectedly".into()),
        }
    }

    /// Sends the batch if its first row has waited [`BATCH_WAIT`].
    fn send_if_due(&mut self) -> Result<(), String> {
        match self {
            Sink::Thread {
                since: Some(since), ..
            } if since.elapsed().as_secs_f64() >= BATCH_WAIT => self.send(),
            _ => Ok(()),
        }
    }

    /// Hands the batch to the writer thread (if it holds rows) and takes
    /// back the row buffers of the batches it has written.
    fn send(&mut self) -> Result<(), String> {
        let Sink::Thread {
            rows,
            spent,
            batch,
            since,
            sent,
            free,
            failed,
            ..
        } = self
        else {
            return Ok(());
        };
        *since = None;
        if batch.is_empty() {
            return Ok(());
        }
        *sent = Some(Instant::now());
        let mut next = match spent.try_recv() {
            Ok(mut done) => {
                free.append(&mut done);
                done
            }
            Err(_) => Vec::with_capacity(BATCH_ROWS),
        };
        std::mem::swap(batch, &mut next);
        // Fails only once the writer has stopped: at an error (set before
        // it stops) or a panic.
        rows.send(next).map_err(|_| {
            failed
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .clone()
                .unwrap_or_else(|| "writing the rows failed unexpectedly".into())
        })
    }

    /// Waits for the writer to write every row handed to it: the rows
    /// written, the last one's time \[s\], and the error it stopped at.
    fn finish(mut self) -> (Sink, usize, f64, Option<String>) {
        // An error here is the writer's, returned by its join below.
        let _ = self.send();
        match self {
            Sink::Thread { rows, writer, .. } => {
                // Closing the channel ends the writer's loop.
                drop(rows);
                match writer.join() {
                    Ok(Some((rows, written, last_t, error))) => (
                        Sink::Here {
                            rows,
                            written,
                            last_t,
                            spare: RowData::default(),
                            summary_at: None,
                        },
                        written,
                        last_t,
                        error,
                    ),
                    Ok(None) | Err(_) => (
                        Sink::Lost,
                        0,
                        0.0,
                        Some("writing the rows failed unexpectedly".into()),
                    ),
                }
            }
            Sink::Here {
                written, last_t, ..
            } => (self, written, last_t, None),
            Sink::Lost => (Sink::Lost, 0, 0.0, None),
        }
    }
}

/// Records, writes and keeps output rows as the integration produces them.
pub struct Streamer {
    recorder: Recorder,
    columns: Columns,
    sink: Sink,
    progress: Arc<Mutex<Progress>>,
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
        let columns = rows.columns();
        let sink = Sink::start(rows, &progress);
        Self {
            recorder: Recorder::with_sampling(model, sampling),
            columns,
            sink,
            progress,
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

    /// Waits until every row handed to the writer is written (call once
    /// the integration has ended): afterwards the rows written and the last
    /// time are the files', and a write error the writer stopped at is
    /// [`Streamer::error`].
    pub fn finish_rows(&mut self) {
        let sink = std::mem::replace(&mut self.sink, Sink::Lost);
        let (sink, written, last_t, error) = sink.finish();
        self.sink = sink;
        if let Some(e) = error {
            self.error.get_or_insert(e);
        }
        if written < self.next {
            // The rows after a failed write were computed, not written.
            (self.next, self.last_t) = (written, last_t);
        }
    }

    /// The file writer (for `trajectory.npz` at the end; after
    /// [`Streamer::finish_rows`]), unless it was lost.
    pub fn rows(&self) -> Option<&RowWriter> {
        match &self.sink {
            Sink::Here { rows, .. } => Some(rows),
            _ => None,
        }
    }

    /// The frames of the 3-D view kept from the rows written (after
    /// [`Streamer::finish_rows`]).
    pub fn take_view(&mut self) -> Option<softrod_viz::collect::FrameCollector> {
        match &mut self.sink {
            Sink::Here { rows, .. } => rows.take_view(),
            _ => None,
        }
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
        let columns = &self.columns;
        self.sink.push(&self.progress, |d| d.fill(columns, rec))?;
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
        // The writer counts the rows in `progress` as it writes them, under
        // its lock: the watchdog sees whole rows only.
        if let Err(e) = self.write_row(s) {
            self.error = Some(e.clone());
            return Err(e);
        }
        self.next += 1;
        self.last_t = t;
        if let Some(sig) = signals::received() {
            self.interrupted = Some(sig);
            Progress::lock(&self.progress).closing = true;
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
        // A row computed long ago reaches the files also while no new row
        // comes (a slow run); a failed write shows at the next row.
        let _ = self.sink.send_if_due();
        self.last_stats = *stats;
        Progress::lock(&self.progress).stats = *stats;
        if let Some(b) = &self.bar {
            b.set_position((t / self.duration * 1000.0) as u64);
            b.set_message(format!("{t:.4}"));
        }
    }
}
