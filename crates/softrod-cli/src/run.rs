//! `softrod run`: integrate, stream the trajectory, write shape, summary, plots.

use std::fs::File;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use softrod::dynamics::{Model, energies};
use softrod::integrate::Stats;
use softrod::{EnergyBalance, Error, Flow, Observer, Sample, output_times};
use softrod_scene::Scene;

use crate::common::{CliError, Poser, failed, load, out_dir, position, quaternion};
use crate::plots;

/// What is kept in memory for the plots.
#[derive(Default)]
pub struct Series {
    pub t: Vec<f64>,
    pub tip: Vec<[f64; 3]>,
    pub energy: Vec<[f64; 4]>,
    /// Snapshots: time and, per rod, the boundary positions.
    pub shapes: Vec<(f64, Vec<Vec<[f64; 3]>>)>,
}

/// Writes output rows as the integration produces them.
pub struct Streamer {
    traj: BufWriter<File>,
    shape: BufWriter<File>,
    expected: usize,
    next: usize,
    snapshot_at: Vec<usize>,
    poser: Poser,
    n: usize,
    pub series: Series,
    pub error: Option<String>,
    pub last_stats: Stats,
    pub last_t: f64,
    bar: Option<ProgressBar>,
    duration: f64,
}

fn create(path: &Path) -> Result<BufWriter<File>, CliError> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|e| failed(format!("cannot create {}: {e}", path.display())))
}

impl Streamer {
    pub fn new(
        dir: &Path,
        model: &Model,
        times: Vec<f64>,
        bar: Option<ProgressBar>,
    ) -> Result<Self, CliError> {
        let n = model.n_dof();
        let mut traj = create(&dir.join("trajectory.csv"))?;
        let mut header = String::from("t,tip_x,tip_y,tip_z,tip_qw,tip_qx,tip_qy,tip_qz,energy");
        for i in 0..n {
            header.push_str(&format!(",q{i}"));
        }
        let mut shape = create(&dir.join("shape.csv"))?;
        let io = |e: std::io::Error| failed(format!("writing outputs: {e}"));
        writeln!(traj, "{header}").map_err(io)?;
        traj.flush().map_err(io)?;
        writeln!(shape, "t,rod,s,x,y,z,qw,qx,qy,qz").map_err(io)?;
        let m = times.len();
        let snaps = 6.min(m);
        let mut snapshot_at: Vec<usize> = (0..snaps)
            .map(|k| {
                if snaps == 1 {
                    0
                } else {
                    k * (m - 1) / (snaps - 1)
                }
            })
            .collect();
        snapshot_at.dedup();
        Ok(Self {
            traj,
            shape,
            next: 0,
            snapshot_at,
            poser: Poser::new(model),
            n,
            series: Series::default(),
            error: None,
            last_stats: Stats::default(),
            last_t: 0.0,
            duration: times.last().copied().unwrap_or(0.0),
            expected: times.len(),
            bar,
        })
    }

    pub fn rows_written(&self) -> usize {
        self.next
    }

    pub fn rows_expected(&self) -> usize {
        self.expected
    }

    fn write_row(&mut self, s: Sample<'_>) -> Result<(), String> {
        let (t, q, qd, model) = (s.t, s.q, s.qd, s.model);
        let non_finite = |v: &[f64]| v.iter().position(|x| !x.is_finite());
        if let Some(i) = non_finite(q) {
            return Err(format!("non-finite q{i} at t = {t:e}; output stopped"));
        }
        if let Some(i) = non_finite(qd) {
            return Err(format!("non-finite qdot{i} at t = {t:e}; output stopped"));
        }
        debug_assert_eq!(q.len(), self.n);
        let e = energies(model, s.data, q, qd).map_err(|e| format!("energy at t = {t:e}: {e}"))?;
        if !e.total().is_finite() {
            return Err(format!("non-finite energy at t = {t:e}; output stopped"));
        }
        self.poser
            .update(model, q)
            .map_err(|e| format!("at t = {t:e}: {e}"))?;
        let tip = *self.poser.tip(0);
        let p = position(&tip);
        let qt = quaternion(&tip);
        if p.iter().chain(qt.iter()).any(|v| !v.is_finite()) {
            return Err(format!("non-finite tip pose at t = {t:e}; output stopped"));
        }
        let mut line = format!(
            "{t},{},{},{},{},{},{},{},{}",
            p[0],
            p[1],
            p[2],
            qt[0],
            qt[1],
            qt[2],
            qt[3],
            e.total()
        );
        for v in q {
            line.push(',');
            line.push_str(&v.to_string());
        }
        let io = |e: std::io::Error| format!("writing trajectory.csv: {e}");
        writeln!(self.traj, "{line}").map_err(io)?;
        self.traj.flush().map_err(io)?;
        let mut shape_rows = String::new();
        let mut snap = Vec::new();
        for (r, rm) in model.rods().iter().enumerate() {
            let rod = &rm.spec.rod;
            let mut pts = Vec::new();
            for (k, g) in self.poser.boundaries(r).iter().enumerate() {
                let s = if k == 0 {
                    0.0
                } else {
                    rod.pieces()[k - 1].end()
                };
                let p = position(g);
                let qq = quaternion(g);
                if p.iter().chain(qq.iter()).any(|v| !v.is_finite()) {
                    return Err(format!(
                        "non-finite pose of rod '{}' at s = {s} m, t = {t:e}; output stopped",
                        rm.spec.name
                    ));
                }
                shape_rows.push_str(&format!(
                    "{t},{},{s},{},{},{},{},{},{},{}\n",
                    rm.spec.name, p[0], p[1], p[2], qq[0], qq[1], qq[2], qq[3]
                ));
                pts.push(p);
            }
            snap.push(pts);
        }
        let io = |e: std::io::Error| format!("writing shape.csv: {e}");
        self.shape.write_all(shape_rows.as_bytes()).map_err(io)?;
        self.shape.flush().map_err(io)?;
        self.series.t.push(t);
        self.series.tip.push(p);
        self.series
            .energy
            .push([e.total(), e.kinetic, e.elastic, e.gravitational]);
        if self.snapshot_at.contains(&self.next) {
            self.series.shapes.push((t, snap));
        }
        Ok(())
    }
}

