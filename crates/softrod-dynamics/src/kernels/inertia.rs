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
///
/// The isotropic form also carries `Σ m T_a` and `Σ m T_aᵀT_a` as scalar
/// sums: `T_a = xI + c_b k̃ + c_c k̃²` is a polynomial in `k̃`
/// ([`softrod_lie::PieceMaps::eval_with_ta`]), and
/// `T_aᵀT_a = −2c_b I + (2x c_c − c_b² − θ²c_c²) kkᵀ` (D91): four scalar sums
/// per point and one assembly per piece replace a symmetric 3×3 product, a
/// scaling and two 3×3 sums. Both coefficients are non-negative sums without
/// cancellation, so the assembled `𝓓₂₂` is positive definite at any bend
/// angle (the form `x²I + g k̃²` is not: across `k` it cancels to a relative
/// `~εψ²`, D91).
#[derive(Default)]
pub(crate) struct FullSums {
    u11: softrod_lie::Mat3,
    u12: softrod_lie::Mat3,
    u21: softrod_lie::Mat3,
    u22: softrod_lie::Mat3,
    d11: softrod_lie::Mat3,
    d12: softrod_lie::Mat3,
    d22: softrod_lie::Mat3,
    /// `Σ m T_b` of the isotropic form (`u21`, `u22`, `d22` unused).
    tb_m: softrod_lie::Mat3,
    /// `Σ m x`, `Σ m c_b`, `Σ m c_c` (so `Σ m T_a`) and `Σ m g`,
    /// `g = 2x c_c − c_b² − θ²c_c²` (with `Σ m c_b`, `Σ m T_aᵀT_a`, D91), of
    /// the isotropic form.
    ta_sums: [f64; 4],
    isotropic: bool,
}

/// `ψ² = θ²L²` of a piece above which [`FullSums`] takes the general form
/// even for an isotropic inertia (D111): beyond `ψ = 1e8` the cross-`k`
/// entries of `T_a` keep a relative `εψ > 1e-8` and less (none beyond
/// `1/ε`), and only sums of the same rounded `T₋` (a Gram matrix of its
/// columns) keep `𝓓ᶠ` positive semidefinite there; the scalar `𝓓₂₂` of D91
/// is exact where `𝓓₁₂` is not.
const PSI2_SCALAR_MAX: f64 = 1e16;

impl FullSums {
    /// Empty sums for a piece whose points all have an isotropic linear
    /// inertia `m·I` (`isotropic`) or not, bent by `ψ² = θ²L²` (`psi2`): the
    /// isotropic form for `ψ ≤ 1e8` only (D111).
    #[inline(always)]
    pub(crate) fn new(isotropic: bool, psi2: f64) -> Self {
        Self {
            isotropic: isotropic && psi2 <= PSI2_SCALAR_MAX,
            ..Self::default()
        }
    }

    /// Adds one point, `A = Ad⁻¹_g` given by `g = (R, p)`: with
    /// `Aᵀ = [[R, p̃R], [0, R]]` the U blocks are `RP + p̃(RQ)`, `p̃(RR')`,
    /// `RQ`, `RR'`: three products and two cross-product sweeps, and no
    /// `Ad⁻¹` block built.
    ///
    /// `ta = [x, c_b, c_c]` and `theta2 = θ²` describe `T_a` as a polynomial
    /// in `k̃` ([`softrod_lie::PieceMaps::eval_with_ta`]).
    #[inline(always)]
    pub(crate) fn add(&mut self, g: &Pose, t: &AdOp, mw: &Vec6, ta: &[f64; 3], theta2: f64) {
        if self.isotropic {
            let m = mw[3];
            let p = scale_rows(&softrod_lie::angular(mw), &t.a);
            let q = t.b * m;
            // Taᵀ J Ta + Tbᵀ m Tb is symmetric.
            self.d11 += tr_mul_sym2(&t.a, &p, &t.b, &q);
            self.d12 += q.tr_mul(&t.a);
            let [x, cb, cc] = *ta;
            let s = &mut self.ta_sums;
            s[0] += m * x;
            s[1] += m * cb;
            s[2] += m * cc;
            s[3] += m * ((2.0 * x * cc - cb * cb) - theta2 * (cc * cc));
            // RQ = m(T_bᵀ − p̃T_aᵀ) and p̃RR' = m p̃T_aᵀ (see the type's docs).
            let pta = cross_cols(&g.translation, &t.a.transpose()) * m;
            let rq = q.transpose() - pta;
            self.u11 += g.rotation * p + cross_cols(&g.translation, &rq);
            self.u12 += pta;
            self.tb_m += q;
            return;
        }
        let (p, r, q) = scaled_blocks(&softrod_lie::angular(mw), &softrod_lie::linear(mw), t);
        // Taᵀ J Ta + Tbᵀ m Tb and Taᵀ m Ta are symmetric.
        self.d11 += tr_mul_sym2(&t.a, &p, &t.b, &q);
        self.d12 += t.b.tr_mul(&r);
        self.d22 += tr_mul_sym(&t.a, &r);
        let rot = &g.rotation;
        let rq = rot * q;
        let rr = rot * r;
        self.u11 += rot * p + cross_cols(&g.translation, &rq);
        self.u12 += cross_cols(&g.translation, &rr);
        self.u21 += rq;
        self.u22 += rr;
    }

