//! `softrod run`: integrate, stream the trajectory, write shape, summary, plots.

use std::fs::File;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::DVector;
use softrod_dynamics::{Model, energies};
use softrod_integrate::{
    Control, Hooks, Method, Options, RodSystem, Stats, integrate_second_order,
};
use softrod_scene::{Integrator, Scene};

use crate::common::{CliError, Poser, failed, load, out_dir, position, quaternion};
use crate::plots;

/// High-frequency spectral radius used for `integrator = "generalized-alpha"`:
/// 0.9 damps the unresolved shear/extension modes a little while keeping the
/// resolved bending modes almost undamped (period error and damping of a mode
/// with ω·dt ≪ 1 are second order either way).
pub const GENERALIZED_ALPHA_RHO_INF: f64 = 0.9;

/// The Jacobian the stiff methods get: `−M⁻¹K`, `−M⁻¹D` only
/// (`RodJacobian::ElasticOnly`). Rosenbrock-W keeps its order with any
/// Jacobian, and on the undamped cantilever release it took the same steps
/// with the same accuracy as with the full finite-difference Jacobian at a
/// third of the cost (docs/performance.md, "softrod-integrate"); the
/// geometric stiffness of gravity, loads and cables is soft next to `K`.
pub fn stiff_jacobian() -> softrod_integrate::RodJacobian {
    softrod_integrate::RodJacobian::ElasticOnly
}

/// The integrator and its options for a scene's `[run]`.
pub fn method_and_options(scene: &Scene) -> Result<(Method, Options), CliError> {
    let run = &scene.run;
    let fixed_steps = (run.duration / run.dt).ceil() as usize;
    let (method, mut opts) = match run.integrator {
        Integrator::Rk4 => (Method::Rk4, Options::fixed(run.dt)),
        Integrator::GeneralizedAlpha => (
            Method::GeneralizedAlpha {
                rho_inf: GENERALIZED_ALPHA_RHO_INF,
            },
            Options {
                rtol: run.rtol,
                atol: run.atol,
                error_control: run.error_control,
                ..Options::fixed(run.dt)
            },
        ),
        Integrator::Dopri5 => (Method::Dopri5, Options::tol(run.rtol, run.atol)),
        Integrator::Rosenbrock => (Method::Rosw34, Options::tol(run.rtol, run.atol)),
    };
    if run.integrator == Integrator::GeneralizedAlpha && run.linearly_implicit {
        // One iteration with W = M⁻¹K, always accepted: the IMEX scheme of
        // `Options::linearly_implicit` (ρ∞ = GENERALIZED_ALPHA_RHO_INF < 1,
        // which its explicit remainder needs).
        opts.newton_tol = f64::INFINITY;
        opts.newton_max_iter = 1;
    }
    let gen_alpha_controlled = run.integrator == Integrator::GeneralizedAlpha && run.error_control;
    if run.integrator.is_adaptive() || gen_alpha_controlled {
        // The scene's dt is the initial step of adaptive methods.
        opts.dt = Some(run.dt.min(run.duration));
        opts.max_steps = 50_000_000;
    } else {
        opts.max_steps = 2 * fixed_steps + 100;
    }
    Ok((method, opts))
}

/// Output times `0, Δ, 2Δ, …` up to the duration, which is always included.
pub fn output_times(duration: f64, every: f64) -> Vec<f64> {
    let n = (duration / every + 1e-9).floor() as usize;
    let mut t: Vec<f64> = (0..=n).map(|k| (k as f64 * every).min(duration)).collect();
    if duration - t[t.len() - 1] > 1e-9 * duration {
        t.push(duration);
    } else {
        let last = t.len() - 1;
        t[last] = duration;
    }
    t.dedup();
    t
}

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
    times: Vec<f64>,
    next: usize,
    snapshot_at: Vec<usize>,
    poser: Poser,
    n: usize,
    pub series: Series,
    pub error: Option<String>,
    pub last_stats: Stats,
    pub last_t: f64,
}

fn create(path: &Path) -> Result<BufWriter<File>, CliError> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|e| failed(format!("cannot create {}: {e}", path.display())))
}

