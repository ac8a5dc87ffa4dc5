//! Inverse dynamics, O(N) forward dynamics, the mass matrix and the
//! Cholesky forward dynamics.

use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::forces::external::gravity_base_acceleration;
use crate::forces::strain::strain_forces;
use crate::kernels::blocks::{Blk6, Sym6, ad_inv_tr_vec, ad_inv_vec};
use crate::kernels::chol::{backward_sub, cholesky_k, forward_sub, right_solve_lt};
use crate::kernels::inertia::project_add_blocks;
use crate::model::Model;
use crate::model::data::Data;
use crate::passes::{Pass, outward, outward_inl};
use nalgebra::DVector;
use softrod_lie::{Mat6, Vec6};

/// Checks a generalized vector argument: length `n_dof`, all finite.
pub(crate) fn check_vec(model: &Model, what: &'static str, v: &[f64]) -> Result<(), DynamicsError> {
    if v.len() != model.n_dof() {
        return Err(DynamicsError::SizeMismatch {
            what,
            got: v.len(),
            expected: model.n_dof(),
        });
    }
    if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(DynamicsError::NotFinite {
            what: format!("{what}[{i}]"),
            value: *x,
        });
    }
    Ok(())
}

crate::kernels::simd::dispatch! {
    /// Inverse dynamics by recursive Newton–Euler for PCS (docs/theory.md §4):
    /// the actuator force `τ_act` (n_dof) that produces `q̈` at `(q, q̇, t)`,
    ///
    /// `τ_act = M q̈ + C q̇ + G + τ_e + D q̇ − τ_c − Σ Jᵀ𝓕_p − ∫Jᵀ𝓕_d`.
    ///
    /// Outward pass (D7–D10) at the Gauss points, point-load abscissae and piece
    /// tips; inward pass (D17) for the transmitted wrenches `W_n`; projection
    /// (D18) on each piece's `S_n`. Gravity enters as a base acceleration. O(N).
    /// `q`, `q̇`, `q̈`: dim `n_dof`. Result in `data.tau`.
    pub fn inverse_dynamics_with<'a>(model: &Model, data: &'a mut Data, forces: Forces, t: f64, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<&'a DVector<f64>, DynamicsError>
    => inverse_dynamics_impl, inverse_dynamics_avx2
}

/// [`inverse_dynamics_with`] of every force of the model ([`Forces::ALL`]).
pub fn inverse_dynamics<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    inverse_dynamics_with(model, data, Forces::ALL, t, q, qd, qdd)
}

#[inline(always)]
pub(crate) fn inverse_dynamics_impl<'a>(
    model: &Model,
    data: &'a mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    forces.check()?;
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    check_vec(model, "qddot", qdd)?;
    if model.has_closures() {
        return Err(DynamicsError::UnsupportedClosed {
            what: "inverse_dynamics",
        });
    }
    if let Some(tree) = &model.tree {
        model.set_time(data, t);
        crate::tree_algorithms::inverse_dynamics(
            model,
            tree,
            data,
            forces,
            t,
            q,
            Some(qd),
            Some(qdd),
        );
        return Ok(&data.tau);
    }
    outward_inl(model, data, q, Some(qd), Some(qdd), Pass::Inverse, forces);
    strain_forces(model, data, forces, t, q, Some(qd), None);
    inward_inverse(model, data);
    Ok(&data.tau)
}

/// (D17–D18): `W_n = 𝓟_n + A_ℓᵀ W_{n+1}`, `τ_n = B_nᵀ(𝓹_n + T₋(ℓ)ᵀ W_{n+1}) − τ̃_n`.
pub(crate) fn inward_inverse(model: &Model, data: &mut Data) {
    for (r, rm) in model.rods().iter().enumerate() {
        if let (true, Some(pr)) = (model.uses_planar_path(r), &rm.planar) {
            crate::planar::inward_inverse(rm, pr, data, r);
            continue;
        }
        let mut wv = Vec6::zeros();
        for (n, piece) in rm.spec.rod.pieces().iter().enumerate().rev() {
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
    /// Forward dynamics by the O(N) articulated recursion (docs/theory.md
    /// §6, (D23)–(D27); §9 lists what it corrects in the model document): `q̈` (n_dof) at `(q, q̇, t)` under actuator
    /// force `τ_act` (n_dof, `None` = 0) and every term of the model.
    ///
    /// Pass 1 (outward): `g, η`, the per-piece integrals (D20) and bias sums (D23).
    /// Pass 2 (inward): articulated inertia and bias (D24–D26), one `k_n×k_n`
    /// Cholesky per piece. Pass 3 (outward): `q̈_n` and `η̇(L_n)` (D27). Cost
    /// O(N·n_g). Result in `data.qdd`.
    ///
    /// Fails if `D̂_n` is not positive definite (a degenerate basis or inertia).
    /// `forces` says which forces act ([`forward_dynamics`]: all of them).
    pub fn forward_dynamics_with<'a>(model: &Model, data: &'a mut Data, forces: Forces, t: f64, q: &[f64], qd: &[f64], tau_act: Option<&[f64]>) -> Result<&'a DVector<f64>, DynamicsError>
    => forward_dynamics_impl, forward_dynamics_avx2
}

/// [`forward_dynamics_with`] of every force of the model ([`Forces::ALL`]).
pub fn forward_dynamics<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<&'a DVector<f64>, DynamicsError> {
    forward_dynamics_with(model, data, Forces::ALL, t, q, qd, tau_act)
}

