//! The implicit methods' linear algebra: the structured shifted-mass solve
//! runs without any dense matrix, a poor structured matrix falls back to the
//! exact Jacobian, a failing cheap Rosenbrock–W matrix is refreshed to the
//! exact one, and the stiff van der Pol oscillator — all against exact
//! solutions or a second method.

mod common;

use std::convert::Infallible;

use common::{VanDerPol, dv};
use nalgebra::{DMatrix, DVector};
use softrod_integrate::{
    Integrator, NoHooks, Options, SecondOrderSystem, integrate, integrate_second_order,
};

/// `M q̈ = −K q − (D + C(t)) q̇` with constant SPD `M`, `K`, `D` and a damping
/// `C(t) = c·e^(g t)·e₃e₃ᵀ` on the third coordinate that the structured
/// matrix `M + aK + bD` (and the mass-matrix form) leave out, as they leave
/// out the gyroscopic terms of a rod. For `g = 0` the exact solution is
/// `exp(A t) y₀`, `A = [[0, I], [−M⁻¹K, −M⁻¹(D + C)]]`.
#[derive(Clone)]
struct Structured {
    m: DMatrix<f64>,
    k: DMatrix<f64>,
    c: f64,
    growth: f64,
    d: DMatrix<f64>,
    /// Whether the structured solve and force residual are offered.
    structured: bool,
    /// Whether the cheap mass-matrix form (`M`, `K`, `D`, no `G`) is offered.
    mass_form: bool,
    /// Whether `jacobians` may be called (else it panics: no dense path).
    dense_allowed: bool,
    jacobian_calls: usize,
    factor: Option<nalgebra::Cholesky<f64, nalgebra::Dyn>>,
}

impl Structured {
    /// Three coupled modes, ω² ≈ 1 … 600 (M has eigenvalues ≈ 0.5 … 4.5),
    /// light damping, plus `C = c·e₃e₃ᵀ`.
    fn new(c: f64) -> Self {
        let b = DMatrix::from_row_slice(3, 3, &[2.0, 0.3, 0.0, 0.3, 1.5, 0.2, 0.0, 0.2, 1.0]);
        let m = &b * b.transpose();
        let k = DMatrix::from_diagonal(&DVector::from_row_slice(&[4.0, 100.0, 2500.0]));
        let d = &k * 1e-3;
        Self {
            c,
            growth: 0.0,
            m,
            k,
            d,
            structured: true,
            mass_form: false,
            dense_allowed: true,
            jacobian_calls: 0,
            factor: None,
        }
    }

    fn cmat(&self, t: f64) -> DMatrix<f64> {
        let mut c = DMatrix::zeros(3, 3);
        c[(2, 2)] = self.c * (self.growth * t).exp();
        c
    }

    fn a(&self, t: f64) -> DMatrix<f64> {
        let mi = self.m.clone().try_inverse().unwrap();
        let mut a = DMatrix::zeros(6, 6);
        a.view_mut((0, 3), (3, 3)).fill_with_identity();
        a.view_mut((3, 0), (3, 3)).copy_from(&(-&mi * &self.k));
        a.view_mut((3, 3), (3, 3))
            .copy_from(&(-&mi * (&self.d + self.cmat(t))));
        a
    }

    fn exact(&self, t: f64, y0: &DVector<f64>) -> DVector<f64> {
        assert_eq!(self.growth, 0.0);
        (self.a(0.0) * t).exp() * y0
    }
}

