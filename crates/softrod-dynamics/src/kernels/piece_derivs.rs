//! Strain derivatives of the maps of one PCS piece (docs/theory-derivatives.md
//! §1, (D30)–(D36)): the directional derivative of `T₋(x)` as linear maps of
//! the strain perturbation, the second-order term of the bias `Ṡq̇`, and the
//! scalar coefficient families they need.
//!
//! Every map is a combination of per-piece matrices (powers of `P = ad_ξ`,
//! the operators `E_i`, `F_i`, `Ê_i` of (D32)–(D35)) with scalar
//! coefficients of `ψ = xθ`; the matrices are built once per piece
//! ([`PieceDerivMaps::new`]), the coefficients per evaluation point
//! ([`Coefficients::at`]).

use super::mat6::{Cols, mm_lower, tm, tmk};
use softrod_lie::series::{PSI_SWITCH, tau_rho};
use softrod_lie::{Mat6, Vec6, ad, angular, linear};

/// `σ_i(ψ) = ρ_i′(ψ)/ψ`, `i = 1…4` (D31): the second strain derivative of
/// the tangent coefficients. Series below [`PSI_SWITCH`] (14 terms,
/// `σ_i = Σ_{m≥2} 4m(m−1) c_{i,m} u^{m−2}/(i+2m+1)`, `u = ψ²`, Horner), closed
/// form `σ_i = (ψP_i′ − (i+3)P_i)/(2ψ^{i+5})`, `P_i = ψN_i′ − (i+1)N_i`,
/// `P_i′ = ψN_i″ − iN_i′` above (`N_i` of (D3)).
#[inline(always)]
pub(crate) fn sigma(psi: f64) -> [f64; 4] {
    let psi = psi.abs();
    if psi < PSI_SWITCH {
        sigma_series(psi * psi)
    } else {
        sigma_closed(psi)
    }
}

/// `c_{i,m}` of (D5): `(−1)^m (1−m)/(2m+i)!` for `i ≤ 2`, `(−1)^m (1+m)/(2m+i)!` otherwise.
const fn c_im(i: usize, m: usize) -> f64 {
    let mut f = 1.0;
    let mut n = 2;
    while n <= 2 * m + i {
        f *= n as f64;
        n += 1;
    }
    let sign = if m % 2 == 0 { 1.0 } else { -1.0 };
    let num = if i <= 2 {
        1.0 - m as f64
    } else {
        1.0 + m as f64
    };
    sign * num / f
}

const SIGMA_TERMS: usize = 14;

const fn sigma_table() -> [[f64; SIGMA_TERMS]; 4] {
    let mut out = [[0.0; SIGMA_TERMS]; 4];
    let mut i = 1;
    while i <= 4 {
        let mut t = 0;
        while t < SIGMA_TERMS {
            let m = t + 2;
            out[i - 1][t] =
                4.0 * (m as f64) * ((m - 1) as f64) * c_im(i, m) / ((i + 2 * m + 1) as f64);
            t += 1;
        }
        i += 1;
    }
    out
}

static SIGMA_SERIES: [[f64; SIGMA_TERMS]; 4] = sigma_table();

#[inline(always)]
fn sigma_series(u: f64) -> [f64; 4] {
    let mut out = [0.0; 4];
    for (o, row) in out.iter_mut().zip(SIGMA_SERIES.iter()) {
        let mut acc = 0.0;
        for c in row.iter().rev() {
            acc = acc * u + c;
        }
        *o = acc;
    }
    out
}

#[inline(always)]
fn sigma_closed(p: f64) -> [f64; 4] {
    let (s, c) = p.sin_cos();
    // N_i, N_i′, N_i″ (D3, D5).
    let n = [
        (4.0 - 4.0 * c - p * s, 3.0 * s - p * c, 2.0 * c + p * s),
        (
            4.0 * p - 5.0 * s + p * c,
            4.0 - 4.0 * c - p * s,
            3.0 * s - p * c,
        ),
        (2.0 - 2.0 * c - p * s, s - p * c, p * s),
        (2.0 * p - 3.0 * s + p * c, 2.0 - 2.0 * c - p * s, s - p * c),
    ];
    let mut out = [0.0; 4];
    for (i, ((n0, n1, n2), o)) in n.iter().zip(out.iter_mut()).enumerate() {
        let i = (i + 1) as f64;
        let pp = p * n1 - (i + 1.0) * n0;
        let dp = p * n2 - i * n1;
        *o = (p * dp - (i + 3.0) * pp) / (2.0 * p.powi(i as i32 + 5));
    }
    out
}

