//! The integrators on the PCS rod: energy conservation of the undamped
//! release under gravity (adaptive methods to their tolerance, generalized-α
//! bounded without dissipation and decreasing with it), the stiff steel wire
//! at steps far above the explicit stability limit, the linearly implicit
//! (IMEX) generalized-α, and bit-identical reruns.

use nalgebra::DVector;
use softrod_dynamics::{Data, Model, Rod, energies, modes};
use softrod_integrate::{
    Callbacks, IntegrateError, Integrator, Iteration, NoHooks, Options, RodJacobian, RodSystem,
    Solution, integrate_second_order,
};
use softrod_kinematics::{Basis, RodGeometry, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{Material, RodProperties, Section};

/// A horizontal cantilever (along x, clamped at the origin, gravity −z),
/// undamped, all six strains on `pieces` equal pieces, 4 Gauss points.
fn cantilever(
    length: f64,
    radius: f64,
    density: f64,
    young: f64,
    poisson: f64,
    pieces: usize,
) -> Model {
    let rod =
        RodGeometry::uniform(length, pieces, Basis::all(), straight(), Pose::identity()).unwrap();
    let mat = Material::with_poisson(density, young, poisson, 0.0).unwrap();
    let body = RodProperties::new(Section::Circle { radius }, mat, length).unwrap();
    Model::new(
        vec![Rod::new("rod", rod, body)],
        Some(Vec3::new(0.0, 0.0, -9.81)),
        4,
    )
    .unwrap()
}

/// The soft cantilever (L = 0.5 m, r = 1 cm, ρ = 1000, E = 1e7,
/// ν = 0.5).
fn soft(pieces: usize) -> Model {
    cantilever(0.5, 0.01, 1000.0, 1e7, 0.5, pieces)
}

/// The steel wire: E = 200 GPa, ρ = 7800, r = 1 mm, L = 1 m, ν = 0.3.
fn steel_wire(pieces: usize) -> Model {
    cantilever(1.0, 1e-3, 7800.0, 2e11, 0.3, pieces)
}

fn run(
    model: &Model,
    jacobian: RodJacobian,
    method: Integrator,
    t1: f64,
    opts: &Options,
) -> Result<(RodSystem, Solution), IntegrateError> {
    let mut sys = RodSystem::new(model.clone());
    sys.jacobian = jacobian;
    let z = DVector::zeros(model.n_dof());
    let sol = integrate_second_order(&mut sys, method, (0.0, t1), &z, &z, opts, &mut NoHooks)?;
    Ok((sys, sol))
}

/// Total energy at every output and the energy scale: the largest kinetic,
/// elastic or |gravitational| energy seen. Released from rest, straight:
/// `E(0) = 0`.
fn energy_series(sys: &mut RodSystem, sol: &Solution) -> (Vec<f64>, f64) {
    let n = sys.model.n_dof();
    let mut scale: f64 = 0.0;
    let e = sol
        .y
        .iter()
        .map(|y| {
            let e = energies(
                &sys.model,
                &mut sys.data,
                &y.as_slice()[..n],
                &y.as_slice()[n..],
            )
            .unwrap();
            scale = scale
                .max(e.kinetic)
                .max(e.elastic)
                .max(e.gravitational.abs());
            e.total()
        })
        .collect();
    (e, scale)
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// (a) The adaptive methods conserve the energy of the undamped release to
/// their tolerance: rtol = 1e-8 gives |E(t) − E(0)| ≤ 10·rtol·scale over
/// 0.2 s (every accepted step is checked). A 2-piece, softer (E = 1e6)
/// cantilever keeps the stiff method's resolved fast modes affordable.
#[test]
fn undamped_release_conserves_energy_to_tolerance() {
    let model = cantilever(0.5, 0.01, 1000.0, 1e6, 0.5, 2);
    let rtol = 1e-8;
    for (method, jac) in [
        (Integrator::Dopri5, RodJacobian::Exact),
        (Integrator::Rosenbrock, RodJacobian::Exact),
        (Integrator::Rosenbrock, RodJacobian::ElasticOnly),
    ] {
        let opts = Options {
            max_steps: 1_000_000,
            ..Options::tol(rtol, 1e-10)
        };
        let (mut sys, sol) = run(&model, jac, method, 0.2, &opts).unwrap();
        let (e, scale) = energy_series(&mut sys, &sol);
        let worst = max_abs(&e);
        println!(
            "{method:?} {jac:?}: |ΔE|max / scale = {:.2e} (scale {scale:.3e} J), {:?}",
            worst / scale,
            sol.stats
        );
        // The rod fell: the energy scale is the potential released.
        assert!(scale > 1e-3, "scale {scale}");
        assert!(
            worst <= 10.0 * rtol * scale,
            "{method:?} {jac:?}: energy error {worst:e} > 10·rtol·scale = {:e}",
            10.0 * rtol * scale
        );
    }
}

/// (b) Generalized-α on the 5-piece cantilever with a fixed step of
/// 1 ms over 2 s (two bending periods): with `rho_inf = 1` the energy error
/// stays bounded and does not grow between the first and the second second;
/// with `rho_inf = 0.5` it dissipates: the energy decreases.
#[test]
fn generalized_alpha_energy_bounded_without_dissipation_decreasing_with() {
    let model = soft(5);
    let t1 = 2.0;
    let half = |sol: &Solution, e: &[f64], second: bool| {
        let v: Vec<f64> = sol
            .t
            .iter()
            .zip(e)
            .filter(|(t, _)| (**t > 0.5 * t1) == second)
            .map(|(_, e)| *e)
            .collect();
        v
    };
    let opts = Options {
        jacobian_max_age: 20,
        ..Options::fixed(1e-3)
    };
    let (mut sys, sol) = run(
        &model,
        RodJacobian::ElasticOnly,
        Integrator::GeneralizedAlpha,
        t1,
        &Options {
            rho_inf: 1.0,
            ..opts.clone()
        },
    )
    .unwrap();
    let (e, scale) = energy_series(&mut sys, &sol);
    let (first, second) = (
        max_abs(&half(&sol, &e, false)),
        max_abs(&half(&sol, &e, true)),
    );
    println!(
        "rho_inf = 1: |ΔE|/scale first half {:.2e}, second half {:.2e} (scale {scale:.3e} J), {:?}",
        first / scale,
        second / scale,
        sol.stats
    );
    assert!(
        first < 0.02 * scale && second < 0.02 * scale,
        "energy error not bounded"
    );
    assert!(
        second < 1.5 * first,
        "energy error grows: {first:e} → {second:e}"
    );

    let (mut sys, sol) = run(
        &model,
        RodJacobian::ElasticOnly,
        Integrator::GeneralizedAlpha,
        t1,
        &Options {
            rho_inf: 0.5,
            ..opts.clone()
        },
    )
    .unwrap();
    let (e, scale) = energy_series(&mut sys, &sol);
    let (e_mid, e_end) = {
        let f = half(&sol, &e, false);
        (f[f.len() - 1], e[e.len() - 1])
    };
    println!(
        "rho_inf = 0.5: E(1 s)/scale = {:.2e}, E(2 s)/scale = {:.2e}, max E/scale = {:.2e}",
        e_mid / scale,
        e_end / scale,
        e.iter().cloned().fold(f64::MIN, f64::max) / scale
    );
    // Dissipation (small: the resolved bending modes have ω·dt ≪ 1 and are
    // damped only to third order): the energy ends below E(0) = 0 by several
    // times the undamped run's whole error band, keeps decreasing, and never
    // rises above E(0) by more than that band.
    let band = first.max(second);
    assert!(
        e_end < -3.0 * band,
        "no dissipation: E(2 s) = {e_end:e}, band {band:e}"
    );
    assert!(
        e_end < e_mid,
        "energy not decreasing: {e_mid:e} → {e_end:e}"
    );
    assert!(e.iter().all(|&x| x <= band));
}

/// (c) The steel wire, 10 pieces, all strains, undamped: the explicit
/// stability limit from the highest natural frequency is `2.8/ω_max` (RK4's
/// stability interval on the imaginary axis is |hω| ≤ 2√2). The stiff
/// methods run stably with steps ≥ 100× that limit; RK4 at 3× the limit
/// fails with an `IntegrateError` (not a NaN trajectory).
#[test]
fn steel_wire_stable_far_above_explicit_limit() {
    let model = steel_wire(10);
    let n = model.n_dof();
    let mut data = Data::new(&model);
    let md = modes(&model, &mut data, &vec![0.0; n], 0.0).unwrap();
    let w_max = md.omega[n - 1];
    let w_1 = md.omega[0];
    let limit = 2.8 / w_max;
    println!("steel wire: ω1 = {w_1:.3} rad/s, ω_max = {w_max:.3e} rad/s, RK4 limit {limit:.3e} s");
    let t1 = 0.2;
    let dt = 100.0 * limit;
    for (method, opts, jac) in [
        (
            Integrator::Rosenbrock,
            Options::fixed(dt),
            RodJacobian::Exact,
        ),
        (
            Integrator::Rosenbrock,
            Options::fixed(dt),
            RodJacobian::ElasticOnly,
        ),
        (
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: 1.0,
                ..Options::fixed(dt)
            },
            RodJacobian::Exact,
        ),
        (
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: 0.8,
                ..Options::linearly_implicit(dt)
            },
            RodJacobian::ElasticOnly,
        ),
    ] {
        let (mut sys, sol) = run(&model, jac, method, t1, &opts).unwrap();
        let (e, scale) = energy_series(&mut sys, &sol);
        let h_min = sol.t[..sol.t.len() - 1]
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        println!(
            "{method:?} {jac:?}: steps {} (smallest {:.1}× limit), max |E|/scale {:.2e}, scale {scale:.3e} J",
            sol.stats.steps,
            h_min / limit,
            max_abs(&e) / scale
        );
        assert!(sol.y.iter().all(|y| y.iter().all(|v| v.is_finite())));
        // The wire sags (static tip sag ≈ ρAgL⁴/(8EI) ≈ 2 cm): energy moves.
        assert!(scale > 1e-5);
        // Bounded: never more than the gravitational energy released.
        assert!(max_abs(&e) < 0.5 * scale, "energy not bounded");
        // Every step at least 100× the explicit limit (the last may be cut
        // to land on t1).
        let n_short = sol
            .t
            .windows(2)
            .filter(|w| w[1] - w[0] < 99.9 * limit)
            .count();
        assert!(n_short <= 1, "{n_short} steps below 100× the limit");
    }

    // Adaptive Rosenbrock–W at a loose tolerance: after the release
    // transient its steps are far above the limit too (average ≥ 100×).
    let (mut sys, sol) = run(
        &model,
        RodJacobian::ElasticOnly,
        Integrator::Rosenbrock,
        t1,
        &Options::tol(1e-3, 1e-6),
    )
    .unwrap();
    let (e, scale) = energy_series(&mut sys, &sol);
    let avg = t1 / sol.stats.steps as f64;
    println!(
        "Rosw34 adaptive rtol 1e-3: {} steps, average {:.0}× limit, max |E|/scale {:.2e}",
        sol.stats.steps,
        avg / limit,
        max_abs(&e) / scale
    );
    assert!(avg >= 100.0 * limit);
    assert!(max_abs(&e) < 0.5 * scale);

    // RK4 at 3× the limit: the stiff modes blow up; reported as an error.
    let res = run(
        &model,
        RodJacobian::Exact,
        Integrator::Rk4,
        t1,
        &Options::fixed(3.0 * limit),
    );
    match res {
        Err(e) => println!("RK4 at 3× the limit: {e}"),
        Ok((_, sol)) => panic!(
            "RK4 at 3× the stability limit completed ({} steps)",
            sol.stats.steps
        ),
    }
}

