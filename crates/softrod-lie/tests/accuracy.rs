//! Accuracy of the closed forms + series of `softrod-lie` against independent
//! references computed here (see `common/mod.rs`):
//!
//! - `expm` by scaling and squaring (‖A/2^s‖∞ ≤ 1/2, 20 Taylor terms) in
//!   double-double arithmetic (~32 digits), so the reference error is far
//!   below the tolerances and any failure is the crate's;
//! - `T(x)`, `T₋(x)` by the Van Loan block trick and, independently, by
//!   composite Gauss–Legendre quadrature of `expm(l·ad_ξ)` (`f64`), the two
//!   cross-checked; `T₋` also as the product `exp(−x ad_ξ)·T(x)`;
//! - `D_ξT[δ]`, `D_ξT₋[δ]` by a three-block Van Loan construction that equals
//!   the quadrature form of docs/theory.md §1, by that quadrature form itself,
//!   and by central finite differences in `ξ`; `D_ξ exp(x ad_ξ)[δ]` by the
//!   Van Loan form of the Fréchet derivative and by finite differences.
//!
//! # Tolerances
//! Error = `max|code − ref| / max(1, max|ref|)`. docs/theory.md §8(a) measured
//! ≤ 4e-15 for exp, T, T₋ and D T₋ against an 80-digit reference over the same
//! θ grid with `xθ ≤ 17.3`, and ≤ 8e-16 across the switch. The irreducible
//! part is the rounding of `θ = |k|` and `ψ = xθ` (relative ε each), which moves
//! `sin ψ`, `cos ψ` by up to `ψ·ε ≈ 17.3 × 1.1e-16 ≈ 2e-15`; a few such terms
//! and the 3×3 products give the ~4e-15 measured. `TOL = 1e-14` leaves a
//! factor ≈ 2.5 over that. docs/theory.md measured 7e-14 at θ = 1e3 and
//! attributed it to the rounding of `x·θ`; here the reference takes the same
//! `f64` inputs `x` and `ξ` as the code and forms `x·ξ` exactly, so only the
//! code's own rounding of `ψ` (≤ 17.3 here too) remains. Measured worst at
//! θ = 1e3: 8e-16 (≤ 1e-15 even without the floor at 1), so θ = 1e3 gets the
//! same `TOL`; no exception is needed.
//! Finite differences are only good to ~h² + ε/h ≈ 1e-10: tolerance 1e-8.

mod common;

use common::*;
use softrod_lie as lie;

/// Tolerance on closed forms/series vs the double-double reference (see the
/// module docs for the reasoning).
const TOL: f64 = 1e-14;
/// Central finite differences, h ≈ 1e-5 in the scaled strain x·ξ.
const TOL_FD: f64 = 1e-8;
/// Van Loan (double-double) vs composite Gauss–Legendre (double-double
/// integrand, `f64` nodes, weights and sums): the quadrature adds ~10·panels
/// rounded terms, measured ≤ 2e-15; the same bound as the code.
const TOL_REF_CROSS: f64 = 1e-14;

const THETAS: [f64; 11] = [
    0.0, 1e-12, 1e-9, 1e-6, 1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0, 1e3,
];
/// Angles `ψ = xθ` covered for θ ≥ 1e-3: both sides of the switch and up to
/// 17.3 rad ≈ 2.75 turns.
const PSIS: [f64; 8] = [1e-3, 0.5, 2.0, 2.4999, 2.5001, 4.0, 9.5, 17.3];
/// Arc lengths for every θ (kept only where xθ ≤ 17.3).
const XS_SMALL: [f64; 4] = [0.01, 0.5, 1.0, 3.0];
const DIRECTIONS: usize = 3;

#[derive(Clone, Copy, Debug)]
struct Case {
    theta: f64,
    x: f64,
    xi: Vec6,
    delta: Vec6,
}

impl Case {
    /// The same everywhere, θ = 1e3 included (see the module docs).
    fn tol(&self) -> f64 {
        TOL
    }
}