/// The scalar coefficients at one abscissa `x` (D30–D31):
/// `c_i = (−1)^i x^{i+1}τ_i`, `d_i = (−1)^i x^{i+3}ρ_i`, `h_i = (−1)^i x^{i+5}σ_i`,
/// `i = 1…4`, so that `T₋(x) = xI + Σ c_i P^i` and `D_ξ c_i[ζ] = d_i (k·ζ_k)`,
/// `D_ξ d_i[ζ] = h_i (k·ζ_k)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Coefficients {
    pub c: [f64; 4],
    pub d: [f64; 4],
    pub h: [f64; 4],
}

impl Coefficients {
    #[inline(always)]
    pub fn at(x: f64, theta: f64) -> Self {
        let psi = x * theta;
        let (t, r) = tau_rho(psi);
        let s = sigma(psi);
        let mut out = Self {
            c: [0.0; 4],
            d: [0.0; 4],
            h: [0.0; 4],
        };
        let mut xp = x * x; // x^{i+1}
        let mut sign = -1.0;
        for i in 0..4 {
            out.c[i] = sign * xp * t[i];
            out.d[i] = sign * xp * x * x * r[i];
            out.h[i] = sign * xp * x * x * x * x * s[i];
            xp *= x;
            sign = -sign;
        }
        out
    }
}

/// Per-piece matrices of the strain derivatives (D32–D35), for strain `ξ`,
/// rate `ξ̇`, acceleration `ξ̈` (all 6-vectors), `P = ad_ξ`.
#[derive(Clone, Debug)]
pub(crate) struct PieceDerivMaps {
    pub theta: f64,
    /// `P^i`, `i = 1…4` (index `i − 1`).
    pub p: [Mat6; 4],
    /// `k̄ = (k; 0)`, `ξ̇̄ = (ξ̇_k; 0)`, `k·ξ̇_k`.
    kbar: Vec6,
    kdbar: Vec6,
    kd: f64,
    /// `P^i ξ̇`, `P^i ξ̈` and `E_i(ξ̇)`, `E_i(ξ̈)` (D32).
    vd: [Vec6; 4],
    vdd: [Vec6; 4],
    ed: [Mat6; 4],
    edd: [Mat6; 4],
    /// `F_i = D(P^i)[ξ̇]` (D33).
    f: [Mat6; 4],
    /// `e_i` of the bias (D34) and `Ê_i = D_ξ e_i` (D35).
    e: [Vec6; 4],
    ehat: [Mat6; 4],
}

