//! `softrod report`: work–precision of a scene over pieces, quadrature,
//! integrators and tolerances (or steps), with the spatial (PCS pieces) and
//! temporal (integrator) error sources measured separately.
//!
//! Dynamics scenes:
//!
//! - **spatial study**: pieces ×{1, 2, 4} of the scene's, quadrature
//!   {2, 4, 6}, each at a tight tolerance, against a finer reference
//!   (pieces ×8, quadrature 6, same tight integrator);
//! - **temporal study**: the scene's pieces and quadrature; dopri5 and
//!   rosenbrock and esdirk over tolerances, generalized-α over steps, against the
//!   reference integrator at the same pieces;
//! - an analytic `[reference] tip` (at `[reference] time`, default the end) is
//!   compared with every run as well.
//!
//! Statics scenes sweep pieces and quadrature against `[reference] tip`, or
//! against pieces ×8, quadrature 6 when the scene has none.
//!
//! Errors are distances of the first rod's tip: at the final time and the
//! largest over evenly spaced comparison times. Wall time is the median of
//! the repeats (3, or 1 with `--quick`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use plotters::prelude::*;
use softrod_dynamics::{Data, StaticsOptions, statics};
use softrod_integrate::{
    Control, Hooks, Method, Options, RodSystem, Stats, Status, integrate_second_order,
};
use softrod_scene::{Built, Integrator, Mode, Scene};

use crate::common::{CliError, Poser, failed, load, out_dir};
use softrod::GENERALIZED_ALPHA_RHO_INF;

/// Comparison intervals over the run (N_COMPARE + 1 times, both ends included).
const N_COMPARE: usize = 50;

/// How `softrod report` runs.
#[derive(Clone, Copy, Debug)]
pub struct ReportOptions {
    /// One repeat instead of three, and smaller time budgets.
    pub quick: bool,
    /// No progress messages, no table on stdout.
    pub quiet: bool,
}

/// One run's result.
struct Outcome {
    /// Tip of the first rod at the comparison times.
    tips: Vec<[f64; 3]>,
    stats: Stats,
    /// Median wall seconds over the repeats.
    wall: f64,
}

/// A tight integrator setting and its description.
#[derive(Clone)]
struct Tight {
    method: Method,
    opts: Options,
    text: String,
}