fn grid() -> Vec<Case> {
    let mut rng = Rng::new(0x5eed_0001);
    let mut out = Vec::new();
    for &theta in &THETAS {
        for _ in 0..DIRECTIONS {
            let k = rng.unit3() * theta;
            let q = rng.vec3();
            let delta = rng.vec6();
            let xi = Vec6::new(k[0], k[1], k[2], q[0], q[1], q[2]);
            let mut xs: Vec<f64> = XS_SMALL
                .iter()
                .copied()
                .filter(|&x| x * theta <= 17.3)
                .collect();
            if theta >= 1e-3 {
                xs.extend(PSIS.iter().map(|&p| p / theta));
            }
            for x in xs {
                out.push(Case {
                    theta,
                    x,
                    xi,
                    delta,
                });
            }
        }
    }
    out
}

/// Strains with ψ = xθ exactly across the switch: ψ*(1 ± 1e-9), ψ*(1 ± 1e-3),
/// and ψ* itself.
fn switch_cases() -> Vec<Case> {
    let mut rng = Rng::new(0x5eed_0002);
    let mut out = Vec::new();
    let s = lie::series::PSI_SWITCH;
    for &theta in &[0.7, 1.0, 3.0] {
        for &psi in &[
            s * (1.0 - 1e-9),
            s * (1.0 + 1e-9),
            s * (1.0 - 1e-3),
            s * (1.0 + 1e-3),
            s,
        ] {
            let k = rng.unit3() * theta;
            let q = rng.vec3();
            let xi = Vec6::new(k[0], k[1], k[2], q[0], q[1], q[2]);
            out.push(Case {
                theta,
                x: psi / theta,
                xi,
                delta: rng.vec6(),
            });
        }
    }
    out
}

/// Worst error per θ, printed with `--nocapture` so the report can quote it.
struct Worst {
    name: &'static str,
    rows: Vec<(f64, f64, f64)>, // (θ, worst error, at ψ)
}

impl Worst {
    fn new(name: &'static str) -> Self {
        Worst {
            name,
            rows: Vec::new(),
        }
    }
    fn record(&mut self, c: &Case, err: f64) {
        let psi = c.x * c.theta;
        match self.rows.iter_mut().find(|r| r.0 == c.theta) {
            Some(r) => {
                if err > r.1 {
                    r.1 = err;
                    r.2 = psi;
                }
            }
            None => self.rows.push((c.theta, err, psi)),
        }
    }
    fn print(&self) {
        let worst = self.rows.iter().map(|r| r.1).fold(0.0, f64::max);
        let mut s = format!("{:<28} worst {:9.2e} |", self.name, worst);
        for (t, e, p) in &self.rows {
            s += &format!(" θ={t:.0e}: {e:.1e} (ψ={p:.3}) ");
        }
        println!("{s}");
    }
}

fn check(w: &mut Worst, c: &Case, err: f64, tol: f64, what: &str) {
    w.record(c, err);
    assert!(
        err <= tol,
        "{what}: error {err:.3e} > {tol:.0e} at θ = {}, x = {}, ψ = {}, ξ = {:?}",
        c.theta,
        c.x,
        c.x * c.theta,
        c.xi.as_slice()
    );
}

fn all_cases() -> Vec<Case> {
    let mut v = grid();
    v.extend(switch_cases());
    v
}

// ---------------------------------------------------------------------------
// The reference itself.
// ---------------------------------------------------------------------------