impl PieceDerivMaps {
    #[inline(always)]
    pub fn new(xi: &Vec6, xid: &Vec6, xidd: &Vec6) -> Self {
        // Every matrix here is of the form [[X, 0], [Y, X]] (`ad_v` and
        // its sums and products): products in that form (`mm_lower`).
        let k = angular(xi);
        let pm = ad(xi);
        let mut p = [pm; 4];
        for i in 1..4 {
            p[i] = mm_lower(&pm, &p[i - 1]);
        }
        let powers = |v: &Vec6| {
            let mut out = [pm * v; 4];
            for i in 1..4 {
                out[i] = pm * out[i - 1];
            }
            out
        };
        let vd = powers(xid);
        let vdd = powers(xidd);
        // E_1(v) = ad_v, E_{i+1}(v) = P E_i(v) + ad_{P^i v}.
        let e_ops = |v: &Vec6, pv: &[Vec6; 4]| {
            let mut out = [ad(v); 4];
            for i in 1..4 {
                out[i] = mm_lower(&pm, &out[i - 1]) + ad(&pv[i - 1]);
            }
            out
        };
        let ed = e_ops(xid, &vd);
        let edd = e_ops(xidd, &vdd);
        // F_1 = ad_ξ̇, F_{i+1} = P F_i + ad_ξ̇ P^i.
        let adv = ad(xid);
        let mut f = [adv; 4];
        for i in 1..4 {
            f[i] = mm_lower(&pm, &f[i - 1]) + mm_lower(&adv, &p[i - 1]);
        }
        // e_1 = 0, e_{i+1} = ad_ξ̇ P^i ξ̇ + P e_i;
        // Ê_1 = 0, Ê_{i+1} = P Ê_i − ad_ξ̇ E_i(ξ̇) − ad_{e_i}.
        let mut e = [Vec6::zeros(); 4];
        let mut ehat = [Mat6::zeros(); 4];
        for i in 1..4 {
            e[i] = adv * vd[i - 1] + pm * e[i - 1];
            ehat[i] = mm_lower(&pm, &ehat[i - 1]) - mm_lower(&adv, &ed[i - 1]) - ad(&e[i - 1]);
        }
        let kd = k.dot(&angular(xid));
        Self {
            theta: k.norm(),
            p,
            kbar: softrod_lie::join(&k, &softrod_lie::Vec3::zeros()),
            kdbar: softrod_lie::join(&angular(xid), &softrod_lie::Vec3::zeros()),
            kd,
            vd,
            vdd,
            ed,
            edd,
            f,
            e,
            ehat,
        }
    }

    /// `𝒟_v(x)` with `𝒟_v ζ = D_ξT₋(x)[ζ] v` (D32) for `v = ξ̇` (`acc = false`)
    /// or `v = ξ̈` (`acc = true`): `Σ_i d_i (P^i v) k̄ᵀ − c_i E_i(v)`.
    #[inline(always)]
    pub fn d_tangent_applied(&self, co: &Coefficients, acc: bool) -> Mat6 {
        let (pv, e) = if acc {
            (&self.vdd, &self.edd)
        } else {
            (&self.vd, &self.ed)
        };
        let mut u = Vec6::zeros();
        let mut out = Mat6::zeros();
        for i in 0..4 {
            u.axpy(co.d[i], &pv[i], 1.0);
            axpy6(&mut out, -co.c[i], &e[i]);
        }
        add_outer_angular(&mut out, &u, &self.kbar);
        out
    }

    /// `Ṫ(x) = D_ξT₋(x)[ξ̇] = Σ_i d_i (k·ξ̇_k) P^i + c_i F_i` (D33), the
    /// matrix of `Ṡ_n = Ṫ B_n` (D9).
    #[inline(always)]
    pub fn tangent_rate(&self, co: &Coefficients) -> Mat6 {
        let mut out = Mat6::zeros();
        for i in 0..4 {
            axpy6(&mut out, co.d[i] * self.kd, &self.p[i]);
            axpy6(&mut out, co.c[i], &self.f[i]);
        }
        out
    }

    /// `𝒟²(x)` with `𝒟² ζ = D_ξ(D_ξT₋(x)[ξ̇]ξ̇)[ζ]` (D35):
    /// `Σ_i h_i(k·ξ̇_k)(P^iξ̇)k̄ᵀ + d_i(P^iξ̇)ξ̇̄ᵀ − d_i(k·ξ̇_k)E_i(ξ̇) + d_i e_i k̄ᵀ + c_i Ê_i`.
    #[inline(always)]
    pub fn bias_strain_derivative(&self, co: &Coefficients) -> Mat6 {
        let mut uk = Vec6::zeros();
        let mut ud = Vec6::zeros();
        let mut out = Mat6::zeros();
        for i in 0..4 {
            uk.axpy(co.h[i] * self.kd, &self.vd[i], 1.0);
            uk.axpy(co.d[i], &self.e[i], 1.0);
            ud.axpy(co.d[i], &self.vd[i], 1.0);
            axpy6(&mut out, co.c[i], &self.ehat[i]);
            axpy6(&mut out, -co.d[i] * self.kd, &self.ed[i]);
        }
        add_outer_angular(&mut out, &uk, &self.kbar);
        add_outer_angular(&mut out, &ud, &self.kdbar);
        out
    }

