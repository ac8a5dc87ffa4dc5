//! The chain path: the recursions of docs/theory.md §4–§6 on rods clamped
//! to the world, piece by piece — the outward sweep (D7–D10) shared by
//! every algorithm, the inward passes of the inverse dynamics (D17–D18),
//! the articulated forward dynamics (D23–D27) and the composite mass
//! matrix (D19–D20). Planar rods run their sweeps in [`super::planar`].
//! The hot functions are compiled twice, as is and with AVX2
//! (`crate::kernels::simd`).

use super::{Motion, Pass, planar};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::forces::external::{external_density, gravity_base_acceleration};
use crate::forces::strain::strain_forces;
use crate::kernels::blocks::{Blk6, Sym6, ad_inv_tr_vec, ad_inv_vec};
use crate::kernels::chol::{backward_sub, cholesky_k, forward_sub, right_solve_lt};
use crate::kernels::inertia::{FullSums, PointInertia, diag_mul, project_add_blocks, s_columns};
use crate::model::Model;
use crate::model::data::Data;
use softrod_kinematics::Piece;
use softrod_lie::{Mat6, PieceMaps, Pose, Vec6, ad_vec, coad_vec};

/// `ξ_n = B_n q_n + ξ̄_n` of a piece, out of line: inlined into the sweep,
/// its loops over the basis compile to more instructions (+1.4k per
/// inverse dynamics at N = 10, measured with callgrind).
#[inline(never)]
fn strain(piece: &Piece, q: &[f64]) -> Vec6 {
    piece.strain(q)
}

/// `ξ̇_n = B_n q̇_n` (or `ξ̈_n`) of a piece, out of line as [`strain`].
#[inline(never)]
fn strain_rate(piece: &Piece, qd: &[f64]) -> Vec6 {
    piece.strain_rate(qd)
}

/// One outward sweep over every rod (D7–D10 at the evaluation points),
/// accumulating per piece what `pass` needs under `forces` at `motion`
/// (`q̈` only for [`Pass::Inverse`]).
pub(crate) fn outward(model: &Model, data: &mut Data, motion: Motion, pass: Pass, forces: Forces) {
    outward_inl(model, data, motion, pass, forces);
}