#[inline(always)]
pub(crate) fn forward_dynamics_impl<'a>(
    model: &Model,
    data: &'a mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<&'a DVector<f64>, DynamicsError> {
    forces.check()?;
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    if let Some(ta) = tau_act {
        check_vec(model, "tau", ta)?;
    }
    if let Some(tree) = &model.tree {
        model.set_time(data, t);
        if model.has_closures() {
            crate::constrained::forward_dynamics(model, tree, data, forces, t, q, qd, tau_act)?;
        } else {
            crate::tree_algorithms::forward_dynamics(model, tree, data, forces, t, q, qd, tau_act)?;
        }
        return check_qdd(data, t);
    }
    outward_inl(model, data, q, Some(qd), None, Pass::Articulated, forces);
    strain_forces(model, data, forces, t, q, Some(qd), tau_act);
    let scale = forces.load_scale;
    for (r, rm) in model.rods().iter().enumerate() {
        if model.uses_planar_path(r) {
            crate::planar::forward_rod(model, data, r, q, qd, forces)?;
            continue;
        }
        let pieces = rm.spec.rod.pieces();
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
    check_qdd(data, t)
}

/// `data.qdd`, or the first entry that is not finite as an error.
fn check_qdd(data: &Data, t: f64) -> Result<&DVector<f64>, DynamicsError> {
    if let Some((i, v)) = data.qdd.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(DynamicsError::NotFinite {
            what: format!("qddot[{i}] at t = {t}"),
            value: *v,
        });
    }
    Ok(&data.qdd)
}

crate::kernels::simd::dispatch! {
    /// Mass matrix `M(q) = ∫ Jᵀ𝓜J ds` (D19) by the composite recursion (D20):
    /// `𝓜ᶜ_n = 𝓜ᵗ_n + A_ℓᵀ𝓜ᶜ_{n+1}A_ℓ`, `M_mm = 𝓓_m + S_ℓᵀ𝓜ᶜ_{m+1}S_ℓ`, and
    /// the off-diagonal blocks `M_nm = S_n(ℓ)ᵀ A…ᵀ F_m` (n < m) of
    /// `F_m = 𝓤_m + A_ℓᵀ𝓜ᶜ_{m+1}S_ℓ` carried down the chain, evaluated as the
    /// pairing `(Ad_{g_n(ℓ)}S_n(ℓ))ᵀ(Ad*_{g_m(0)⁻¹}F_m)` of world-frame twists
    /// and wrenches (the pairing is frame-independent). Block diagonal across
    /// rods. Result in `data.mass` (n_dof × n_dof, symmetric positive
    /// definite). Cost O(N·n_dof). With prescribed joints (D59), at their
    /// values of the last [`Model::set_time`] or dynamics evaluation.
    pub fn mass_matrix<'a>(model: &Model, data: &'a mut Data, q: &[f64]) -> Result<&'a nalgebra::DMatrix<f64>, DynamicsError>
    => mass_matrix_impl, mass_matrix_avx2
}

#[inline(always)]
pub(crate) fn mass_matrix_impl<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
) -> Result<&'a nalgebra::DMatrix<f64>, DynamicsError> {
    check_vec(model, "q", q)?;
    if let Some(tree) = &model.tree {
        crate::tree_algorithms::mass_matrix(model, tree, data, q);
        return Ok(&data.mass);
    }
    outward_inl(model, data, q, None, None, Pass::Composite, Forces::ALL);
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
        let pieces = rm.spec.rod.pieces();
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
    Ok(&data.mass)
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

/// Forward dynamics through the mass matrix, the cross-check of the O(N)
/// recursion: `q̈ = M⁻¹(τ_act − ID(q, q̇, 0))` with a dense Cholesky
/// (O(n_dof³), allocates the factor). Result in `data.qdd`.
pub fn forward_dynamics_cholesky<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<&'a DVector<f64>, DynamicsError> {
    let zero = vec![0.0; model.n_dof()];
    inverse_dynamics(model, data, t, q, qd, &zero)?;
    let mut rhs = -data.tau.clone();
    if let Some(ta) = tau_act {
        check_vec(model, "tau", ta)?;
        rhs += DVector::from_column_slice(ta);
    }
    mass_matrix(model, data, q)?;
    let chol = data
        .mass
        .clone()
        .cholesky()
        .ok_or(DynamicsError::NotPositiveDefinite {
            what: "mass matrix",
        })?;
    data.qdd = chol.solve(&rhs);
    Ok(&data.qdd)
}

/// The bias `b(q, q̇, t) = ID(q, q̇, 0)`: `C q̇ + G + τ_e + D q̇ − τ_c − Q_ext`
/// (the equations of motion read `M q̈ + b = τ_act`; with loop closures
/// `M q̈ + b = τ_act + Jᵀλ`, docs/theory.md D67: `b` is the open tree's,
/// without the constraint forces), with prescribed joints (D59) moving as
/// prescribed at `t`. Result in `data.tau`.
pub fn bias_force<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    bias_force_with(model, data, Forces::ALL, t, q, qd)
}

/// [`bias_force`] under `forces`.
pub(crate) fn bias_force_with<'a>(
    model: &Model,
    data: &'a mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    if let Some(tree) = &model.tree {
        // With prescribed joints (D59) `b` includes their acceleration's
        // effect: only the free coordinates' `M q̈` is left out.
        model.set_time(data, t);
        crate::tree_algorithms::inverse_dynamics(model, tree, data, forces, t, q, Some(qd), None);
        return Ok(&data.tau);
    }
    outward(model, data, q, Some(qd), None, Pass::Inverse, forces);
    strain_forces(model, data, forces, t, q, Some(qd), None);
    inward_inverse(model, data);
    Ok(&data.tau)
}
