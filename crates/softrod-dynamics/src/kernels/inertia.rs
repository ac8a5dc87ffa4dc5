//! Sums over a piece's evaluation points of the inertia integrals the
//! recursions need (D20): `𝓜ᵗ = Σ wAᵀ𝓜A` ([`PointInertia`]), `𝓤ᶠ`, `𝓓ᶠ`
//! in 3×3 blocks ([`FullSums`]), their projection on a strain basis
//! ([`project_add`]) and the columns of `S = T₋B` ([`s_columns`]).

use crate::kernels::blocks::{Sym6, cross_cols, mul_tr_sym, tr_mul_sym, tr_mul_sym2};
use softrod_lie::{AdOp, Mat6, Pose, Vec6};

/// `diag(d) M` by row scaling (bit-identical to the product with the
/// diagonal matrix: the off-diagonal terms only add exact zeros).
#[inline(always)]
fn scale_rows(d: &softrod_lie::Vec3, m: &softrod_lie::Mat3) -> softrod_lie::Mat3 {
    softrod_lie::Mat3::from_fn(|i, j| d[i] * m[(i, j)])
}

/// `diag(dw, dv)·Y` for a block operator `Y = [[ya,0],[yb,ya]]`, kept as the
/// three distinct 3×3 blocks `(dw ya, dv ya, dv yb)`.
#[inline(always)]
fn scaled_blocks(
    dw: &softrod_lie::Vec3,
    dv: &softrod_lie::Vec3,
    y: &AdOp,
) -> (softrod_lie::Mat3, softrod_lie::Mat3, softrod_lie::Mat3) {
    (
        scale_rows(dw, &y.a),
        scale_rows(dv, &y.a),
        scale_rows(dv, &y.b),
    )
}

/// `acc += Xᵀ diag(d) Y` with `diag(d) Y` given by [`scaled_blocks`]
/// (the weight already in `d`): five 3×3 products instead of two dense
/// 6×6 ones.
#[inline(always)]
fn add_sandwich(
    acc: &mut Mat6,
    x: &AdOp,
    (dw_ya, dv_ya, dv_yb): &(softrod_lie::Mat3, softrod_lie::Mat3, softrod_lie::Mat3),
) {
    let tl = x.a.tr_mul(dw_ya) + x.b.tr_mul(dv_yb);
    let tr = x.b.tr_mul(dv_ya);
    let bl = x.a.tr_mul(dv_yb);
    let br = x.a.tr_mul(dv_ya);
    let mut v = acc.fixed_view_mut::<3, 3>(0, 0);
    v += tl;
    let mut v = acc.fixed_view_mut::<3, 3>(0, 3);
    v += tr;
    let mut v = acc.fixed_view_mut::<3, 3>(3, 0);
    v += bl;
    let mut v = acc.fixed_view_mut::<3, 3>(3, 3);
    v += br;
}

/// `a bᵀ` known to be symmetric (`a` a multiple of `b`): six products,
/// mirrored.
#[inline(always)]
fn outer_sym(a: &softrod_lie::Vec3, b: &softrod_lie::Vec3) -> softrod_lie::Mat3 {
    let (m00, m01, m02) = (a[0] * b[0], a[0] * b[1], a[0] * b[2]);
    let (m11, m12, m22) = (a[1] * b[1], a[1] * b[2], a[2] * b[2]);
    softrod_lie::Mat3::new(m00, m01, m02, m01, m11, m12, m02, m12, m22)
}

/// Elementwise product with a diagonal given as a vector.
#[inline(always)]
pub(crate) fn diag_mul(d: &Vec6, v: &Vec6) -> Vec6 {
    d.component_mul(v)
}

/// Running sums of `𝓜ᵗ = Σ w Aᵀ𝓜A` over a piece's points: the
/// spatial-inertia form for isotropic linear inertia, a block sandwich for
/// the others.
#[derive(Default)]
pub(crate) struct PointInertia {
    sp: SpatialSums,
    mt: Mat6,
    sandwiched: bool,
}

impl PointInertia {
    /// Adds `Aᵀ diag(mw) A`, `A = Ad⁻¹_g` (the weight already in `mw`).
    #[inline(always)]
    pub(crate) fn add(&mut self, gl: &Pose, mw: &Vec6) {
        // With an isotropic linear inertia m·I and A = Ad⁻¹ of (R, p) this
        // is the classic spatial inertia [[R J Rᵀ − m p̃², m p̃], [−m p̃, m I]];
        // accumulate its parts.
        if mw[3] == mw[4] && mw[3] == mw[5] {
            // R J Rᵀ = (RJ)Rᵀ and m ppᵀ by their upper halves (symmetric
            // by construction): 27 multiplications where the three outer
            // products of R's columns and the dense ppᵀ take 63.
            let sp = &mut self.sp;
            let r = &gl.rotation;
            let pt = &gl.translation;
            let rj = softrod_lie::Mat3::from_fn(|i, j| r[(i, j)] * mw[j]);
            sp.rot += mul_tr_sym(&rj, r);
            let mp = pt * mw[3];
            sp.mass += mw[3];
            sp.mp += mp;
            sp.mpp += outer_sym(&mp, pt);
            sp.mp2 += mp.dot(pt);
        } else {
            let a = gl.ad_inv();
            let dw = softrod_lie::angular(mw);
            let dv = softrod_lie::linear(mw);
            let m_a = scaled_blocks(&dw, &dv, &a);
            add_sandwich(&mut self.mt, &a, &m_a);
            self.sandwiched = true;
        }
    }

