//! `check`, `statics` and `modes`.

use std::path::Path;

use softrod::Equilibrium;

use crate::common::{CliError, Loaded, Poser, failed, load, pose_json};

pub fn check(path: &Path) -> Result<(), CliError> {
    let Loaded {
        scene,
        warnings,
        sim,
    } = load(path)?;
    let m = sim.model();
    println!("scene: {}", scene.source);
    println!("degrees of freedom: {}", m.n_dof());
    for (r, rm) in scene.rods.iter().zip(m.rods()) {
        println!(
            "rod '{}': length {} m, {} pieces, strains [{}], {} DoF (q[{}..{}])",
            r.name,
            r.body.length(),
            r.rod.n_pieces(),
            r.rod.pieces()[0].basis,
            rm.n_dof(),
            rm.dofs().start,
            rm.dofs().end
        );
    }
    crate::robot::print_elements(m);
    if scene.n_cables() > 0 {
        println!("cables: {}", scene.n_cables());
    }
    if scene.n_point_loads() > 0 {
        println!("point loads: {}", scene.n_point_loads());
    }
    println!("terms: {}", m.terms().join(", "));
    let run = &scene.run;
    println!(
        "run: mode {}, duration {} s, integrator {}, rtol {:e}, atol {:e}, dt {:e}, output every {:e} s, {} Gauss points per piece",
        run.mode.name(),
        run.duration,
        run.integrator,
        run.rtol,
        run.atol,
        run.dt,
        run.output_every,
        run.quadrature
    );
    if warnings.is_empty() {
        println!("warnings: none");
    } else {
        println!("warnings: {}", warnings.len());
        for w in &warnings {
            println!("  warning: {}: {w}", scene.source);
        }
    }
    Ok(())
}

/// Largest model whose equilibrium `softrod statics` checks for stability
/// with a modal analysis (dense eigenproblem, ~1 s at this size).
pub const STABILITY_CHECK_MAX_DOF: usize = 600;

pub fn statics(path: &Path, json: bool) -> Result<(), CliError> {
    let mut l = load(path)?;
    let res = l.sim.statics()?;
    if res.q.iter().any(|v| !v.is_finite()) || !res.residual.is_finite() {
        return Err(failed("statics returned a non-finite state"));
    }
    // Newton finds equilibria, stable or not (a soft rod under gravity has an
    // unstable upright one): check the lowest linearized mode when that is
    // affordable (O(n_dof³)).
    let stable = (l.sim.n_dof() <= STABILITY_CHECK_MAX_DOF)
        .then(|| l.sim.modes_about(res.q.as_slice()))
        .and_then(Result::ok)
        .map(|m| (m.omega.iter().all(|w| *w > 0.0), m.omega.min()));
    let model = l.sim.model();
    let mut poser = Poser::new(model);
    poser.update(model, res.q.as_slice())?;
    if let Some((false, w)) = stable {
        eprintln!(
            "warning: this equilibrium is unstable (lowest linearized ω² = {:.3e} rad²/s²); \
             a stable one may exist nearby: start statics from another [initial] q",
            -w * w
        );
    }
    if json {
        let rods: Vec<_> = model
            .rods()
            .iter()
            .enumerate()
            .map(
                |(i, r)| serde_json::json!({ "name": r.spec.name, "tip": pose_json(poser.tip(i)) }),
            )
            .collect();
        let v = serde_json::json!({
            // A returned equilibrium is converged (failures are errors);
            // the key is in the contract.
            "converged": true,
            "iterations": res.iterations,
            "residual": res.residual,
            "load_steps": res.load_steps,
            "stable": stable.map(|(s, _)| s),
            "q": res.q.as_slice(),
            "tip": pose_json(poser.tip(0)),
            "rods": rods,
        });
        let mut v = v;
        crate::robot::add_statics_json(model, &poser, res.q.as_slice(), &mut v);
        println!("{v}");
    } else {
        println!(
            "statics converged: {} Newton iterations, {} load step(s), residual {:.3e}",
            res.iterations, res.load_steps, res.residual
        );
        for (i, r) in model.rods().iter().enumerate() {
            let p = poser.tip(i).translation;
            println!(
                "rod '{}' tip: [{:.9}, {:.9}, {:.9}] m",
                r.spec.name, p[0], p[1], p[2]
            );
        }
        if let Some(reference) = &l.scene.reference {
            if let Some(tip) = reference.tip {
                let p = poser.tip(reference.rod_index).translation;
                let err = (p - nalgebra::Vector3::from(tip)).norm();
                let tol = reference.tolerance.map_or(String::new(), |t| {
                    format!(
                        " (tolerance {t:e} m: {})",
                        if err <= t { "agrees" } else { "DISAGREES" }
                    )
                });
                println!("reference tip {:?}: distance {err:.3e} m{tol}", tip);
            }
        }
    }
    Ok(())
}

pub fn modes(path: &Path, json: bool, count: usize) -> Result<(), CliError> {
    let mut l = load(path)?;
    let analysis = l.sim.modes()?;
    let m = &analysis.modes;
    let equilibrium = match analysis.equilibrium {
        Equilibrium::Rest => "rest",
        Equilibrium::Statics(_) => "statics",
    };
    let f: Vec<f64> = m.frequencies_hz().into_iter().take(count).collect();
    if f.iter().any(|v| !v.is_finite()) {
        return Err(failed("modal analysis gave a non-finite frequency"));
    }
    if json {
        println!(
            "{}",
            serde_json::json!({ "frequencies_hz": f, "equilibrium": equilibrium })
        );
    } else {
        println!(
            "natural frequencies about the {} ({} of {}):",
            if equilibrium == "rest" {
                "rest shape"
            } else {
                "static equilibrium"
            },
            f.len(),
            l.sim.n_dof()
        );
        for (i, v) in f.iter().enumerate() {
            println!("  mode {:>2}: {v:.6} Hz", i + 1);
        }
        if m.asymmetry > 1e-8 {
            println!(
                "note: tangent stiffness asymmetry {:.2e} (follower loads or cables); its symmetric part was used",
                m.asymmetry
            );
        }
    }
    Ok(())
}