/// Same input twice → the same bits (adaptive stiff, explicit, linearly
/// implicit with fixed step and with error control), including the
/// streamed outputs.
#[test]
fn reruns_are_bit_identical() {
    let model = soft(3);
    let te: Vec<f64> = (0..=20).map(|k| 0.005 * k as f64).collect();
    let cases = [
        (
            Integrator::Rosenbrock,
            Options::tol(1e-4, 1e-7).with_t_eval(te.clone()),
            RodJacobian::Exact,
        ),
        (
            Integrator::Dopri5,
            Options::tol(1e-6, 1e-9).with_t_eval(te.clone()),
            RodJacobian::Exact,
        ),
        (
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: 0.8,
                ..Options::linearly_implicit(1e-3).with_t_eval(te.clone())
            },
            RodJacobian::ElasticOnly,
        ),
        (
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: 0.0,
                ..Options::linearly_implicit_tol(1e-2, 1e-4).with_t_eval(te.clone())
            },
            RodJacobian::ElasticOnly,
        ),
    ];
    for (method, opts, jac) in cases {
        let go = || {
            let mut sys = RodSystem::new(model.clone());
            sys.jacobian = jac;
            let z = DVector::zeros(model.n_dof());
            let mut streamed: Vec<(f64, DVector<f64>)> = Vec::new();
            let record = |t, y: &DVector<f64>, _: &mut RodSystem| {
                streamed.push((t, y.clone()));
                softrod_integrate::Control::Continue
            };
            let sol = integrate_second_order(
                &mut sys,
                method,
                (0.0, 0.1),
                &z,
                &z,
                &opts,
                &mut Callbacks::new().on_output(record),
            )
            .unwrap();
            (sol, streamed)
        };
        let (a, sa) = go();
        let (b, sb) = go();
        let bits = |s: &Solution| -> Vec<u64> {
            s.y.iter()
                .flat_map(|y| y.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
                .chain(s.y_final.iter().map(|v| v.to_bits()))
                .collect()
        };
        assert_eq!(a.t, b.t);
        assert_eq!(bits(&a), bits(&b), "{method:?}: solutions differ");
        assert_eq!(a.stats, b.stats);
        assert_eq!(a.t.len(), te.len());
        // The streamed outputs are the stored ones, bit for bit.
        assert_eq!(sa.len(), a.t.len());
        for ((t, y), (ta, ya)) in sa.iter().zip(a.t.iter().zip(&a.y)) {
            assert_eq!(t.to_bits(), ta.to_bits());
            assert!(
                y.iter()
                    .zip(ya.iter())
                    .all(|(u, v)| u.to_bits() == v.to_bits())
            );
        }
        assert_eq!(sa.len(), sb.len());
    }
}