    /// Projects on the basis: `ut = 𝓤ᶠB` (6×k), `dt = Bᵀ𝓓ᶠB` (k×k, full);
    /// `maps` are the piece's, whose `k̃` the isotropic sums need.
    pub(crate) fn project(
        &mut self,
        maps: &softrod_lie::PieceMaps,
        basis: &softrod_kinematics::Basis,
        ut: &mut Mat6,
        dt: &mut Mat6,
    ) {
        if self.isotropic {
            let (km, k2) = (maps.k_skew(), maps.k_skew_squared());
            let [sx, scb, scc, sg] = self.ta_sums;
            // (Σ m T_a)ᵀ = Σm x I − Σm c_b k̃ + Σm c_c k̃².
            self.u22 = km * (-scb) + k2 * scc + softrod_lie::Mat3::from_diagonal_element(sx);
            self.u21 = self.tb_m.transpose() - self.u12;
            // Σ m T_aᵀT_a = −2Σm c_b I + Σm g kkᵀ (D91), both terms ≥ 0.
            let k = maps.k();
            self.d22 =
                outer_sym(&(k * sg), &k) + softrod_lie::Mat3::from_diagonal_element(-2.0 * scb);
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

#[cfg(test)]
mod tests {
    use super::*;
    use softrod_lie::PieceMaps;

    /// The isotropic form of [`FullSums`] (the scalar sums of `T_a`, the
    /// identities `R T_a = T_aᵀ`, `R T_b = T_bᵀ − p̃T_aᵀ`) against the general
    /// form's dense products, on the same points with `m·I` linear inertia.
    #[test]
    fn isotropic_sums_equal_the_general_ones() {
        let basis = softrod_kinematics::Basis::all();
        let d = Vec6::new(0.2, 0.1, -0.4, 0.3, -0.5, 0.9);
        let xis = [
            Vec6::new(0.3, -1.1, 0.7, 1.05, 0.2, -0.1),
            Vec6::new(1e-9, 0.0, 2e-9, 0.9, 0.01, 0.0),
            Vec6::new(12.0, -30.0, 5.0, 1.2, -0.3, 0.4),
        ];
        for xi in &xis {
            for rate in [None, Some(&d)] {
                let maps = PieceMaps::new(xi, rate);
                let (mut iso, mut general) = (FullSums::new(true, 0.0), FullSums::new(false, 0.0));
                for (x, w) in [(0.07, 0.17), (0.3, 0.33), (0.55, 0.33), (0.78, 0.17)] {
                    let (g, t, _, ta) = maps.eval_with_ta(x);
                    // A tapered section: the inertia changes along the piece.
                    let mw = Vec6::new(2e-3, 1e-3, 1.1e-3, 0.5, 0.5, 0.5) * (w * (1.0 + x));
                    iso.add(&g, &t, &mw, &ta, maps.theta_squared());
                    general.add(&g, &t, &mw, &ta, maps.theta_squared());
                }
                let (mut u_iso, mut d_iso) = (Mat6::zeros(), Mat6::zeros());
                let (mut u_gen, mut d_gen) = (Mat6::zeros(), Mat6::zeros());
                iso.project(&maps, &basis, &mut u_iso, &mut d_iso);
                general.project(&maps, &basis, &mut u_gen, &mut d_gen);
                let tol_u = 1e-13 * (1.0 + u_gen.amax());
                let tol_d = 1e-13 * (1.0 + d_gen.amax());
                assert!((u_iso - u_gen).amax() < tol_u, "{xi:?}: {u_iso} vs {u_gen}");
                assert!((d_iso - d_gen).amax() < tol_d, "{xi:?}: {d_iso} vs {d_gen}");
            }
        }
    }

    /// `𝓓₂₂ = Σ m T_aᵀT_a` of the isotropic form (D91) at bend angles per
    /// piece `ψ = θL` from 1e-8 to 1e6 rad, against its eigenvalues — `Σ m x²`
    /// along `k`, `Σ m (2 sin(θx/2)/θ)²` across it (`|∫₀ˣ e^{iθu} du|²`, here
    /// with `sin` where the code has `b = (1 − cos ψ)/ψ²`) — and against the
    /// dense products of the general form (what the isotropic form computed
    /// before the scalar sums). Bounds: each eigenvalue to a few ε of itself
    /// where `k` lies along an axis (no entry mixes the two), and to a few ε
    /// of the largest, `Σ m x²`, in a general direction, the rounding of
    /// entries of that size (D91); the dense products to the latter.
    #[test]
    fn isotropic_d22_holds_at_any_bend_angle() {
        let basis = softrod_kinematics::Basis::all();
        let len = 0.02;
        // 4-point Gauss–Legendre on [0, L].
        let (g1, g2) = (0.339_981_043_584_856_3, 0.861_136_311_594_052_6);
        let (w1, w2) = (0.652_145_154_862_546_1, 0.347_854_845_137_453_9);
        let points = [(g2, w2), (g1, w1), (-g1, w1), (-g2, w2)]
            .map(|(g, w)| (0.5 * len * (1.0 - g), 0.5 * len * w));
        let (mass, inertia) = (0.221, 3.5e-6);
        let dirs = [
            softrod_lie::Vec3::new(0.0, 1.0, 0.0),
            softrod_lie::Vec3::new(0.36, -0.8, 0.48),
        ];
        let mut psis: Vec<f64> = (-16..=12).map(|e| 10f64.powf(0.5 * e as f64)).collect();
        psis.extend([0.3, 1.5, 2.0, std::f64::consts::PI, 5.0, 6.3, 2.5e5]);
        let eps = f64::EPSILON;
        for (axis_aligned, n) in dirs.iter().enumerate().map(|(i, n)| (i == 0, n)) {
            // Two unit vectors across `k`.
            let u1 = n.cross(&softrod_lie::Vec3::new(1.0, 0.0, 0.0)).normalize();
            let u2 = n.cross(&u1);
            for &psi in &psis {
                let theta = psi / len;
                let k = n * theta;
                let xi = Vec6::new(k[0], k[1], k[2], 0.9, 0.1, -0.2);
                let maps = PieceMaps::new(&xi, None);
                let (mut iso, mut general) = (FullSums::new(true, 0.0), FullSums::new(false, 0.0));
                let (mut along, mut across) = (0.0, 0.0);
                for &(x, w) in &points {
                    let (g, t, _, ta) = maps.eval_with_ta(x);
                    let mw = Vec6::new(inertia, inertia, 2.0 * inertia, mass, mass, mass) * w;
                    iso.add(&g, &t, &mw, &ta, maps.theta_squared());
                    general.add(&g, &t, &mw, &ta, maps.theta_squared());
                    along += mass * w * x * x;
                    let chord = if theta > 0.0 {
                        2.0 * (0.5 * theta * x).sin() / theta
                    } else {
                        x
                    };
                    across += mass * w * chord * chord;
                }
                let (mut u_iso, mut d_iso) = (Mat6::zeros(), Mat6::zeros());
                let (mut u_gen, mut d_gen) = (Mat6::zeros(), Mat6::zeros());
                iso.project(&maps, &basis, &mut u_iso, &mut d_iso);
                general.project(&maps, &basis, &mut u_gen, &mut d_gen);
                let di: softrod_lie::Mat3 = d_iso.fixed_view::<3, 3>(3, 3).into();
                let dg: softrod_lie::Mat3 = d_gen.fixed_view::<3, 3>(3, 3).into();
                let quad = |d: &softrod_lie::Mat3, a: &softrod_lie::Vec3, b: &softrod_lie::Vec3| {
                    a.dot(&(d * b))
                };
                let at = format!("ψ = {psi:e}, k along an axis: {axis_aligned}");
                // Along k: x² per point, no cancellation.
                let e = (quad(&di, n, n) - along).abs();
                assert!(e <= 16.0 * eps * along, "{at}: along {e:e} of {along:e}");
                // Across k.
                let tol = if axis_aligned { across } else { along } * 16.0 * eps;
                for (a, b) in [(&u1, &u1), (&u2, &u2)] {
                    let e = (quad(&di, a, b) - across).abs();
                    assert!(e <= tol, "{at}: across {e:e} of {across:e}");
                }
                for (a, b) in [(&u1, &u2), (&u1, n), (&u2, n)] {
                    let e = quad(&di, a, b).abs();
                    assert!(e <= 16.0 * eps * along, "{at}: off-diagonal {e:e}");
                }
                // The dense products: the same matrix to the rounding of
                // entries of size Σ m x².
                let e = (di - dg).amax();
                assert!(e <= 16.0 * eps * along, "{at}: dense {e:e} of {along:e}");
                // Definite where the dense products are.
                if dg.cholesky().is_some() {
                    assert!(di.cholesky().is_some(), "{at}: {di} not definite");
                }
                if axis_aligned {
                    assert!(di.cholesky().is_some(), "{at}: {di} not definite");
                }
                // The 𝓤 blocks (the isotropic identities, `Σ m T_a` from
                // its scalar sums) to the rounding of their entries.
                let e = (u_iso - u_gen).amax();
                assert!(e <= 16.0 * eps * u_gen.amax(), "{at}: 𝓤 {e:e}");
            }
        }
    }

    /// Beyond `ψ = 1e8` an isotropic piece takes the general form (D111),
    /// here at the strain a diverged rk4 step reached in
    /// softrod-cli's tests/watch.rs (`ψ = 3.4e30`, a shear of 1e45): the
    /// sums equal the general ones bit for bit, and the `(k_y, q_z)` block of
    /// `𝓓ᶠ`, a Gram matrix of the rounded `T₋` columns, keeps a non-negative
    /// determinant, where the exact scalar `𝓓₂₂` of D91 (4e-67, next to a
    /// `𝓓₁₂` whose rounding is 1e-10) makes it negative.
    #[test]
    fn a_bend_beyond_double_precision_takes_the_general_form() {
        let basis = softrod_kinematics::Basis::all();
        let len = 0.02;
        let xi = Vec6::new(
            0.0,
            1.682_825_912_807_287_2e32,
            0.0,
            1.0,
            0.7,
            -1.321_359_538_564_532_7e45,
        );
        let psi2 = xi[1] * xi[1] * len * len;
        let maps = PieceMaps::new(&xi, None);
        let (mut guarded, mut general, mut scalar) = (
            FullSums::new(true, psi2),
            FullSums::new(false, psi2),
            FullSums::new(true, 0.0),
        );
        let (g1, g2) = (0.339_981_043_584_856_3, 0.861_136_311_594_052_6);
        let (w1, w2) = (0.652_145_154_862_546_1, 0.347_854_845_137_453_9);
        for (g, w) in [(g2, w2), (g1, w1), (-g1, w1), (-g2, w2)] {
            let (x, w) = (0.5 * len * (1.0 - g), 0.5 * len * w);
            let (pose, t, _, ta) = maps.eval_with_ta(x);
            let mw = Vec6::new(7.0e-6, 3.5e-6, 3.5e-6, 0.221, 0.221, 0.221) * w;
            for fs in [&mut guarded, &mut general, &mut scalar] {
                fs.add(&pose, &t, &mw, &ta, maps.theta_squared());
            }
        }
        let mut out = [(Mat6::zeros(), Mat6::zeros()); 3];
        for (fs, (u, d)) in [guarded, general, scalar].iter_mut().zip(&mut out) {
            fs.project(&maps, &basis, u, d);
        }
        assert_eq!(out[0], out[1]);
        let det = |d: &Mat6| d[(1, 1)] * d[(5, 5)] - d[(1, 5)] * d[(5, 1)];
        assert!(det(&out[0].1) >= 0.0, "{}", out[0].1);
        // What the guard avoids: the scalar 𝓓₂₂ there.
        assert!(det(&out[2].1) < 0.0, "{}", out[2].1);
    }
}