fn dist(p: &[f64; 3], q: &[f64; 3]) -> f64 {
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter().zip(b).map(|(p, q)| dist(p, q)).fold(0.0, f64::max)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// One integration, stopped (as a failure) when it exceeds `budget` wall s.
fn simulate_once(
    built: &Built,
    method: Method,
    opts: &Options,
    times: &[f64],
    budget: f64,
) -> Result<Outcome, String> {
    let mut sys = RodSystem::new(built.model.clone());
    // Each method with the Jacobian `softrod run` gives it.
    let integrator = match method {
        Method::Esdirk46 => Integrator::Esdirk,
        Method::Radau5 => Integrator::Radau5,
        _ => Integrator::Rosenbrock,
    };
    sys.jacobian = softrod::Settings::default()
        .with_integrator(integrator)
        .stiff_jacobian();
    let t1 = *times.last().expect("times");
    let opts = Options {
        t_eval: Some(times.to_vec()),
        max_steps: opts.max_steps.max(50_000_000),
        ..opts.clone()
    };
    let start = Instant::now();
    let hooks = Hooks::new().on_step(move |_, _: &mut RodSystem| {
        if start.elapsed().as_secs_f64() > budget {
            Control::Stop
        } else {
            Control::Continue
        }
    });
    let sol = integrate_second_order(
        &mut sys, method, 0.0, t1, &built.q0, &built.qd0, &opts, hooks,
    )
    .map_err(|e| e.to_string())?;
    let wall = start.elapsed().as_secs_f64();
    if sol.status == Status::Stopped {
        return Err(format!(
            "stopped at t = {:.3e} s: over the time budget of {budget} s ({} steps)",
            sol.t_final, sol.stats.steps
        ));
    }
    let n = sys.model.n_dof();
    let mut poser = Poser::new(&sys.model);
    let mut tips = Vec::with_capacity(sol.y.len());
    for y in &sol.y {
        poser
            .update(&sys.model, &y.as_slice()[..n])
            .map_err(|e| e.to_string())?;
        let p = poser.tip(0).translation;
        tips.push([p[0], p[1], p[2]]);
    }
    if tips.len() != times.len() {
        return Err(format!(
            "run ended at t = {} before the last comparison time",
            sol.t_final
        ));
    }
    Ok(Outcome {
        tips,
        stats: sol.stats,
        wall,
    })
}

/// `repeats` integrations; the median wall time (a failure is not repeated).
fn simulate(
    built: &Built,
    method: Method,
    opts: &Options,
    times: &[f64],
    budget: f64,
    repeats: usize,
) -> Result<Outcome, String> {
    let first = simulate_once(built, method, opts, times, budget)?;
    let mut walls = vec![first.wall];
    for _ in 1..repeats {
        walls.push(simulate_once(built, method, opts, times, budget)?.wall);
    }
    Ok(Outcome {
        wall: median(walls),
        ..first
    })
}

/// The scene with every piece cut in `k` equal parts (same strains,
/// `[initial]` values repeated) and `quadrature` Gauss points per piece.
fn variant(scene: &Scene, k: usize, quadrature: usize) -> Result<Scene, CliError> {
    let mut s = scene.clone();
    s.run.quadrature = quadrature;
    if k == 1 {
        return Ok(s);
    }
    for r in &mut s.rods {
        r.rod = r
            .rod
            .subdivided(k)
            .map_err(|e| failed(format!("pieces x{k}: {e}")))?;
    }
    let dup = |v: &Vec<f64>| -> Vec<f64> {
        let mut out = Vec::with_capacity(k * v.len());
        let mut off = 0;
        for r in &scene.rods {
            let c = r.rod.pieces()[0].basis.dof();
            for _ in 0..r.rod.n_pieces() {
                for _ in 0..k {
                    out.extend_from_slice(&v[off..off + c]);
                }
                off += c;
            }
        }
        out
    };
    s.initial.q = scene.initial.q.as_ref().map(dup);
    s.initial.qdot = scene.initial.qdot.as_ref().map(dup);
    Ok(s)
}

fn build_variant(scene: &Scene, k: usize, quadrature: usize) -> Result<Built, CliError> {
    variant(scene, k, quadrature)?
        .build()
        .map_err(|e| failed(format!("pieces x{k}, quadrature {quadrature}: {e}")))
}

fn pieces(scene: &Scene) -> usize {
    scene.rods.iter().map(|r| r.rod.n_pieces()).sum()
}

/// A row of a study.
struct Row {
    study: &'static str,
    integrator: String,
    setting: String,
    pieces: usize,
    quadrature: usize,
    result: Result<Outcome, String>,
    err_final: f64,
    err_max: f64,
    err_analytic: Option<f64>,
    pareto: bool,
}

impl Row {
    fn name(&self) -> String {
        format!(
            "{} {} | pieces {} | quadrature {}",
            self.integrator, self.setting, self.pieces, self.quadrature
        )
    }
}

/// Marks the rows on the wall–error Pareto front (no other row is both
/// faster and more accurate), by `err_max`.
fn mark_pareto(rows: &mut [Row]) {
    let mut idx: Vec<usize> = (0..rows.len())
        .filter(|&i| rows[i].result.is_ok() && rows[i].err_max.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        let (wa, wb) = (wall(&rows[a]), wall(&rows[b]));
        wa.total_cmp(&wb)
            .then(rows[a].err_max.total_cmp(&rows[b].err_max))
    });
    let mut best = f64::INFINITY;
    for i in idx {
        if rows[i].err_max < best {
            best = rows[i].err_max;
            rows[i].pareto = true;
        }
    }
}

fn wall(r: &Row) -> f64 {
    r.result.as_ref().map_or(f64::NAN, |o| o.wall)
}

fn sci(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3e}")
    } else {
        String::new()
    }
}