/// The rod with `RodJacobian::ElasticOnly` but only through
/// `SecondOrderSystem::jacobians` (dense `−M⁻¹K`, `−M⁻¹D`, LU of the
/// iteration matrix): the reference for the mass-matrix form.
struct DenseW(RodSystem);

impl softrod_integrate::SecondOrderSystem for DenseW {
    type Error = softrod_dynamics::DynamicsError;
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn accel(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), Self::Error> {
        self.0.accel(t, q, qd, qdd)
    }
    fn jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        jq: &mut nalgebra::DMatrix<f64>,
        jv: &mut nalgebra::DMatrix<f64>,
    ) -> Result<(), Self::Error> {
        let _ = (t, qd);
        self.0.elastic_jacobians(q, jq, jv)
    }
    fn is_autonomous(&self) -> bool {
        self.0.is_autonomous()
    }
}

/// A damped 4-piece soft cantilever (so the `D` terms count).
fn damped_soft() -> Model {
    let rod = RodGeometry::uniform(0.5, 4, Basis::all(), straight(), Pose::identity()).unwrap();
    let mat = Material::with_poisson(1000.0, 1e7, 0.5, 50.0).unwrap();
    let body = RodProperties::new(Section::Circle { radius: 0.01 }, mat, 0.5).unwrap();
    Model::new(
        vec![Rod::new("rod", rod, body)],
        Some(Vec3::new(0.0, 0.0, -9.81)),
        4,
    )
    .unwrap()
}

