//! The rows of the loop closures (docs/theory.md §11, D63–D66): their
//! residual `φ(q)`, the constraint Jacobian `J = ∂φ/∂q` and the
//! velocity-product term `J̇q̇`, from the frames' world twists on the tree
//! (the spatial columns `Ad_{g_world} S` of every ancestor node and the
//! in-piece column at the frame's arc length).

use crate::algorithms::Motion;
use crate::algorithms::frames::{
    FrameState, RowBlock, add_frame_columns, frame_state, parent_column,
};
use crate::model::Model;
use crate::model::closure::{ClosureKind, ResolvedClosure};
use crate::model::data::{ConstraintRows, Data};
use crate::model::tree::Tree;
use nalgebra::DMatrix;
use softrod_lie::{Mat3, Mat6, Vec3, Vec6, skew};

/// Rotation vector `r` of a rotation matrix (`R = exp(r̂)`, |r| ≤ π),
/// accurate to round-off near the identity (where the closures hold): the
/// angle from `atan2(|w|, c)` with `ŵ = (R − Rᵀ)/2`, `c = (tr R − 1)/2`, not
/// from `acos c`, which loses half the digits there.
pub(crate) fn rotation_vector(r: &Mat3) -> Vec3 {
    let w = Vec3::new(
        0.5 * (r[(2, 1)] - r[(1, 2)]),
        0.5 * (r[(0, 2)] - r[(2, 0)]),
        0.5 * (r[(1, 0)] - r[(0, 1)]),
    );
    let c = 0.5 * (r.trace() - 1.0);
    let s = w.norm();
    let th = s.atan2(c);
    if c > -0.9 {
        // θ/sin θ, by its series where sin θ is tiny.
        let f = if s < 1e-6 {
            1.0 + th * th / 6.0
        } else {
            th / s
        };
        return w * f;
    }
    // Near π: the axis from the symmetric part (R + Rᵀ)/2 − c I = (1 − c) a aᵀ.
    let sym = (r + r.transpose()) * 0.5 - Mat3::identity() * c;
    let k = (0..3)
        .max_by(|&i, &j| sym[(i, i)].total_cmp(&sym[(j, j)]))
        .expect("three columns");
    let mut a = sym.column(k).into_owned().normalize();
    if a.dot(&w) < 0.0 {
        a = -a;
    }
    a * th
}

/// `J_l(r)⁻¹`, the inverse left Jacobian of SO(3) (D64): `ṙ = J_l⁻¹ u`
/// when `Ṙ Rᵀ = û`.
pub(crate) fn left_jacobian_inv(r: &Vec3) -> Mat3 {
    let th2 = r.norm_squared();
    let rh = skew(r);
    let c = if th2 < 1e-8 {
        // Series of 1/θ² − (1 + cos θ)/(2θ sin θ).
        1.0 / 12.0 + th2 / 720.0
    } else {
        let th = th2.sqrt();
        1.0 / th2 - (1.0 + th.cos()) / (2.0 * th * th.sin())
    };
    Mat3::identity() - rh * 0.5 + rh * rh * c
}

/// Per closure, the residual `φ` (rows into `phi`), the row operator `C`
/// (m×6, padded to 6×6) with `φ̇ = C (V_a − V_b)` (exact rows when `exact`,
/// else the velocity rows with `u = R_bᵀΔω` for the rotation) and the
/// velocity-product `J̇q̇` of the velocity rows (D64–D65).
pub(crate) struct ClosureRows {
    pub c: Mat6,
    pub phi: Vec6,
    pub jdot_qd: Vec6,
}

