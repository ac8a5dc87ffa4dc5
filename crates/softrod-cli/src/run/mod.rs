//! `softrod run`: integrate, stream the trajectory, write shape, summary,
//! plots. What each row holds is recorded by the facade
//! (`softrod::record`); this module formats and writes it:
//! [`rows`] the CSV files and the NumPy archive, [`summary`] summary.json,
//! [`stream`] the observer that ties them to the run.

mod rows;
mod stream;
mod summary;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use softrod::integrate::Stats;
use softrod::record::{CLOSURE_WARN_RELATIVE, Columns, RodSampling, closure_length_scale};
use softrod::{Error, output_times};

use crate::common::{CliError, failed, load, out_dir};
use crate::{npz, outputs, plots, signals};
use rows::RowWriter;
use stream::{Progress, Streamer, chosen_rows};
use summary::Summary;

/// The scene's file stem: the title of figures and view.
pub fn scene_title(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
}

pub fn run(
    path: &Path,
    out: Option<PathBuf>,
    snapshots: Option<Vec<f64>>,
    quiet: bool,
    npz_out: bool,
    png: bool,
) -> Result<(), CliError> {
    let mut l = load(path)?;
    let dir = out_dir(path, out);
    let scene = &l.scene;
    let duration = scene.run.duration;
    let every = l.sim.settings().output_spacing(duration);
    let initial_contacts = if l.sim.model().has_contact() {
        let (q0, qd0) = l.sim.initial_state();
        l.sim
            .model()
            .contacts(0.0, q0.as_slice(), qd0.as_slice())
            .map_or(0, |c| c.len())
    } else {
        0
    };
    // What can be refused without the directory is, before it exists: the
    // run's own admission (step budget, sizes) first, as `check` does.
    l.sim.check_run(duration)?;
    let times = output_times(duration, every);
    if npz_out {
        let width = Columns::of(l.sim.model()).width();
        npz::check_size(times.len() as u64, width).map_err(CliError::Input)?;
    }
    let snapshot_at = chosen_rows(&times, snapshots.as_deref())?;
    let sampling = RodSampling::of_model(l.sim.model(), scene.run.shape_points_per_piece);
    let per_row = outputs::output_bytes_per_row(
        l.sim.model(),
        sampling.iter().map(|s| s.s.len()).sum(),
        initial_contacts,
        npz_out,
    );
    // A directory that cannot be created is said so (not "0.0 MB free");
    // one created here and then refused is removed again.
    let existed = dir.exists();
    outputs::prepare_out_dir(&dir)?;
    if let Err(e) = outputs::check_disk_space(&dir, duration, every, per_row) {
        if !existed {
            let _ = std::fs::remove_dir(&dir);
        }
        return Err(e);
    }
    let stale = outputs::clear_stale(&dir)?;
    if !quiet && !stale.is_empty() {
        eprintln!(
            "softrod: removed the previous run's outputs from {}: {}",
            dir.display(),
            stale.join(", ")
        );
    }
    // Written first so that a run that never gets to its first row leaves
    // a summary that says so.
    let summary = Summary::new(
        &dir,
        scene,
        (l.sim.q_names(), l.sim.prescribed_names()),
        times.len(),
    );
    summary
        .write(&Stats::default(), 0.0, 0.0, "running", 0)
        .map_err(|e| CliError::Input(e.to_string()))?;
    let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
        let b = ProgressBar::new(1000);
        if let Ok(style) = ProgressStyle::with_template(
            "{bar:40} {percent:>3}% t = {msg} s  [{elapsed_precise} < {eta}]",
        ) {
            b.set_style(style);
        }
        b
    });
    let mut summary_final = Summary::new(
        &dir,
        scene,
        (l.sim.q_names(), l.sim.prescribed_names()),
        times.len(),
    );
    let rows = RowWriter::create(&dir, l.sim.model(), npz_out)?;
    let start = Instant::now();
    let progress = Arc::new(Mutex::new(Progress {
        summary,
        rows: 0,
        expected: times.len(),
        t: 0.0,
        stats: Stats::default(),
        start,
        closing: false,
        finished: None,
    }));
    let mut streamer = Streamer::new(
        l.sim.model(),
        &times,
        sampling,
        rows,
        snapshot_at,
        Arc::clone(&progress),
        bar,
    );
    signals::install();
    {
        // A signal that a long step keeps the run from seeing (one dense
        // factorization can take minutes) still ends it within GRACE.
        let (progress, dir) = (Arc::clone(&progress), dir.clone());
        signals::watchdog(move |sig| {
            let p = Progress::lock(&progress);
            let status = p.expire(sig);
            eprintln!(
                "softrod: simulation failed: {} (outputs up to t = {} in {})",
                status.trim_start_matches("error: "),
                p.t,
                dir.display()
            );
            // The lock stays held: the main thread writes nothing more.
            std::mem::forget(p);
        });
    }
    // Rows are the integrator's dense output at the output times, streamed
    // to the observer as the run proceeds; nothing is kept in between.
    let result = match l.sim.simulate_with(duration, &mut streamer) {
        // Refused before it started (too large for the machine): bad input,
        // and the summary says so rather than "running".
        Err(e) if e.is_input() => {
            let _ = summary_final.write(&Stats::default(), 0.0, 0.0, &format!("refused: {e}"), 0);
            return Err(e.into());
        }
        r => r,
    };
    Progress::lock(&progress).closing = true;
    streamer.finish_rows();
    if let Some(b) = &streamer.bar {
        b.finish_and_clear();
    }
    let wall = start.elapsed().as_secs_f64();
    let (mut status, stats, t_final) = match (&result, &streamer.error) {
        (_, None) if streamer.interrupted.is_some() => (
            format!(
                "error: interrupted by {} at t = {} ({} of {} output rows written)",
                streamer.interrupted.unwrap_or("a signal"),
                streamer.last_t,
                streamer.rows_written(),
                streamer.rows_expected()
            ),
            result.as_ref().map_or(streamer.last_stats, |s| s.stats),
            streamer.last_t,
        ),
        (_, Some(e)) => (format!("error: {e}"), streamer.last_stats, streamer.last_t),
        (Err(e), None) => (
            format!("error: {}", e.report()),
            streamer.last_stats,
            streamer.last_t,
        ),
        (Ok(sum), None) => {
            if streamer.rows_written() < streamer.rows_expected() {
                streamer.error = Some(format!(
                    "integration ended at t = {} before the last output time",
                    sum.t_final
                ));
            }
            match &streamer.error {
                Some(e) => (format!("error: {e}"), sum.stats, sum.t_final),
                None => ("ok".to_string(), sum.stats, sum.t_final),
            }
        }
    };
    let watch = match &result {
        Ok(sum) => sum.energy.as_ref().map(|b| (b, sum.warnings.as_slice())),
        Err(Error::EnergyBalance { balance, .. }) => Some((&**balance, &[][..])),
        Err(_) => None,
    };
    if let Some((b, warnings)) = watch {
        summary_final.add_watch(b, warnings);
        if !quiet {
            for w in warnings {
                eprintln!("softrod: warning: {w}");
            }
        }
    }
    if l.sim.model().has_contact() {
        summary_final.add_contact(streamer.max_penetration(), streamer.max_contacts());
        // Beyond the stated bound (CT3) the run goes on (it fails only at
        // 15 % of the radius, CT15), but never silently.
        if let Some(w) = streamer.penetration_warning(l.sim.model()) {
            if !quiet {
                eprintln!("softrod: warning: {w}");
            }
            summary_final.add_warning(w);
        }
    }
    if l.sim.model().has_closures() {
        let r = streamer.closure_residual_max();
        summary_final.add_closures(r);
        let warn = CLOSURE_WARN_RELATIVE * closure_length_scale(l.sim.model());
        if !quiet && r > warn {
            eprintln!(
                "softrod: warning: the largest closure residual {r:.3e} m exceeds {warn:.3e} m \
                 ({CLOSURE_WARN_RELATIVE:e} of the longest rod): tighten rtol/atol or dt"
            );
        }
    }
    // The archive holds the rows the CSV holds, also after a failure; if it
    // cannot be written it is removed, and the run says so.
    if let Err(e) = streamer.rows().map_or(Ok(()), |rows| {
        rows.write_npz(&dir, &l.sim.q_names(), &l.sim.prescribed_names())
    }) {
        status = if status == "ok" {
            format!("error: {e}")
        } else {
            format!("{status}; {e}")
        };
    }
    summary_final.write(&stats, wall, t_final, &status, streamer.rows_written())?;
    {
        let mut p = Progress::lock(&progress);
        (p.stats, p.t) = (stats, t_final);
        p.finished = Some((summary_final.clone(), status.clone()));
    }
    // Plots and view of whatever was computed (also after a failure: they
    // show where it went wrong).
    let title = scene_title(path);
    let model = l.sim.model();
    let frames = streamer.take_view().filter(|_| streamer.rows_written() > 0);
    let series = streamer.finish_series();
    // The 3-D view and the figures are independent files from the same
    // rows: drawn side by side, the process ends when the longer is done
    // (their bytes are those of one after the other).
    let plot_result = std::thread::scope(|scope| {
        let view = scope.spawn(|| match frames {
            Some(frames) => outputs::write_view(&dir, model, &title, frames).map(|_| ()),
            None => Ok(()),
        });
        let figures = plots::run_figures(&dir, series, model, &title).and_then(|names| {
            if png {
                plots::rasterize(&dir, &names, quiet)
            } else {
                Ok(())
            }
        });
        let view = view
            .join()
            .unwrap_or_else(|_| Err(failed("writing the 3-D view failed unexpectedly")));
        figures.and(view)
    });
    if status != "ok" {
        return Err(failed(format!(
            "simulation failed: {} (outputs up to t = {} in {})",
            status.trim_start_matches("error: "),
            streamer.series.t.last().copied().unwrap_or(0.0),
            dir.display()
        )));
    }
    plot_result?;
    if !quiet {
        eprintln!(
            "softrod: {} s simulated in {:.3} s wall: {} steps ({} rejected), {} rhs evaluations; wrote {}",
            t_final,
            wall,
            stats.steps,
            stats.rejected_steps,
            stats.rhs_evaluations,
            dir.display()
        );
    }
    Ok(())
}

/// `softrod view DIR`: rebuilds `DIR/view.html` and prints its path.
pub fn view(dir: &Path, quiet: bool) -> Result<(), CliError> {
    if !dir.join(softrod_viz::run_dir::SHAPE_CSV).is_file() {
        return Err(CliError::Input(format!(
            "{}: not a run directory (no {}; write one with `softrod run SCENE --out DIR`)",
            dir.display(),
            softrod_viz::run_dir::SHAPE_CSV
        )));
    }
    let stats = softrod_viz::run_dir::write_view(dir, &softrod_viz::ViewOptions::default())
        .map_err(|e| CliError::Input(format!("{}: {}", dir.display(), softrod::report(&e))))?
        .1;
    let page = dir.join(softrod_viz::run_dir::VIEW_HTML);
    println!("{}", page.display());
    if !quiet {
        eprintln!(
            "softrod: {} frames of {} output times, {} bytes; open it in a browser",
            stats.frames.len(),
            stats.source_frames,
            stats.bytes
        );
    }
    Ok(())
}
