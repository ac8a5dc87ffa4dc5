//! `softrod inverse SCENE [--json]`: the cable tensions that bring the
//! scene's `[[target]]` sections and bodies closest to their targets, within each
//! cable's `max_tension` (inverse statics, docs/theory-control.md).

use std::path::Path;

use softrod::control::{ActuationOptions, Target};

use crate::common::{CliError, failed, load, pose_json};

pub fn inverse(path: &Path, json: bool) -> Result<(), CliError> {
    let mut l = load(path)?;
    if l.scene.targets.is_empty() {
        return Err(CliError::Input(format!(
            "{}: target: the scene has no [[target]] (softrod inverse needs at least one)",
            l.scene.source
        )));
    }
    if l.sim.n_cables() == 0 {
        return Err(CliError::Input(format!(
            "{}: cable: the scene has no [[cable]] to solve for",
            l.scene.source
        )));
    }
    let targets: Vec<Target> = l
        .scene
        .targets
        .iter()
        .map(|t| Target {
            rod: t.rod,
            s: t.s,
            body: t.body,
            position: t.position,
            rotation: t.rotation,
            weight: t.weight,
        })
        .collect();
    let bounds = l.scene.max_tensions();
    let options = ActuationOptions {
        max_tension: bounds.iter().map(|b| b.1).collect(),
        ..ActuationOptions::default()
    };
    let a = l.sim.solve_actuation(&targets, &options)?;
    if a.tensions.iter().chain(a.q.iter()).any(|v| !v.is_finite()) {
        return Err(failed("inverse statics returned a non-finite state"));
    }
    let model = l.sim.model();
    // Cables in the model's order (rod by rod), named by their file index.
    let rod_of: Vec<&str> = model
        .rods()
        .iter()
        .flat_map(|r| r.spec.cables.iter().map(|_| r.spec.name.as_str()))
        .collect();
    let cables: Vec<serde_json::Value> = bounds
        .iter()
        .zip(&rod_of)
        .zip(a.tensions.iter().zip(&a.bounds))
        .map(|(((j, max), rod), (t, b))| {
            serde_json::json!({
                "cable": j,
                "rod": rod,
                "tension": t,
                "max_tension": if max.is_finite() { serde_json::json!(max) } else { serde_json::Value::Null },
                "bound": b.name(),
            })
        })
        .collect();
    let target_json: Vec<serde_json::Value> = l
        .scene
        .targets
        .iter()
        .zip(&a.residuals)
        .map(|(t, r)| {
            serde_json::json!({
                "element": t.element,
                // A body's target is its frame: no arc length.
                "s": if t.body.is_some() { serde_json::Value::Null } else { serde_json::json!(t.s) },
                "target": {
                    "position": t.position.map(|p| [p.x, p.y, p.z]),
                    "rotation": t.rotation.map(|m| (0..3).map(|i| [m[(i, 0)], m[(i, 1)], m[(i, 2)]]).collect::<Vec<_>>()),
                },
                "reached": pose_json(&softrod::lie::Pose { rotation: r.rotation, translation: r.position }),
                "position_error": r.position_error,
                "rotation_error": r.rotation_error,
            })
        })
        .collect();
    let rods: Vec<serde_json::Value> = model
        .rods()
        .iter()
        .enumerate()
        .map(|(i, r)| {
            l.sim
                .tip_pose(i, a.q.as_slice())
                .map(|p| serde_json::json!({ "name": r.spec.name, "tip": pose_json(&p) }))
        })
        .collect::<Result<_, _>>()?;
    if json {
        let v = serde_json::json!({
            "converged": a.converged,
            "reached": a.reached,
            "message": a.message,
            "iterations": a.iterations,
            "statics_iterations": a.statics_iterations,
            "residual": a.target_error,
            "cost": a.cost,
            "tensions": a.tensions.as_slice(),
            "cables": cables,
            "targets": target_json,
            "q": a.q.as_slice(),
            "rods": rods,
        });
        println!("{v}");
    } else {
        println!("{}", a.message);
        println!(
            "{} Gauss-Newton iterations ({} statics Newton iterations)",
            a.iterations, a.statics_iterations
        );
        for c in &cables {
            println!(
                "cable[{}] on {}: tension {:.6e} N ({})",
                c["cable"],
                c["rod"].as_str().unwrap_or(""),
                c["tension"].as_f64().unwrap_or(f64::NAN),
                c["bound"].as_str().unwrap_or("")
            );
        }
        for (t, r) in l.scene.targets.iter().zip(&a.residuals) {
            let p = r.position;
            if t.body.is_some() {
                print!(
                    "target on body {}: frame at ({:.6}, {:.6}, {:.6}) m",
                    t.element, p.x, p.y, p.z
                );
            } else {
                print!(
                    "target on {} at s = {}: section at ({:.6}, {:.6}, {:.6}) m",
                    t.element, t.s, p.x, p.y, p.z
                );
            }
            if t.position.is_some() {
                print!(", position error {:.3e} m", r.position_error);
            }
            if t.rotation.is_some() {
                print!(", rotation error {:.3e} rad", r.rotation_error);
            }
            println!();
        }
        println!("weighted residual {:.3e}", a.target_error);
    }
    if !a.converged {
        return Err(failed(format!(
            "inverse statics did not converge: {}",
            a.message
        )));
    }
    Ok(())
}