/// The mass-matrix form (Cholesky of `M + β'K + γ'D`, resp. `c²M + cD + K`,
/// one product with `M` per solve; generalized-α's Newton on the force
/// residual) solves the same equations as the dense `W = −M⁻¹K, −M⁻¹D` with
/// an LU and the acceleration residual, on a damped rod over 0.1 s:
/// ROS34PW2 with fixed steps (the same linear algebra: equal to rounding)
/// and generalized-α with Newton converged far below the compared accuracy
/// (both iterations have the step's gen-α solution as their fixed point).
#[test]
fn mass_matrix_form_matches_dense_inverse_mass_stiffness() {
    let model = damped_soft();
    let n = model.n_dof();
    let z = DVector::zeros(n);
    let cases = [
        (Integrator::Rosenbrock, Options::fixed(1e-3), 1e-10),
        (
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: 0.8,
                rtol: 1e-12,
                atol: 1e-14,
                iteration: Iteration::Newton {
                    tol: 1e-2,
                    max_iter: 30,
                },
                ..Options::fixed(1e-3)
            },
            1e-8,
        ),
    ];
    for (method, opts, tol) in cases {
        let opts = Options {
            t_eval: Some(vec![0.1]),
            ..opts
        };
        let mut fast = RodSystem::new(model.clone());
        fast.jacobian = RodJacobian::ElasticOnly;
        let a = integrate_second_order(&mut fast, method, (0.0, 0.1), &z, &z, &opts, &mut NoHooks)
            .unwrap();
        let mut slow = RodSystem::new(model.clone());
        slow.jacobian = RodJacobian::ElasticOnly;
        let mut slow = DenseW(slow);
        let b = integrate_second_order(&mut slow, method, (0.0, 0.1), &z, &z, &opts, &mut NoHooks)
            .unwrap();
        assert_eq!(a.stats.steps, b.stats.steps, "{method:?}");
        let (ya, yb) = (&a.y[0], &b.y[0]);
        let q_scale = ya.rows(0, n).amax();
        let v_scale = ya.rows(n, n).amax();
        let dq = (ya.rows(0, n) - yb.rows(0, n)).amax();
        let dv = (ya.rows(n, n) - yb.rows(n, n)).amax();
        assert!(q_scale > 1e-3 && v_scale > 1e-3, "the rod moved");
        assert!(
            dq <= tol * q_scale && dv <= tol * v_scale,
            "{method:?}: |Δq| = {dq:e} (scale {q_scale:e}), |Δv| = {dv:e} (scale {v_scale:e})"
        );
    }
}