/// The reference `expm` reproduces known exponentials: a plane rotation by
/// 17.3 rad (6×6, dense after a random similarity by a rotation-like
/// orthogonal matrix) and a nilpotent 12×12 block, plus `e^A e^{−A} = I` for
/// a dense random 12×12 matrix.
#[test]
fn reference_expm_is_exact_on_known_cases() {
    // 2×2 rotation generator embedded in 6×6: exp = [[cos, −sin], [sin, cos]].
    let psi = 17.3f64;
    let mut a = Mat::<Dd>::zeros(6);
    a.set(0, 1, Dd::new(-psi));
    a.set(1, 0, Dd::new(psi));
    let e = expm(&a);
    let (s, c) = psi.sin_cos();
    assert!((e.at(0, 0).to_f64() - c).abs() < 1e-16);
    assert!((e.at(1, 0).to_f64() - s).abs() < 1e-16);
    assert!((e.at(2, 2).to_f64() - 1.0).abs() == 0.0);
    // Nilpotent: N = x·(superdiagonal), exp(N)_{0,j} = x^j/j!.
    let x = 3.0;
    let mut n = Mat::<Dd>::zeros(12);
    for i in 0..11 {
        n.set(i, i + 1, Dd::new(x));
    }
    let e = expm(&n);
    let mut fact = 1.0;
    for j in 0..12 {
        if j > 0 {
            fact *= j as f64;
        }
        let exact = x.powi(j as i32) / fact;
        assert!(
            (e.at(0, j).to_f64() - exact).abs() <= 1e-15 * exact,
            "nilpotent entry {j}"
        );
    }
    // e^A e^{−A} = I for a dense 12×12 matrix of norm ~ 20.
    let mut rng = Rng::new(7);
    let mut a = Mat::<Dd>::zeros(12);
    for v in a.d.iter_mut() {
        *v = Dd::new(3.0 * rng.sym());
    }
    let mut ma = a.clone();
    for v in ma.d.iter_mut() {
        *v = -*v;
    }
    let p = expm(&a).mul(&expm(&ma));
    let id = Mat::<Dd>::identity(12);
    let scale = expm(&a).norm_inf() * expm(&ma).norm_inf();
    for (u, v) in p.d.iter().zip(id.d.iter()) {
        assert!((*u - *v).to_f64().abs() < 1e-26 * scale);
    }
    // f64 and double-double agree on a dense 6×6.
    let mut b = Mat::<f64>::zeros(6);
    let mut bd = Mat::<Dd>::zeros(6);
    for i in 0..36 {
        let v = 2.0 * rng.sym();
        b.d[i] = v;
        bd.d[i] = Dd::new(v);
    }
    let (e1, e2) = (expm(&b), expm(&bd));
    let m = e2.norm_inf();
    for (u, v) in e1.d.iter().zip(e2.d.iter()) {
        assert!((u - v.to_f64()).abs() < 1e-13 * m);
    }
}

/// The three references of `T` (Van Loan in double-double, Van Loan in `f64`,
/// composite Gauss–Legendre of `f64` `expm`) and of `T₋` (also the product
/// `exp(−x ad)·T`) agree, and the quadrature form of `D T₋` agrees with the
/// three-block Van Loan form. A subset of the grid (the quadrature is
/// the expensive part).
#[test]
fn references_agree_with_each_other() {
    let mut wt = Worst::new("ref T: VanLoan vs GL");
    let mut wtm = Worst::new("ref T-: VanLoan vs GL/prod");
    let mut wd = Worst::new("ref DT-: VanLoan vs GL");
    let mut wf = Worst::new("ref T: f64 VanLoan vs dd");
    for (i, c) in all_cases().iter().enumerate() {
        let t_vl = ref_tangent(c.x, &c.xi);
        let t_q = quad_tangent(c.x, &c.xi, 1.0);
        let e = rel_err(&t_q, &t_vl);
        check(&mut wt, c, e, TOL_REF_CROSS, "T quadrature vs Van Loan");
        // The same Van Loan construction in plain f64 is a much weaker
        // reference once ‖x·ad_ξ‖ is large (x = 17300 with |q| ~ 1 needs 16
        // squarings): measured 4.6e-12 there. That is why every reference
        // above is double-double; here it is only asserted for x ≤ 20.
        let e = rel_err(&ref_tangent_f64(c.x, &c.xi), &t_vl);
        wf.record(c, e);
        if c.x <= 20.0 {
            check(&mut wf, c, e, TOL_REF_CROSS, "T Van Loan f64 vs dd");
        }

        let tm_vl = ref_tangent(c.x, &(-c.xi));
        let e = rel_err(&ref_tangent_minus_product(c.x, &c.xi), &tm_vl);
        check(&mut wtm, c, e, TOL, "T₋ product vs Van Loan");
        let e = rel_err(&quad_tangent(c.x, &c.xi, -1.0), &tm_vl);
        check(&mut wtm, c, e, TOL_REF_CROSS, "T₋ quadrature vs Van Loan");

        // The D T₋ quadrature nests a 12×12 expm in every node: every third
        // case keeps the runtime small.
        if i % 3 == 0 {
            let d_vl = ref_d_tangent(c.x, &c.xi, &c.delta, -1.0);
            let d_q = quad_d_tangent_minus(c.x, &c.xi, &c.delta);
            let e = rel_err(&d_q, &d_vl);
            check(&mut wd, c, e, TOL_REF_CROSS, "D T₋ quadrature vs Van Loan");
        }
    }
    wt.print();
    wtm.print();
    wd.print();
    wf.print();
}

