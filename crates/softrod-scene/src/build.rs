//! Building the physics model from a validated [`Scene`].
//!
//! [`build`] turns a scene into a `softrod_dynamics::Model` holding only the
//! terms the scene has (design.md: "leave out what a given scene does not
//! need"): no gravity term when gravity is zero, no drag term when both drag
//! coefficients are zero, no cables or loads unless the scene lists them, and
//! a strain basis with only the selected strains.

use nalgebra::{DVector, Matrix3, Vector3};
use softrod_dynamics::{Model, RodSpec};
use softrod_kinematics::{Basis, Rod as KinRod};
use softrod_lie::{Pose as LiePose, Vec6};
use softrod_mechanics as mech;

use crate::actuation::{LoadFrame, Routing, Tension};
use crate::error::SceneError;
use crate::rod::Section;
use crate::scene::Scene;

/// A model ready to simulate, with the scene's initial state.
#[derive(Clone, Debug)]
pub struct Built {
    /// The model (rods in scene order, `q` laid out rod by rod).
    pub model: Model,
    /// Initial coordinates (`[initial].q`, or the rest configuration, zeros).
    pub q0: DVector<f64>,
    /// Initial velocities (`[initial].qdot`, or zeros).
    pub qd0: DVector<f64>,
}

fn invalid(scene: &Scene, path: String, message: String) -> SceneError {
    SceneError::Invalid {
        file: scene.source.clone(),
        path,
        at: None,
        message,
    }
}

/// The mechanics section of a scene section.
pub fn section(s: &Section) -> mech::Section {
    match *s {
        Section::Circle { radius } => mech::Section::Circle { radius },
        Section::TaperedCircle {
            radius_base,
            radius_tip,
        } => mech::Section::TaperedCircle {
            radius_base,
            radius_tip,
        },
        Section::Tube {
            radius,
            inner_radius,
        } => mech::Section::Tube {
            radius,
            inner_radius,
        },
        Section::Rectangle { width, height } => mech::Section::Rectangle { width, height },
    }
}

/// The base pose of a scene rod as a `softrod_lie::Pose`.
pub fn base_pose(p: &crate::rod::Pose) -> LiePose {
    let r = p.rotation;
    LiePose::new(
        Matrix3::new(
            r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
        ),
        Vector3::from(p.position),
    )
}