    /// The sum `𝓜ᵗ`.
    #[inline(always)]
    pub(crate) fn finish(&self) -> Sym6 {
        if self.sandwiched {
            Sym6::from_mat6(&self.mt) + self.sp.to_sym6()
        } else {
            self.sp.to_sym6()
        }
    }
}

/// Running sums of the spatial-inertia form of `∫Aᵀ𝓜A` (isotropic `ρA`).
#[derive(Default)]
struct SpatialSums {
    rot: softrod_lie::Mat3,
    mass: f64,
    mp: softrod_lie::Vec3,
    mpp: softrod_lie::Mat3,
    mp2: f64,
}

impl SpatialSums {
    /// `[[Σ R J Rᵀ + Σm|p|² I − Σm ppᵀ, (Σ m p)~], [−(Σ m p)~, Σm I]]`.
    fn to_sym6(&self) -> Sym6 {
        Sym6 {
            a: self.rot + softrod_lie::Mat3::from_diagonal_element(self.mp2) - self.mpp,
            b: softrod_lie::skew(&self.mp),
            c: softrod_lie::Mat3::from_diagonal_element(self.mass),
        }
    }
}

/// Running sums of `𝓤ᶠ = Σ w Aᵀ𝓜T₋` and `𝓓ᶠ = Σ w T₋ᵀ𝓜T₋` in 3×3
/// blocks, before the projection on the basis (`𝓤 = 𝓤ᶠB`, `𝓓 = Bᵀ𝓓ᶠB`).
/// With `𝓜T₋ = [[P, 0], [Q, R]]` (`P = J_ω T_a`, `Q = m T_b`, `R = m T_a`)
/// both cost six 3×3 products (the symmetric ones by their upper halves)
/// and two cross-product sweeps per point, where the column-by-column form
/// costs `k` matrix–vector products and `k(k+1)/2` 6-vector dots: for
/// `k ≥ 4` the blocks win.
///
/// With an isotropic linear inertia `m·I` (every Cosserat section) two of
/// the three rotations go: for a constant strain `R(x) T_a(x) = T_aᵀ(x)` and
/// `R(x) T_b(x) = T_bᵀ(x) − p̃ T_aᵀ(x)` exactly. Both follow from
/// `Ad_g T₋ = ∫₀ˣ e^{u ad_ξ} du = T₊` (substitute `u = x − s`) and from the
/// blocks of `T₊` being the transposes of those of `T₋` (in the block form of
/// `tangent_blocks`, the sign flips exactly the skew parts). So
/// `RR' = m T_aᵀ` and `RQ = m(T_bᵀ − p̃T_aᵀ)` need no product, `𝓤₂₂ = (Σ m T_a)ᵀ`,
/// `𝓤₂₁ = (Σ m T_b)ᵀ − 𝓤₁₂` are formed once per piece.
#[derive(Default)]
pub(crate) struct FullSums {
    u11: softrod_lie::Mat3,
    u12: softrod_lie::Mat3,
    u21: softrod_lie::Mat3,
    u22: softrod_lie::Mat3,
    d11: softrod_lie::Mat3,
    d12: softrod_lie::Mat3,
    d22: softrod_lie::Mat3,
    /// `Σ m T_a`, `Σ m T_b` of the isotropic form (`u21`, `u22` unused).
    ta_m: softrod_lie::Mat3,
    tb_m: softrod_lie::Mat3,
    isotropic: bool,
}

impl FullSums {
    /// Empty sums for a piece whose points all have an isotropic linear
    /// inertia `m·I` (`isotropic`) or not.
    #[inline(always)]
    pub(crate) fn new(isotropic: bool) -> Self {
        Self {
            isotropic,
            ..Self::default()
        }
    }