// ---------------------------------------------------------------------------
// The crate against the references.
// ---------------------------------------------------------------------------

#[test]
fn exponentials_match_expm() {
    let mut wg = Worst::new("exp_twist vs expm(x·hat)");
    let mut wa = Worst::new("exp_ad vs expm(x·ad)");
    let mut wp = Worst::new("exp_and_tangent_minus");
    for c in all_cases() {
        let g = lie::exp_twist(c.x, &c.xi);
        let e = rel_err(&g.to_homogeneous(), &ref_exp_hat(c.x, &c.xi));
        check(&mut wg, &c, e, c.tol(), "exp_twist");
        let ea = ref_exp_ad(c.x, &c.xi);
        let e = rel_err(&lie::exp_ad(c.x, &c.xi).to_mat6(), &ea);
        check(&mut wa, &c, e, c.tol(), "exp_ad");
        // Ad⁻¹ = exp(−x ad) too.
        let e = rel_err(&g.ad_inv().to_mat6(), &ref_exp_ad(-c.x, &c.xi));
        check(&mut wa, &c, e, c.tol(), "ad_inv of exp_twist");
        // The fused version gives the same pose and T₋ as the separate ones.
        let (g2, tm2) = lie::exp_and_tangent_minus(c.x, &c.xi);
        let e = rel_err(&g2.to_homogeneous(), &ref_exp_hat(c.x, &c.xi))
            .max(rel_err(&tm2.to_mat6(), &ref_tangent(c.x, &(-c.xi))));
        check(&mut wp, &c, e, c.tol(), "exp_and_tangent_minus");
    }
    wg.print();
    wa.print();
    wp.print();
}

#[test]
fn tangents_match_references() {
    let mut wt = Worst::new("tangent");
    let mut wtm = Worst::new("tangent_minus");
    let mut wts = Worst::new("tangent, no floor");
    let mut wds = Worst::new("d_tangent_minus, no floor");
    for c in all_cases() {
        let e = rel_err(
            &lie::tangent(c.x, &c.xi).to_mat6(),
            &ref_tangent(c.x, &c.xi),
        );
        check(&mut wt, &c, e, c.tol(), "tangent");
        let e = rel_err(
            &lie::tangent_minus(c.x, &c.xi).to_mat6(),
            &ref_tangent(c.x, &(-c.xi)),
        );
        check(&mut wtm, &c, e, c.tol(), "tangent_minus");
        // Without the floor at 1: T ~ x is small for small x (θ = 1e3 has
        // x ≤ 0.0173), and must still be right to the last digits.
        let r = ref_tangent(c.x, &c.xi);
        let e = (lie::tangent(c.x, &c.xi).to_mat6() - r).amax() / r.amax();
        check(&mut wts, &c, e, c.tol(), "tangent (relative to max|T|)");
        let r = ref_d_tangent(c.x, &c.xi, &c.delta, -1.0);
        let e = (lie::d_tangent_minus(c.x, &c.xi, &c.delta).to_mat6() - r).amax() / r.amax();
        check(
            &mut wds,
            &c,
            e,
            c.tol(),
            "d_tangent_minus (relative to max|DT₋|)",
        );
    }
    wts.print();
    wds.print();
    wt.print();
    wtm.print();
}