fn md_table(rows: &[Row], analytic: bool) -> String {
    let mut md = String::from(
        "| integrator | setting | pieces | quadrature | wall s | error final m | error max m |",
    );
    if analytic {
        md.push_str(" error vs analytic m |");
    }
    md.push_str(" steps | rhs evaluations | Pareto | status |\n|---|---|---|---|---|---|---|");
    if analytic {
        md.push_str("---|");
    }
    md.push_str("---|---|---|---|\n");
    for r in rows {
        let _ = write!(
            md,
            "| {} | {} | {} | {} |",
            r.integrator, r.setting, r.pieces, r.quadrature
        );
        match &r.result {
            Ok(o) => {
                let _ = write!(
                    md,
                    " {:.4} | {} | {} |",
                    o.wall,
                    sci(r.err_final),
                    sci(r.err_max)
                );
                if analytic {
                    let _ = write!(md, " {} |", r.err_analytic.map_or(String::new(), sci));
                }
                let _ = writeln!(
                    md,
                    " {} | {} | {} | ok |",
                    o.stats.steps,
                    o.stats.rhs_evaluations,
                    if r.pareto { "★" } else { "" }
                );
            }
            Err(e) => {
                md.push_str(" | | |");
                if analytic {
                    md.push_str(" |");
                }
                let _ = writeln!(md, " | | | failed: {} |", e.replace('|', "/"));
            }
        }
    }
    md
}

fn csv_rows(csv: &mut String, rows: &[Row]) {
    for r in rows {
        let mut f: Vec<String> = vec![
            r.name(),
            r.study.to_string(),
            r.integrator.to_string(),
            r.setting.to_string(),
            r.pieces.to_string(),
            r.quadrature.to_string(),
        ];
        match &r.result {
            Ok(o) => f.extend([
                o.wall.to_string(),
                format!("{:e}", r.err_final),
                format!("{:e}", r.err_max),
                r.err_analytic.map_or(String::new(), |e| format!("{e:e}")),
                o.stats.steps.to_string(),
                o.stats.rejected_steps.to_string(),
                o.stats.rhs_evaluations.to_string(),
                r.pareto.to_string(),
                "ok".into(),
            ]),
            Err(e) => {
                f.extend(std::iter::repeat_n(String::new(), 7));
                f.extend(["false".into(), format!("failed: {e}")]);
            }
        }
        csv.push_str(&crate::outputs::csv_line(&f));
    }
}

const CSV_HEADER: &str = "configuration,study,integrator,setting,pieces,quadrature,wall_seconds,error_final_m,error_max_m,error_analytic_m,steps,rejected_steps,rhs_evaluations,pareto,status\n";

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Log-log error against wall time, one curve per group (`key`), the
/// Pareto front as a dashed black line with ringed points.
fn work_precision_svg(
    path: &Path,
    title: &str,
    rows: &[Row],
    key: impl Fn(&Row) -> String,
) -> Result<(), CliError> {
    type Res = Result<(), Box<dyn std::error::Error>>;
    let pts: Vec<(String, f64, f64, bool)> = rows
        .iter()
        .filter_map(|r| {
            let w = wall(r);
            (r.result.is_ok() && w > 0.0 && r.err_max > 0.0 && r.err_max.is_finite())
                .then(|| (key(r), w, r.err_max, r.pareto))
        })
        .collect();
    let r: Res = (|| {
        let root = SVGBackend::new(path, (1000, 650)).into_drawing_area();
        root.fill(&WHITE)?;
        let (mut wlo, mut whi, mut elo, mut ehi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
        for (_, w, e, _) in &pts {
            wlo = wlo.min(*w);
            whi = whi.max(*w);
            elo = elo.min(*e);
            ehi = ehi.max(*e);
        }
        if pts.is_empty() {
            (wlo, whi, elo, ehi) = (1e-3, 1.0, 1e-12, 1.0);
        }
        let mut c = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(90)
            .build_cartesian_2d(
                (wlo / 1.5..whi * 1.5).log_scale(),
                (elo / 3.0..ehi * 3.0).log_scale(),
            )?;
        c.configure_mesh()
            .x_desc("wall time [s] (median of repeats)")
            .y_desc("max tip error over the run [m]")
            // Powers of ten come out of the log axis as 9.999…e-5: round.
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .x_label_formatter(&|v| format!("{v:.2}"))
            .draw()?;
        let mut groups: Vec<String> = Vec::new();
        for (g, ..) in &pts {
            if !groups.contains(g) {
                groups.push(g.clone());
            }
        }
        for (k, g) in groups.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            let mut p: Vec<(f64, f64)> = pts
                .iter()
                .filter(|(h, ..)| h == g)
                .map(|(_, w, e, _)| (*w, *e))
                .collect();
            p.sort_by(|a, b| b.1.total_cmp(&a.1));
            c.draw_series(LineSeries::new(p.clone(), color.stroke_width(2)))?
                .label(g.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            c.draw_series(p.iter().map(|&q| Circle::new(q, 4, color.filled())))?;
        }
        let mut front: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.3)
            .map(|(_, w, e, _)| (*w, *e))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        if !front.is_empty() {
            // A staircase: below and left of it nothing was measured.
            let mut stair = Vec::new();
            for (i, &(w, e)) in front.iter().enumerate() {
                if i > 0 {
                    stair.push((w, front[i - 1].1));
                }
                stair.push((w, e));
            }
            c.draw_series(DashedLineSeries::new(stair, 6, 4, BLACK.stroke_width(1)))?
                .label("Pareto front")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
            c.draw_series(
                front
                    .iter()
                    .map(|&q| Circle::new(q, 8, BLACK.stroke_width(2))),
            )?;
        }
        c.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
        root.present()?;
        Ok(())
    })();
    r.map_err(|e| failed(format!("plot {}: {e}", path.display())))
}