pub(crate) fn closure_rows(
    rc: &ResolvedClosure,
    fa: &FrameState,
    fb: &FrameState,
    exact: bool,
) -> ClosureRows {
    let (ra, pa) = (fa.pose.rotation, fa.pose.translation);
    let (rb, pb) = (fb.pose.rotation, fb.pose.translation);
    let rbt = rb.transpose();
    let d = rbt * (pa - pb);
    let dw = fa.vel - fb.vel;
    let da = fa.acc - fb.acc;
    let (dom, dv) = (
        Vec3::new(dw[0], dw[1], dw[2]),
        Vec3::new(dw[3], dw[4], dw[5]),
    );
    let (aom, av) = (
        Vec3::new(da[0], da[1], da[2]),
        Vec3::new(da[3], da[4], da[5]),
    );
    let omb = Vec3::new(fb.vel[0], fb.vel[1], fb.vel[2]);
    let va = Vec3::new(fa.vel[3], fa.vel[4], fa.vel[5]);
    let oma = Vec3::new(fa.vel[0], fa.vel[1], fa.vel[2]);
    // Position rows: ḋ = R_bᵀ(Δv + Δω × p_a) = R_bᵀ[−p̂_a | I] ΔV (D64).
    let mut cpos = nalgebra::Matrix3x6::<f64>::zeros();
    cpos.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(-rbt * skew(&pa)));
    cpos.fixed_view_mut::<3, 3>(0, 3).copy_from(&rbt);
    // d̈ at q̈ = 0 (D65): R_bᵀ(ẇ − ω_b × w), w = Δv + Δω × p_a.
    let w = dv + dom.cross(&pa);
    let pdot_a = va + oma.cross(&pa);
    let wdot = av + aom.cross(&pa) + dom.cross(&pdot_a);
    let dd = rbt * (wdot - omb.cross(&w));
    let mut out = ClosureRows {
        c: Mat6::zeros(),
        phi: Vec6::zeros(),
        jdot_qd: Vec6::zeros(),
    };
    match &rc.spec.kind {
        ClosureKind::Weld => {
            let r = rotation_vector(&(rbt * ra));
            let rot = if exact {
                left_jacobian_inv(&r) * rbt
            } else {
                rbt
            };
            out.c.fixed_view_mut::<3, 3>(0, 0).copy_from(&rot);
            out.c.fixed_view_mut::<3, 6>(3, 0).copy_from(&cpos);
            let ud = rbt * (aom - omb.cross(&dom));
            for i in 0..3 {
                out.phi[i] = r[i];
                out.phi[3 + i] = d[i];
                out.jdot_qd[i] = ud[i];
                out.jdot_qd[3 + i] = dd[i];
            }
        }
        ClosureKind::Ball => {
            out.c.fixed_view_mut::<3, 6>(0, 0).copy_from(&cpos);
            for i in 0..3 {
                out.phi[i] = d[i];
                out.jdot_qd[i] = dd[i];
            }
        }
        ClosureKind::Slider { .. } => {
            for (i, e) in rc.normals.iter().enumerate() {
                let row = e.transpose() * cpos;
                for j in 0..6 {
                    out.c[(i, j)] = row[j];
                }
                out.phi[i] = e.dot(&d);
                out.jdot_qd[i] = e.dot(&dd);
            }
        }
    }
    out
}

/// Fills `out` for every closure after an outward pass at `motion`: `φ`
/// (m), `J` (m×n, zeroed first) and, with `q̇`, `J̇q̇` (m). `exact` selects
/// `∂φ/∂q` (rotation rows through `J_l⁻¹`) over the velocity rows.
pub(crate) fn assemble(
    model: &Model,
    tree: &Tree,
    data: &Data,
    motion: Motion,
    exact: bool,
    out: &mut ConstraintRows,
) {
    let Motion { q, qd, .. } = motion;
    out.jac.fill(0.0);
    for rc in &model.closures {
        let fa = frame_state(model, tree, data, &rc.a, q, qd);
        let fb = frame_state(model, tree, data, &rc.b, q, qd);
        let rows = closure_rows(rc, &fa, &fb, exact);
        let m = rc.spec.kind.n_constraints();
        for i in 0..m {
            out.phi[rc.row + i] = rows.phi[i];
            out.jdot_qd[rc.row + i] = rows.jdot_qd[i];
        }
        for (fs, sign) in [(&fa, 1.0), (&fb, -1.0)] {
            let block = RowBlock {
                c: &rows.c,
                m,
                row: rc.row,
                sign,
            };
            add_frame_columns(tree, data, fs, block, &mut out.jac);
        }
    }
}