/// Builds the model and the initial state of `scene`.
///
/// Errors (a model the physics layers reject although the scene validated)
/// are [`SceneError::Invalid`] with the key path of the offending rod, cable
/// or load.
pub fn build(scene: &Scene) -> Result<Built, SceneError> {
    let mut specs = Vec::with_capacity(scene.rods.len());
    for (i, r) in scene.rods.iter().enumerate() {
        let p = |k: &str| format!("rod[{i}].{k}");
        let basis = Basis::from_indices(&r.strains.indices())
            .map_err(|e| invalid(scene, p("strains"), e.to_string()))?;
        let rest = Vec6::from_row_slice(&r.rest_strain);
        let rod = KinRod::with_lengths(&r.piece_lengths, basis, rest, base_pose(&r.base))
            .map_err(|e| invalid(scene, p("pieces"), e.to_string()))?;
        let m = &r.material;
        let material = mech::Material::builder()
            .density(m.density)
            .young(m.young)
            .shear_modulus(m.shear_modulus)
            .viscosity(m.viscosity)
            .build()
            .map_err(|e| invalid(scene, p("material"), e.to_string()))?;
        let body = mech::RodBody::new(section(&r.section), material, rod.length())
            .map_err(|e| invalid(scene, p("section"), e.to_string()))?;
        let mut spec = RodSpec::new(r.name.clone(), rod, body);
        if r.drag.translational != 0.0 || r.drag.rotational != 0.0 {
            spec.drag = Some(mech::Drag {
                translational: r.drag.translational,
                rotational: r.drag.rotational,
            });
        }
        specs.push(spec);
    }
    for (j, c) in scene.cables.iter().enumerate() {
        let cable = mech::Cable {
            routing: match &c.routing {
                Routing::Offset([y, z]) => mech::Routing::Offset { y: *y, z: *z },
                Routing::Path(pts) => mech::Routing::Path(pts.clone()),
            },
            span: mech::Span::Between {
                from: c.from,
                to: c.to,
            },
            tension: match &c.tension {
                Tension::Constant(v) => mech::Tension::Constant(*v),
                Tension::Schedule { times, values } => mech::Tension::Table {
                    times: times.clone(),
                    values: values.clone(),
                },
            },
        };
        let len = specs[c.rod_index].rod.length();
        cable
            .validate(len)
            .map_err(|e| invalid(scene, format!("cable[{j}]"), e.to_string()))?;
        specs[c.rod_index].cables.push(cable);
    }
    for (j, l) in scene.loads.iter().enumerate() {
        let load = mech::PointLoad {
            s: l.s,
            force: Vector3::from(l.force),
            moment: Vector3::from(l.moment),
            frame: match l.frame {
                LoadFrame::World => mech::LoadFrame::World,
                LoadFrame::Body => mech::LoadFrame::Body,
            },
        };
        let spec = &specs[l.rod_index];
        spec.rod
            .locate(l.s)
            .map_err(|e| invalid(scene, format!("load[{j}].s"), e.to_string()))?;
        specs[l.rod_index].point_loads.push(load);
    }
    let gravity = scene
        .has_gravity()
        .then(|| Vector3::from(scene.world.gravity));
    let model = Model::new(specs, gravity, scene.run.quadrature).map_err(|e| {
        // Messages name the rod as "rod 'name': …"; find its index for the path.
        let msg = e.to_string();
        let path = scene
            .rods
            .iter()
            .position(|r| msg.contains(&format!("rod '{}'", r.name)))
            .map_or_else(String::new, |i| format!("rod[{i}]"));
        invalid(scene, path, msg)
    })?;
    let n = model.n_dof();
    let q0 = scene
        .initial
        .q
        .as_ref()
        .map_or_else(|| DVector::zeros(n), |v| DVector::from_column_slice(v));
    let qd0 = scene
        .initial
        .qdot
        .as_ref()
        .map_or_else(|| DVector::zeros(n), |v| DVector::from_column_slice(v));
    if q0.len() != n || qd0.len() != n {
        return Err(SceneError::InconsistentLengths {
            file: scene.source.clone(),
            path: "initial".into(),
            at: None,
            message: format!(
                "q has {}, qdot {} entries; the model has {n} coordinates",
                q0.len(),
                qd0.len()
            ),
        });
    }
    Ok(Built { model, q0, qd0 })
}

impl Scene {
    /// Builds the physics model and initial state (see [`build`]).
    pub fn build(&self) -> Result<Built, SceneError> {
        build(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
[[rod]]
name = "arm"
length = 0.5
pieces = 4
strains = ["ky", "qx", "qz"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }
"#;

    #[test]
    fn minimal_scene_has_only_inertia_and_elasticity() {
        let (scene, _) = Scene::from_str(BASE, "t.toml").unwrap();
        let b = scene.build().unwrap();
        assert_eq!(b.model.n_dof(), 12);
        assert_eq!(b.model.terms(), vec!["inertia", "elasticity"]);
        assert!(b.model.gravity.is_none());
        assert_eq!(b.q0.len(), 12);
    }

    #[test]
    fn terms_follow_the_scene() {
        let text = format!(
            "[world]\ngravity = [0, 0, -9.81]\n{BASE}drag = {{ translational = 0.1 }}\n\
             [[cable]]\nrod = \"arm\"\noffset = [0.0, 0.005]\ntension = 1.0\n\
             [[load]]\nrod = \"arm\"\ns = 0.5\nforce = [0, 0, -1]\nframe = \"body\"\n"
        );
        let (scene, _) = Scene::from_str(&text, "t.toml").unwrap();
        let b = scene.build().unwrap();
        let t = b.model.terms();
        for w in ["gravity", "cables", "point loads", "drag"] {
            assert!(t.iter().any(|x| x == w), "{w} missing from {t:?}");
        }
        assert!(!t.iter().any(|x| x == "damping"));
        let rm = &b.model.rods()[0];
        assert_eq!(rm.spec.cables.len(), 1);
        assert_eq!(rm.spec.point_loads[0].frame, mech::LoadFrame::Body);
    }

    #[test]
    fn base_rotation_is_row_major() {
        let p = crate::rod::Pose {
            position: [1.0, 2.0, 3.0],
            rotation: [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]],
        };
        let g = base_pose(&p);
        // Local x maps to world -z.
        let x = g.rotation * Vector3::new(1.0, 0.0, 0.0);
        assert!((x - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
        assert_eq!(g.translation, Vector3::new(1.0, 2.0, 3.0));
    }
}