impl SecondOrderSystem for Structured {
    type Error = Infallible;
    fn dim(&self) -> usize {
        3
    }
    fn accel(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), Infallible> {
        let f = -&self.k * q - (&self.d + self.cmat(t)) * qd;
        qdd.copy_from(&self.m.clone().cholesky().unwrap().solve(&f));
        Ok(())
    }
    fn jacobians(
        &mut self,
        t: f64,
        _q: &DVector<f64>,
        _qd: &DVector<f64>,
        jq: &mut DMatrix<f64>,
        jv: &mut DMatrix<f64>,
    ) -> Result<(), Infallible> {
        assert!(self.dense_allowed, "the dense Jacobian was asked for");
        self.jacobian_calls += 1;
        let a = self.a(t);
        jq.copy_from(&a.view((3, 0), (3, 3)));
        jv.copy_from(&a.view((3, 3), (3, 3)));
        Ok(())
    }
    fn has_mass_form(&self) -> bool {
        self.mass_form
    }
    fn mass_form_jacobians(
        &mut self,
        _t: f64,
        _q: &DVector<f64>,
        _qd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
        constant: Option<(&mut DMatrix<f64>, &mut DMatrix<f64>)>,
    ) -> Result<bool, Infallible> {
        if !self.mass_form {
            return Ok(false);
        }
        mass.copy_from(&self.m);
        if let Some((k, d)) = constant {
            k.copy_from(&self.k);
            d.copy_from(&self.d);
        }
        Ok(true)
    }
    fn force_residual(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        r: &mut DVector<f64>,
    ) -> Result<bool, Infallible> {
        if !self.structured {
            return Ok(false);
        }
        r.copy_from(&(&self.m * qdd + &self.k * q + (&self.d + self.cmat(t)) * qd));
        Ok(true)
    }
    fn factor_shifted_mass(
        &mut self,
        _t: f64,
        _q: &DVector<f64>,
        a: f64,
        b: f64,
    ) -> Result<bool, Infallible> {
        if !self.structured {
            return Ok(false);
        }
        self.factor = Some((&self.m + &self.k * a + &self.d * b).cholesky().unwrap());
        Ok(true)
    }
    fn solve_shifted_mass(&mut self, x: &mut DVector<f64>) -> Result<(), Infallible> {
        self.factor.as_ref().unwrap().solve_mut(x);
        Ok(())
    }
    fn is_autonomous(&self) -> bool {
        self.growth == 0.0
    }
}

fn y0() -> DVector<f64> {
    dv(&[0.3, -0.2, 0.01, 0.0, 1.0, -0.5])
}

fn run(sys: &mut Structured, method: Integrator, opts: &Options) -> softrod_integrate::Solution {
    let y = y0();
    let q0 = y.rows(0, 3).into_owned();
    let v0 = y.rows(3, 3).into_owned();
    integrate_second_order(sys, method, (0.0, 2.0), &q0, &v0, opts, &mut NoHooks).unwrap()
}

/// Largest position error at t = 2 against the exact solution.
fn q_error(sys: &Structured, sol: &softrod_integrate::Solution) -> f64 {
    let ex = sys.exact(2.0, &y0());
    (sol.y_final.rows(0, 3) - ex.rows(0, 3)).amax()
}

/// A run converges to the exact solution when its position error at
/// `rtol = atol = 1e-9` is below [`Q_BOUND`] and at least [`CONVERGENCE`]
/// times smaller than at `1e-6`. Why these numbers: the error per step is
/// controlled, so the global error is about the number of steps (≈ 200–900
/// here) times the tolerance; a fourth-order method at 1000× the tolerance
/// takes ≈ 1000^(1/5) ≈ 4 times fewer steps, so its error ratio is ≈ 250.
const Q_BOUND: f64 = 1e-5;
const CONVERGENCE: f64 = 30.0;

fn assert_converges(
    label: &str,
    mut make: impl FnMut() -> Structured,
    method: Integrator,
) -> Vec<Structured> {
    let mut systems = Vec::new();
    let mut errs = Vec::new();
    for tol in [1e-6, 1e-9] {
        let mut sys = make();
        let sol = run(&mut sys, method, &Options::tol(tol, tol));
        let e = q_error(&sys, &sol);
        println!(
            "{label}, tol {tol:e}: q error {e:.2e}, {} exact Jacobians, {:?}",
            sys.jacobian_calls, sol.stats
        );
        errs.push(e);
        systems.push(sys);
    }
    assert!(errs[1] < Q_BOUND, "{label}: {errs:?}");
    assert!(errs[0] > CONVERGENCE * errs[1], "{label}: {errs:?}");
    systems
}

#[test]
fn structured_solve_needs_no_dense_matrix() {
    // C = 0: the structured matrix is the Newton matrix.
    let systems = assert_converges(
        "structured, C = 0",
        || {
            let mut s = Structured::new(0.0);
            s.dense_allowed = false;
            s
        },
        Integrator::Esdirk,
    );
    assert!(systems.iter().all(|s| s.jacobian_calls == 0));
}

#[test]
fn poor_structured_matrix_falls_back_to_the_exact_jacobian() {
    // C = 1e4 on one coordinate makes a mode with λ ≈ −C/m ~ −1e4 that the
    // L-stable method steps over; M + aK + bD misses C, and at such steps
    // (hγ·C/m ≫ 1) the simplified Newton iteration diverges on it: the
    // exact Jacobian takes over.
    let systems = assert_converges(
        "structured, C = 1e4",
        || Structured::new(1e4),
        Integrator::Esdirk,
    );
    assert!(systems.iter().all(|s| s.jacobian_calls > 0));
}

#[test]
fn esdirk_converges_through_the_dense_path() {
    // Without the structured hook: the dense exact Jacobian only.
    let systems = assert_converges(
        "dense",
        || {
            let mut s = Structured::new(1e4);
            s.structured = false;
            s
        },
        Integrator::Esdirk,
    );
    assert!(systems.iter().all(|s| s.jacobian_calls > 0));
}

