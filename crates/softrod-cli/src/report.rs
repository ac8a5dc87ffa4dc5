//! `softrod report`: error against run time over integrators and tolerances.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use softrod_integrate::{Hooks, Method, Options, RodSystem, Stats, integrate_second_order};
use softrod_scene::{Built, Scene};

use crate::common::{CliError, Poser, failed, load, out_dir};
use crate::plots;

/// Number of comparison times (evenly spaced over the run, end included).
const N_COMPARE: usize = 20;

struct Outcome {
    tips: Vec<[f64; 3]>,
    stats: Stats,
    wall: f64,
}

fn simulate(
    built: &Built,
    method: Method,
    opts: &Options,
    times: &[f64],
) -> Result<Outcome, String> {
    let mut sys = RodSystem::new(built.model.clone());
    let t1 = *times.last().expect("times");
    let opts = Options {
        t_eval: Some(times.to_vec()),
        max_steps: 20_000_000,
        ..opts.clone()
    };
    let start = Instant::now();
    let sol = integrate_second_order(
        &mut sys,
        method,
        0.0,
        t1,
        &built.q0,
        &built.qd0,
        &opts,
        Hooks::new(),
    )
    .map_err(|e| e.to_string())?;
    let wall = start.elapsed().as_secs_f64();
    let n = sys.model.n_dof();
    let mut poser = Poser::new(&sys.model);
    let mut tips = Vec::new();
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

/// The scene with every piece cut in two (same strains, `[initial].q` repeated).
fn refined(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for r in &mut s.rods {
        r.piece_lengths = r
            .piece_lengths
            .iter()
            .flat_map(|&l| [0.5 * l, 0.5 * l])
            .collect();
    }
    let dup = |v: &Vec<f64>| -> Vec<f64> {
        let mut out = Vec::with_capacity(2 * v.len());
        let mut off = 0;
        for r in &scene.rods {
            let k = r.strains.count();
            for _ in 0..r.n_pieces() {
                let block = &v[off..off + k];
                out.extend_from_slice(block);
                out.extend_from_slice(block);
                off += k;
            }
        }
        out
    };
    s.initial.q = scene.initial.q.as_ref().map(dup);
    s.initial.qdot = scene.initial.qdot.as_ref().map(dup);
    s
}

fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

pub fn report(path: &Path, out: Option<PathBuf>, quiet: bool) -> Result<(), CliError> {
    let l = load(path)?;
    let dir = out_dir(path, out);
    std::fs::create_dir_all(&dir)
        .map_err(|e| failed(format!("cannot create {}: {e}", dir.display())))?;
    let d = l.scene.run.duration;
    let times: Vec<f64> = (0..=N_COMPARE)
        .map(|k| d * k as f64 / N_COMPARE as f64)
        .collect();
    let say = |m: String| {
        if !quiet {
            eprintln!("softrod report: {m}");
        }
    };
    let ref_opts = Options::tol(1e-10, 1e-13);
    say("reference: dopri5, rtol 1e-10, atol 1e-13".into());
    let reference = simulate(&l.built, Method::Dopri5, &ref_opts, &times)
        .map_err(|e| failed(format!("reference run failed: {e}")))?;
    let mut configs: Vec<(String, String, usize, Method, Options)> = Vec::new();
    let pieces: usize = l.scene.rods.iter().map(|r| r.n_pieces()).sum();
    for rtol in [1e-4, 1e-6, 1e-8] {
        configs.push((
            "dopri5".into(),
            format!("rtol {rtol:e}"),
            pieces,
            Method::Dopri5,
            Options::tol(rtol, rtol * 1e-3),
        ));
    }
    for rtol in [1e-3, 1e-4, 1e-5, 1e-6] {
        configs.push((
            "rosenbrock".into(),
            format!("rtol {rtol:e}"),
            pieces,
            Method::Rosw34,
            Options::tol(rtol, rtol * 1e-3),
        ));
    }
    let mut csv = String::from(
        "configuration,integrator,setting,pieces,wall_seconds,tip_error_m,steps,rejected_steps,rhs_evaluations,status\n",
    );
    let mut md = String::new();
    let _ = writeln!(md, "# softrod report: {}\n", l.scene.source);
    let _ = writeln!(
        md,
        "Error = largest distance of the first rod's tip from the reference at {} evenly spaced times over the {d} s run.\n\n\
         **Reference**: the tightest run, dopri5 with rtol 1e-10, atol 1e-13, same pieces ({} wall s, {} steps). \
         It measures time-integration error only; the `pieces x2` row measures the spatial (PCS) discretization \
         error of the scene as given, against the same reference.\n",
        N_COMPARE + 1,
        format_args!("{:.3}", reference.wall),
        reference.stats.steps
    );
    md.push_str("| configuration | pieces | wall s | tip error m | steps | rejected | rhs evaluations | status |\n|---|---|---|---|---|---|---|---|\n");
    let mut groups: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let row = |name: &str,
               integ: &str,
               setting: &str,
               pieces: usize,
               o: Result<&Outcome, String>,
               err: f64,
               groups: &mut Vec<(String, Vec<(f64, f64)>)>,
               csv: &mut String,
               md: &mut String| {
        match o {
            Ok(o) => {
                let _ = writeln!(
                    csv,
                    "{name},{integ},{setting},{pieces},{},{err:e},{},{},{},ok",
                    o.wall, o.stats.steps, o.stats.rejected_steps, o.stats.rhs_evaluations
                );
                let _ = writeln!(
                    md,
                    "| {name} | {pieces} | {:.4} | {err:.3e} | {} | {} | {} | ok |",
                    o.wall, o.stats.steps, o.stats.rejected_steps, o.stats.rhs_evaluations
                );
                match groups.iter_mut().find(|(g, _)| g == integ) {
                    Some((_, p)) => p.push((o.wall, err)),
                    None => groups.push((integ.to_string(), vec![(o.wall, err)])),
                }
            }
            Err(e) => {
                let e = e.replace([',', '\n'], ";");
                let _ = writeln!(csv, "{name},{integ},{setting},{pieces},,,,,,failed: {e}");
                let _ = writeln!(md, "| {name} | {pieces} | | | | | | failed: {e} |");
            }
        }
    };
    for (integ, setting, p, method, opts) in &configs {
        let name = format!("{integ} {setting}");
        say(format!("running {name}"));
        let o = simulate(&l.built, *method, opts, &times);
        let err = o
            .as_ref()
            .map_or(f64::NAN, |o| max_dist(&o.tips, &reference.tips));
        row(
            &name,
            integ,
            setting,
            *p,
            o.as_ref().map_err(|e| e.clone()),
            err,
            &mut groups,
            &mut csv,
            &mut md,
        );
    }
    // Spatial convergence: twice the pieces, tight tolerance.
    let fine = refined(&l.scene);
    let fine_pieces: usize = fine.rods.iter().map(|r| r.n_pieces()).sum();
    say(format!(
        "running pieces x2 ({fine_pieces} pieces), dopri5 rtol 1e-8"
    ));
    let fine_built = fine
        .build()
        .map_err(|e| failed(format!("refined scene: {e}")))?;
    let o = simulate(
        &fine_built,
        Method::Dopri5,
        &Options::tol(1e-8, 1e-11),
        &times,
    );
    let err = o
        .as_ref()
        .map_or(f64::NAN, |o| max_dist(&o.tips, &reference.tips));
    row(
        "pieces x2 dopri5 rtol 1e-8",
        "pieces x2 (spatial)",
        "rtol 1e-8",
        fine_pieces,
        o.as_ref().map_err(|e| e.clone()),
        err,
        &mut groups,
        &mut csv,
        &mut md,
    );
    md.push_str(
        "\nPlot: `report.svg` (log-log tip error against wall time). Data: `report.csv`.\n",
    );
    let w = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).map_err(|e| failed(format!("cannot write {}: {e}", p.display())))
    };
    w("report.md", &md)?;
    w("report.csv", &csv)?;
    plots::loglog(&dir.join("report.svg"), "tip error vs wall time", &groups)?;
    if !quiet {
        print!("{md}");
    }
    Ok(())
}