fn write(dir: &Path, name: &str, text: &str) -> Result<(), CliError> {
    let p = dir.join(name);
    std::fs::write(&p, text).map_err(|e| failed(format!("cannot write {}: {e}", p.display())))
}

pub fn report(path: &Path, out: Option<PathBuf>, o: ReportOptions) -> Result<(), CliError> {
    let l = load(path)?;
    let dir = out_dir(path, out);
    std::fs::create_dir_all(&dir)
        .map_err(|e| failed(format!("cannot create {}: {e}", dir.display())))?;
    let md = match l.scene.run.mode {
        Mode::Statics => statics_report(&l.scene, &dir, o)?,
        Mode::Dynamics => dynamics_report(&l.scene, &dir, o)?,
    };
    write(&dir, "report.md", &md)?;
    if !o.quiet {
        print!("{md}");
    }
    Ok(())
}

/// The command that regenerates a report (stated in it).
fn command(scene: &Scene, o: ReportOptions) -> String {
    format!(
        "softrod report {}{}",
        scene.source,
        if o.quick { " --quick" } else { "" }
    )
}

fn dynamics_report(scene: &Scene, dir: &Path, o: ReportOptions) -> Result<String, CliError> {
    let say = |m: String| {
        if !o.quiet {
            eprintln!("softrod report: {m}");
        }
    };
    let repeats = if o.quick { 1 } else { 3 };
    let budget = if o.quick { 10.0 } else { 60.0 };
    let ref_budget = if o.quick { 120.0 } else { 300.0 };
    let d = scene.run.duration;
    let mut times: Vec<f64> = (0..=N_COMPARE)
        .map(|k| d * k as f64 / N_COMPARE as f64)
        .collect();
    // The analytic reference, if any, at its time.
    let analytic = scene
        .reference
        .as_ref()
        .filter(|r| r.rod_index == 0)
        .and_then(|r| r.tip.map(|tip| (tip, r.time.unwrap_or(d), r.note.clone())));
    let t_analytic =
        analytic.as_ref().map(
            |a| match times.iter().position(|t| (t - a.1).abs() <= 1e-12 * d) {
                Some(i) => i,
                None => {
                    times.push(a.1);
                    times.sort_by(f64::total_cmp);
                    times.iter().position(|t| *t == a.1).expect("inserted")
                }
            },
        );
    let last = times.len() - 1;
    let q0 = scene.run.quadrature;
    let n0 = pieces(scene);

    // Reference integrator: dopri5 at rtol 1e-9 if it finishes within the
    // budget (non-stiff scenes), else rosenbrock at rtol 1e-8.
    let tights = [
        Tight {
            method: Method::Dopri5,
            opts: Options::tol(1e-9, 1e-12),
            text: "dopri5, rtol 1e-9, atol 1e-12".into(),
        },
        Tight {
            method: Method::Rosw34,
            opts: Options::tol(1e-8, 1e-11),
            text: "rosenbrock (ROS34PW2), rtol 1e-8, atol 1e-11".into(),
        },
    ];
    let base = build_variant(scene, 1, q0)?;
    // Temporal study: the scene's pieces and quadrature (errors below, once
    // the reference is known).
    let mut configs: Vec<(&str, String, Method, Options)> = Vec::new();
    for rtol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
        configs.push((
            "dopri5",
            format!("rtol {rtol:e}"),
            Method::Dopri5,
            Options::tol(rtol, rtol * 1e-3),
        ));
    }
    for rtol in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7] {
        configs.push((
            "rosenbrock",
            format!("rtol {rtol:e}"),
            Method::Rosw34,
            Options::tol(rtol, rtol * 1e-3),
        ));
    }
    for rtol in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
        configs.push((
            "esdirk",
            format!("rtol {rtol:e}"),
            Method::Esdirk46,
            Options::tol(rtol, rtol * 1e-3),
        ));
    }
    for div in [100.0, 300.0, 1000.0, 3000.0, 10000.0] {
        let dt = d / div;
        configs.push((
            "generalized-alpha",
            format!("dt {dt:.3e}"),
            Method::GeneralizedAlpha {
                rho_inf: GENERALIZED_ALPHA_RHO_INF,
            },
            Options::fixed(dt),
        ));
    }
    let mut temporal = Vec::new();
    // Configurations of one integrator go from cheap to expensive: once one is
    // over the time budget, the tighter ones are skipped.
    let mut over: Vec<&str> = Vec::new();
    for (name, setting, method, opts) in configs {
        let res = if over.contains(&name) {
            Err("skipped: a looser setting of this integrator was over the time budget".to_string())
        } else {
            say(format!("temporal: {name} {setting}"));
            simulate(&base, method, &opts, &times, budget, repeats)
        };
        if matches!(&res, Err(e) if e.contains("time budget")) && !over.contains(&name) {
            over.push(name);
        }
        temporal.push(Row {
            study: "temporal",
            integrator: name.into(),
            setting,
            pieces: n0,
            quadrature: q0,
            result: res,
            err_final: f64::NAN,
            err_max: f64::NAN,
            err_analytic: None,
            pareto: false,
        });
    }
    // The reference integrator: the one whose tightest sweep setting finished
    // (dopri5 first: it is the more accurate at tight tolerances).
    let finished = |name: &str| {
        temporal
            .iter()
            .rev()
            .find(|r| r.integrator == name)
            .is_some_and(|r| r.result.is_ok())
    };
    let mut tights = tights.to_vec();
    if !finished("dopri5") && finished("rosenbrock") {
        tights.reverse();
    }
    let mut chosen = None;
    let mut notes = Vec::new();
    for t in &tights {
        say(format!(
            "temporal reference: {} at the scene's {n0} pieces, quadrature {q0}",
            t.text
        ));
        match simulate(&base, t.method, &t.opts, &times, ref_budget / 2.0, 1) {
            Ok(out) => {
                chosen = Some((t.clone(), out));
                break;
            }
            Err(e) => notes.push(format!("{} failed: {e}", t.text)),
        }
    }
    let Some((tight, temporal_ref)) = chosen else {
        return Err(failed(format!(
            "no reference run succeeded: {}",
            notes.join("; ")
        )));
    };
    let err_an = |tips: &[[f64; 3]]| {
        analytic
            .as_ref()
            .zip(t_analytic)
            .map(|((tip, ..), i)| dist(&tips[i], tip))
    };
    // Spatial study: pieces x{1,2,4}, quadrature {2,4,6}, with generalized-α
    // at a small fixed step: unconditionally stable, so refining the pieces
    // (which raises the shear/extension frequencies ~1/ℓ) does not force tiny
    // steps as it does for error-controlled methods. Its own temporal error is
    // measured below against the temporal reference.
    let sp_dt = d / 4000.0;
    let sp_method = Method::GeneralizedAlpha {
        rho_inf: GENERALIZED_ALPHA_RHO_INF,
    };
    let sp_opts = Options::fixed(sp_dt);
    let sp_setting = format!("dt {sp_dt:.3e}");
    let mut spatial = Vec::new();
    for k in [1usize, 2, 4] {
        for q in [2usize, 4, 6] {
            let built = build_variant(scene, k, q)?;
            say(format!("spatial: {} pieces, quadrature {q}", n0 * k));
            let res = simulate(&built, sp_method, &sp_opts, &times, ref_budget, repeats);
            spatial.push(Row {
                study: "spatial",
                integrator: "generalized-alpha".into(),
                setting: sp_setting.clone(),
                pieces: n0 * k,
                quadrature: q,
                result: res,
                err_final: f64::NAN,
                err_max: f64::NAN,
                err_analytic: None,
                pareto: false,
            });
        }
    }
    let tips_of = |k: usize, q: usize| -> Result<&Vec<[f64; 3]>, CliError> {
        spatial
            .iter()
            .find(|r| r.pieces == n0 * k && r.quadrature == q)
            .and_then(|r| r.result.as_ref().ok())
            .map(|o| &o.tips)
            .ok_or_else(|| {
                failed(format!(
                    "the spatial run with pieces x{k}, quadrature {q} failed"
                ))
            })
    };
    // Richardson extrapolation of x2 and x4 (quadrature 6): PCS converges at
    // order 2 in the piece length (docs/validation.md).
    let (t1q, t2q, t4q) = (tips_of(1, 6)?, tips_of(2, 6)?, tips_of(4, 6)?);
    let spatial_ref: Vec<[f64; 3]> = t2q
        .iter()
        .zip(t4q)
        .map(|(a, b)| std::array::from_fn(|i| b[i] + (b[i] - a[i]) / 3.0))
        .collect();
    let observed_order = (max_dist(t1q, t2q) / max_dist(t2q, t4q)).log2();
    let sp_temporal = tips_of(1, q0)
        .map(|t| max_dist(t, &temporal_ref.tips))
        .unwrap_or(f64::NAN);
    for r in &mut spatial {
        if let Ok(out) = &r.result {
            r.err_final = dist(&out.tips[last], &spatial_ref[last]);
            r.err_max = max_dist(&out.tips, &spatial_ref);
            r.err_analytic = err_an(&out.tips);
        }
    }
    mark_pareto(&mut spatial);

    // Temporal errors, against the temporal reference.
    for r in &mut temporal {
        if let Ok(out) = &r.result {
            r.err_final = dist(&out.tips[last], &temporal_ref.tips[last]);
            r.err_max = max_dist(&out.tips, &temporal_ref.tips);
            r.err_analytic = err_an(&out.tips);
        }
    }
    mark_pareto(&mut temporal);

    // Outputs.
    let mut csv = String::from(CSV_HEADER);
    csv_rows(&mut csv, &spatial);
    csv_rows(&mut csv, &temporal);
    write(dir, "report.csv", &csv)?;
    work_precision_svg(
        &dir.join("report.svg"),
        &format!(
            "temporal work-precision: {} ({n0} pieces, quadrature {q0})",
            scene.source
        ),
        &temporal,
        |r| r.integrator.clone(),
    )?;
    work_precision_svg(
        &dir.join("report_spatial.svg"),
        &format!(
            "spatial work-precision: {} (pieces x1, x2, x4)",
            scene.source
        ),
        &spatial,
        |r| format!("quadrature {}", r.quadrature),
    )?;

    let scene_spatial = spatial
        .iter()
        .find(|r| r.pieces == n0 && r.quadrature == q0)
        .map_or(f64::NAN, |r| r.err_max);
    let mut md = String::new();
    let _ = writeln!(md, "# softrod report: {}\n", scene.source);
    let _ = writeln!(
        md,
        "Regenerate with `{}` (release build). {} repeat(s) per configuration, wall time = median; \
         errors are distances of the first rod's tip: at the final time t = {d} s (`error final`) and \
         the largest over {} evenly spaced times (`error max`). Runs over a wall-time budget of {budget} s \
         are stopped and listed as failed.\n",
        command(scene, o),
        repeats,
        N_COMPARE + 1
    );
    md.push_str("## References\n\n");
    let _ = writeln!(
        md,
        "- **Temporal reference** (for the integrator study): {}, at the scene's {n0} pieces and \
         quadrature {q0}: {:.3} s wall, {} steps.",
        tight.text, temporal_ref.wall, temporal_ref.stats.steps
    );
    for n in &notes {
        let _ = writeln!(md, "  (Tried first: {n}.)");
    }
    let _ = writeln!(
        md,
        "- **Spatial reference** (for the pieces/quadrature study): Richardson extrapolation \
         `x4 + (x4 − x2)/3` of the pieces x2 ({} pieces) and x4 ({} pieces) runs at quadrature 6, \
         order 2 (observed order from x1, x2, x4: {observed_order:.2}). The spatial runs use \
         generalized-α (ρ∞ = {GENERALIZED_ALPHA_RHO_INF}) at the fixed step {sp_dt:.3e} s; its \
         temporal error at the scene's pieces is {} m (max over the run, against the temporal \
         reference), which bounds how small a spatial error this study resolves.",
        n0 * 2,
        n0 * 4,
        sci(sp_temporal)
    );
    let _ = writeln!(
        md,
        "- The scene's pieces and quadrature are {} m (max over the run) from the spatial \
         reference: the scene's spatial error.",
        sci(scene_spatial)
    );
    if let (Some((tip, t, note)), Some(i)) = (&analytic, t_analytic) {
        let _ = writeln!(
            md,
            "- **Analytic reference** (`[reference]`): tip {tip:?} m at t = {t} s{}; the spatial \
             reference is {} m from it, the temporal reference {} m.",
            note.as_ref().map_or(String::new(), |n| format!(" ({n})")),
            sci(dist(&spatial_ref[i], tip)),
            sci(dist(&temporal_ref.tips[i], tip))
        );
    }
    md.push_str(
        "\n## Spatial error: pieces and quadrature\n\nEach row against the spatial reference. \
         Plot: `report_spatial.svg` (one curve per quadrature order).\n\n",
    );
    md.push_str(&md_table(&spatial, analytic.is_some()));
    md.push_str(
        "\n## Temporal error: integrators and tolerances\n\nThe scene's pieces and quadrature, each row \
         against the temporal reference (same model), so only the integrator's error is measured. \
         Plot: `report.svg` (log-log work-precision, one curve per integrator, Pareto front dashed \
         and ringed).\n\n",
    );
    md.push_str(&md_table(&temporal, analytic.is_some()));
    md.push_str("\n## Cheapest setting per error target\n\n");
    let _ = writeln!(
        md,
        "The scene's own spatial error ({n0} pieces, quadrature {q0}) is {} m: integrator errors far \
         below it buy nothing.\n",
        sci(scene_spatial)
    );
    md.push_str("| target (max tip error) m | cheapest integrator setting | wall s | its error m |\n|---|---|---|---|\n");
    let mut targets = vec![1e-3, 1e-4, 1e-5, 1e-6];
    if scene_spatial.is_finite() {
        targets.insert(0, scene_spatial / 10.0);
    }
    for tgt in targets {
        let best = temporal
            .iter()
            .filter(|r| r.result.is_ok() && r.err_max <= tgt)
            .min_by(|a, b| wall(a).total_cmp(&wall(b)));
        match best {
            Some(r) => {
                let _ = writeln!(
                    md,
                    "| {} | {} {} | {:.4} | {} |",
                    sci(tgt),
                    r.integrator,
                    r.setting,
                    wall(r),
                    sci(r.err_max)
                );
            }
            None => {
                let _ = writeln!(md, "| {} | none reached it | | |", sci(tgt));
            }
        }
    }
    md.push_str("\nData: `report.csv` (both studies, column `study`).\n");
    Ok(md)
}