#[test]
fn rosenbrock_w_refreshes_a_failing_cheap_jacobian_to_the_exact_one() {
    // The cheap W is the mass-matrix form M, K, D without C(t) = 10·e^(8t)
    // (1e1 … 9e7 over [0, 2]): as a W-method ROS34PW2 keeps its order, but
    // C is then treated explicitly, whose stability limit h ≲ 2m/C shrinks
    // from ~0.1 to ~1e-8 — the steps collapse, until W is refreshed to the
    // exact Jacobian (which the system counts). Reference: Radau IIA at
    // rtol 1e-11 (a different method, exact Jacobian).
    let make = || {
        let mut s = Structured::new(10.0);
        s.growth = 8.0;
        s.structured = false;
        s.mass_form = true;
        s
    };
    let reference = run(&mut make(), Integrator::Radau5, &Options::tol(1e-11, 1e-11));
    let mut errs = Vec::new();
    for tol in [1e-5, 1e-8] {
        let mut sys = make();
        let sol = run(&mut sys, Integrator::Rosenbrock, &Options::tol(tol, tol));
        let e = (sol.y_final.rows(0, 3) - reference.y_final.rows(0, 3)).amax();
        println!(
            "rosw34, cheap W without C(t), tol {tol:e}: q error {e:.2e}, {} exact Jacobians, {:?}",
            sys.jacobian_calls, sol.stats
        );
        assert!(sys.jacobian_calls > 0);
        errs.push(e);
    }
    assert!(errs[1] < Q_BOUND, "{errs:?}");
    assert!(errs[0] > CONVERGENCE * errs[1], "{errs:?}");
}

/// Van der Pol as a second-order equation, `y'' = μ(1 − y²) y' − y`.
struct VdpSecond {
    mu: f64,
}

impl SecondOrderSystem for VdpSecond {
    type Error = Infallible;
    fn dim(&self) -> usize {
        1
    }
    fn accel(
        &mut self,
        _t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), Infallible> {
        qdd[0] = self.mu * (1.0 - q[0] * q[0]) * qd[0] - q[0];
        Ok(())
    }
    fn jacobians(
        &mut self,
        _t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        jq: &mut DMatrix<f64>,
        jv: &mut DMatrix<f64>,
    ) -> Result<(), Infallible> {
        jq[(0, 0)] = -2.0 * self.mu * q[0] * qd[0] - 1.0;
        jv[(0, 0)] = self.mu * (1.0 - q[0] * q[0]);
        Ok(())
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// μ = 1000 over [0, 3000] (two relaxation periods), as the Rosenbrock test
/// in `stiff.rs`: the explicit stability limit alone needs ~10⁶ steps.
const VDP_T1: f64 = 3000.0;
const VDP_BUDGET: usize = 5_000;

#[test]
fn van_der_pol_mu_1000_with_radau5_and_esdirk_within_budget() {
    let opts = |tol: f64| Options {
        max_steps: VDP_BUDGET,
        ..Options::tol(tol, tol)
    };
    let y0 = dv(&[2.0, 0.0]);
    let radau = |tol: f64| {
        integrate(
            &mut VanDerPol { mu: 1000.0 },
            Integrator::Radau5,
            (0.0, VDP_T1),
            &y0,
            &opts(tol),
            &mut NoHooks,
        )
        .unwrap()
    };
    let r6 = radau(1e-6);
    let r9 = radau(1e-9);
    let esd = integrate_second_order(
        &mut VdpSecond { mu: 1000.0 },
        Integrator::Esdirk,
        (0.0, VDP_T1),
        &dv(&[2.0]),
        &dv(&[0.0]),
        &opts(1e-6),
        &mut NoHooks,
    )
    .unwrap();
    println!(
        "radau5 1e-6 {:?}\nradau5 1e-9 {:?}\nesdirk46 1e-6 {:?}",
        r6.stats, r9.stats, esd.stats
    );
    // On a slow branch at t1 the solutions agree to the accuracy the jump
    // times allow (relative tolerance 1e-6 over two periods of ~1614).
    let y_ref = r9.y_final[0];
    assert!(
        (r6.y_final[0] - y_ref).abs() < 1e-3,
        "{} vs {y_ref}",
        r6.y_final[0]
    );
    assert!(
        (esd.y_final[0] - y_ref).abs() < 1e-3,
        "{} vs {y_ref}",
        esd.y_final[0]
    );
    assert!(r6.y.iter().all(|y| y[0].abs() < 2.01));
}
