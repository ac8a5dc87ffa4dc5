//! Work of the implicit integrators on closed chains (issues 25, 30): a
//! scene file (e.g. the cosseratbench catenary's, written by its adapter)
//! integrated by `softrod_integrate` directly, with the dense Newton
//! matrices or the experimental structured KKT solve of closed models
//! (`RodSystem::structured_closures`, docs/theory-derivatives.md CD5–CD8). Prints one CSV row per run: the
//! wall time of the integration (best of `--repeat`), the work counters,
//! the largest closure residual over the samples and the largest distance
//! of the final centre lines (every rod at 11 points) from the first run's
//! (the methods must agree).
//!
//! `--newton` takes `structured` (the KKT solve of CD6), `structured-geometric`
//! (with the geometric stiffness of gravity and the closure forces, CD11:
//! `RodSystem::geometric_in_closures`) and `dense`.
//!
//! `cargo run --release -p softrod --example closed_chains -- SCENE.toml [--duration 5] [--rtol 1e-3] [--atol 1e-5] [--method esdirk,radau5] [--newton structured,dense] [--reference RTOL] [--repeat 1] [--samples 101] [--steps-to-outputs]`

use std::time::Instant;

use softrod::dynamics::max_closure_residual;
use softrod::integrate::{
    Integrator, NoHooks, Options, RodJacobian, RodSystem, integrate_second_order,
};
use softrod::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .first()
        .ok_or("usage: closed_chains SCENE.toml [options]")?;
    let flag = |name: &str, default: &str| -> String {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1).cloned())
            .unwrap_or_else(|| default.to_string())
    };
    let duration: f64 = flag("--duration", "5").parse()?;
    let rtol: f64 = flag("--rtol", "1e-3").parse()?;
    let atol: f64 = flag("--atol", "1e-5").parse()?;
    let repeat: usize = flag("--repeat", "1").parse()?;
    let samples: usize = flag("--samples", "101").parse()?;
    let methods = flag("--method", "esdirk,radau5");
    let newton = flag("--newton", "structured,dense");
    // The cosseratbench adapter's quasi-static ESDIRK runs end their steps
    // on the outputs (docs/theory-derivatives.md CD10).
    let steps_to_outputs = args.iter().any(|a| a == "--steps-to-outputs");
    // A reference run first (its row says "reference"): ESDIRK on the
    // dense exact Jacobian at this tolerance (atol = rtol / 1000).
    let reference: Option<f64> = args
        .iter()
        .position(|a| a == "--reference")
        .and_then(|i| args.get(i + 1))
        .map(|v| v.parse())
        .transpose()?;
    let text = std::fs::read_to_string(path)?;
    let (sim, _, _) = Simulation::from_toml(&text, path)?;
    let model = sim.model().clone();
    let (q0, v0) = sim.initial_state();
    let (q0, v0) = (q0.clone(), v0.clone());
    let n = model.n_dof();
    println!(
        "scene,n_dof,m,method,newton,wall_s,steps,rejected,newton_iterations,jacobians,factorizations,solves,rhs,max_closure_residual_m,final_distance_m"
    );
    // The final centre lines: 11 points per rod (the drives' poses do
    // not depend on the run, so any time of the data will do for a
    // comparison).
    let lines = |q: &[f64]| -> Result<Vec<[f64; 3]>, softrod::Error> {
        let mut out = Vec::new();
        for (r, rm) in sim.model().rods().iter().enumerate() {
            let l = rm.spec.geometry.length();
            for k in 0..=10 {
                let p = sim.pose(r, l * k as f64 / 10.0, q)?.translation;
                out.push([p[0], p[1], p[2]]);
            }
        }
        Ok(out)
    };
    let mut first: Option<Vec<[f64; 3]>> = None;
    let mut runs: Vec<(String, &str, f64, f64)> = Vec::new();
    if let Some(r) = reference {
        runs.push(("esdirk".into(), "dense", r, r * 1e-3));
    }
    for method in methods.split(',') {
        for kind in newton.split(',') {
            if !matches!(kind, "structured" | "structured-geometric" | "dense") {
                return Err(format!("--newton: unknown {kind:?}").into());
            }
            runs.push((method.into(), kind, rtol, atol));
        }
    }
    for (k, (method, kind, rtol, atol)) in runs.iter().enumerate() {
        let (method, kind, rtol, atol) = (method.as_str(), *kind, *rtol, *atol);
        let structured = kind != "dense";
        let integrator: Integrator = method.parse()?;
        {
            let mut opts = Options::tol(rtol, atol);
            opts.steps_to_outputs = steps_to_outputs;
            opts.t_eval = Some(
                (0..samples)
                    .map(|k| duration * k as f64 / (samples - 1) as f64)
                    .collect(),
            );
            let mut best = f64::INFINITY;
            let mut out = None;
            for _ in 0..repeat.max(1) {
                let mut sys = RodSystem::new(model.clone());
                sys.jacobian = RodJacobian::recommended(integrator);
                sys.structured_closures = structured;
                sys.geometric_in_closures = kind == "structured-geometric";
                let start = Instant::now();
                let sol = integrate_second_order(
                    &mut sys,
                    integrator,
                    (0.0, duration),
                    &q0,
                    &v0,
                    &opts,
                    &mut NoHooks,
                );
                best = best.min(start.elapsed().as_secs_f64());
                out = Some((sol, sys));
            }
            let (sol, mut sys) = out.expect("one repeat");
            let sol = match sol {
                Ok(s) => s,
                Err(e) => {
                    println!(
                        "{path},{n},{},{method},{kind},failed: {e}",
                        model.n_constraints()
                    );
                    continue;
                }
            };
            let mut residual: f64 = 0.0;
            for (t, y) in sol.t.iter().zip(&sol.y) {
                // Prescribed joints: the closure frames stand where the
                // drives hold them at t.
                sys.model.set_time(&mut sys.data, *t);
                residual = residual.max(max_closure_residual(
                    &sys.model,
                    &mut sys.data,
                    &y.as_slice()[..n],
                )?);
            }
            let line = lines(&sol.y_final.as_slice()[..n])?;
            let diff = match &first {
                None => {
                    first = Some(line);
                    0.0
                }
                Some(f) => f
                    .iter()
                    .zip(&line)
                    .map(|(a, b)| {
                        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2))
                            .sqrt()
                    })
                    .fold(0.0, f64::max),
            };
            let s = sol.stats;
            println!(
                "{path},{n},{},{method},{},{best:.3},{},{},{},{},{},{},{},{residual:.2e},{diff:.2e}",
                model.n_constraints(),
                if reference.is_some() && k == 0 {
                    "reference"
                } else {
                    kind
                },
                s.steps,
                s.rejected_steps,
                s.newton_iterations,
                s.jacobian_evaluations,
                s.factorizations,
                s.lu_solves,
                s.rhs_evaluations,
            );
        }
    }
    Ok(())
}
