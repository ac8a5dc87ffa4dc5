//! What `check` says about contact (scene-format.md, "Contact: obstacles,
//! rods touching rods, friction"): one line per obstacle, the settings of
//! rod–rod contact and each rod's contact radius. The data are the scene's
//! (`Scene::obstacles`, `Scene::contact`, `Scene::contact_radius`); this
//! module only words them.

use softrod::mechanics::contact::{Obstacle, Shape};
use softrod_scene::Scene;

/// `[x, y, z]` with the shortest decimals that read back exactly.
fn v3(v: &softrod::lie::Vec3) -> String {
    format!("[{}, {}, {}]", v[0], v[1], v[2])
}

/// The geometry of an obstacle in words, in its carrier's frame.
pub fn shape_text(shape: &Shape) -> String {
    match shape {
        Shape::Plane { point, normal } => {
            format!("plane through {} m, normal {}", v3(point), v3(normal))
        }
        Shape::Sphere { center, radius } => {
            format!("sphere at {} m, radius {radius} m", v3(center))
        }
        Shape::Cylinder {
            point,
            axis,
            radius,
        } => format!(
            "cylinder (infinite) through {} m, axis {}, radius {radius} m",
            v3(point),
            v3(axis)
        ),
        Shape::Capsule {
            center,
            axis,
            length,
            radius,
        } => format!(
            "capsule at {} m, axis {}, length {length} m, radius {radius} m",
            v3(center),
            v3(axis)
        ),
        Shape::Box {
            center,
            rotation,
            half_extents,
        } => {
            let r = |i: usize| {
                format!(
                    "[{}, {}, {}]",
                    rotation[(i, 0)],
                    rotation[(i, 1)],
                    rotation[(i, 2)]
                )
            };
            format!(
                "box at {} m, half extents {} m, rotation [{}, {}, {}]",
                v3(center),
                v3(half_extents),
                r(0),
                r(1),
                r(2)
            )
        }
    }
}

fn obstacle_line(o: &Obstacle) -> String {
    let carrier = match &o.parent {
        Some(b) => format!("carried by body '{b}'"),
        None => "fixed in the world".to_owned(),
    };
    format!(
        "obstacle '{}': {}, {carrier}, friction {}, restitution {}",
        o.name,
        shape_text(&o.shape),
        o.friction,
        o.restitution
    )
}

/// `check`'s contact lines: nothing for a scene without contact.
pub fn print_contact(scene: &Scene) {
    if !scene.has_contact() {
        return;
    }
    for o in &scene.obstacles {
        println!("{}", obstacle_line(o));
    }
    let c = &scene.contact;
    let yes = |b: bool| if b { "yes" } else { "no" };
    println!(
        "contact between rods: different rods {}, a rod with itself {}, friction {}, restitution {}",
        yes(c.rods),
        yes(c.self_contact),
        c.friction,
        c.restitution
    );
    for (i, r) in scene.rods.iter().enumerate() {
        let length = r.properties.length();
        let (r0, r1) = (
            scene.contact_radius(i, 0.0),
            scene.contact_radius(i, length),
        );
        let radius = if r0 == r1 {
            format!("{r0} m")
        } else {
            format!("{r0} m at the base to {r1} m at the tip")
        };
        println!("contact radius of rod '{}': {radius}", r.name);
    }
}

/// `statics --json`'s `contacts` entries (scene-format.md, "Contact"): `a`
/// and `s`, `b` (an obstacle's or a rod's name) and `b_s` (null for an
/// obstacle), `point`, `normal` (from b to a), `gap`, `force` (on `a`,
/// world); and `max_penetration`, the largest `−gap` (0 if none).
pub fn contacts_json(
    model: &softrod::dynamics::Model,
    contacts: &[softrod::mechanics::ContactPoint],
) -> (serde_json::Value, f64) {
    use softrod::mechanics::Contactee;
    let v3 = |v: &softrod::lie::Vec3| [v[0], v[1], v[2]];
    let entries: Vec<serde_json::Value> = contacts
        .iter()
        .map(|c| {
            let (b, b_s) = match c.b {
                Contactee::Obstacle(k) => (model.obstacles()[k].name.clone(), None),
                Contactee::Rod { rod, s } => (model.rods()[rod].spec.name.clone(), Some(s)),
            };
            serde_json::json!({
                "a": model.rods()[c.a].spec.name,
                "s": c.s,
                "b": b,
                "b_s": b_s,
                "point": v3(&c.point),
                "normal": v3(&c.normal),
                "gap": c.gap,
                "force": v3(&c.force),
            })
        })
        .collect();
    let deepest = contacts.iter().fold(0.0, |m, c| f64::max(m, -c.gap));
    (serde_json::json!(entries), deepest)
}

/// An obstacle's shape as the viewer's plain data (the scene's keys).
pub fn viz_shape(shape: &Shape) -> softrod_viz::ObstacleShape {
    use softrod_viz::ObstacleShape as V;
    let a = |v: &softrod::lie::Vec3| [v[0], v[1], v[2]];
    match shape {
        Shape::Plane { point, normal } => V::Plane {
            position: a(point),
            normal: a(normal),
        },
        Shape::Sphere { center, radius } => V::Sphere {
            position: a(center),
            radius: *radius,
        },
        Shape::Cylinder {
            point,
            axis,
            radius,
        } => V::Cylinder {
            position: a(point),
            axis: a(axis),
            radius: *radius,
        },
        Shape::Capsule {
            center,
            axis,
            length,
            radius,
        } => V::Capsule {
            position: a(center),
            axis: a(axis),
            length: *length,
            radius: *radius,
        },
        Shape::Box {
            center,
            rotation,
            half_extents,
        } => V::Box {
            position: a(center),
            rotation: [0, 1, 2].map(|i| [rotation[(i, 0)], rotation[(i, 1)], rotation[(i, 2)]]),
            half_extents: a(half_extents),
        },
    }
}

/// The model's obstacles for a figure of snapshots whose bodies have the
/// poses `body_poses[k]` (model order): a carried obstacle gets its body's
/// pose at each snapshot.
pub fn obstacle_tracks(
    model: &softrod::dynamics::Model,
    body_poses: &[&[softrod_viz::Pose]],
) -> Vec<softrod_viz::ObstacleTrack> {
    model
        .obstacles()
        .iter()
        .map(|o| {
            let body = o
                .parent
                .as_ref()
                .and_then(|p| model.bodies().iter().position(|b| &b.spec.name == p));
            softrod_viz::ObstacleTrack {
                name: o.name.clone(),
                shape: viz_shape(&o.shape),
                poses: body.map(|b| body_poses.iter().map(|poses| poses[b]).collect()),
            }
        })
        .collect()
}