    /// `k̄ = (k; 0)`.
    pub fn kbar(&self) -> Vec6 {
        self.kbar
    }
}

/// `𝒬` of (D36) from the powers `P^i = ad_ξ^i` (`p[i − 1]`), `k̄ = (k; 0)`
/// and the sums `φ_i = Σ w d_i f`, `χ_i = Σ w c_i f` of a wrench field `f`
/// over evaluation points of the piece: the matrix with
/// `(Σ w D_ξT₋(x)[ζ]ᵀ f)ᵀ y = yᵀ 𝒬 ζ`,
/// `𝒬 = Σ_i (P^{iᵀ}φ_i) k̄ᵀ − Σ_i Σ_{l<i} (P^{i−1−l})ᵀ Λ((Pᵀ)^l χ_i)`.
#[inline(always)]
pub(crate) fn tangent_transpose_form(
    p: &[Mat6; 4],
    kbar: &Vec6,
    phi: &[Vec6; 4],
    chi: &[Vec6; 4],
) -> Mat6 {
    let mut out = Mat6::zeros();
    for i in 0..4 {
        out += (p[i].transpose() * phi[i]) * kbar.transpose();
        let mut fl = chi[i];
        for l in 0..=i {
            // (P^{i−l})ᵀ with P^0 = I, for the term l of i + 1 (1-based).
            let lam = lambda(&fl);
            let m = i - l;
            if m == 0 {
                out -= lam;
            } else {
                out -= tm(&p[m - 1], &lam);
            }
            fl = p[0].transpose() * fl;
        }
    }
    out
}

/// `Bᵀ 𝒬 B` (the leading `k × k` block) of [`tangent_transpose_form`] for
/// a selection basis `cols` (D90): each term on the selected rows and
/// columns only, `(P^m B)ᵀ(Λ B)` over `K ≥ k` columns; the same operations
/// on the entries kept, so the numbers are those of `𝒬` gathered, bit for
/// bit. A general `B` takes the whole `𝒬` and projects it.
#[inline(always)]
pub(crate) fn tangent_transpose_form_basis(
    p: &[Mat6; 4],
    kbar: &Vec6,
    phi: &[Vec6; 4],
    chi: &[Vec6; 4],
    cols: &Cols,
) -> Mat6 {
    match (cols.selection().is_some(), cols.k) {
        // A general `B`, or all six directions: the whole form.
        (false, _) | (true, 6) => cols.both(&tangent_transpose_form(p, kbar, phi, chi)),
        (true, 0..=3) => form_selected::<3>(p, kbar, phi, chi, cols),
        (true, 4) => form_selected::<4>(p, kbar, phi, chi, cols),
        (true, _) => form_selected::<6>(p, kbar, phi, chi, cols),
    }
}

#[inline(always)]
fn form_selected<const K: usize>(
    p: &[Mat6; 4],
    kbar: &Vec6,
    phi: &[Vec6; 4],
    chi: &[Vec6; 4],
    cols: &Cols,
) -> Mat6 {
    let pb = [
        cols.right(&p[0]),
        cols.right(&p[1]),
        cols.right(&p[2]),
        cols.right(&p[3]),
    ];
    let kb = cols.right(&Mat6::from_rows(&[kbar.transpose(); 6]));
    let mut out = Mat6::zeros();
    for i in 0..4 {
        let u = pb[i].transpose() * phi[i];
        for b in 0..K {
            for a in 0..K {
                out[(a, b)] += u[a] * kb[(0, b)];
            }
        }
        let mut fl = chi[i];
        for l in 0..=i {
            let lb = cols.right(&lambda(&fl));
            let m = i - l;
            if m == 0 {
                out -= cols.left(&lb);
            } else {
                out -= tmk::<K, K>(&pb[m - 1], &lb);
            }
            fl = p[0].transpose() * fl;
        }
    }
    out
}

