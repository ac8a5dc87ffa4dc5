//! The planar (se(2)) path of the O(N) forward and the inverse dynamics
//! (docs/theory.md §13, D71–D75): the sweeps; their arithmetic is in
//! `crate::kernels::planar`.
//!
//! A rod whose every piece selects strains among `(κ_a, q_b, q_c)` — the
//! bending about one body axis `a` and the two strains in the plane
//! normal to it, `(a, b, c)` a cyclic permutation of `(x, y, z)` — and
//! whose rest strain has no other component stays in the `b, c` plane of
//! its base frame. The subspace `P = (ω_a, v_b, v_c)` of twists is
//! invariant under `ad_ξ`, `Ad_g`, `T₋` for `ξ ∈ P` and `g = exp(ξ)`, and
//! `Ad_g`, the diagonal section inertia and `ad*` are block diagonal on
//! `P ⊕ P⊥` (D71). Every term the forward dynamics projects on the
//! coordinates therefore lives in `P`: the per-point twists, biases and
//! wrenches are 3-vectors and every inertia a 3×3 matrix, where the
//! general path carries 6-vectors and 6×6 blocks. Loads with components
//! in `P⊥` (gravity or a world load out of the plane) are held by the
//! section's rigidity in those directions and do no work: they are
//! dropped by the projection on `P`, exactly as the general path drops
//! them in `Sᵀ`.

use super::Motion;
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::forces::external::{external_density, gravity_base_acceleration};
use crate::kernels::planar::{PlanarSums, Pose2, ad2, cholesky, coad2, maps};
use crate::model::data::Data;
use crate::model::planar::PlanarRod;
use crate::model::{Model, RodModel};
use softrod_lie::{Mat3, Pose, Vec3};