/// `RodSystem::force_residual` is `M(q)·(q̈ − a(q, q̇))` with the actuator
/// force in `a` (mass matrix and forward dynamics computed independently),
/// and `mass_form_jacobians` gives `M(q)` and the constant `K`, `D` whose
/// `−M⁻¹K`, `−M⁻¹D` are the dense `jacobians`.
#[test]
fn force_residual_and_mass_form_are_consistent() {
    use nalgebra::DMatrix;
    use softrod_integrate::SecondOrderSystem;
    let model = damped_soft();
    let n = model.n_dof();
    let mut sys = RodSystem::new(model.clone());
    sys.jacobian = RodJacobian::ElasticOnly;
    sys.tau = Some(DVector::from_fn(n, |i, _| 1e-3 * ((i as f64) * 0.7).cos()));
    let q = DVector::from_fn(n, |i, _| 0.05 * ((i as f64) * 1.3).sin());
    let v = DVector::from_fn(n, |i, _| 0.3 * ((i as f64) * 0.9).cos());
    let x = DVector::from_fn(n, |i, _| 5.0 * ((i as f64) * 2.1).sin());
    let mut a = DVector::zeros(n);
    sys.accel(0.0, &q, &v, &mut a).unwrap();
    let mut r = DVector::zeros(n);
    assert!(sys.force_residual(0.0, &q, &v, &x, &mut r).unwrap());
    let m = softrod_dynamics::mass_matrix(&model, &mut Data::new(&model), q.as_slice())
        .unwrap()
        .clone();
    let expect = &m * (&x - &a);
    assert!(
        (&r - &expect).amax() <= 1e-10 * expect.amax(),
        "{:e}",
        (&r - &expect).amax() / expect.amax()
    );
    let (mut mm, mut k, mut d) = (
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
    );
    assert!(
        sys.mass_form_jacobians(0.0, &q, &v, &mut mm, Some((&mut k, &mut d)))
            .unwrap()
    );
    assert_eq!(mm, m);
    let (mut jq, mut jv) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    sys.elastic_jacobians(&q, &mut jq, &mut jv).unwrap();
    assert!((&m * &jq + &k).amax() <= 1e-10 * k.amax());
    assert!((&m * &jv + &d).amax() <= 1e-10 * d.amax());
    assert!(d.amax() > 0.0);
    assert!(sys.has_mass_form());
    // The shifted mass matrix M + aK + bD, solved structurally, against the
    // dense matrices above.
    let (sa, sb) = (2.5e-6, 3.0e-3);
    assert!(sys.factor_shifted_mass(0.0, &q, sa, sb).unwrap());
    let mut y = x.clone();
    sys.solve_shifted_mass(&mut y).unwrap();
    let back = (&m + &k * sa + &d * sb) * &y;
    assert!(
        (&back - &x).amax() <= 1e-9 * x.amax(),
        "{:e}",
        (&back - &x).amax() / x.amax()
    );
    // Exact Jacobians: no mass-matrix form; the force residual and the
    // shifted solve stay (the implicit methods' structured Newton matrix).
    sys.jacobian = RodJacobian::Exact;
    assert!(!sys.has_mass_form());
    let mut r2 = DVector::zeros(n);
    assert!(sys.force_residual(0.0, &q, &v, &x, &mut r2).unwrap());
    assert_eq!(r, r2);
    assert!(!sys.mass_form_jacobians(0.0, &q, &v, &mut mm, None).unwrap());
}