#[test]
fn strain_derivatives_match_references() {
    let mut wd = Worst::new("d_tangent");
    let mut wdm = Worst::new("d_tangent_minus");
    let mut wds = Worst::new("d_tangent_minus_self");
    let mut we = Worst::new("d_exp_ad");
    for c in all_cases() {
        let r = ref_d_tangent(c.x, &c.xi, &c.delta, 1.0);
        let e = rel_err(&lie::d_tangent(c.x, &c.xi, &c.delta).to_mat6(), &r);
        check(&mut wd, &c, e, c.tol(), "d_tangent");

        let rm = ref_d_tangent(c.x, &c.xi, &c.delta, -1.0);
        let e = rel_err(&lie::d_tangent_minus(c.x, &c.xi, &c.delta).to_mat6(), &rm);
        check(&mut wdm, &c, e, c.tol(), "d_tangent_minus");

        // The vector D T₋[δ]δ, normalised like its matrix: by max(1, ‖DT₋‖·‖δ‖).
        let rv = rm * c.delta;
        let v = lie::d_tangent_minus_self(c.x, &c.xi, &c.delta);
        let e = (v - rv).amax() / (rm.amax() * c.delta.amax()).max(1.0);
        check(&mut wds, &c, e, c.tol(), "d_tangent_minus_self");

        let re = ref_d_exp_ad(c.x, &c.xi, &c.delta);
        let e = rel_err(&lie::d_exp_ad(c.x, &c.xi, &c.delta).to_mat6(), &re);
        check(&mut we, &c, e, c.tol(), "d_exp_ad");
    }
    wd.print();
    wdm.print();
    wds.print();
    we.print();
}

/// Central differences in ξ (direction δ) of `T`, `T₋` and `exp(x ad_ξ)`,
/// against the analytic derivatives, where `x ≤ 20` (beyond that the step
/// would have to shrink below where differences are meaningful).
#[test]
fn strain_derivatives_match_finite_differences() {
    let mut wd = Worst::new("d_tangent vs FD");
    let mut wdm = Worst::new("d_tangent_minus vs FD");
    let mut we = Worst::new("d_exp_ad vs FD");
    for c in all_cases().into_iter().filter(|c| c.x <= 20.0) {
        let h = 1e-5 / c.x.max(1.0);
        let (xp, xm) = (c.xi + c.delta * h, c.xi - c.delta * h);
        let fd = |f: &dyn Fn(&Vec6) -> Mat6| (f(&xp) - f(&xm)) / (2.0 * h);

        let d = fd(&|xi| lie::tangent(c.x, xi).to_mat6());
        let a = lie::d_tangent(c.x, &c.xi, &c.delta).to_mat6();
        check(&mut wd, &c, rel_err(&d, &a), TOL_FD, "d_tangent vs FD");

        let d = fd(&|xi| lie::tangent_minus(c.x, xi).to_mat6());
        let a = lie::d_tangent_minus(c.x, &c.xi, &c.delta).to_mat6();
        check(
            &mut wdm,
            &c,
            rel_err(&d, &a),
            TOL_FD,
            "d_tangent_minus vs FD",
        );

        let d = fd(&|xi| lie::exp_ad(c.x, xi).to_mat6());
        let a = lie::d_exp_ad(c.x, &c.xi, &c.delta).to_mat6();
        check(&mut we, &c, rel_err(&d, &a), TOL_FD, "d_exp_ad vs FD");
    }
    wd.print();
    wdm.print();
    we.print();
}

