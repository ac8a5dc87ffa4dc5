//! What `run` would refuse or fail at its start, found when the scene is
//! read, in the same words (issue 26): the validity of the rest and
//! initial strains (`softrod_mechanics::validity`, the rules a run's watch
//! applies at every step), the fit of `[initial] shape` (its residual and
//! the strains it gives), and closures that hold nothing.

use softrod_dynamics::{Data, Model, constraint_rank};
use softrod_mechanics::validity::{StrainFinding, StrainProblem, strain_validity};

use super::{Ctx, Result};
use crate::scene::Scene;

/// A fitted shape farther than this fraction of the rod's length from one
/// of its points is warned about (the points need more pieces, other
/// strains, or another spacing in arc length).
pub(crate) const SHAPE_FIT_WARN: f64 = 0.01;

impl Ctx<'_> {
    /// The rest shape of rod `i` (`q = 0`): shear beyond the model's
    /// validity or a bending radius below the section's half size (the
    /// centre of curvature inside the section) warn at `rod[i].rest_strain`.
    /// A rest stretch outside `1 ± 0.5` has its own warning, and one ≤ 0 is
    /// an error (`check_rest_stretch`).
    pub(super) fn warn_rest_validity(&mut self, i: usize, spec: &softrod_dynamics::Rod) {
        let zeros = vec![0.0; spec.geometry.n_dof()];
        let v = strain_validity(&spec.geometry, spec.properties.section(), &zeros);
        let shear_only = |f: &StrainFinding| match f.problem {
            StrainProblem::Strain { shear, .. } => shear > softrod_mechanics::validity::SHEAR_LIMIT,
            _ => true,
        };
        for f in [v.strain, v.curvature].into_iter().flatten() {
            if shear_only(&f) {
                self.warn(
                    &format!("rod[{i}].rest_strain"),
                    format!("{} at rest: rod {:?} {f}", f.headline(), spec.name),
                );
            }
        }
    }

    /// The initial state as `run` starts it: closures that hold nothing
    /// are errors; the shape fits' residuals and every strain beyond the
    /// model's validity (a folded piece, which fails the run at once,
    /// among them) are warnings.
    pub(super) fn check_start(&mut self, scene: &Scene) -> Result<()> {
        self.closures_hold_something(scene)?;
        let needs_model = !scene.initial.shape.is_empty() || !scene.robot.closures.is_empty();
        let q0: Vec<f64> = if needs_model {
            // The model does the fits (a rod's base may hang from another's
            // fitted tip). A scene whose model cannot be built is refused by
            // `Scene::build`, where that error has always been reported.
            let Ok(built) = scene.build() else {
                return Ok(());
            };
            self.closure_ranks(scene, &built.model, built.q0.as_slice())?;
            for (k, (sh, fit)) in scene
                .initial
                .shape
                .iter()
                .zip(&built.shape_fits)
                .enumerate()
            {
                let length = scene.rods[sh.rod].geometry.length();
                if fit.max.is_nan() || fit.max > SHAPE_FIT_WARN * length {
                    self.warn(
                        &format!("initial.shape[{k}].centerline"),
                        format!(
                            "the fitted shape of rod {:?} passes {:.3e} m from a point (rms \
                             {:.3e} m), more than {}% of its length: its pieces and strains \
                             cannot take this shape (more pieces, other strains such as \
                             stretch qx, or another spacing in arc length may)",
                            fit.rod,
                            fit.max,
                            fit.rms,
                            100.0 * SHAPE_FIT_WARN
                        ),
                    );
                }
            }
            built.q0.as_slice().to_vec()
        } else if let Some(q) = &scene.initial.q {
            q.clone()
        } else {
            // At rest: `warn_rest_validity` said it all.
            return Ok(());
        };
        for (i, spec) in scene.rods.iter().enumerate() {
            let off = scene.rod_dof_offset(i);
            let q = &q0[off..off + spec.geometry.n_dof()];
            let v = strain_validity(&spec.geometry, spec.properties.section(), q);
            let rest = strain_validity(
                &spec.geometry,
                spec.properties.section(),
                &vec![0.0; spec.geometry.n_dof()],
            );
            let shape = scene.initial.shape.iter().position(|s| s.rod == i);
            let path = |f: &StrainFinding| match shape {
                Some(k) => format!("initial.shape[{k}]"),
                None => format!("initial.q[{}]", off + coordinate(spec, f)),
            };
            if let Some(f) = v.folded {
                self.warn(
                    &path(&f),
                    format!(
                        "{} in the initial state: rod {:?} {f}: the piece is inverted, and \
                         `run` fails at its start",
                        f.headline(),
                        spec.name
                    ),
                );
                continue;
            }
            let mut found = false;
            for (f, at_rest) in [(v.strain, rest.strain), (v.curvature, rest.curvature)] {
                // What the rest shape has already was said at rod[i].rest_strain.
                if let Some(f) = f
                    && at_rest.is_none_or(|r| r.piece != f.piece)
                {
                    found = true;
                    self.warn(
                        &path(&f),
                        format!(
                            "{} in the initial state: rod {:?} {f}",
                            f.headline(),
                            spec.name
                        ),
                    );
                }
            }
            if !found && shape.is_none() {
                self.warn_large_turn(q, off, spec);
            }
        }
        Ok(())
    }

    /// A closure whose two frames are one (the same element, place and
    /// offset) holds nothing: an error naming it.
    fn closures_hold_something(&self, scene: &Scene) -> Result<()> {
        for (i, c) in scene.robot.closures.iter().enumerate() {
            let (a, b) = (&c.a, &c.b);
            if a.element != b.element {
                continue;
            }
            let rod = scene.rods.iter().find(|r| r.name == a.element);
            let place = |at: Option<f64>| match rod {
                Some(r) => at.unwrap_or(r.geometry.length()),
                None => 0.0,
            };
            let same_place = (place(a.at) - place(b.at)).abs() <= 1e-12 * (1.0 + place(a.at));
            let same_offset = (a.base.rotation - b.base.rotation).amax() <= 1e-12
                && (a.base.translation - b.base.translation).amax() <= 1e-12;
            if same_place && same_offset {
                let where_ = match rod {
                    Some(_) if a.at.is_none() => format!("rod {:?} at its tip", a.element),
                    Some(_) => format!("rod {:?} at s = {} m", a.element, place(a.at)),
                    None => format!("{:?}", a.element),
                };
                return Err(self.r.invalid(
                    &format!("closure[{i}]"),
                    format!(
                        "closure {:?} holds a frame to itself (a and b are both {where_} with \
                         the same offset): it has 0 independent constraints",
                        c.name
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Each closure alone must constrain something at the initial state:
    /// one whose frames cannot move apart (a tip welded to a child clamped
    /// there, a base welded where it is clamped) has a constraint Jacobian
    /// of rank 0 and holds nothing.
    fn closure_ranks(&self, scene: &Scene, model: &Model, q0: &[f64]) -> Result<()> {
        if scene.robot.closures.is_empty() {
            return Ok(());
        }
        let gravity = model.gravity();
        for (i, c) in scene.robot.closures.iter().enumerate() {
            let Ok(open) = Model::with_elements(
                scene.robot.elements(&scene.rods),
                gravity,
                scene.run.quadrature,
            ) else {
                return Ok(());
            };
            let Ok(one) = open.with_closures(vec![c.clone()]) else {
                continue;
            };
            let mut data = Data::new(&one);
            if let Ok(0) = constraint_rank(&one, &mut data, q0) {
                return Err(self.r.invalid(
                    &format!("closure[{i}]"),
                    format!(
                        "closure {:?} has 0 independent constraints at the initial state: its \
                         frames a and b cannot move apart, so it holds nothing",
                        c.name
                    ),
                ));
            }
        }
        Ok(())
    }

    /// `initial.q` bending or twisting a piece by more than π: legal, but
    /// rarely meant (a coordinate in degrees, a misplaced value).
    fn warn_large_turn(&mut self, q: &[f64], off: usize, spec: &softrod_dynamics::Rod) {
        for (k, piece) in spec.geometry.pieces().iter().enumerate() {
            let Some(sel) = piece.basis.selection() else {
                continue;
            };
            let l = piece.length;
            for (c, &j) in sel.iter().enumerate() {
                let at = piece.dof_offset + c;
                let xi = piece.rest_strain[j] + q[at];
                if j < 3 && (xi * l).abs() > std::f64::consts::PI {
                    let name = softrod_kinematics::Strain::ALL[j].name();
                    self.warn(
                        &format!("initial.q[{}]", off + at),
                        format!(
                            "rod {:?}: {name} = {xi} 1/m turns piece {k} ({l} m) by {:.2} rad, \
                             more than π",
                            spec.name,
                            (xi * l).abs()
                        ),
                    );
                    return;
                }
            }
        }
    }
}

/// The coordinate of the rod (its own index) a finding is about: the
/// stretch or shear one for a strain, a bending one for a curvature, when
/// the piece has it; else the piece's first.
fn coordinate(spec: &softrod_dynamics::Rod, f: &StrainFinding) -> usize {
    let piece = &spec.geometry.pieces()[f.piece];
    let wanted: &[usize] = match f.problem {
        StrainProblem::Folded { .. } => &[3],
        StrainProblem::Strain { .. } => &[3, 4, 5],
        StrainProblem::Curvature { .. } => &[1, 2],
    };
    let c = piece
        .basis
        .selection()
        .and_then(|sel| sel.iter().position(|j| wanted.contains(j)))
        .unwrap_or(0);
    piece.dof_offset + c
}
