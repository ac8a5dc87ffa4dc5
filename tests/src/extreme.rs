//! Fixtures of the extreme-case tests (`tests/extreme_*.rs`, issue 8): one-rod
//! scenes written inline, statics with an independent residual check, runs
//! that check every state, energy and tip for NaN/Inf, and the energy and
//! tip comparisons the cases assert with.

use std::time::Instant;

use nalgebra::DVector;
use softrod_dynamics::{
    Data, DynamicsError, Model, StaticsOptions, StaticsResult, energies, inverse_dynamics, statics,
};
use softrod_integrate::{
    IntegrateError, Integrator, NoHooks, Options, RodSystem, Solution, integrate_second_order,
};
use softrod_kinematics::RodKinematics;
use softrod_lie::Pose;
use softrod_scene::{Built, Scene};
use std::f64::consts::PI;

/// Parses and builds a scene written inline (warnings ignored); panics on
/// any error: the fixtures are valid by construction.
pub fn build(toml: &str) -> Built {
    let (scene, _warnings) = Scene::from_str(toml, "extreme.toml").expect("scene parses");
    scene.build().expect("scene builds")
}

/// A one-rod scene: `rod` is the body of `[[rod]]` (after name/length/pieces).
pub fn scene(gravity: bool, length: f64, pieces: usize, rod: &str, extra: &str) -> String {
    let g = if gravity { "-9.81" } else { "0.0" };
    format!(
        "[world]\ngravity = [0.0, 0.0, {g}]\n\n[[rod]]\nname = \"arm\"\nlength = {length:?}\n\
         pieces = {pieces}\n{rod}\n{extra}\n"
    )
}

/// Tip pose of the first rod at `q` (its own coordinates first in `q`).
pub fn tip(model: &Model, q: &[f64]) -> Pose {
    let rod = &model.rods()[0].spec.geometry;
    let mut kin = RodKinematics::new(rod);
    kin.update(rod, &q[..rod.n_dof()], None, None).unwrap();
    *kin.tip_pose()
}

/// `‖R − I‖_F` of a pose's rotation: 0 when the frame is back to the identity.
pub fn rot_err(p: &Pose) -> f64 {
    (p.rotation - nalgebra::Matrix3::identity()).norm()
}

/// Statics from `q0`; on success the residual `ID(q, 0, 0)` is recomputed
/// here and must be tiny relative to the largest generalized force `K q`.
pub fn solve_statics(
    model: &Model,
    q0: &[f64],
    opts: &StaticsOptions,
) -> Result<StaticsResult, DynamicsError> {
    let mut data = Data::new(model);
    let res = statics(model, &mut data, q0, opts)?;
    let zero = vec![0.0; model.n_dof()];
    let r = inverse_dynamics(model, &mut data, 0.0, res.q.as_slice(), &zero, &zero)
        .unwrap()
        .amax();
    let k = softrod_dynamics::stiffness_matrix(model);
    let scale = (&k * &res.q).amax();
    assert!(res.q.iter().all(|v| v.is_finite()), "non-finite statics q");
    assert!(
        r <= 1e-7 * scale,
        "statics residual {r:e} vs scale {scale:e}"
    );
    Ok(res)
}

/// The equilibrium, or `None` after checking that the failure is the clear
/// `StaticsFailed` error (load fraction and residual named). Every case
/// converges today and requires it (`expect`); the check of the failure
/// message is what a case that may legitimately fail would keep.
pub fn statics_or_clear_error(what: &str, model: &Model, q0: &[f64]) -> Option<StaticsResult> {
    match solve_statics(model, q0, &StaticsOptions::default()) {
        Ok(r) => {
            println!(
                "{what}: statics converged, {} Newton its, {} load steps, residual {:.2e}",
                r.iterations, r.load_steps, r.residual
            );
            Some(r)
        }
        Err(e @ DynamicsError::StaticsFailed { .. }) => {
            let msg = e.to_string();
            println!("{what}: statics failed clearly: {msg}");
            assert!(msg.contains("load fraction") && msg.contains("residual"));
            None
        }
        Err(e) => panic!("{what}: statics failed with an unexpected error: {e}"),
    }
}

/// A finished run: the solution and the energies at its output times.
pub struct Run {
    pub sol: Solution,
    /// Total mechanical energy (+ cable potential `T ℓ_c` where asked) at `sol.t`.
    pub energy: Vec<f64>,
    /// Kinetic energy at `sol.t`.
    pub kinetic: Vec<f64>,
    /// Wall time of the integration (s): printed, never asserted.
    pub wall: f64,
}