/// `m += c·x` entrywise.
#[inline(always)]
fn axpy6(m: &mut Mat6, c: f64, x: &Mat6) {
    for (a, b) in m.as_mut_slice().iter_mut().zip(x.as_slice()) {
        *a += c * b;
    }
}

/// `m += u vᵀ` for a `v` whose linear half is zero (`k̄`, `ξ̇̄`): only the
/// first three columns change.
#[inline(always)]
fn add_outer_angular(m: &mut Mat6, u: &Vec6, v: &Vec6) {
    for j in 0..3 {
        let mut col = m.column_mut(j);
        col.axpy(v[j], u, 1.0);
    }
}

/// `Λ(h)` with `Λ(h) ζ = ad*_ζ h`: `[[−m̃, −ñ], [−ñ, 0]]` for `h = (m, n)`,
/// skew-symmetric.
#[inline(always)]
pub(crate) fn lambda(h: &Vec6) -> Mat6 {
    let m = softrod_lie::skew(&angular(h));
    let n = softrod_lie::skew(&linear(h));
    let mut out = Mat6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-m));
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-n));
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-n));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use softrod_lie::{coad_vec, d_tangent_minus, d_tangent_minus_self, tangent_minus};

    fn xi() -> Vec6 {
        Vec6::new(0.7, -1.3, 0.4, 1.05, 0.2, -0.1)
    }

    #[test]
    fn sigma_series_and_closed_form_agree_at_the_switch_and_match_differences() {
        // Both branches evaluated at the switch are independent formulas.
        for psi in [PSI_SWITCH, 2.7, 3.5] {
            let a = sigma_series(psi * psi);
            let b = sigma_closed(psi);
            for i in 0..4 {
                // Closed form at ψ ≈ 2.5: cancellation of ~ψ^{-9}-scaled
                // terms leaves ~1e-13 relative (series: 1e-21, mpmath).
                assert!(
                    (a[i] - b[i]).abs() < 1e-12 * b[i].abs(),
                    "{psi} {i}: {a:?} {b:?}"
                );
            }
        }
        // σ = ρ′/ψ by central differences of ρ (softrod-lie), h = 1e-5:
        // truncation ~h²·ρ‴ ~ 1e-12, round-off ~ε/h ~ 1e-11.
        for psi in [0.3, 1.2, 2.4, 2.6, 4.0, 9.0] {
            let h = 1e-5;
            let rp = softrod_lie::series::rho(psi + h);
            let rm = softrod_lie::series::rho(psi - h);
            let s = sigma(psi);
            for i in 0..4 {
                let fd = (rp[i] - rm[i]) / (2.0 * h) / psi;
                assert!(
                    (fd - s[i]).abs() < 1e-8 * s[i].abs().max(1e-3),
                    "ψ = {psi}, i = {i}: {fd} vs {}",
                    s[i]
                );
            }
        }
    }

    #[test]
    fn assembled_maps_equal_the_direct_forms() {
        let xd = Vec6::new(0.2, 0.1, -0.4, 0.3, -0.5, 0.9);
        let xdd = Vec6::new(-1.0, 0.4, 0.3, 0.2, 0.7, -0.6);
        let z = Vec6::new(0.3, -0.8, 0.5, -0.2, 0.4, 0.1);
        for scale in [1e-9, 0.3, 1.0, 6.0] {
            let xi = xi() * scale;
            let pm = PieceDerivMaps::new(&xi, &xd, &xdd);
            for x in [0.0, 0.05, 0.4, 1.0, 2.5] {
                let co = Coefficients::at(x, pm.theta);
                // T₋ = xI + Σ c_i P^i.
                let mut t = Mat6::identity() * x;
                for i in 0..4 {
                    t += pm.p[i] * co.c[i];
                }
                let t0 = tangent_minus(x, &xi).to_mat6();
                assert!((t - t0).amax() < 1e-13 * (1.0 + t0.amax()), "T₋ at {x}");
                let dz = d_tangent_minus(x, &xi, &z).to_mat6();
                let a = pm.d_tangent_applied(&co, false) * z;
                assert!(
                    (a - dz * xd).amax() < 1e-13 * (1.0 + a.amax()),
                    "𝒟_ξ̇ at {x}"
                );
                let a = pm.d_tangent_applied(&co, true) * z;
                assert!(
                    (a - dz * xdd).amax() < 1e-13 * (1.0 + a.amax()),
                    "𝒟_ξ̈ at {x}"
                );
                let td = d_tangent_minus(x, &xi, &xd).to_mat6();
                let r = pm.tangent_rate(&co);
                assert!((r - td).amax() < 1e-13 * (1.0 + td.amax()), "Ṫ at {x}");
                // 𝒟² against central differences of the bias in ξ (h = 1e-6:
                // truncation ~1e-12, round-off ~1e-10 of the bias scale).
                let h = 1e-6;
                let bp = d_tangent_minus_self(x, &(xi + z * h), &xd);
                let bm = d_tangent_minus_self(x, &(xi - z * h), &xd);
                let fd = (bp - bm) / (2.0 * h);
                let an = pm.bias_strain_derivative(&co) * z;
                assert!(
                    (an - fd).amax() < 2e-8 * (1.0 + fd.amax()),
                    "𝒟² at x = {x}, scale {scale}: {an:?} vs {fd:?}"
                );
                // 𝒬: yᵀ 𝒬 ζ = fᵀ DT₋[ζ] y for one point of weight 1.
                let f = Vec6::new(0.5, -0.2, 0.9, 1.1, -0.7, 0.3);
                let mut phi = [Vec6::zeros(); 4];
                let mut chi = [Vec6::zeros(); 4];
                for i in 0..4 {
                    phi[i] = f * co.d[i];
                    chi[i] = f * co.c[i];
                }
                let q = tangent_transpose_form(&pm.p, &pm.kbar(), &phi, &chi);
                let y = Vec6::new(-0.4, 0.6, 0.2, 0.8, 0.1, -0.9);
                let lhs = (y.transpose() * q * z)[0];
                let rhs = f.dot(&(dz * y));
                assert!((lhs - rhs).abs() < 1e-13 * (1.0 + rhs.abs()), "𝒬 at {x}");
            }
        }
    }

    /// `Bᵀ𝒬B` on a selection's rows and columns is `𝒬` gathered, bit for bit.
    #[test]
    fn form_in_basis_directions_equals_the_whole_form_projected() {
        let xd = Vec6::new(0.2, 0.1, -0.4, 0.3, -0.5, 0.9);
        let pm = PieceDerivMaps::new(&xi(), &xd, &xd);
        let f = Vec6::new(0.5, -0.2, 0.9, 1.1, -0.7, 0.3);
        let mut phi = [Vec6::zeros(); 4];
        let mut chi = [Vec6::zeros(); 4];
        for i in 0..4 {
            phi[i] = f * (0.3 + i as f64);
            chi[i] = f.map(|v| v * v) * (1.0 - 0.2 * i as f64);
        }
        let q = tangent_transpose_form(&pm.p, &pm.kbar(), &phi, &chi);
        for sel in [
            &[1usize, 3, 5][..],
            &[4, 0, 2, 5],
            &[0, 1, 2, 3, 4, 5],
            &[3],
            &[5, 4, 3, 2, 1],
        ] {
            let mut bm = Mat6::zeros();
            for (j, &c) in sel.iter().enumerate() {
                bm[(c, j)] = 1.0;
            }
            let cols = Cols::of(&bm);
            let got = tangent_transpose_form_basis(&pm.p, &pm.kbar(), &phi, &chi, &cols);
            assert_eq!(got, bm.transpose() * q * bm, "{sel:?}");
        }
    }

    #[test]
    fn lambda_is_the_coadjoint_in_its_argument() {
        let h = Vec6::new(0.5, -0.2, 0.9, 1.1, -0.7, 0.3);
        let z = Vec6::new(0.3, -0.8, 0.5, -0.2, 0.4, 0.1);
        let l = lambda(&h);
        assert!((l * z - coad_vec(&z, &h)).amax() < 1e-15);
        assert!((l + l.transpose()).amax() == 0.0);
    }
}
