//! Building the physics model from a validated [`Scene`].
//!
//! The scene's rods already are the library's `Rod`s holding only the
//! terms the scene has (a term a scene does not need costs nothing): no drag term when both coefficients are zero, no cables or loads
//! unless the scene lists them, a strain basis with only the selected
//! strains. Building adds gravity (only when non-zero) and the quadrature.

use nalgebra::DVector;
use softrod_dynamics::{Data, Model, frames};
use softrod_kinematics::fit_centerline;
use softrod_lie::{Pose, Vec3};

use crate::error::SceneError;
use crate::keys;
use crate::reporter::Reporter;
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
    /// How well each `[initial] shape` was fitted, in the order given.
    pub shape_fits: Vec<ShapeFit>,
}

/// The fit of a rod's strains to its `[initial] shape` (least squares on
/// positions, `softrod_kinematics::fit_centerline`).
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeFit {
    /// The rod's name.
    pub rod: String,
    /// Root-mean-square distance of the fitted shape to the points \[m\].
    pub rms: f64,
    /// Largest distance to a point \[m\].
    pub max: f64,
}

impl Scene {
    /// Builds the physics model and initial state.
    ///
    /// The model checks its rods again (their fields are public and may
    /// have been changed since validation); its errors become
    /// [`SceneError`]s with the key path of the rod, cable or load, found
    /// from the error's rod index, and the model's error as source.
    pub fn build(&self) -> Result<Built, SceneError> {
        let r = Reporter::without_text(&self.source);
        let gravity = self.has_gravity().then(|| Vec3::from(self.world.gravity));
        let built = if self.robot.is_trivial() {
            let mut b = Model::builder()
                .rods(self.rods.iter().cloned())
                .quadrature(self.run.quadrature);
            if let Some(g) = gravity {
                b = b.gravity(g);
            }
            b.build()
        } else {
            Model::with_elements(
                self.robot.elements(&self.rods),
                gravity,
                self.run.quadrature,
            )
        };
        let model = built.map_err(|e| {
            let rod = e
                .rod()
                .and_then(|id| id.index)
                .and_then(|i| keys::rod_context(&self.rods, &self.origins, i));
            keys::dynamics(&r, rod, e)
        })?;
        let model = if self.robot.closures.is_empty() {
            model
        } else {
            model
                .with_closures(self.robot.closures.clone())
                .map_err(|e| self.closure_error(&r, e))?
        };
        // Only a scene with contact gets any (a model without pays nothing).
        let model = if self.has_contact() {
            model
                .with_contact(self.obstacles.clone(), self.contact)
                .map_err(|e| self.contact_error(&r, e))?
        } else {
            model
        };
        let n = model.n_dof();
        let initial = |v: &Option<Vec<f64>>| {
            v.as_ref()
                .map_or_else(|| DVector::zeros(n), |v| DVector::from_column_slice(v))
        };
        let (q0, qd0) = (initial(&self.initial.q), initial(&self.initial.qdot));
        if q0.len() != n || qd0.len() != n {
            return Err(r.inconsistent(
                "initial",
                format!(
                    "q has {}, qdot {} entries; the model has {n} coordinates",
                    q0.len(),
                    qd0.len()
                ),
            ));
        }
        let mut q0 = q0;
        let mut shape_fits = Vec::with_capacity(self.initial.shape.len());
        // Rods in model order, so a parent rod is fitted before the rods
        // that hang from it (their base poses follow from its strains).
        let mut shapes: Vec<_> = self.initial.shape.iter().enumerate().collect();
        shapes.sort_by_key(|(_, sh)| model.rods()[sh.rod].dof_offset);
        let mut fits = vec![None; shapes.len()];
        for (k, sh) in shapes {
            let path = format!("initial.shape[{k}]");
            let rm = &model.rods()[sh.rod];
            // The points in the frame the rod's kinematics works in.
            let to_local = if model.is_articulated() {
                let mut data = Data::new(&model);
                frames(&model, &mut data, q0.as_slice())
                    .map_err(|e| r.invalid(&path, format!("the rod's base pose: {e}")))?;
                data.rod_to_world(&model, sh.rod).inverse()
            } else {
                Pose::identity()
            };
            let targets: Vec<(f64, Vec3)> = sh
                .points
                .iter()
                .map(|(s, p)| (*s, to_local.transform_point(&Vec3::from(*p))))
                .collect();
            let range = rm.dofs();
            let fit = fit_centerline(&rm.spec.geometry, &targets, &q0.as_slice()[range.clone()])
                .map_err(|e| r.invalid(&path, format!("fitting the strains: {e}")))?;
            q0.as_mut_slice()[range].copy_from_slice(&fit.q);
            fits[k] = Some(ShapeFit {
                rod: rm.spec.name.clone(),
                rms: fit.rms,
                max: fit.max,
            });
        }
        shape_fits.extend(fits.into_iter().flatten());
        if model.has_closures() {
            // A closure must hold at the initial state (docs/theory.md D66;
            // docs/scene-format-extensions.md), after any shape fit: nothing
            // else assembles it.
            let mut data = Data::new(&model);
            softrod_dynamics::check_closures(&model, &mut data, q0.as_slice())
                .map_err(|e| self.closure_error(&r, e))?;
        }
        if model.has_contact() {
            // A rod may not start inside an obstacle (beyond the penetration
            // the contact law allows at rest), after any shape fit.
            model
                .check_initial_contact(q0.as_slice())
                .map_err(|e| self.overlap_error(&r, &model, q0.as_slice(), e))?;
        }
        Ok(Built {
            model,
            q0,
            qd0,
            shape_fits,
        })
    }

