//! Energies (docs/theory.md §7).

use crate::algorithms::tree::outward;
use crate::algorithms::{Motion, Pass, check_vec};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::kernels::planar::{Pose2, maps};
use crate::model::data::Data;
use crate::model::tree::{NodeKind, Tree};
use crate::model::{Model, RodModel};
use softrod_lie::{PieceMaps, Vec3, Vec6, exp_and_tangent_minus, exp_twist};
use softrod_mechanics::elastic_energy;

/// Mechanical energies of the model at `(q, q̇)` \[J\].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energies {
    /// `½ q̇ᵀ M q̇ = ½ ∫ ηᵀ𝓜η ds` (same quadrature as `M`).
    pub kinetic: f64,
    /// `½ Σ_n ∫ (ξ_n − ξ*_n)ᵀ Γ (ξ_n − ξ*_n) ds`.
    pub elastic: f64,
    /// `−∫ ρA g_w·p(s) ds` (zero without gravity).
    pub gravitational: f64,
}

impl Energies {
    /// `kinetic + elastic + gravitational`: conserved without damping,
    /// drag, actuation and non-conservative loads.
    pub fn total(&self) -> f64 {
        self.kinetic + self.elastic + self.gravitational
    }
}

/// Kinetic, elastic and gravitational energy at `(q, q̇)` (dim n_dof each).
/// Uses the model's quadrature; O(N). `data` is not modified except as scratch.
/// With prescribed joints (D59) the configuration and the kinetic energy
/// include their motion at the time of the last [`Model::set_time`] or
/// dynamics evaluation.
pub fn energies(
    model: &Model,
    _data: &mut Data,
    q: &[f64],
    qd: &[f64],
) -> Result<Energies, DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    if let Some(tree) = &model.tree {
        return Ok(tree_energies(model, tree, _data, q, qd));
    }
    let mut e = Energies::default();
    for (r, rm) in model.rods().iter().enumerate() {
        let rod = &rm.spec.geometry;
        let range = rm.dofs();
        let qr = &q[range.clone()];
        let qdr = &qd[range];
        e.elastic += elastic_energy(
            rod,
            &rm.spec.properties,
            rm.spec.stress_free.as_deref(),
            qr,
            &model.quadrature,
        );
        if model.uses_planar_path(r) {
            let (kinetic, gravitational) = planar_rod_energies(model, rm, qr, qdr);
            e.kinetic += kinetic;
            e.gravitational += gravitational;
            continue;
        }
        let mut pose = *rod.base();
        let mut eta0 = Vec6::zeros();
        for (piece, pd) in rod.pieces().iter().zip(&rm.pieces) {
            let xi = piece.strain(qr);
            let dxi = piece.strain_rate(qdr);
            for qp in &pd.points {
                let (gl, tm) = exp_and_tangent_minus(qp.x, &xi);
                let eta = gl.ad_inv().mul_vec(&eta0) + tm.mul_vec(&dxi);
                e.kinetic += 0.5 * qp.w * eta.dot(&qp.inertia.component_mul(&eta));
                if let Some(g) = model.gravity {
                    let p = pose.transform_point(&gl.translation);
                    e.gravitational -= qp.w * qp.mass_per_length * g.dot(&p);
                }
            }
            let (gl, tm) = exp_and_tangent_minus(piece.length, &xi);
            eta0 = gl.ad_inv().mul_vec(&eta0) + tm.mul_vec(&dxi);
            pose = pose.compose(&exp_twist(piece.length, &xi));
        }
    }
    Ok(e)
}