/// The outward sweep of the planar rod `r` (D7–D10 in `P`). For the
/// forward dynamics (`inverse = false`): the per-piece integrals
/// `𝓤ᶠ, 𝓓ᶠ, 𝓜ᵗ` and bias sums of pass 1 (D20, D23). For the inverse
/// dynamics: the wrench sums of (D17) with `f = 𝓜η̇ + ad*_η𝓜η − 𝓕_ext`,
/// gravity as the base acceleration. Both: tip maps and accelerations,
/// the external terms as `forces` asks, at the model's full `motion`.
/// Rod `r` must be planar ([`Model::uses_planar_path`]).
#[inline(always)]
pub(crate) fn outward(
    model: &Model,
    data: &mut Data,
    r: usize,
    motion: Motion,
    inverse: bool,
    forces: Forces,
) {
    let rm = &model.rods[r];
    let Some(pr) = &rm.planar else {
        unreachable!("the planar path runs planar rods only")
    };
    let Motion { q, qd, qdd } = motion;
    let scale = forces.load_scale;
    let only_gravity = forces.gravity_only;
    let rod = &rm.spec.geometry;
    let base = rod.base();
    let range = rm.dofs();
    let qr = &q[range.clone()];
    let qdr = qd.map(|v| &v[range.clone()]);
    let qddr = qdd.map(|v| &v[range]);
    let has_ext =
        !only_gravity && (rm.spec.drag.is_some() || !rm.spec.distributed_loads.is_empty());
    let need_world = rm.needs_world_pose_at_points;
    let mut pose = Pose2::IDENTITY;
    let mut eta0 = Vec3::zeros();
    let mut etadot0 = if inverse {
        pr.gather(&gravity_base_acceleration(model, rm, scale))
    } else {
        Vec3::zeros()
    };
    let pieces = rod.pieces().iter().zip(&rm.pieces).zip(&pr.pieces);
    for (n, ((piece, pd), pp)) in pieces.enumerate() {
        let w = &mut data.planar[r][n];
        let xi = pr.gather(&piece.strain(qr));
        let dxi = qdr.map_or(Vec3::zeros(), |v| pr.gather(&piece.strain_rate(v)));
        let ddxi = qddr.map_or(Vec3::zeros(), |v| pr.gather(&piece.strain_rate(v)));
        // At rest (ξ̇ = 0, η(0) = 0) every velocity and bias term vanishes.
        let has_vel = dxi != Vec3::zeros() || eta0 != Vec3::zeros();
        let (mut p_big, mut p_small) = (Vec3::zeros(), Vec3::zeros());
        let mut sums = PlanarSums::default();
        for (qp, m) in pd.points.iter().zip(&pp.inertia) {
            let (gl, tm, dbias) = maps(&xi, &dxi, qp.x, has_vel);
            let carried = gl.ad_inv_vec(&eta0);
            let sv = tm * dxi;
            let eta = carried + sv;
            let bias = if has_vel {
                ad2(&carried, &sv) + dbias
            } else {
                Vec3::zeros()
            };
            let mut f = coad2(&eta, &m.component_mul(&eta));
            if inverse {
                let etadot = gl.ad_inv_vec(&etadot0) + tm * ddxi + bias;
                f += m.component_mul(&etadot);
            } else if has_vel {
                f += m.component_mul(&bias);
            }
            if has_ext {
                let world = if need_world {
                    base.compose(&pr.embed(&pose.compose(&gl)))
                } else {
                    Pose::identity()
                };
                f -= pr.gather(&external_density(rm, scale, &world, &pr.scatter(&eta)));
            }
            let fw = f * qp.w;
            p_big += gl.ad_inv_tr_vec(&fw);
            p_small += tm.tr_mul(&fw);
            if !inverse {
                sums.add(&gl, &tm, &(m * qp.w));
            }
        }
        if !only_gravity {
            for pl in &pd.loads {
                let load = &rm.spec.point_loads[pl.index];
                let (gl, tm, _) = maps(&xi, &dxi, pl.x, false);
                let world = base.compose(&pr.embed(&pose.compose(&gl)));
                let f = pr.gather(&(load.wrench(&world) * scale));
                p_big -= gl.ad_inv_tr_vec(&f);
                p_small -= tm.tr_mul(&f);
            }
        }
        let (gl, tm, dbias) = maps(&xi, &dxi, piece.length, has_vel);
        let carried = gl.ad_inv_vec(&eta0);
        let sv = tm * dxi;
        let acc = if has_vel {
            ad2(&carried, &sv) + dbias
        } else {
            Vec3::zeros()
        };
        if inverse {
            etadot0 = gl.ad_inv_vec(&etadot0) + tm * ddxi + acc;
        }
        w.acc_tip = acc;
        w.tip = gl;
        w.tm_tip = tm;
        w.p_big = p_big;
        w.p_small = p_small;
        if !inverse {
            (w.ut, w.dt, w.mt) = sums.finish();
        }
        eta0 = carried + sv;
        pose = pose.compose(&gl);
    }
}

/// The inward pass (D17–D18) of the planar rod `r` after an inverse
/// [`outward`]: `W_n = 𝓟_n + Ad⁻ᵀ W_{n+1}`,
/// `τ_n = Bᵀ(𝓹_n + T₋(ℓ)ᵀW_{n+1})` into `data.tau` (the strain-space forces
/// are subtracted by the caller).
#[inline(always)]
pub(crate) fn inward_inverse(rm: &RodModel, pr: &PlanarRod, data: &mut Data, r: usize) {
    let mut wv = Vec3::zeros();
    for (n, (piece, pp)) in rm
        .spec
        .geometry
        .pieces()
        .iter()
        .zip(&pr.pieces)
        .enumerate()
        .rev()
    {
        let w = &data.planar[r][n];
        let v = w.p_small + w.tm_tip.tr_mul(&wv);
        let o = rm.dof_offset + piece.dof_offset;
        for i in 0..pp.k {
            data.tau[o + i] = v[pp.sel[i]];
        }
        wv = w.p_big + w.tip.ad_inv_tr_vec(&wv);
    }
}

