//! `check`, `statics` and `modes`.

use std::path::{Path, PathBuf};

use softrod::Equilibrium;
use softrod::dynamics::Model;

use crate::common::{
    CliError, Loaded, centrelines, failed, load, load_silent, pose_json, position, sampled_poses,
    warning_text,
};
use crate::plots;
use crate::run::scene_title;

pub fn check(path: &Path) -> Result<(), CliError> {
    let Loaded {
        scene,
        mut warnings,
        sim,
    } = load_silent(path)?;
    // What `run` or `statics` would refuse before starting, `check` refuses
    // too (the disk space of `run --out` aside: it depends on the directory).
    match scene.run.mode {
        softrod::scene::Mode::Dynamics => sim.check_run(scene.run.duration)?,
        softrod::scene::Mode::Statics => sim.check_statics()?,
    }
    let m = sim.model();
    println!("scene: {}", scene.source);
    println!("degrees of freedom: {}", m.n_dof());
    for (r, rm) in scene.rods.iter().zip(m.rods()) {
        println!(
            "rod '{}': length {} m, {} pieces, strains [{}], {} DoF (q[{}..{}])",
            r.name,
            r.properties.length(),
            r.geometry.n_pieces(),
            r.geometry.pieces()[0].basis,
            rm.n_dof(),
            rm.dofs().start,
            rm.dofs().end
        );
    }
    crate::robot::print_elements(m);
    if !scene.initial.shape.is_empty() {
        for f in scene
            .build()
            .map_err(|e| failed(format!("{e}")))?
            .shape_fits
        {
            println!(
                "initial shape of rod '{}': strains fitted, distance to the points rms {:.3e} m, max {:.3e} m",
                f.rod, f.rms, f.max
            );
            let length = m
                .rods()
                .iter()
                .find(|r| r.spec.name == f.rod)
                .map_or(0.0, |r| r.spec.geometry.length());
            if f.max > 0.01 * length {
                println!(
                    "  warning: the rod cannot pass within 1% of its length of these points \
                     (pieces, strains or spacing in arc length do not allow it)"
                );
            }
        }
    }
    crate::closures::print_closures(m, sim.initial_state().0.as_slice())?;
    crate::contact::print_contact(&scene);
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
    if run.mode == softrod::scene::Mode::Dynamics {
        output_size(path, &sim, run, &mut warnings);
    }
    if warnings.is_empty() {
        println!("warnings: none");
    } else {
        println!("warnings: {}", warnings.len());
        for w in &warnings {
            println!("  warning: {}", warning_text(&scene.source, w));
        }
    }
    Ok(())
}

/// Prints what `run` would write (at least) and warns, with `run`'s words,
/// when it exceeds the free space where `run` writes by default.
fn output_size(
    path: &Path,
    sim: &softrod::Simulation,
    run: &softrod::scene::Run,
    warnings: &mut Vec<softrod::scene::Warning>,
) {
    let m = sim.model();
    let duration = run.duration;
    let every = sim.settings().output_spacing(duration);
    let contacts = if m.has_contact() {
        let (q0, qd0) = sim.initial_state();
        m.contacts(0.0, q0.as_slice(), qd0.as_slice())
            .map_or(0, |c| c.len())
    } else {
        0
    };
    let samples = softrod::record::RodSampling::of_model(m, run.shape_points_per_piece)
        .iter()
        .map(|s| s.s.len())
        .sum();
    let per_row = crate::outputs::output_bytes_per_row(m, samples, contacts, false);
    let (need, rows) = crate::outputs::disk_need(duration, every, per_row);
    println!(
        "outputs: {rows} output times, at least {} on disk (CSV files)",
        crate::outputs::human(need)
    );
    let dir = crate::common::out_dir(path, None);
    if let Err(e) = crate::outputs::check_disk_space(&dir, duration, every, per_row) {
        warnings.push(softrod::scene::Warning {
            path: "run.output_every".into(),
            at: None,
            message: format!(
                "`run` would refuse this: {}",
                e.to_string().trim_start_matches("run.output_every: ")
            ),
        });
    }
}