    /// A contact error of the model (an obstacle or the settings changed
    /// after validation) at the key path of its `[[obstacle]]` or `[contact]`.
    fn contact_error(&self, r: &Reporter, e: softrod_dynamics::DynamicsError) -> SceneError {
        use softrod_dynamics::DynamicsError as D;
        let path = match &e {
            D::Obstacle { index, .. } => format!("obstacle[{index}]"),
            D::ObstacleParent { index, .. } => format!("obstacle[{index}].parent"),
            D::ContactSettings { .. } => "contact".to_owned(),
            _ => "obstacle".to_owned(),
        };
        r.invalid(&path, &e).caused_by(Box::new(e.clone()))
    }

    /// An initial overlap: the error names the rod and `s`, what it
    /// overlaps and the depth; its key path is that obstacle's
    /// (`obstacle[k]`), or the rod's for rod–rod overlaps. The obstacle is
    /// found from the contacts at `q0`, not from the message.
    fn overlap_error(
        &self,
        r: &Reporter,
        model: &Model,
        q0: &[f64],
        e: softrod_dynamics::DynamicsError,
    ) -> SceneError {
        use softrod_mechanics::contact::Contactee;
        let zero = vec![0.0; q0.len()];
        let deepest = model.contacts(0.0, q0, &zero).ok().and_then(|cs| {
            cs.into_iter()
                .filter(|c| -c.gap > model.allowed_penetration(c.a, c.s))
                .max_by(|x, y| (-x.gap).total_cmp(&-y.gap))
        });
        let path = match deepest.map(|c| (c.a, c.b)) {
            Some((_, Contactee::Obstacle(k))) => format!("obstacle[{k}]"),
            Some((a, Contactee::Rod { .. })) => format!("rod[{a}]"),
            None => "initial".to_owned(),
        };
        let at_start = if self.initial.q.is_some() || !self.initial.shape.is_empty() {
            "the initial state"
        } else {
            "the rest shape"
        };
        r.invalid(
            &path,
            format!("{e} (in {at_start}; move it or the obstacle)"),
        )
        .caused_by(Box::new(e.clone()))
    }

    /// A closure error of the model, at the key path of its `[[closure]]`.
    fn closure_error(&self, r: &Reporter, e: softrod_dynamics::DynamicsError) -> SceneError {
        use softrod_dynamics::DynamicsError as D;
        let index = |name: &str| {
            self.robot
                .closures
                .iter()
                .position(|c| c.name == name)
                .unwrap_or(0)
        };
        let path = match &e {
            D::ClosureFrame { closure, end, .. } => format!("closure[{}].{end}", index(closure)),
            D::ClosureAxis { closure, .. } => format!("closure[{}].axis", index(closure)),
            D::ClosureNotHeld { closure, .. } => format!("closure[{}]", index(closure)),
            _ => "closure".to_owned(),
        };
        r.invalid(&path, &e).caused_by(Box::new(e.clone()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use softrod_mechanics::LoadFrame;

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
        assert!(b.model.gravity().is_none());
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
        assert_eq!(rm.spec.point_loads[0].frame, LoadFrame::Body);
    }

    /// A scene changed after validation is checked again by the model, and
    /// the error names the file's key path of the cable (found from the
    /// model's rod and cable indices, not from the message).
    #[test]
    fn model_errors_after_edits_name_the_file_keys() {
        let text = format!(
            "{BASE}[[rod]]\nname = \"b\"\nlength = 0.2\npieces = 1\n\
             section = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}\n\
             [[cable]]\nrod = \"b\"\noffset = [0.0, 0.005]\ntension = 1.0\n\
             [[cable]]\nrod = \"arm\"\noffset = [0.0, 0.005]\ntension = 1.0\n\
             [[cable]]\nrod = \"b\"\noffset = [0.0, 0.005]\ntension = 1.0\n"
        );
        let (mut scene, _) = Scene::from_str(&text, "t.toml").unwrap();
        scene.rods[1].cables[1].tension = softrod_mechanics::Tension::Constant(-3.0);
        let e = scene.build().unwrap_err();
        assert_eq!(e.path(), Some("cable[2].tension"), "{e}");
        assert!(e.to_string().contains("out of range: -3"), "{e}");
        let model_error = std::error::Error::source(&e).expect("chained");
        assert!(
            model_error
                .to_string()
                .starts_with("rod 1 ('b'), cable 1: ")
        );
        scene.rods[1].cables[1].tension = softrod_mechanics::Tension::Constant(1.0);
        scene.run.quadrature = 0;
        let e = scene.build().unwrap_err();
        assert_eq!(e.path(), Some("run.quadrature"), "{e}");
    }
}
