//! The outward sweep shared by every algorithm of the chain path.

use crate::forces::Forces;
use crate::forces::external::{external_density, gravity_base_acceleration};
use crate::kernels::blocks::ad_inv_vec;
use crate::kernels::inertia::{FullSums, PointInertia, diag_mul, s_columns};
use crate::model::Model;
use crate::model::data::Data;
use softrod_lie::{Mat6, PieceMaps, Pose, Vec6, ad_vec, coad_vec};

/// What the outward sweep accumulates per piece.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pass {
    /// (D17–D18) sums with `f = 𝓜η̇ + ad*_η𝓜η − 𝓕_ext`; needs `q̈`.
    Inverse,
    /// (D20) integrals and (D23) bias sums with `h = 𝓜a + ad*_η𝓜η − 𝓕_ext`.
    Articulated,
    /// (D20) integrals only (mass matrix).
    Composite,
}

/// One outward sweep over every rod (D7–D10 at the evaluation points),
/// accumulating per piece what `pass` needs under `forces`. `q`, `qd`,
/// `qdd` are the model's full vectors; `qd = None` means at rest, `qdd`
/// only for [`Pass::Inverse`].
pub(crate) fn outward(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    qd: Option<&[f64]>,
    qdd: Option<&[f64]>,
    pass: Pass,
    forces: Forces,
) {
    outward_inl(model, data, q, qd, qdd, pass, forces);
}

