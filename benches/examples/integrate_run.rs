//! One run of the integrate bench's scene (for callgrind / quick timing):
//! 1 s of the undamped release of the soft cantilever, linearly implicit
//! generalized-α, ρ∞ 0.8, W = M⁻¹K, M⁻¹D.
//!
//! `N_PIECES=20 DT=1.5e-3 REPS=1 target/release/examples/integrate_run`
//! prints the tip, the work counters and the wall time of each repetition.

use nalgebra::DVector;
use softrod_dynamics::{Model, RodSpec};
use softrod_integrate::{Hooks, Method, Options, RodJacobian, RodSystem, integrate_second_order};
use softrod_kinematics::{Basis, Rod, RodKinematics, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{Material, RodBody, Section};
use std::time::Instant;

fn env<T: std::str::FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

fn main() {
    let n_pieces: usize = env("N_PIECES", 20);
    let dt: f64 = env("DT", 1.5e-3);
    let reps: usize = env("REPS", 1);
    let l = 0.5;
    let rod = Rod::uniform(l, n_pieces, Basis::all(), straight(), Pose::identity()).unwrap();
    let mat = Material::with_poisson(1000.0, 1e7, 0.5, 0.0).unwrap();
    let body = RodBody::new(Section::Circle { radius: 0.01 }, mat, l).unwrap();
    let m = Model::new(
        vec![RodSpec::new("cantilever", rod, body)],
        Some(Vec3::new(0.0, 0.0, -9.81)),
        4,
    )
    .unwrap();
    let n = m.n_dof();
    for _ in 0..reps {
        let t0 = Instant::now();
        let mut sys = RodSystem::new(m.clone());
        sys.jacobian = RodJacobian::ElasticOnly;
        let z = DVector::zeros(n);
        let opts = Options {
            t_eval: Some(vec![1.0]),
            max_steps: 10_000_000,
            ..Options::linearly_implicit(dt)
        };
        let sol = integrate_second_order(
            &mut sys,
            Method::GeneralizedAlpha { rho_inf: 0.8 },
            0.0,
            1.0,
            &z,
            &z,
            &opts,
            Hooks::new(),
        )
        .unwrap();
        let wall = t0.elapsed().as_secs_f64();
        let rod = &m.rods()[0].spec.rod;
        let mut k = RodKinematics::new(rod);
        k.update(rod, &sol.y[0].as_slice()[..n], None, None)
            .unwrap();
        let p = k.tip_pose().translation;
        println!(
            "tip [{:.12e}, {:.12e}, {:.12e}] {:?} wall {:.2} ms",
            p[0],
            p[1],
            p[2],
            sol.stats,
            wall * 1e3
        );
    }
}