fn statics_report(scene: &Scene, dir: &Path, o: ReportOptions) -> Result<String, CliError> {
    let say = |m: String| {
        if !o.quiet {
            eprintln!("softrod report: {m}");
        }
    };
    let repeats = if o.quick { 1 } else { 3 };
    let n0 = pieces(scene);
    let solve = |k: usize, q: usize| -> Result<(Outcome, usize), String> {
        let built = build_variant(scene, k, q).map_err(|e| e.to_string())?;
        let mut walls = Vec::new();
        let mut result = None;
        for _ in 0..repeats {
            let mut data = Data::new(&built.model);
            let start = Instant::now();
            let r = statics(
                &built.model,
                &mut data,
                built.q0.as_slice(),
                &StaticsOptions::default(),
            )
            .map_err(|e| e.to_string())?;
            walls.push(start.elapsed().as_secs_f64());
            result = Some(r);
        }
        let r = result.expect("one repeat");
        let mut poser = Poser::new(&built.model);
        poser
            .update(&built.model, r.q.as_slice())
            .map_err(|e| e.to_string())?;
        let p = poser.tip(0).translation;
        let stats = Stats {
            steps: r.iterations,
            ..Stats::default()
        };
        Ok((
            Outcome {
                tips: vec![[p[0], p[1], p[2]]],
                stats,
                wall: median(walls),
            },
            r.load_steps,
        ))
    };
    let analytic = scene
        .reference
        .as_ref()
        .filter(|r| r.rod_index == 0)
        .and_then(|r| r.tip.map(|t| (t, r.note.clone())));
    let fine_k = 8;
    say(format!(
        "reference: statics at pieces x{fine_k}, quadrature 6"
    ));
    let (fine, _) = solve(fine_k, 6).map_err(|e| failed(format!("fine reference: {e}")))?;
    let reference = analytic.as_ref().map_or(fine.tips[0], |a| a.0);
    let mut rows = Vec::new();
    for k in [1usize, 2, 4] {
        for q in [2usize, 4, 6] {
            say(format!("statics: {} pieces, quadrature {q}", n0 * k));
            let res = solve(k, q);
            let (err, ea) = match &res {
                Ok((out, _)) => (
                    dist(&out.tips[0], &reference),
                    analytic.as_ref().map(|a| dist(&out.tips[0], &a.0)),
                ),
                Err(_) => (f64::NAN, None),
            };
            rows.push(Row {
                study: "statics",
                integrator: "newton".into(),
                setting: res
                    .as_ref()
                    .map_or(String::new(), |(_, ls)| format!("{ls} load step(s)")),
                pieces: n0 * k,
                quadrature: q,
                result: res.map(|(o, _)| o),
                err_final: err,
                err_max: err,
                err_analytic: ea,
                pareto: false,
            });
        }
    }
    mark_pareto(&mut rows);
    let mut csv = String::from(CSV_HEADER);
    csv_rows(&mut csv, &rows);
    write(dir, "report.csv", &csv)?;
    work_precision_svg(
        &dir.join("report.svg"),
        &format!("statics work-precision: {}", scene.source),
        &rows,
        |r| format!("quadrature {}", r.quadrature),
    )?;
    let mut md = String::new();
    let _ = writeln!(md, "# softrod report (statics): {}\n", scene.source);
    let _ = writeln!(
        md,
        "Regenerate with `{}` (release build). {repeats} repeat(s), wall time = median. Error = \
         distance of the first rod's tip from the reference; `steps` = Newton iterations.\n",
        command(scene, o)
    );
    match &analytic {
        Some((tip, note)) => {
            let _ = writeln!(
                md,
                "**Reference**: the scene's `[reference] tip` = {tip:?} m{}. pieces x{fine_k} \
                 ({} pieces), quadrature 6 is {} m from it (the reference's own accuracy and the \
                 model's, e.g. linear theory).\n",
                note.as_ref().map_or(String::new(), |n| format!(" ({n})")),
                n0 * fine_k,
                sci(dist(&fine.tips[0], tip))
            );
        }
        None => {
            let _ = writeln!(
                md,
                "**Reference**: statics at pieces x{fine_k} ({} pieces), quadrature 6 (the scene \
                 has no `[reference] tip`).\n",
                n0 * fine_k
            );
        }
    }
    md.push_str(&md_table(&rows, false));
    md.push_str("\nPlot: `report.svg`. Data: `report.csv`.\n");
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(w: f64, e: f64) -> Row {
        Row {
            study: "t",
            integrator: "x".into(),
            setting: String::new(),
            pieces: 1,
            quadrature: 4,
            result: Ok(Outcome {
                tips: vec![],
                stats: Stats::default(),
                wall: w,
            }),
            err_final: e,
            err_max: e,
            err_analytic: None,
            pareto: false,
        }
    }

    #[test]
    fn pareto_front_keeps_the_undominated() {
        let mut rows = vec![
            row(1.0, 1e-3),
            row(2.0, 1e-2),
            row(0.5, 1e-2),
            row(3.0, 1e-6),
        ];
        mark_pareto(&mut rows);
        let marks: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        assert_eq!(marks, vec![true, false, true, true]);
    }

    #[test]
    fn variant_splits_pieces_and_repeats_initial_values() {
        let text = "[[rod]]\nname = \"a\"\nlength = 0.4\npieces = 2\nstrains = [\"ky\", \"qx\"]\n\
                    section = { shape = \"circle\", radius = 0.01 }\n\
                    material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n\
                    [initial]\nq = [1.0, 0.1, 2.0, 0.2]\n";
        let (s, _) = Scene::from_str(text, "t.toml").unwrap();
        let v = variant(&s, 4, 6).unwrap();
        assert_eq!(v.rods[0].rod.n_pieces(), 8);
        assert_eq!(v.run.quadrature, 6);
        assert!(
            v.rods[0]
                .rod
                .piece_lengths()
                .all(|l| (l - 0.05).abs() < 1e-15)
        );
        let q = v.initial.q.clone().unwrap();
        assert_eq!(q.len(), 16);
        assert_eq!(&q[..2], &[1.0, 0.1]);
        assert_eq!(&q[6..8], &[1.0, 0.1]);
        assert_eq!(&q[8..10], &[2.0, 0.2]);
        assert!(v.build().is_ok());
    }
}