/// ESDIRK5(4)7L\[2\]SA on the soft cantilever's undamped release (4 pieces,
/// all six strains), against a second method: Radau IIA at rtol 1e-10.
/// Compared is the tip position at every output, what the position-norm
/// error control tracks (the curvatures carry the unresolved stretch and
/// shear ringing at ~1e5 rad/s, which each method damps its own way: Radau
/// IIA at rtol 1e-6 is 3e-4 1/m off its own rtol 1e-10 there). The tip
/// stays within `rtol` metres of the reference, and tightening `rtol` by 100
/// tightens the agreement at least 30×.
#[test]
fn esdirk5_agrees_with_radau_at_tight_tolerance_on_the_rod() {
    let model = soft(4);
    let geometry = &model.rods()[0].spec.geometry;
    let mut kin = softrod_kinematics::RodKinematics::new(geometry);
    let n = model.n_dof();
    let times: Vec<f64> = (0..=20).map(|k| 0.01 * k as f64).collect();
    let mut tips = |method: Integrator, rtol: f64| -> Vec<Vec3> {
        let opts = Options {
            t_eval: Some(times.clone()),
            ..Options::tol(rtol, rtol)
        };
        let sol = run(&model, RodJacobian::Exact, method, 0.2, &opts)
            .unwrap()
            .1;
        assert_eq!(sol.y.len(), times.len());
        sol.y
            .iter()
            .map(|y| {
                kin.update(geometry, &y.as_slice()[..n], None, None)
                    .unwrap();
                kin.tip_pose().translation
            })
            .collect()
    };
    let reference = tips(Integrator::Radau5, 1e-10);
    let mut errors = Vec::new();
    for rtol in [1e-6, 1e-8] {
        let e = tips(Integrator::Esdirk5, rtol)
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        println!("esdirk5 rtol {rtol:e}: largest tip distance {e:.2e} m");
        assert!(e < rtol, "rtol {rtol:e}: {e:e} m");
        errors.push(e);
    }
    assert!(errors[1] < errors[0] / 30.0, "{errors:?}");
    let sag = (reference.last().unwrap() - reference[0]).norm();
    assert!(sag > 1e-2, "the tip moved {sag} m");
}