/// [`outward`] inlined into its caller: the hot algorithms inline it into
/// both their baseline and their AVX2 copies (`crate::kernels::simd`).
#[inline(always)]
pub(crate) fn outward_inl(
    model: &Model,
    data: &mut Data,
    motion: Motion,
    pass: Pass,
    forces: Forces,
) {
    let Motion { q, qd, qdd } = motion;
    let scale = forces.load_scale;
    let only_gravity = forces.gravity_only;
    for (r, rm) in model.rods.iter().enumerate() {
        // Planar rods run on 3-vectors and 3×3 blocks (super::planar): the
        // inverse sweep here, the forward dynamics' in its own rod loop.
        if pass != Pass::Composite && model.uses_planar_path(r) {
            if pass == Pass::Inverse {
                planar::outward(model, data, r, motion, true, forces);
            }
            continue;
        }
        let rod = &rm.spec.geometry;
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
            let xi = strain(piece, qr);
            let dxi = qdr.map_or(Vec6::zeros(), |v| strain_rate(piece, v));
            let ddxi = qddr.map_or(Vec6::zeros(), |v| strain_rate(piece, v));
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
            let mut scols = [Vec6::zeros(); 6];
            // Everything x-independent of the local maps, once per piece.
            let maps = PieceMaps::new(&xi, has_vel.then_some(&dxi));
            let theta2 = maps.theta_squared();
            let mut fs = FullSums::new(
                pd.points
                    .iter()
                    .all(|p| p.inertia[3] == p.inertia[4] && p.inertia[3] == p.inertia[5]),
                theta2 * (piece.length * piece.length),
            );
            for qp in &pd.points {
                let (gl, tm, dbias, ta) = maps.eval_with_ta(qp.x);
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
                        fs.add(&gl, &tm, &mw, &ta, theta2);
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
                    fs.project(&maps, &piece.basis, &mut w.ut, &mut w.dt);
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

crate::kernels::simd::dispatch! {
    /// Inverse dynamics of the chain (D17–D18) under `forces` at `(q, q̇,
    /// q̈)` (arguments checked by the caller): the outward sweep, the
    /// strain-space forces and the inward pass. Result in `data.tau`.
    pub(crate) fn inverse_dynamics(model: &Model, data: &mut Data, forces: Forces, t: f64, q: &[f64], qd: &[f64], qdd: &[f64])
    => inverse_dynamics_impl, inverse_dynamics_avx2
}

#[inline(always)]
pub(crate) fn inverse_dynamics_impl(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) {
    outward_inl(
        model,
        data,
        Motion::new(q, Some(qd), Some(qdd)),
        Pass::Inverse,
        forces,
    );
    strain_forces(model, data, forces, t, q, Some(qd), None);
    inward_inverse(model, data);
}

/// [`inverse_dynamics`] at rest (`q̇ = None`) or without `q̈` (the bias
/// `b = ID(q, q̇, 0)`): the same passes, not specialized.
pub(crate) fn inverse_dynamics_general(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    motion: Motion,
) {
    outward(model, data, motion, Pass::Inverse, forces);
    strain_forces(model, data, forces, t, motion.q, motion.qd, None);
    inward_inverse(model, data);
}

/// (D17–D18): `W_n = 𝓟_n + A_ℓᵀ W_{n+1}`, `τ_n = B_nᵀ(𝓹_n + T₋(ℓ)ᵀ W_{n+1}) − τ̃_n`.
pub(crate) fn inward_inverse(model: &Model, data: &mut Data) {
    for (r, rm) in model.rods().iter().enumerate() {
        if let (true, Some(pr)) = (model.uses_planar_path(r), &rm.planar) {
            planar::inward_inverse(rm, pr, data, r);
            continue;
        }
        let mut wv = Vec6::zeros();
        for (n, piece) in rm.spec.geometry.pieces().iter().enumerate().rev() {
            let w = &data.pieces[r][n];
            let v = w.p_small + w.tm_tip.tr_mul_vec(&wv);
            let o = rm.dof_offset + piece.dof_offset;
            let k = piece.basis.dof();
            piece
                .basis
                .tr_apply(&v, &mut data.tau.as_mut_slice()[o..o + k]);
            wv = w.p_big + ad_inv_tr_vec(&w.tip, &wv);
        }
    }
    data.tau -= &data.strain_force;
}

crate::kernels::simd::dispatch! {
    /// Forward dynamics of the chain by the O(N) articulated recursion
    /// (D23–D27) under `forces` (arguments checked by the caller). Pass 1
    /// (outward): `g, η`, the per-piece integrals (D20) and bias sums (D23).
    /// Pass 2 (inward): articulated inertia and bias (D24–D26), one
    /// `k_n×k_n` Cholesky per piece. Pass 3 (outward): `q̈_n` and `η̇(L_n)`
    /// (D27). Result in `data.qdd`. Fails if `D̂_n` is not positive definite.
    pub(crate) fn forward_dynamics(model: &Model, data: &mut Data, forces: Forces, t: f64, q: &[f64], qd: &[f64], tau_act: Option<&[f64]>) -> Result<(), DynamicsError>
    => forward_dynamics_impl, forward_dynamics_avx2
}

#[inline(always)]
pub(crate) fn forward_dynamics_impl(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    outward_inl(
        model,
        data,
        Motion::new(q, Some(qd), None),
        Pass::Articulated,
        forces,
    );
    strain_forces(model, data, forces, t, q, Some(qd), tau_act);
    let scale = forces.load_scale;
    for (r, rm) in model.rods().iter().enumerate() {
        if model.uses_planar_path(r) {
            planar::forward_rod(model, data, r, q, qd, forces)?;
            continue;
        }
        let pieces = rm.spec.geometry.pieces();
        let mut ma_next = Sym6::default();
        let mut pa_next = Vec6::zeros();
        for (n, piece) in pieces.iter().enumerate().rev() {
            let k = piece.basis.dof();
            let o = rm.dof_offset + piece.dof_offset;
            let w = &mut data.pieces[r][n];
            // The tip piece has no child (𝓜ᴬ = 0): skip its products.
            let leaf = n + 1 == pieces.len();
            // In place: `ut` becomes Û, then W = Û L⁻ᵀ; `dt` becomes D̂,
            // then its factor L.
            // The child's inertia carried to this piece's base,
            // C = A_ℓᵀ𝓜ᴬA_ℓ, is needed below anyway; with T₋(ℓ) = A_ℓT₊(ℓ)
            // it also gives A_ℓᵀ𝓜ᴬT₋ = C T₊ and T₋ᵀ𝓜ᴬT₋ = T₊ᵀ C T₊.
            let carried = if leaf {
                Sym6::default()
            } else {
                ma_next.congruence_ad_inv(&w.tip)
            };
            let y = if leaf {
                pa_next
            } else {
                // Û = 𝓤 + A_ℓᵀ𝓜ᴬT₋(ℓ)B, D̂ = 𝓓 + BᵀT₋(ℓ)ᵀ𝓜ᴬT₋(ℓ)B (D24).
                let tplus = w.tm_tip.transpose_blocks();
                let mat = carried.mul_op(&tplus);
                project_add_blocks(
                    &piece.basis,
                    &mat,
                    &Blk6::tr_premul_sym(&tplus, &mat),
                    &mut w.ut,
                    &mut w.dt,
                );
                ma_next.mul_vec(&w.acc_tip) + pa_next
            };
            let mut sty = Vec6::zeros();
            piece
                .basis
                .tr_apply(&w.tm_tip.tr_mul_vec(&y), &mut sty.as_mut_slice()[..k]);
            let mut u = Vec6::zeros();
            for i in 0..k {
                u[i] = data.strain_force[o + i] - w.p_small[i] - sty[i];
            }
            if !cholesky_k(&mut w.dt, k) {
                return Err(DynamicsError::Singular {
                    rod: r,
                    piece: n,
                    what: "articulated piece inertia D̂_n",
                });
            }
            // With D̂ = LLᵀ, W = ÛL⁻ᵀ and ũ = L⁻¹u: ÛD̂⁻¹Ûᵀ = WWᵀ and
            // ÛD̂⁻¹u = Wũ, and pass 3 needs only q̈ = L⁻ᵀ(ũ − Wᵀη̇).
            right_solve_lt(&w.dt, k, &mut w.ut);
            forward_sub(&w.dt, k, &mut u);
            let wm = &w.ut;
            let wwt = Sym6::gram_rows(wm);
            let mut next = if leaf { w.mt } else { w.mt + carried };
            next -= wwt;
            ma_next = next;
            pa_next = w.p_big + ad_inv_tr_vec(&w.tip, &y) + wm * u;
            w.u = u;
        }
        let mut etadot = gravity_base_acceleration(model, rm, scale);
        for (n, piece) in pieces.iter().enumerate() {
            let k = piece.basis.dof();
            let o = rm.dof_offset + piece.dof_offset;
            let w = &data.pieces[r][n];
            let mut qn = w.u - w.ut.tr_mul(&etadot);
            backward_sub(&w.dt, k, &mut qn);
            data.qdd.as_mut_slice()[o..o + k].copy_from_slice(&qn.as_slice()[..k]);
            let sq = w.tm_tip.mul_vec(&piece.basis.apply(&qn.as_slice()[..k]));
            etadot = ad_inv_vec(&w.tip, &etadot) + sq + w.acc_tip;
        }
    }
    Ok(())
}

crate::kernels::simd::dispatch! {
    /// Mass matrix of the chain by the composite recursion (D19–D20), block
    /// diagonal across rods (argument checked by the caller). Result in
    /// `data.mass`.
    pub(crate) fn mass_matrix(model: &Model, data: &mut Data, q: &[f64])
    => mass_matrix_impl, mass_matrix_avx2
}

#[inline(always)]
pub(crate) fn mass_matrix_impl(model: &Model, data: &mut Data, q: &[f64]) {
    outward_inl(
        model,
        data,
        Motion::at_rest(q),
        Pass::Composite,
        Forces::ALL,
    );
    let n = model.n_dof();
    if data.mass.nrows() != n {
        data.mass = nalgebra::DMatrix::zeros(n, n);
    }
    // One rod writes every entry below; several leave cross-rod blocks that
    // must be zero.
    if model.rods().len() > 1 {
        data.mass.as_mut_slice().fill(0.0);
    }
    for (r, rm) in model.rods().iter().enumerate() {
        let pieces = rm.spec.geometry.pieces();
        let mut mc_next = Sym6::default();
        for m in (0..pieces.len()).rev() {
            let w = &data.pieces[r][m];
            let km = pieces[m].basis.dof();
            let om = rm.dof_offset + pieces[m].dof_offset;
            // M_mm = 𝓓 + BᵀT₋ᵀ𝓜ᶜT₋B, F = 𝓤 + A_ℓᵀ𝓜ᶜT₋B (D20), from
            // C = A_ℓᵀ𝓜ᶜA_ℓ (needed for 𝓜ᶜ_m anyway) and T₋ = A_ℓT₊ as in
            // the forward dynamics.
            let mut f = w.ut;
            let mut mmm = w.dt;
            let carried = mc_next.congruence_ad_inv(&w.tip);
            let tplus = w.tm_tip.transpose_blocks();
            let mct = carried.mul_op(&tplus);
            project_add_blocks(
                &pieces[m].basis,
                &mct,
                &Blk6::tr_premul_sym(&tplus, &mct),
                &mut f,
                &mut mmm,
            );
            // Upper triangle only (rows of earlier pieces); mirrored below.
            // The k×k block whole: the lower half is overwritten by the
            // mirror anyway, and whole columns copy without `memcpy` calls.
            put_block(&mut data.mass, om, om, &mmm, km, km);
            // M_nm = S_n(ℓ)ᵀ A…ᵀ F for n < m, evaluated as the pairing of
            // the world-frame twists Ad_{g_n(ℓ)}S_n(ℓ) with the world-frame
            // wrench Ad*_{g_m(0)⁻¹}F: one 6×6 product per block instead
            // of carrying F down the chain with a second one.
            let to_world = w.base_pose.ad_inv();
            let mut f_world = Mat6::zeros();
            for j in 0..km {
                f_world.set_column(j, &to_world.tr_mul_vec(&f.column(j).into_owned()));
            }
            for (wn, pn) in data.pieces[r][..m].iter().zip(&pieces[..m]) {
                let kn = pn.basis.dof();
                let on = rm.dof_offset + pn.dof_offset;
                let blk = wn.s_world.tr_mul(&f_world);
                put_block(&mut data.mass, on, om, &blk, kn, km);
            }
            mc_next = w.mt + carried;
        }
    }
    data.mass.fill_lower_triangle_with_upper_triangle();
}

/// Writes the top-left `nr × nc` of `src` into `dst` at `(r0, c0)`.
///
/// Full 6-row columns go as fixed-size copies: nalgebra's `copy_from` on
/// views (and a plain element loop, which LLVM turns back into one) calls
/// `memcpy` per column, which cost ~10 % of the mass matrix at N = 10.
#[inline]
fn put_block(
    dst: &mut nalgebra::DMatrix<f64>,
    r0: usize,
    c0: usize,
    src: &Mat6,
    nr: usize,
    nc: usize,
) {
    let ld = dst.nrows();
    let out = dst.as_mut_slice();
    for j in 0..nc {
        let col = &mut out[(c0 + j) * ld + r0..][..nr];
        let s = &src.as_slice()[6 * j..6 * j + 6];
        if let Ok(c6) = <&mut [f64; 6]>::try_from(&mut *col) {
            *c6 = [s[0], s[1], s[2], s[3], s[4], s[5]];
        } else {
            for (d, v) in col.iter_mut().zip(s) {
                *d = *v;
            }
        }
    }
}