impl Observer for Streamer {
    /// One output row: the integrator's dense output at the next output time.
    fn sample(&mut self, s: Sample<'_>) -> Result<Flow, String> {
        let t = s.t;
        if let Err(e) = self.write_row(s) {
            self.error = Some(e.clone());
            return Err(e);
        }
        self.next += 1;
        self.last_t = t;
        Ok(Flow::Continue)
    }

    fn step(&mut self, t: f64, stats: &Stats) {
        self.last_stats = *stats;
        if let Some(b) = &self.bar {
            b.set_position((t / self.duration * 1000.0) as u64);
            b.set_message(format!("{t:.4}"));
        }
    }
}

/// The summary object.
#[allow(clippy::too_many_arguments)]
pub fn write_summary(
    dir: &Path,
    stats: &Stats,
    wall: f64,
    final_time: f64,
    status: &str,
    scene: &Scene,
    rows: usize,
    rows_expected: usize,
    watch: Option<(&EnergyBalance, &[String])>,
) -> Result<(), CliError> {
    let mut v = serde_json::json!({
        "steps": stats.steps,
        "rejected_steps": stats.rejected_steps,
        "rhs_evaluations": stats.rhs_evaluations,
        "wall_seconds": wall,
        "final_time": final_time,
        "status": status,
        "integrator": scene.run.integrator.name(),
        "jacobian_evaluations": stats.jacobian_evaluations,
        "factorizations": stats.factorizations,
        "duration": scene.run.duration,
        "output_rows": rows,
        "output_rows_expected": rows_expected,
        "n_dof": scene.n_dof(),
    });
    if let (Some((b, warnings)), Some(map)) = (watch, v.as_object_mut()) {
        // The energy balance of the run (docs/scene-format-extensions.md,
        // `[run] energy_tolerance`) and what the run's watch warned about.
        for (key, value) in [
            ("energy_error", b.error),
            ("energy_error_relative", b.relative),
            ("energy_scale", b.scale),
            ("energy_change", b.change),
            ("energy_work", b.work),
        ] {
            map.insert(key.into(), serde_json::json!(value));
        }
        map.insert("warnings".into(), serde_json::json!(warnings));
    }
    let path = dir.join("summary.json");
    let text = serde_json::to_string_pretty(&v).map_err(failed)?;
    std::fs::write(&path, text + "\n")
        .map_err(|e| failed(format!("cannot write {}: {e}", path.display())))
}

pub fn run(path: &Path, out: Option<PathBuf>, quiet: bool) -> Result<(), CliError> {
    let mut l = load(path)?;
    let dir = out_dir(path, out);
    std::fs::create_dir_all(&dir)
        .map_err(|e| failed(format!("cannot create {}: {e}", dir.display())))?;
    let scene = &l.scene;
    let duration = scene.run.duration;
    let times = output_times(duration, l.sim.settings().output_spacing(duration));
    // Written first so that an interrupted run leaves a summary that says so.
    write_summary(
        &dir,
        &Stats::default(),
        0.0,
        0.0,
        "error: did not finish (running, or interrupted)",
        scene,
        0,
        times.len(),
        None,
    )?;
    let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
        let b = ProgressBar::new(1000);
        if let Ok(style) = ProgressStyle::with_template(
            "{bar:40} {percent:>3}% t = {msg} s  [{elapsed_precise} < {eta}]",
        ) {
            b.set_style(style);
        }
        b
    });
    let mut streamer = Streamer::new(&dir, l.sim.model(), times, bar)?;
    let start = Instant::now();
    // Rows are the integrator's dense output at the output times, streamed
    // to the observer as the run proceeds; nothing is kept in between.
    let result = match l.sim.simulate_with(duration, &mut streamer) {
        // Refused before it started (too large for the machine): bad input.
        Err(e) if e.is_input() => return Err(e.into()),
        r => r,
    };
    if let Some(b) = &streamer.bar {
        b.finish_and_clear();
    }
    let wall = start.elapsed().as_secs_f64();
    let (status, stats, t_final) = match (&result, &streamer.error) {
        (_, Some(e)) => (format!("error: {e}"), streamer.last_stats, streamer.last_t),
        (Err(e), None) => (format!("error: {e}"), streamer.last_stats, streamer.last_t),
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
    if let (false, Some((_, warnings))) = (quiet, watch) {
        for w in warnings {
            eprintln!("softrod: warning: {w}");
        }
    }
    write_summary(
        &dir,
        &stats,
        wall,
        t_final,
        &status,
        scene,
        streamer.rows_written(),
        streamer.rows_expected(),
        watch,
    )?;
    // Plots of whatever was computed (also after a failure: they show where it went wrong).
    let plot_result = plots::all(&dir, &streamer.series, scene);
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
