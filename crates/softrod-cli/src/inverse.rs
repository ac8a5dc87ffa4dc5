//! `softrod inverse SCENE [--json]`: the cable tensions, actuated joints'
//! forces and unknown point loads that bring the scene's `[[target]]`
//! sections and bodies closest to their targets, within each cable's
//! `max_tension`, each actuator's and unknown load's `max_force` (inverse
//! statics, docs/theory-control.md IS1–IS14).

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
    if l.sim.n_cables() == 0
        && l.sim.model().n_joint_inputs() == 0
        && l.scene.unknown_loads.is_empty()
    {
        return Err(CliError::Input(format!(
            "{}: cable: the scene has no [[cable]], no joint with an actuator and no [[load]] with \
             unknown = true to solve for",
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
        unknown_loads: l.sim.scene_unknown_loads().to_vec(),
        ..ActuationOptions::default()
    };
    let a = l.sim.solve_actuation(&targets, &options)?;
    if a.tensions
        .iter()
        .chain(a.q.iter())
        .chain(&a.joint_forces)
        .chain(a.forces.iter().flat_map(|f| f.iter()))
        .any(|v| !v.is_finite())
    {
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
    let bound_or_null = |m: f64| {
        if m.is_finite() {
            serde_json::json!(m)
        } else {
            serde_json::Value::Null
        }
    };
    let loads: Vec<serde_json::Value> = l
        .scene
        .unknown_loads
        .iter()
        .zip(a.forces.iter().zip(&a.force_bounds))
        .map(|(u, (f, b))| {
            serde_json::json!({
                "load": u.load,
                "rod": model.rods()[u.rod].spec.name,
                "s": u.s,
                "force": [f.x, f.y, f.z],
                "max_force": u.max_force.map(bound_or_null),
                "bounds": b.map(|x| x.name()),
            })
        })
        .collect();
    let joints: Vec<serde_json::Value> = model
        .elements()
        .iter()
        .filter_map(|e| e.attachment.joint.actuator.as_ref().map(|act| (e, act)))
        .map(|(e, act)| {
            let r = e.actuator_inputs.clone();
            serde_json::json!({
                "element": e.name,
                "type": e.attachment.joint.kind.name(),
                "forces": &a.joint_forces[r.clone()],
                "max_force": (0..r.len()).map(|i| bound_or_null(act.bound(i))).collect::<Vec<_>>(),
                "bounds": a.joint_force_bounds[r].iter().map(|b| b.name()).collect::<Vec<_>>(),
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
            "joint_forces": a.joint_forces,
            "joints": joints,
            "loads": loads,
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
        for j in &joints {
            println!(
                "joint of {} ({}): forces {} N or N m ({})",
                j["element"].as_str().unwrap_or(""),
                j["type"].as_str().unwrap_or(""),
                j["forces"],
                j["bounds"]
            );
        }
        for ld in &loads {
            println!(
                "load[{}] on {} at s = {}: force {} N ({})",
                ld["load"],
                ld["rod"].as_str().unwrap_or(""),
                ld["s"],
                ld["force"],
                ld["bounds"]
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