/// [`outward`] inlined into its caller: the hot algorithms inline it into
/// both their baseline and their AVX2 copies (`crate::kernels::simd`).
#[inline(always)]
pub(crate) fn outward_inl(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    qd: Option<&[f64]>,
    qdd: Option<&[f64]>,
    pass: Pass,
    forces: Forces,
) {
    let scale = forces.load_scale;
    let only_gravity = forces.gravity_only;
    for (r, rm) in model.rods.iter().enumerate() {
        // Planar rods run on 3-vectors and 3×3 blocks (crate::planar): the
        // inverse sweep here, the forward dynamics' in its own rod loop.
        if pass != Pass::Composite && model.uses_planar_path(r) {
            if let (Pass::Inverse, Some(pr)) = (pass, &rm.planar) {
                crate::planar::outward(model, rm, pr, data, r, q, qd, qdd, true, forces);
            }
            continue;
        }
        let rod = &rm.spec.rod;
        let range = rm.dofs();
        let qr = &q[range.clone()];
        let qdr = qd.map(|v| &v[range.clone()]);
        let qddr = qdd.map(|v| &v[range.clone()]);
        let mut pose = *rod.base();
        let mut eta0 = Vec6::zeros();
        let mut etadot0 = if pass == Pass::Inverse {
            gravity_base_acceleration(model, rm, scale)
        } else {
            Vec6::zeros()
        };
        let has_vel = qdr.is_some();
        // Drag or distributed loads on this rod (else the density is zero
        // and `f` skips it).
        let has_ext =
            !only_gravity && (rm.spec.drag.is_some() || !rm.spec.distributed_loads.is_empty());
        let need_world = rm.needs_world_pose_at_points;
        for (n, (piece, pd)) in rod.pieces().iter().zip(&rm.pieces).enumerate() {
            let w = &mut data.pieces[r][n];
            let xi = piece.strain(qr);
            let dxi = qdr.map_or(Vec6::zeros(), |v| piece.strain_rate(v));
            let ddxi = qddr.map_or(Vec6::zeros(), |v| piece.strain_rate(v));
            if pass == Pass::Composite {
                w.base_pose = pose;
            }
            let (mut pb_m, mut pb_n) = (softrod_lie::Vec3::zeros(), softrod_lie::Vec3::zeros());
            let (mut ps_m, mut ps_n) = (softrod_lie::Vec3::zeros(), softrod_lie::Vec3::zeros());
            let full = piece.basis.dof() >= 4;
            // The column-by-column sums (k < 4) accumulate in place; the
            // block sums overwrite both in `project`.
            if pass != Pass::Inverse && !full {
                w.ut.fill(0.0);
                w.dt.fill(0.0);
            }
            let mut sp = PointInertia::default();
            let mut fs = FullSums::new(
                pd.points
                    .iter()
                    .all(|p| p.inertia[3] == p.inertia[4] && p.inertia[3] == p.inertia[5]),
            );
            let mut scols = [Vec6::zeros(); 6];
            // Everything x-independent of the local maps, once per piece.
            let maps = PieceMaps::new(&xi, has_vel.then_some(&dxi));
            for qp in &pd.points {
                let (gl, tm, dbias) = maps.eval(qp.x);
                let m = &qp.inertia;
                if pass != Pass::Composite {
                    let carried = ad_inv_vec(&gl, &eta0);
                    let sv = tm.mul_vec(&dxi);
                    let eta = carried + sv;
                    let bias = if has_vel {
                        ad_vec(&carried, &sv) + dbias
                    } else {
                        Vec6::zeros()
                    };
                    let world = if need_world {
                        pose.compose(&gl)
                    } else {
                        Pose::identity()
                    };
                    let gyro = coad_vec(&eta, &diag_mul(m, &eta));
                    let mut f = if pass == Pass::Inverse {
                        let etadot = ad_inv_vec(&gl, &etadot0) + tm.mul_vec(&ddxi) + bias;
                        diag_mul(m, &etadot) + gyro
                    } else {
                        diag_mul(m, &bias) + gyro
                    };
                    if has_ext {
                        f -= external_density(rm, scale, &world, &eta);
                    }
                    // Aᵀ(wf) and T₋ᵀ(wf) on the 3-vector halves: one split of
                    // f for both, no 6-vector temporaries.
                    let fw = f * qp.w;
                    let (fm, fn_) = (softrod_lie::angular(&fw), softrod_lie::linear(&fw));
                    // Aᵀ(wf) = (R f_M + p × R f_N, R f_N).
                    let rfn = gl.rotation * fn_;
                    pb_m += gl.rotation * fm + gl.translation.cross(&rfn);
                    pb_n += rfn;
                    ps_m += tm.a.tr_mul(&fm) + tm.b.tr_mul(&fn_);
                    ps_n += tm.a.tr_mul(&fn_);
                }
                if pass != Pass::Inverse {
                    let mw = m * qp.w;
                    // 𝓤 += w Aᵀ𝓜S and 𝓓 += w Sᵀ𝓜S: in 3×3 blocks of the
                    // full T₋ for k ≥ 4 ([`FullSums`]), column by column on
                    // S = T₋B (k products and k(k+1)/2 dots) below that.
                    if full {
                        fs.add(&gl, &tm, &mw);
                    } else {
                        let a = gl.ad_inv();
                        let k = s_columns(&tm, &piece.basis, &mut scols);
                        for c in 0..k {
                            let ms = mw.component_mul(&scols[c]);
                            let u = a.tr_mul_vec(&ms);
                            let mut col = w.ut.fixed_view_mut::<6, 1>(0, c);
                            col += u;
                            for (r, sr) in scols.iter().enumerate().take(c + 1) {
                                w.dt[(r, c)] += sr.dot(&ms);
                            }
                        }
                    }
                    sp.add(&gl, &mw);
                }
            }
            let mut p_big = softrod_lie::join(&pb_m, &pb_n);
            let mut p_small = softrod_lie::join(&ps_m, &ps_n);
            if pass != Pass::Composite && !only_gravity {
                for pl in &pd.loads {
                    let load = &rm.spec.point_loads[pl.index];
                    let (gl, tm) = maps.exp_and_tangent_minus(pl.x);
                    let f = load.wrench(&pose.compose(&gl)) * scale;
                    let a = gl.ad_inv();
                    p_big -= a.tr_mul_vec(&f);
                    p_small -= tm.tr_mul_vec(&f);
                }
            }
            let (gl, tm, dbias) = maps.eval(piece.length);
            let carried = ad_inv_vec(&gl, &eta0);
            let sv = tm.mul_vec(&dxi);
            let acc = if has_vel {
                ad_vec(&carried, &sv) + dbias
            } else {
                Vec6::zeros()
            };
            w.tip = gl;
            w.tm_tip = tm;
            w.acc_tip = acc;
            w.p_big = p_big;
            if pass == Pass::Inverse {
                w.p_small = p_small;
                etadot0 = ad_inv_vec(&gl, &etadot0) + tm.mul_vec(&ddxi) + acc;
            } else {
                let k = piece.basis.dof();
                if pass == Pass::Composite {
                    // The mass matrix's off-diagonal blocks pair S(ℓ) with
                    // wrenches in the world frame: Ad_{g(ℓ)} S(ℓ).
                    s_columns(&tm, &piece.basis, &mut scols);
                    let ad_tip = pose.compose(&gl).ad();
                    w.s_world = Mat6::zeros();
                    for (c, col) in scols.iter().enumerate().take(k) {
                        w.s_world.set_column(c, &ad_tip.mul_vec(col));
                    }
                }
                if full {
                    fs.project(&piece.basis, &mut w.ut, &mut w.dt);
                } else {
                    for c in 0..k {
                        for r in 0..c {
                            w.dt[(c, r)] = w.dt[(r, c)];
                        }
                    }
                }
                w.mt = sp.finish();
                w.p_small = Vec6::zeros();
                piece
                    .basis
                    .tr_apply(&p_small, &mut w.p_small.as_mut_slice()[..k]);
            }
            eta0 = carried + sv;
            pose = pose.compose(&gl);
        }
    }
}