    /// Adds one point, `A = Ad⁻¹_g` given by `g = (R, p)`: with
    /// `Aᵀ = [[R, p̃R], [0, R]]` the U blocks are `RP + p̃(RQ)`, `p̃(RR')`,
    /// `RQ`, `RR'`: three products and two cross-product sweeps, and no
    /// `Ad⁻¹` block built.
    #[inline(always)]
    pub(crate) fn add(&mut self, g: &Pose, t: &AdOp, mw: &Vec6) {
        let (p, r, q) = scaled_blocks(&softrod_lie::angular(mw), &softrod_lie::linear(mw), t);
        // Taᵀ J Ta + Tbᵀ m Tb and Taᵀ m Ta are symmetric.
        self.d11 += tr_mul_sym2(&t.a, &p, &t.b, &q);
        self.d12 += t.b.tr_mul(&r);
        self.d22 += tr_mul_sym(&t.a, &r);
        if self.isotropic {
            // RQ = m(T_bᵀ − p̃T_aᵀ) and p̃RR' = m p̃T_aᵀ (see the type's docs).
            let m = mw[3];
            let pta = cross_cols(&g.translation, &t.a.transpose()) * m;
            let rq = q.transpose() - pta;
            self.u11 += g.rotation * p + cross_cols(&g.translation, &rq);
            self.u12 += pta;
            self.ta_m += r;
            self.tb_m += q;
            return;
        }
        let rot = &g.rotation;
        let rq = rot * q;
        let rr = rot * r;
        self.u11 += rot * p + cross_cols(&g.translation, &rq);
        self.u12 += cross_cols(&g.translation, &rr);
        self.u21 += rq;
        self.u22 += rr;
    }

    /// Projects on the basis: `ut = 𝓤ᶠB` (6×k), `dt = Bᵀ𝓓ᶠB` (k×k, full).
    pub(crate) fn project(
        &mut self,
        basis: &softrod_kinematics::Basis,
        ut: &mut Mat6,
        dt: &mut Mat6,
    ) {
        if self.isotropic {
            self.u22 = self.ta_m.transpose();
            self.u21 = self.tb_m.transpose() - self.u12;
        }
        let d = Sym6 {
            a: self.d11,
            b: self.d12,
            c: self.d22,
        };
        if basis.is_identity() {
            // In place: no 6×6 temporaries to copy.
            ut.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.u11);
            ut.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.u12);
            ut.fixed_view_mut::<3, 3>(3, 0).copy_from(&self.u21);
            ut.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.u22);
            d.write_dense(dt);
        } else {
            let mut uf = Mat6::zeros();
            uf.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.u11);
            uf.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.u12);
            uf.fixed_view_mut::<3, 3>(3, 0).copy_from(&self.u21);
            uf.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.u22);
            ut.fill(0.0);
            dt.fill(0.0);
            project_add(basis, &uf, &d.dense(), ut, dt);
        }
    }
}

/// [`project_add`] for block-form `X_u`, `X_d`: an `I₆` piece adds the
/// blocks in place, other bases go through the dense forms.
#[inline(always)]
pub(crate) fn project_add_blocks(
    basis: &softrod_kinematics::Basis,
    xu: &crate::kernels::blocks::Blk6,
    xd: &Sym6,
    ut: &mut Mat6,
    dt: &mut Mat6,
) {
    if basis.is_identity() {
        xu.add_to(ut);
        xd.add_to(dt);
    } else {
        project_add(basis, &xu.dense(), &xd.dense(), ut, dt);
    }
}

/// `ut += X_u B` (6×k) and `dt += Bᵀ X_d B` (k×k) for full-coordinate
/// matrices `X_u`, `X_d` (6×6): column gathers for a selection basis, a
/// plain copy for the identity.
#[inline(always)]
pub(crate) fn project_add(
    basis: &softrod_kinematics::Basis,
    xu: &Mat6,
    xd: &Mat6,
    ut: &mut Mat6,
    dt: &mut Mat6,
) {
    if basis.is_identity() {
        *ut += xu;
        *dt += xd;
        return;
    }
    match basis.selection() {
        Some(sel) => {
            for (c, &j) in sel.iter().enumerate() {
                let mut col = ut.column_mut(c);
                col += xu.column(j);
                for (r, &i) in sel.iter().enumerate() {
                    dt[(r, c)] += xd[(i, j)];
                }
            }
        }
        None => {
            for c in 0..basis.dof() {
                let bc = basis.column(c);
                let mut col = ut.column_mut(c);
                col += xu * bc;
                let xb = xd * bc;
                for r in 0..basis.dof() {
                    dt[(r, c)] += basis.column(r).dot(&xb);
                }
            }
        }
    }
}

/// The columns of `S = T₋ B` (6×k) into `out`; returns `k`. Selection bases
/// gather columns of `T₋ = [[A, 0], [B, A]]` instead of multiplying.
#[inline(always)]
pub(crate) fn s_columns(
    tm: &AdOp,
    basis: &softrod_kinematics::Basis,
    out: &mut [Vec6; 6],
) -> usize {
    let k = basis.dof();
    match basis.selection() {
        Some(sel) => {
            for (c, &j) in sel.iter().enumerate() {
                out[c] = if j < 3 {
                    let a = tm.a.column(j);
                    let b = tm.b.column(j);
                    Vec6::new(a[0], a[1], a[2], b[0], b[1], b[2])
                } else {
                    let a = tm.a.column(j - 3);
                    Vec6::new(0.0, 0.0, 0.0, a[0], a[1], a[2])
                };
            }
        }
        None => {
            for (c, o) in out.iter_mut().enumerate().take(k) {
                *o = tm.mul_vec(&basis.column(c));
            }
        }
    }
    k
}