/// The constraint rows' columns of the prescribed coordinates (D59), `J_p`
/// (m×n_p, velocity rows), after an outward pass at `motion`: the
/// prescribed joints' spatial columns on each frame's path to the root.
pub(crate) fn prescribed_columns(
    model: &Model,
    tree: &Tree,
    data: &Data,
    motion: Motion,
    jac_p: &mut DMatrix<f64>,
) {
    let Motion { q, qd, .. } = motion;
    jac_p.fill(0.0);
    for rc in &model.closures {
        let fa = frame_state(model, tree, data, &rc.a, q, qd);
        let fb = frame_state(model, tree, data, &rc.b, q, qd);
        let rows = closure_rows(rc, &fa, &fb, false);
        let m = rc.spec.kind.n_constraints();
        for (fs, sign) in [(&fa, 1.0), (&fb, -1.0)] {
            let mut c = fs.from;
            let mut anc = fs.ancestors;
            while let Some(j) = anc {
                let nj = &tree.nodes[j];
                if let (Some((o, kp)), Some(cc)) = (nj.prescribed, c) {
                    let blk = rows.c * parent_column(tree, data, cc);
                    for r in 0..m {
                        for col in 0..kp {
                            jac_p[(rc.row + r, o + col)] += sign * blk[(r, col)];
                        }
                    }
                }
                c = Some(j);
                anc = nj.parent;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_vector_inverts_exp_near_zero_and_near_pi() {
        for r in [
            Vec3::new(1e-10, -2e-10, 3e-11),
            Vec3::new(0.3, -0.2, 0.5),
            Vec3::new(0.0, 0.0, 3.1),
            Vec3::new(1.0, 2.0, -2.0).normalize() * (std::f64::consts::PI - 1e-4),
        ] {
            let m = *nalgebra::Rotation3::from_scaled_axis(r).matrix();
            let back = rotation_vector(&m);
            assert!(
                (back - r).norm() < 1e-12 * r.norm().max(1e-3),
                "{r} → {back}"
            );
        }
    }
}

#[cfg(test)]
mod jdot_tests {
    use super::*;
    use crate::algorithms::tree::outward;
    use crate::algorithms::{Motion, Pass};
    use crate::forces::Forces;
    use crate::model::closure::ClosureKind;
    use crate::{Attachment, BodySpec, Closure, ClosureFrame, Joint, Model, Rod};
    use nalgebra::DVector;
    use softrod_lie::{Pose, Vec3};
    use softrod_mechanics::Material;

    /// `J̇q̇` of the velocity rows against central differences of
    /// `J_v(q(t)) q̇` along `q(t) = q + t q̇`.
    #[test]
    fn jdot_qd_matches_differences_of_the_velocity_rows() {
        let mat = Material::builder()
            .density(1000.0)
            .young(1e6)
            .poisson(0.5)
            .build()
            .unwrap();
        let rod = |n: &str, l: f64| Rod::builder(l).name(n).pieces(2).circle(0.01).material(mat);
        let model = Model::builder()
            .rod_on(
                rod("a", 0.3),
                Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.2])),
            )
            .body(
                BodySpec::principal("hand", 0.03, [2e-5, 3e-5, 2.5e-5]),
                Attachment::to("a", Joint::spherical()),
            )
            .rod_on(
                rod("b", 0.2),
                Attachment::to("hand", Joint::universal([0.0, 1.0, 0.0], [0.0, 0.0, 1.0])),
            )
            .rod_on(rod("c", 0.25), Attachment::world_joint(Joint::free()))
            .build()
            .unwrap();
        for kind in [
            ClosureKind::Ball,
            ClosureKind::Weld,
            ClosureKind::Slider {
                axis: Vec3::new(0.2, 1.0, 0.3),
            },
        ] {
            for (ea, eb) in [("b", "world"), ("hand", "c"), ("b", "c"), ("a", "hand")] {
                let m = model
                    .clone()
                    .with_closures(vec![Closure::new(
                        "t",
                        kind.clone(),
                        ClosureFrame::on(
                            ea,
                            Some(0.13).filter(|_| ea != "hand"),
                            Pose::new(
                                *nalgebra::Rotation3::from_euler_angles(0.1, 0.2, 0.3).matrix(),
                                Vec3::new(0.01, 0.02, 0.03),
                            ),
                        ),
                        ClosureFrame::on(
                            eb,
                            None,
                            Pose::new(
                                *nalgebra::Rotation3::from_euler_angles(-0.1, 0.2, 0.0).matrix(),
                                Vec3::new(0.0, 0.02, -0.01),
                            ),
                        ),
                    )])
                    .unwrap();
                let tree = m.tree.as_ref().unwrap();
                let mut data = Data::new(&m);
                let n = m.n_dof();
                let nc = m.n_constraints();
                let q: Vec<f64> = (0..n).map(|i| 0.3 * ((i as f64) * 1.7).sin()).collect();
                let qd: Vec<f64> = (0..n)
                    .map(|i| 0.5 * ((i as f64) * 2.3 + 1.0).cos())
                    .collect();
                let mut rows = ConstraintRows::new(nc, n);
                let motion = Motion::new(&q, Some(&qd), None);
                outward(&m, tree, &mut data, motion, Pass::Articulated, Forces::ALL);
                assemble(&m, tree, &data, motion, false, &mut rows);
                let jd = rows.jdot_qd;
                let jv_at = |data: &mut Data, t: f64| {
                    let qt: Vec<f64> = (0..n).map(|i| q[i] + t * qd[i]).collect();
                    let mut rows = ConstraintRows::new(nc, n);
                    let motion = Motion::at_rest(&qt);
                    outward(&m, tree, data, motion, Pass::Composite, Forces::ALL);
                    assemble(&m, tree, data, motion, false, &mut rows);
                    rows.jac * DVector::from_column_slice(&qd)
                };
                let h = 1e-6;
                let fd = (jv_at(&mut data, h) - jv_at(&mut data, -h)) / (2.0 * h);
                let err = (&fd - &jd).amax();
                assert!(
                    err < 1e-6 * fd.amax().max(1.0),
                    "{kind:?} {ea}-{eb}: {jd} vs {fd}"
                );
            }
        }
    }
}