/// Integrates `built` to `t1` with output at `n_out + 1` even times; checks
/// that every state, energy and tip is finite.
#[allow(clippy::too_many_arguments)]
pub fn integrate(
    built: &Built,
    q0: &DVector<f64>,
    qd0: &DVector<f64>,
    method: Integrator,
    opts: Options,
    t1: f64,
    n_out: usize,
    cable_tension: f64,
) -> Result<Run, IntegrateError> {
    let mut sys = RodSystem::new(built.model.clone());
    let times: Vec<f64> = (0..=n_out).map(|k| t1 * k as f64 / n_out as f64).collect();
    let opts = opts.with_t_eval(times);
    let start = Instant::now();
    let sol = integrate_second_order(&mut sys, method, (0.0, t1), q0, qd0, &opts, &mut NoHooks)?;
    let wall = start.elapsed().as_secs_f64();
    let n = sys.model.n_dof();
    let mut energy = Vec::new();
    let mut kinetic = Vec::new();
    for y in &sol.y {
        assert!(
            y.iter().all(|v| v.is_finite()),
            "NaN/Inf in a returned state"
        );
        let (q, qd) = (&y.as_slice()[..n], &y.as_slice()[n..]);
        let e = energies(&sys.model, &mut sys.data, q, qd).unwrap();
        let mut total = e.total();
        if cable_tension != 0.0 {
            let rm = &sys.model.rods()[0];
            for c in &rm.spec.cables {
                total += cable_tension * c.length(&rm.spec.geometry, q, sys.model.quadrature());
            }
        }
        assert!(total.is_finite(), "non-finite energy");
        let p = tip(&sys.model, q).translation;
        assert!(p.iter().all(|v| v.is_finite()), "non-finite tip");
        energy.push(total);
        kinetic.push(e.kinetic);
    }
    Ok(Run {
        sol,
        energy,
        kinetic,
        wall,
    })
}

/// Largest `|E(t) − E(0)|` relative to `scale`.
pub fn drift(e: &[f64], scale: f64) -> f64 {
    e.iter().map(|v| (v - e[0]).abs()).fold(0.0, f64::max) / scale
}

/// Largest increase `E(t_{k+1}) − E(t_k)` relative to `scale` (≤ 0 when the
/// energy never increases).
pub fn worst_increase(e: &[f64], scale: f64) -> f64 {
    e.windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::NEG_INFINITY, f64::max)
        / scale
}

/// Tip positions (m, world frame) of the first rod at every output of `sol`.
pub fn tips(model: &Model, sol: &Solution) -> Vec<[f64; 3]> {
    let n = model.n_dof();
    sol.y
        .iter()
        .map(|y| {
            let p = tip(model, &y.as_slice()[..n]).translation;
            [p.x, p.y, p.z]
        })
        .collect()
}

/// Largest Euclidean distance (m) between two tip sequences, time by time.
pub fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

/// An explicit run either succeeds and agrees with `reference` (tips at the
/// same output times) within `tol`, or stops with an `IntegrateError`.
#[allow(clippy::too_many_arguments)]
pub fn explicit_ok_or_clear_error(
    what: &str,
    built: &Built,
    method: Integrator,
    opts: Options,
    t1: f64,
    n_out: usize,
    reference: &[[f64; 3]],
    tol: f64,
) -> bool {
    match integrate(built, &built.q0, &built.qd0, method, opts, t1, n_out, 0.0) {
        Ok(run) => {
            let d = max_dist(&tips(&built.model, &run.sol), reference);
            println!(
                "{what}: explicit {method:?} succeeded, {} steps, max tip deviation from the stiff reference {d:.2e} m",
                run.sol.stats.steps
            );
            assert!(
                d < tol,
                "{what}: explicit run returned a wrong trajectory ({d:e} m)"
            );
            true
        }
        Err(e) => {
            println!("{what}: explicit {method:?} stopped with a clear error: {e}");
            false
        }
    }
}

/// The standard soft rod: all six strains, radius 1 cm, E = 1e7 Pa,
/// ρ = 1000 kg/m³, ν = 0.5 (G = E/3).
pub const SOFT_ROD: &str = "strains = \"all\"\nsection = { shape = \"circle\", radius = 0.01 }\n\
                        material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }";

/// Bending stiffness `EI = E π r⁴/4` (N m²) of a solid circle of radius `r`.
pub fn ei(young: f64, r: f64) -> f64 {
    young * PI * r.powi(4) / 4.0
}
