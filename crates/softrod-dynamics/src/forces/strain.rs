//! The forces that act in strain space (D13, D15, D53): elasticity with its
//! stress-free offset, Kelvin–Voigt damping, cables, joint springs and
//! dampers, and the actuator force, summed into `Data::strain_force`.

use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::{Data, cable_tension};
use softrod_lie::Vec6;

/// Strain-space generalized forces into `data.strain_force`:
/// `τ_act + λ τ_c(q, t) − τ_e(q) − D q̇` ((D13), (D15); `λ` =
/// `forces.load_scale`; only `τ_act` for gravity alone).
#[inline(always)]
pub(crate) fn strain_forces(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: Option<&[f64]>,
    tau_act: Option<&[f64]>,
) {
    let sf = &mut data.strain_force;
    match tau_act {
        Some(ta) => sf.as_mut_slice().copy_from_slice(ta),
        None => sf.fill(0.0),
    }
    if forces.gravity_only {
        return;
    }
    for rm in model.rods() {
        let rod = &rm.spec.geometry;
        let off = rm.dof_offset;
        for (piece, pd) in rod.pieces().iter().zip(&rm.pieces) {
            let k = piece.basis.dof();
            let o = off + piece.dof_offset;
            // Zero padding keeps `K_n q_n` exact: the pad adds exact zeros.
            let pad = |v: &[f64]| Vec6::from_fn(|i, _| if i < k { v[i] } else { 0.0 });
            let mut e = match &pd.diagonal {
                Some((kd, _)) => kd.component_mul(&pad(&q[o..o + k])),
                None => pd.stiffness6 * pad(&q[o..o + k]),
            };
            if pd.has_offset {
                e += pd.offset6;
            }
            if let (true, Some(v)) = (pd.has_damping, qd) {
                e += match &pd.diagonal {
                    Some((_, dd)) => dd.component_mul(&pad(&v[o..o + k])),
                    None => pd.damping6 * pad(&v[o..o + k]),
                };
            }
            for (s, ei) in sf.as_mut_slice()[o..o + k].iter_mut().zip(e.iter()) {
                *s -= ei;
            }
        }
        if !rm.spec.cables.is_empty() && rm.spec.cables.iter().all(|c| c.is_constant_per_piece()) {
            // Every cable's integrand is constant on a piece: one strain and
            // one projection per piece for all of them,
            // `τ_n −= B_nᵀ Σ_c T_c w_c` (D15), instead of one per cable.
            let qr = &q[rm.dofs()];
            for piece in rod.pieces() {
                let mut acc = Vec6::zeros();
                let mut xi = None;
                for (c, cable) in rm.spec.cables.iter().enumerate() {
                    let tension =
                        cable_tension(data.tensions.as_ref(), rm, c, t) * forces.load_scale;
                    if tension == 0.0 {
                        continue;
                    }
                    let xi = *xi.get_or_insert_with(|| piece.strain(qr));
                    acc += cable.constant_piece_wrench(piece, &xi) * tension;
                }
                if acc == Vec6::zeros() {
                    continue;
                }
                let o = off + piece.dof_offset;
                for (c, s) in sf.as_mut_slice()[o..o + piece.basis.dof()]
                    .iter_mut()
                    .enumerate()
                {
                    *s -= piece.basis.column(c).dot(&acc);
                }
            }
        } else if !rm.spec.cables.is_empty() {
            let range = rm.dofs();
            for (c, cable) in rm.spec.cables.iter().enumerate() {
                let tension = cable_tension(data.tensions.as_ref(), rm, c, t) * forces.load_scale;
                if tension == 0.0 {
                    continue;
                }
                let scratch = &mut data.cable_scratch.as_mut_slice()[range.clone()];
                scratch.fill(0.0);
                cable.add_force_per_tension(rod, &q[range.clone()], &model.quadrature, scratch);
                for (s, c) in sf.as_mut_slice()[range.clone()]
                    .iter_mut()
                    .zip(scratch.iter())
                {
                    *s += tension * c;
                }
            }
        }
    }
}

/// `τ ← τ − k(q − q_rest) − d q̇` of every joint (D53), and `+ λ f(t)` of
/// every joint actuator (docs/theory-control.md IS14: its schedule, or the
/// inputs of [`Data::set_joint_forces`]; `λ` = `forces.load_scale`), into
/// the strain forces (skipped for gravity only).
pub(crate) fn joint_forces(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: Option<&[f64]>,
) {
    if forces.gravity_only {
        return;
    }
    for e in &model.elements {
        let j = &e.attachment.joint;
        if let Some(a) = &j.actuator {
            for (i, o) in e.joint_dofs.clone().enumerate() {
                data.strain_force[o] +=
                    forces.load_scale * actuator_force(data.joint_inputs.as_ref(), e, a, i, t);
            }
        }
        if j.stiffness.is_empty() && j.damping.is_empty() {
            continue;
        }
        for (i, o) in e.joint_dofs.clone().enumerate() {
            let (k, d, rest) = j.coefficients(i);
            let v = qd.map_or(0.0, |v| v[o]);
            data.strain_force[o] -= k * (q[o] - rest) + d * v;
        }
    }
}

/// The force of coordinate `i` of element `e`'s joint actuator `a` at `t`
/// \[N or N·m\]: the input when set, else the actuator's schedule (without
/// the load factor).
#[inline]
pub(crate) fn actuator_force(
    inputs: Option<&nalgebra::DVector<f64>>,
    e: &crate::model::ElementInfo,
    a: &crate::model::JointActuator,
    i: usize,
    t: f64,
) -> f64 {
    match inputs {
        Some(u) => u[e.actuator_inputs.start + i],
        None => a.force.at(i, t),
    }
}