/// Largest model whose equilibrium `softrod statics` checks for stability
/// with a modal analysis (dense eigenproblem, ~1 s at this size).
pub const STABILITY_CHECK_MAX_DOF: usize = 600;

/// Creates the output directory of a command (exit 2 when it cannot be).
fn make_dir(dir: &Path) -> Result<(), CliError> {
    crate::outputs::prepare_out_dir(dir)
}

/// Sampled centrelines of every rod at `q` (the default sampling of `run`).
fn centrelines_at(model: &Model, q: &[f64]) -> Result<Vec<Vec<[f64; 3]>>, CliError> {
    Ok(centrelines(&sampled_poses(model, 0.0, q)?))
}

pub fn statics(path: &Path, json: bool, out: Option<PathBuf>, png: bool) -> Result<(), CliError> {
    let mut l = load(path)?;
    let res = l.sim.statics()?;
    if res.q.iter().any(|v| !v.is_finite()) || !res.residual.is_finite() {
        return Err(failed("statics returned a non-finite state"));
    }
    // Newton finds equilibria, stable or not (a soft rod under gravity has an
    // unstable upright one): check the linearized modes when that is
    // affordable (O(n_dof³)). Rigid (zero) modes — a free body nothing
    // holds — are neutral, not unstable (docs/theory.md E7).
    let modes = (l.sim.n_dof() <= STABILITY_CHECK_MAX_DOF)
        .then(|| l.sim.modes_about(res.q.as_slice()))
        .and_then(Result::ok);
    let stable = modes.as_ref().map(|m| m.n_unstable() == 0);
    let mut warnings = res.warnings.clone();
    if let Some(m) = modes.as_ref().filter(|m| m.n_unstable() > 0) {
        let w = m.omega.min();
        warnings.push(format!(
            "this equilibrium is unstable ({} mode(s) with ω² < −{:.1e} rad²/s², the lowest \
             ω² = {:.3e} rad²/s²); a stable one may exist nearby: start statics from another \
             [initial] q",
            m.n_unstable(),
            m.rigid_tolerance,
            -w * w
        ));
    }
    for w in &warnings {
        eprintln!("softrod: warning: {w}");
    }
    // The contacts at the equilibrium (frictionless: statics has no
    // history to anchor friction to), with the contact stiffness the
    // solve raised (docs/theory-contact.md CT15).
    let contacts = if l.sim.model().has_contact() {
        let zero = vec![0.0; res.q.len()];
        Some(
            l.sim
                .contacts(0.0, res.q.as_slice(), &zero)
                .map_err(|e| failed(format!("contacts at the equilibrium: {e}")))?,
        )
    } else {
        None
    };
    let model = l.sim.model();
    let poser = sampled_poses(model, 0.0, res.q.as_slice())?;
    if let Some(dir) = &out {
        make_dir(dir)?;
        let c = centrelines(&poser);
        let bodies: Vec<[f64; 3]> = poser.bodies().iter().map(position).collect();
        let body_poses: Vec<softrod_viz::Pose> = poser
            .bodies()
            .iter()
            .map(|g| softrod_viz::Pose {
                position: position(g),
                rotation: softrod::record::quaternion(g),
            })
            .collect();
        let name = plots::statics_figure(dir, model, &c, &bodies, &body_poses, &scene_title(path))?;
        if png {
            plots::rasterize(dir, std::slice::from_ref(&name), json)?;
        }
        if !json {
            println!("wrote {}", dir.join(name).display());
        }
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
            "stable": stable,
            "rigid_modes": modes.as_ref().map(|m| m.n_rigid()),
            "warnings": warnings,
            "q": res.q.as_slice(),
            "tip": pose_json(poser.tip(0)),
            "rods": rods,
        });
        let mut v = v;
        crate::robot::add_statics_json(model, &poser, res.q.as_slice(), &mut v);
        crate::closures::add_statics_json(model, res.q.as_slice(), &mut v)?;
        if let Some(c) = &contacts {
            let (entries, deepest) = crate::contact::contacts_json(model, c);
            v["contacts"] = entries;
            v["max_penetration"] = serde_json::json!(deepest);
        }
        println!("{v}");
    } else {
        println!(
            "statics converged: {} Newton iterations, {} load step(s), residual {:.3e}",
            res.iterations, res.load_steps, res.residual
        );
        if let Some(m) = &modes {
            let rigid = m.n_rigid();
            println!(
                "stability: {}{}",
                if m.n_unstable() > 0 {
                    "unstable"
                } else {
                    "stable"
                },
                if rigid > 0 {
                    format!(
                        " ({rigid} rigid mode(s), |ω²| ≤ {:.1e} rad²/s²: neutral)",
                        m.rigid_tolerance
                    )
                } else {
                    String::new()
                }
            );
        }
        println!(
            "warnings: {}",
            if warnings.is_empty() {
                "none".to_string()
            } else {
                format!("{} (on stderr)", warnings.len())
            }
        );
        if let Some(c) = &contacts {
            let (_, deepest) = crate::contact::contacts_json(model, c);
            println!("contacts: {}, largest penetration {deepest:.3e} m", c.len());
        }
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

/// Mode shapes drawn by `modes --out`: at most this many.
const MODE_PLOTS: usize = 6;
/// Each drawn mode displaces the rods by this fraction of the longest rod
/// at the point that moves most (visible, still near the linear regime).
const MODE_AMPLITUDE: f64 = 0.1;

/// The equilibrium and the lowest modes as displaced centrelines.
fn mode_curves(
    model: &Model,
    q_eq: &[f64],
    modes: &softrod::dynamics::Modes,
    count: usize,
) -> Result<ModeCurves, CliError> {
    let eq = centrelines_at(model, q_eq)?;
    let length = model
        .rods()
        .iter()
        .map(|r| r.spec.geometry.length())
        .fold(0.0, f64::max);
    let freq = modes.frequencies_hz();
    let mut out = Vec::new();
    for (k, &f_k) in freq
        .iter()
        .enumerate()
        .take(count.min(modes.shapes.ncols()))
    {
        let v = modes.shapes.column(k);
        let at = |a: f64| -> Result<Vec<Vec<[f64; 3]>>, CliError> {
            let q: Vec<f64> = q_eq.iter().zip(v.iter()).map(|(q, v)| q + a * v).collect();
            centrelines_at(model, &q)
        };
        // Scale from a small probe: the displacement is linear in the
        // amplitude there, so one probe sets the amplitude.
        let probe = 1e-6 / v.amax().max(1e-300);
        let moved = at(probe)?;
        let d = eq
            .iter()
            .flatten()
            .zip(moved.iter().flatten())
            .map(|(a, b)| {
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .fold(0.0, f64::max);
        if d <= 0.0 || !d.is_finite() {
            continue;
        }
        out.push((f_k, at(probe * MODE_AMPLITUDE * length / d)?));
    }
    Ok((eq, out))
}

/// Relative asymmetry of `K_eff` above which `softrod modes` says that it
/// reports the symmetric part: conservative loads leave round-off
/// (~3e-14), world-frame moments and cables ~1e-6 (docs/performance.md).
const ASYMMETRY_NOTE: f64 = 1e-9;

type ModeCurves = (Vec<Vec<[f64; 3]>>, Vec<(f64, Vec<Vec<[f64; 3]>>)>);

pub fn modes(
    path: &Path,
    json: bool,
    count: usize,
    out: Option<PathBuf>,
    png: bool,
) -> Result<(), CliError> {
    let mut l = load(path)?;
    let analysis = l.sim.lowest_modes(count)?;
    let m = &analysis.modes;
    for w in &analysis.warnings {
        eprintln!("softrod: warning: {w}");
    }
    if let Some(dir) = &out {
        make_dir(dir)?;
        let q_eq = match &analysis.equilibrium {
            Equilibrium::Rest => vec![0.0; l.sim.n_dof()],
            Equilibrium::Statics(q) => q.as_slice().to_vec(),
        };
        let model = l.sim.model();
        let (eq, curves) = mode_curves(model, &q_eq, m, count.min(MODE_PLOTS))?;
        if !curves.is_empty() {
            let name = plots::modes_figure(dir, model, &eq, curves, &scene_title(path))?;
            if png {
                plots::rasterize(dir, std::slice::from_ref(&name), json)?;
            }
            if !json {
                println!("wrote {}", dir.join(name).display());
            }
        }
    }
    let equilibrium = match analysis.equilibrium {
        Equilibrium::Rest => "rest",
        Equilibrium::Statics(_) => "statics",
    };
    let f: Vec<f64> = m.frequencies_hz().into_iter().take(count).collect();
    if f.iter().any(|v| !v.is_finite()) {
        return Err(failed("modal analysis gave a non-finite frequency"));
    }
    // ω² < 0: the equilibrium is unstable along that mode, whose
    // "frequency" is imaginary, i·|f|: it grows like exp(2π|f| t). The
    // library reports such ω as −√|ω²|, hence negative entries; rigid
    // modes (|ω²| within the rigid tolerance) as exactly 0.
    let imaginary: Vec<f64> = m
        .frequencies_hz()
        .into_iter()
        .filter(|v| *v < 0.0)
        .map(f64::abs)
        .collect();
    let unstable = !imaginary.is_empty();
    if unstable {
        eprintln!(
            "softrod: warning: the equilibrium is unstable: {} mode(s) with ω² < 0 \
             (imaginary frequencies i·{} Hz, printed as negative numbers; such a mode grows \
             like exp(2π·f·t) instead of oscillating)",
            imaginary.len(),
            imaginary
                .iter()
                .map(|v| format!("{v:.6}"))
                .collect::<Vec<_>>()
                .join(", i·")
        );
    }
    if m.asymmetry > ASYMMETRY_NOTE {
        eprintln!(
            "softrod: note: the tangent stiffness is not symmetric (relative asymmetry {:.1e}: \
             follower loads, world-frame moments or cables are not conservative); these are the \
             frequencies of its symmetric part, and a non-symmetric linearization can flutter",
            m.asymmetry
        );
    }
    if json {
        println!(
            "{}",
            serde_json::json!({
                "frequencies_hz": f,
                "equilibrium": equilibrium,
                "unstable": unstable,
                "imaginary_frequencies_hz": imaginary,
                "rigid_modes": m.n_rigid(),
                "rigid_tolerance_omega2": m.rigid_tolerance,
                "asymmetry": m.asymmetry,
                "warnings": analysis.warnings,
            })
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
            if *v < 0.0 {
                println!(
                    "  mode {:>2}: i·{:.6} Hz (unstable: grows like exp(2π·{:.6}·t))",
                    i + 1,
                    -v,
                    -v
                );
            } else if *v == 0.0 {
                println!("  mode {:>2}: 0 Hz (rigid)", i + 1);
            } else {
                println!("  mode {:>2}: {v:.6} Hz", i + 1);
            }
        }
        let rigid = m.n_rigid();
        if rigid > 0 {
            println!(
                "rigid modes: {rigid} (|ω²| ≤ {:.3e} rad²/s², the round-off of the eigenproblem; \
                 a free body or joint that nothing holds: neutral, not unstable)",
                m.rigid_tolerance
            );
        }
        if !analysis.warnings.is_empty() {
            println!("warnings: {} (on stderr)", analysis.warnings.len());
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
