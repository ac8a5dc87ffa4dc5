//! One run of the integrate bench's scene (for callgrind / quick timing):
//! 1 s of the undamped release of the soft cantilever, linearly implicit
//! generalized-α, ρ∞ 0.8, W = M⁻¹K, M⁻¹D.
//!
//! `N_PIECES=20 DT=1.5e-3 REPS=1 target/release/examples/integrate_run`
//! prints the tip, the work counters and the wall time of each repetition.
//! `REF=1` also computes the bench's converged reference (generalized-α
//! ρ∞ = 1, full Newton, dt 5e-5) twice — with the force-residual Newton of
//! `RodSystem` and with the acceleration-form Newton on dense `−M⁻¹K`
//! (a wrapper that hides the mass-matrix form) — and prints the tip errors.

use nalgebra::{DMatrix, DVector};
use softrod_dynamics::{Model, Rod};
use softrod_integrate::{
    Integrator, Iteration, NoHooks, Options, RodJacobian, RodSystem, SecondOrderSystem,
    integrate_second_order,
};
use softrod_kinematics::{Basis, RodGeometry, RodKinematics, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{Material, RodProperties, Section};
use std::time::Instant;

fn env<T: std::str::FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

/// `RodSystem` through `accel` and `jacobians` only (dense `−M⁻¹K`).
struct Dense(RodSystem);

impl SecondOrderSystem for Dense {
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
        jq: &mut DMatrix<f64>,
        jv: &mut DMatrix<f64>,
    ) -> Result<(), Self::Error> {
        let _ = (t, qd);
        self.0.elastic_jacobians(q, jq, jv)
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// `RodSystem` with its mass-matrix form but without the force residual:
/// generalized-α then corrects with `(M_J + β'K)⁻¹ M_J (a − x)` from a
/// forward dynamics (`VARIANT=accel`).
struct NoResidual(RodSystem);

impl SecondOrderSystem for NoResidual {
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
    fn mass_form_jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
        constant: Option<(&mut DMatrix<f64>, &mut DMatrix<f64>)>,
    ) -> Result<bool, Self::Error> {
        self.0.mass_form_jacobians(t, q, qd, mass, constant)
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

fn tip(m: &Model, y: &DVector<f64>) -> [f64; 3] {
    let rod = &m.rods()[0].spec.geometry;
    let mut k = RodKinematics::new(rod);
    k.update(rod, &y.as_slice()[..m.n_dof()], None, None)
        .unwrap();
    let p = k.tip_pose().translation;
    [p[0], p[1], p[2]]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn main() {
    let n_pieces: usize = env("N_PIECES", 20);
    // A comma-separated list: each step size is run REPS times.
    let dts: Vec<f64> = std::env::var("DT")
        .unwrap_or_else(|_| "1.5e-3".into())
        .split(',')
        .map(|v| v.trim().parse().expect("DT: numbers separated by commas"))
        .collect();
    let reps: usize = env("REPS", 1);
    let accel_form = std::env::var("VARIANT").is_ok_and(|v| v == "accel");
    let l = 0.5;
    let rod =
        RodGeometry::uniform(l, n_pieces, Basis::all(), straight(), Pose::identity()).unwrap();
    let mat = Material::with_poisson(1000.0, 1e7, 0.5, 0.0).unwrap();
    let body = RodProperties::new(Section::Circle { radius: 0.01 }, mat, l).unwrap();
    let m = Model::new(
        vec![Rod::new("cantilever", rod, body)],
        Some(Vec3::new(0.0, 0.0, -9.81)),
        4,
    )
    .unwrap();
    let n = m.n_dof();
    // Outputs every 10 ms: the tip error at t = 1 (the bench's measure) and
    // its maximum over the run (which a lucky phase at t = 1 cannot hide).
    let times: Vec<f64> = (1..=100).map(|k| k as f64 / 100.0).collect();
    let mut refs: Vec<Vec<[f64; 3]>> = Vec::new();
    if env("REF", 0) == 1 {
        let z = DVector::zeros(n);
        let opts = Options {
            iteration: Iteration::Newton {
                tol: 1e-3,
                max_iter: 8,
            },
            t_eval: Some(times.clone()),
            max_steps: 10_000_000,
            rho_inf: 1.0,
            ..Options::fixed(5e-5)
        };
        let ga = Integrator::GeneralizedAlpha;
        let mut sys = RodSystem::new(m.clone());
        sys.jacobian = RodJacobian::ElasticOnly;
        let t0 = Instant::now();
        let a =
            integrate_second_order(&mut sys, ga, (0.0, 1.0), &z, &z, &opts, &mut NoHooks).unwrap();
        let ta: Vec<_> = a.y.iter().map(|y| tip(&m, y)).collect();
        println!(
            "ref (force residual): {ta:?} {:?} {:.1} s",
            a.stats,
            t0.elapsed().as_secs_f64()
        );
        let mut dense = Dense(sys.clone());
        let t0 = Instant::now();
        let b = integrate_second_order(&mut dense, ga, (0.0, 1.0), &z, &z, &opts, &mut NoHooks)
            .unwrap();
        let tb: Vec<_> = b.y.iter().map(|y| tip(&m, y)).collect();
        println!(
            "ref (accel, dense M⁻¹K): {:?} {:?} {:.1} s; refs differ by {:.2e} m (max over t)",
            tb[99],
            b.stats,
            t0.elapsed().as_secs_f64(),
            ta.iter()
                .zip(&tb)
                .map(|(a, b)| dist(*a, *b))
                .fold(0.0, f64::max)
        );
        refs = vec![ta, tb];
    }
    // TOL=rtol list: error-controlled runs (atol = rtol/100) instead of DT.
    let tols: Vec<f64> = std::env::var("TOL")
        .map(|v| {
            v.split(',')
                .map(|x| x.trim().parse().expect("TOL: numbers separated by commas"))
                .collect()
        })
        .unwrap_or_default();
    let settings: Vec<(f64, bool)> = if tols.is_empty() {
        dts.iter().map(|&d| (d, false)).collect()
    } else {
        tols.iter().map(|&t| (t, true)).collect()
    };
    for ((dt, controlled), _) in settings
        .iter()
        .flat_map(|&s| (0..reps).map(move |r| (s, r)))
    {
        let t0 = Instant::now();
        let mut sys = RodSystem::new(m.clone());
        sys.jacobian = RodJacobian::ElasticOnly;
        let z = DVector::zeros(n);
        let opts = Options {
            t_eval: Some(times.clone()),
            max_steps: 10_000_000,
            rho_inf: env("RHO", 0.8),
            ..if controlled {
                Options::linearly_implicit_tol(dt, dt * 1e-2)
            } else {
                Options::linearly_implicit(dt)
            }
        };
        let method = Integrator::GeneralizedAlpha;
        let sol = if accel_form {
            let mut sys = NoResidual(sys);
            integrate_second_order(&mut sys, method, (0.0, 1.0), &z, &z, &opts, &mut NoHooks)
        } else {
            integrate_second_order(&mut sys, method, (0.0, 1.0), &z, &z, &opts, &mut NoHooks)
        }
        .unwrap();
        let wall = t0.elapsed().as_secs_f64();
        let tips: Vec<_> = sol.y.iter().map(|y| tip(&m, y)).collect();
        let p = tips[99];
        println!(
            "{} {dt:e}: tip [{:.12e}, {:.12e}, {:.12e}] {:?} wall {:.2} ms",
            if controlled { "rtol" } else { "dt" },
            p[0],
            p[1],
            p[2],
            sol.stats,
            wall * 1e3
        );
        for r in &refs {
            let max = tips
                .iter()
                .zip(r)
                .map(|(a, b)| dist(*a, *b))
                .fold(0.0, f64::max);
            println!(
                "  tip error vs reference: {:.3e} m at t = 1, {max:.3e} m max over t",
                dist(p, r[99])
            );
        }
    }
}