/// Forward dynamics of one planar rod (D75): pass 1 ([`outward`]), the
/// articulated inward pass (D24–D26) and the outward pass (D27) on 3×3
/// blocks. `data.strain_force` must hold the rod's strain-space forces.
/// Inlined into the forward dynamics' baseline and AVX2 copies.
#[inline(always)]
pub(crate) fn forward_rod(
    model: &Model,
    data: &mut Data,
    r: usize,
    q: &[f64],
    qd: &[f64],
    forces: Forces,
) -> Result<(), DynamicsError> {
    let rm = &model.rods()[r];
    let pr = rm.planar.as_ref().expect("planar rod");
    outward(
        model,
        data,
        r,
        Motion::new(q, Some(qd), None),
        false,
        forces,
    );
    let pieces = &pr.pieces;
    let mut ma_next = Mat3::zeros();
    let mut pa_next = Vec3::zeros();
    for (n, pp) in pieces.iter().enumerate().rev() {
        let k = pp.k;
        let o = rm.dof_offset + rm.spec.geometry.pieces()[n].dof_offset;
        let w = &mut data.planar[r][n];
        let leaf = n + 1 == pieces.len();
        let (carried, y) = if leaf {
            (Mat3::zeros(), pa_next)
        } else {
            let a = w.tip.ad_inv();
            let at_ma = a.tr_mul(&ma_next);
            let ma_t = ma_next * w.tm_tip;
            // Û = 𝓤 + A_ℓᵀ𝓜ᴬT₋(ℓ)B, D̂ = 𝓓 + BᵀT₋(ℓ)ᵀ𝓜ᴬT₋(ℓ)B (D24).
            w.ut += a.tr_mul(&ma_t);
            w.dt += w.tm_tip.tr_mul(&ma_t);
            (at_ma * a, ma_next * w.acc_tip + pa_next)
        };
        let sty = w.tm_tip.tr_mul(&y);
        let mut u = Vec3::zeros();
        let mut hat_u = Mat3::zeros();
        let mut hat_d = Mat3::zeros();
        for i in 0..k {
            let si = pp.sel[i];
            u[i] = data.strain_force[o + i] - w.p_small[si] - sty[si];
            hat_u.set_column(i, &w.ut.column(si));
            for j in 0..k {
                hat_d[(i, j)] = w.dt[(si, pp.sel[j])];
            }
        }
        if !cholesky(&mut hat_d, k) {
            return Err(DynamicsError::Singular {
                rod: r,
                piece: n,
                what: "articulated piece inertia D̂_n",
            });
        }
        // W = ÛL⁻ᵀ, ũ = L⁻¹u: ÛD̂⁻¹Ûᵀ = WWᵀ, ÛD̂⁻¹u = Wũ.
        for i in 0..k {
            let mut col = hat_u.column(i).into_owned();
            let mut s = u[i];
            for p in 0..i {
                col -= hat_u.column(p) * hat_d[(i, p)];
                s -= hat_d[(i, p)] * u[p];
            }
            let inv = 1.0 / hat_d[(i, i)];
            hat_u.set_column(i, &(col * inv));
            u[i] = s * inv;
        }
        ma_next = w.mt + carried - hat_u * hat_u.transpose();
        pa_next = w.p_big + w.tip.ad_inv_tr_vec(&y) + hat_u * u;
        w.ut = hat_u;
        w.dt = hat_d;
        w.u = u;
    }
    let mut etadot = pr.gather(&gravity_base_acceleration(model, rm, forces.load_scale));
    for (n, pp) in pieces.iter().enumerate() {
        let k = pp.k;
        let o = rm.dof_offset + rm.spec.geometry.pieces()[n].dof_offset;
        let w = &data.planar[r][n];
        let mut qn = w.u - w.ut.tr_mul(&etadot);
        for i in (0..k).rev() {
            let mut s = qn[i];
            for p in (i + 1)..k {
                s -= w.dt[(p, i)] * qn[p];
            }
            qn[i] = s / w.dt[(i, i)];
        }
        let mut bq = Vec3::zeros();
        for i in 0..k {
            bq[pp.sel[i]] = qn[i];
            data.qdd[o + i] = qn[i];
        }
        etadot = w.tip.ad_inv_vec(&etadot) + w.tm_tip * bq + w.acc_tip;
    }
    Ok(())
}