/// Both sides of the switch ψ* agree with the reference, and with each other
/// (continuity of every map across ψ*).
#[test]
fn continuous_across_the_switch() {
    let s = lie::series::PSI_SWITCH;
    let mut rng = Rng::new(11);
    for _ in 0..5 {
        let k = rng.unit3();
        let q = rng.vec3();
        let xi = Vec6::new(k[0], k[1], k[2], q[0], q[1], q[2]);
        let d = rng.vec6();
        let (lo, hi) = (s * (1.0 - 1e-12), s * (1.0 + 1e-12));
        let pairs: [(&str, Mat6, Mat6); 4] = [
            (
                "tangent",
                lie::tangent(lo, &xi).to_mat6(),
                lie::tangent(hi, &xi).to_mat6(),
            ),
            (
                "tangent_minus",
                lie::tangent_minus(lo, &xi).to_mat6(),
                lie::tangent_minus(hi, &xi).to_mat6(),
            ),
            (
                "exp_ad",
                lie::exp_ad(lo, &xi).to_mat6(),
                lie::exp_ad(hi, &xi).to_mat6(),
            ),
            (
                "d_tangent_minus",
                lie::d_tangent_minus(lo, &xi, &d).to_mat6(),
                lie::d_tangent_minus(hi, &xi, &d).to_mat6(),
            ),
        ];
        for (name, a, b) in pairs {
            // The maps move by O(ψ·2e-12) between the two points.
            let jump = rel_err(&a, &b);
            assert!(jump < 1e-11, "{name} jumps by {jump:e} across ψ*");
        }
    }
}

// ---------------------------------------------------------------------------
// Why the series exist.
// ---------------------------------------------------------------------------

/// `T(x)` built from the naive closed forms `τ_i = N_i/(2ψ^{i+1})`
/// (`series::closed_forms`) at small ψ is wrong by many orders of magnitude
/// more than the series version (docs/theory.md §8(a): 2.5e-4 at θ = 1e-6).
#[test]
fn naive_closed_form_fails_near_zero_series_does_not() {
    let mut rng = Rng::new(3);
    let k = rng.unit3();
    let q = rng.vec3();
    for &(theta, naive_at_least) in &[(1e-6, 1e-6), (1e-4, 1e-10), (1e-3, 1e-12)] {
        let xi = Vec6::new(k[0] * theta, k[1] * theta, k[2] * theta, q[0], q[1], q[2]);
        let x = 1.0;
        let psi = x * theta;
        let (_, tau_naive, _) = lie::series::closed_forms(psi);
        let a = ad_ref(&xi);
        let mut naive = Mat6::identity() * x;
        let mut p = Mat6::identity();
        for (i, t) in tau_naive.iter().enumerate() {
            p *= a;
            naive += p * (x.powi(i as i32 + 2) * t);
        }
        let reference = ref_tangent(x, &xi);
        let e_naive = rel_err(&naive, &reference);
        let e_series = rel_err(&lie::tangent(x, &xi).to_mat6(), &reference);
        println!("θ = {theta:e}: naive closed-form T error {e_naive:.2e}, series {e_series:.2e}");
        assert!(
            e_naive > naive_at_least,
            "naive T unexpectedly accurate at θ = {theta}: {e_naive:e}"
        );
        assert!(e_series < TOL, "series T error {e_series:e} at θ = {theta}");

        // The coefficients themselves: τ₄ = N₄/(2ψ⁵) from ~1-sized terms of
        // N₄ has no correct digit at ψ = 1e-6 (it should be ≈ 1/120).
        if theta == 1e-6 {
            let tau = lie::series::tau(psi);
            assert!((tau[3] - 1.0 / 120.0).abs() < 1e-15);
            assert!((tau_naive[3] - 1.0 / 120.0).abs() > 1e-2 / 120.0);
        }
    }
}