impl Streamer {
    pub fn new(dir: &Path, model: &Model, times: Vec<f64>) -> Result<Self, CliError> {
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
            times,
            next: 0,
            snapshot_at,
            poser: Poser::new(model),
            n,
            series: Series::default(),
            error: None,
            last_stats: Stats::default(),
            last_t: 0.0,
        })
    }

    pub fn rows_written(&self) -> usize {
        self.next
    }

    pub fn rows_expected(&self) -> usize {
        self.times.len()
    }

    /// The output times, in order.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// One output row at `(t, y)`, `y = (q, q̇)`: the integrator's dense
    /// output at the next output time, handed over by its output callback.
    pub fn output(&mut self, sys: &mut RodSystem, t: f64, y: &DVector<f64>) -> Result<(), String> {
        self.write_row(sys, t, y)?;
        self.next += 1;
        self.last_t = t;
        Ok(())
    }

    fn write_row(&mut self, sys: &mut RodSystem, t: f64, y: &DVector<f64>) -> Result<(), String> {
        let n = self.n;
        if let Some(i) = y.iter().position(|v| !v.is_finite()) {
            let what = if i < n {
                format!("q{i}")
            } else {
                format!("qdot{}", i - n)
            };
            return Err(format!("non-finite {what} at t = {t:e}; output stopped"));
        }
        let (q, qd) = (&y.as_slice()[..n], &y.as_slice()[n..]);
        let e = energies(&sys.model, &mut sys.data, q, qd)
            .map_err(|e| format!("energy at t = {t:e}: {e}"))?;
        if !e.total().is_finite() {
            return Err(format!("non-finite energy at t = {t:e}; output stopped"));
        }
        self.poser
            .update(&sys.model, q)
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
        for (r, rm) in sys.model.rods().iter().enumerate() {
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
) -> Result<(), CliError> {
    let v = serde_json::json!({
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
    let path = dir.join("summary.json");
    let text = serde_json::to_string_pretty(&v).map_err(failed)?;
    std::fs::write(&path, text + "\n")
        .map_err(|e| failed(format!("cannot write {}: {e}", path.display())))
}

pub fn run(path: &Path, out: Option<PathBuf>, quiet: bool) -> Result<(), CliError> {
    let l = load(path)?;
    let (method, mut opts) = method_and_options(&l.scene)?;
    let dir = out_dir(path, out);
    std::fs::create_dir_all(&dir)
        .map_err(|e| failed(format!("cannot create {}: {e}", dir.display())))?;
    let scene = &l.scene;
    let duration = scene.run.duration;
    let times = output_times(duration, scene.run.output_every);
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
    )?;
    let mut sys = RodSystem::new(l.built.model.clone());
    sys.jacobian = stiff_jacobian();
    let mut streamer = Streamer::new(&dir, &sys.model, times)?;
    let start = Instant::now();
    let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
        let b = ProgressBar::new(1000);
        if let Ok(style) = ProgressStyle::with_template(
            "{bar:40} {percent:>3}% t = {msg} s  [{elapsed_precise} < {eta}]",
        ) {
            b.set_style(style);
        }
        b
    });
    // Rows are the integrator's dense output at the output times, streamed
    // by its output callback as the run proceeds; the driver keeps none.
    opts.t_eval = Some(streamer.times().to_vec());
    let result = {
        let st = std::cell::RefCell::new(&mut streamer);
        let bar_ref = bar.as_ref();
        let hooks = Hooks::new()
            .stream_outputs(|t, y, sys: &mut RodSystem| {
                let mut st = st.borrow_mut();
                match st.output(sys, t, y) {
                    Ok(()) => Control::Continue,
                    Err(e) => {
                        st.error = Some(e);
                        Control::Stop
                    }
                }
            })
            .on_step(|info, _: &mut RodSystem| {
                st.borrow_mut().last_stats = *info.stats;
                if let Some(b) = bar_ref {
                    b.set_position((info.t / duration * 1000.0) as u64);
                    b.set_message(format!("{:.4}", info.t));
                }
                Control::Continue
            });
        integrate_second_order(
            &mut sys,
            method,
            0.0,
            duration,
            &l.built.q0,
            &l.built.qd0,
            &opts,
            hooks,
        )
    };
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let wall = start.elapsed().as_secs_f64();
    let (status, stats, t_final) = match (&result, &streamer.error) {
        (_, Some(e)) => (format!("error: {e}"), streamer.last_stats, streamer.last_t),
        (Err(e), None) => (format!("error: {e}"), streamer.last_stats, streamer.last_t),
        (Ok(sol), None) => {
            if streamer.rows_written() < streamer.rows_expected() {
                streamer.error = Some(format!(
                    "integration ended at t = {} before the last output time",
                    sol.t_final
                ));
            }
            match &streamer.error {
                Some(e) => (format!("error: {e}"), sol.stats, sol.t_final),
                None => ("ok".to_string(), sol.stats, sol.t_final),
            }
        }
    };
    write_summary(
        &dir,
        &stats,
        wall,
        t_final,
        &status,
        scene,
        streamer.rows_written(),
        streamer.rows_expected(),
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

#[cfg(test)]
mod tests {
    use super::{method_and_options, output_times};
    use softrod_scene::Scene;

    /// `[run] error_control` reaches the integrator options of
    /// generalized-alpha, with `dt` as the first step and an adaptive step
    /// budget; without it generalized-alpha keeps its fixed step.
    #[test]
    fn generalized_alpha_error_control_is_wired_through() {
        let scene = |extra: &str| {
            let text = format!(
                "[[rod]]\nname = \"r\"\nlength = 0.4\npieces = 2\n\
                 section = {{ shape = \"circle\", radius = 0.01 }}\n\
                 material = {{ density = 1200, young = 2e6, poisson = 0.45 }}\n\
                 [run]\nintegrator = \"generalized-alpha\"\ndt = 1e-3\nrtol = 1e-4\n{extra}\n"
            );
            Scene::from_str(&text, "t.toml").unwrap().0
        };
        let (_, o) = method_and_options(&scene("error_control = true")).unwrap();
        assert!(o.error_control);
        assert_eq!((o.dt, o.rtol), (Some(1e-3), 1e-4));
        assert!(o.max_steps > 1_000_000);
        let (_, o) = method_and_options(&scene("")).unwrap();
        assert!(!o.error_control);
        assert_eq!(o.max_steps, 2 * 1000 + 100);
        assert!(o.newton_max_iter > 1);
        // linearly_implicit = the options of `Options::linearly_implicit`.
        let (_, o) = method_and_options(&scene("linearly_implicit = true")).unwrap();
        let li = softrod_integrate::Options::linearly_implicit(1e-3);
        assert_eq!(
            (o.newton_max_iter, o.newton_tol),
            (li.newton_max_iter, li.newton_tol)
        );
        assert_eq!(o.dt, Some(1e-3));
    }

    #[test]
    fn output_times_include_both_ends() {
        let t = output_times(1.0, 0.25);
        assert_eq!(t, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        let t = output_times(1.0, 0.3);
        assert_eq!(t.len(), 5);
        assert_eq!(*t.last().unwrap(), 1.0);
        let t = output_times(1.0, 1e-3);
        assert_eq!(t.len(), 1001);
        assert_eq!(*t.last().unwrap(), 1.0);
    }
}