/// Kinetic and gravitational energy of a rod on the planar path (D71):
/// the same quadrature and the same integrands as the general loop of
/// [`energies`], with twists in `P` and the planar maps (D72–D74), which
/// cost a fraction of the six-strain exponential and tangent at each
/// point. The terms dropped are exactly zero: `η` has no component in `P⊥`
/// (D71).
fn planar_rod_energies(model: &Model, rm: &RodModel, qr: &[f64], qdr: &[f64]) -> (f64, f64) {
    let Some(pr) = &rm.planar else {
        unreachable!("the planar path runs planar rods only")
    };
    let rod = &rm.spec.geometry;
    let base = rod.base();
    let (b, c) = ((pr.axis + 1) % 3, (pr.axis + 2) % 3);
    let (mut kinetic, mut gravitational) = (0.0, 0.0);
    let mut pose = Pose2::IDENTITY;
    let mut eta0 = Vec3::zeros();
    let pieces = rod.pieces().iter().zip(&rm.pieces).zip(&pr.pieces);
    for ((piece, pd), pp) in pieces {
        let xi = pr.gather(&piece.strain(qr));
        let dxi = pr.gather(&piece.strain_rate(qdr));
        for (qp, m) in pd.points.iter().zip(&pp.inertia) {
            let (gl, tm, _) = maps(&xi, &dxi, qp.x, false);
            let eta = gl.ad_inv_vec(&eta0) + tm * dxi;
            kinetic += 0.5 * qp.w * eta.dot(&m.component_mul(&eta));
            if let Some(g) = model.gravity {
                let local = pose.compose(&gl).p;
                let mut p = Vec3::zeros();
                p[b] = local[0];
                p[c] = local[1];
                gravitational -= qp.w * qp.mass_per_length * g.dot(&base.transform_point(&p));
            }
        }
        let (gl, tm, _) = maps(&xi, &dxi, piece.length, false);
        eta0 = gl.ad_inv_vec(&eta0) + tm * dxi;
        pose = pose.compose(&gl);
    }
    (kinetic, gravitational)
}

/// Energies on the tree: kinetic `½q̇ᵀMq̇`, elastic (rods and joint
/// springs), gravitational (rod points and bodies' centres of mass).
fn tree_energies(model: &Model, tree: &Tree, data: &mut Data, q: &[f64], qd: &[f64]) -> Energies {
    // Kinetic energy point by point (D59: it includes the prescribed
    // joints' motion, which `½q̇ᵀMq̇` would miss); the poses of this pass
    // serve the gravitational energy below.
    let kinetic = outward(
        model,
        tree,
        data,
        Motion::new(q, Some(qd), None),
        Pass::Inverse,
        Forces::ALL,
    );
    let mut e = Energies {
        kinetic,
        ..Energies::default()
    };
    for rm in model.rods() {
        e.elastic += elastic_energy(
            &rm.spec.geometry,
            &rm.spec.properties,
            rm.spec.stress_free.as_deref(),
            &q[rm.dofs()],
            &model.quadrature,
        );
    }
    for el in &model.elements {
        for (i, o) in el.joint_dofs.clone().enumerate() {
            let (k, _, rest) = el.attachment.joint.coefficients(i);
            e.elastic += 0.5 * k * (q[o] - rest).powi(2);
        }
    }
    if let Some(g) = model.gravity {
        for (i, node) in tree.nodes.iter().enumerate() {
            let base = &data.nodes[i].base_world;
            match node.kind {
                NodeKind::Piece { rod, piece } => {
                    let rm = &model.rods[rod];
                    let pc = &rm.spec.geometry.pieces()[piece];
                    let maps = PieceMaps::new(&pc.strain(&q[rm.dofs()]), None);
                    for qp in &rm.pieces[piece].points {
                        let p = base.transform_point(&maps.exp(qp.x).translation);
                        e.gravitational -= qp.w * qp.mass_per_length * g.dot(&p);
                    }
                }
                NodeKind::Body { body } => {
                    let b = &model.bodies[body].spec;
                    let p = base.transform_point(&b.center_of_mass);
                    e.gravitational -= b.mass * g.dot(&p);
                }
                NodeKind::Joint { .. } => {}
            }
        }
    }
    e
}
