//! What `check` and `statics --json` say about joints and bodies
//! (scene-format.md, "Bodies, joints, bases and closures").

use softrod::record::WorldPoses;
use softrod_dynamics::{ElementKind, Model};

use crate::common::pose_json;

/// `check`: one line per joint with coordinates and per body.
pub fn print_elements(m: &Model) {
    if !m.is_articulated() {
        return;
    }
    for e in m.elements() {
        let j = &e.attachment.joint;
        let what = match e.kind {
            ElementKind::Rod(_) => "rod",
            ElementKind::Body(_) => "body",
        };
        let parent = e.attachment.parent.as_deref().unwrap_or("world");
        let at = e
            .attachment
            .at
            .map_or(String::new(), |s| format!(" at s = {s} m"));
        let dofs = if j.prescribed.is_some() {
            format!(
                ", prescribed: {} coordinates, not DoF (prescribed[{}..{}])",
                j.kind.dof(),
                e.prescribed_dofs.start,
                e.prescribed_dofs.end
            )
        } else if j.dof() > 0 {
            format!(
                ", {} DoF (q[{}..{}])",
                j.dof(),
                e.joint_dofs.start,
                e.joint_dofs.end
            )
        } else {
            String::new()
        };
        println!(
            "joint of {what} '{}': {} on '{parent}'{at}{dofs}",
            e.name,
            j.kind.name()
        );
    }
    for b in m.bodies() {
        let s = &b.spec;
        println!(
            "body '{}': mass {} kg, centre of mass [{}, {}, {}] m",
            s.name, s.mass, s.center_of_mass[0], s.center_of_mass[1], s.center_of_mass[2]
        );
    }
}

/// `statics --json`: `"bodies": [{name, position, rotation}]` and
/// `"joints": [{element, type, values}]` (`"prescribed": true` on a
/// prescribed joint, its values those at t = 0).
pub fn add_statics_json(m: &Model, poser: &WorldPoses, q: &[f64], v: &mut serde_json::Value) {
    if !m.is_articulated() {
        return;
    }
    let bodies: Vec<_> = m
        .bodies()
        .iter()
        .zip(poser.bodies())
        .map(|(b, p)| {
            let mut o = pose_json(p);
            o["name"] = serde_json::json!(b.spec.name);
            o
        })
        .collect();
    let joints: Vec<_> = m
        .elements()
        .iter()
        .map(|e| match &e.attachment.joint.prescribed {
            // Statics holds a prescribed joint at its value at t = 0, at rest.
            Some(p) => serde_json::json!({
                "element": e.name,
                "type": e.attachment.joint.kind.name(),
                "values": p.curves.iter().map(|c| c.eval(0.0).0).collect::<Vec<_>>(),
                "prescribed": true,
            }),
            None => serde_json::json!({
                "element": e.name,
                "type": e.attachment.joint.kind.name(),
                "values": &q[e.joint_dofs.clone()],
            }),
        })
        .collect();
    v["bodies"] = serde_json::json!(bodies);
    v["joints"] = serde_json::json!(joints);
}
