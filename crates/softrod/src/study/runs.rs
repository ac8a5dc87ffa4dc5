//! Runs of a study: one configuration integrated (wall time, tips at the
//! comparison times), scene variants with refined pieces, distances.

use std::time::Instant;

use softrod_integrate::{
    Callbacks, Control, Integrator, Options, RodSystem, Status, integrate_second_order,
};
use softrod_scene::{Built, Scene};

use super::Outcome;
use crate::error::{Error, Result};
use crate::record::WorldPoses;

/// Euclidean distance \[m\].
pub fn dist(p: &[f64; 3], q: &[f64; 3]) -> f64 {
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

/// Largest distance between corresponding points \[m\].
pub fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter().zip(b).map(|(p, q)| dist(p, q)).fold(0.0, f64::max)
}

pub(super) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The first rod's tip at `q` \[m\], prescribed joints at `t`.
pub(super) fn tip(poses: &mut WorldPoses, built: &Built, t: f64, q: &[f64]) -> Result<[f64; 3]> {
    poses.update(&built.model, t, q)?;
    let p = poses.tip(0).translation;
    Ok([p[0], p[1], p[2]])
}

/// One integration, stopped (as a failure) when it exceeds `budget` wall s.
pub(super) fn simulate_once(
    built: &Built,
    method: Integrator,
    opts: &Options,
    times: &[f64],
    budget: f64,
) -> std::result::Result<Outcome, String> {
    let mut sys = RodSystem::new(built.model.clone());
    // Each method with the Jacobian `softrod run` gives it.
    sys.jacobian = crate::Settings::default()
        .with_integrator(method)
        .stiff_jacobian();
    let t1 = *times.last().expect("times");
    let opts = Options {
        t_eval: Some(times.to_vec()),
        max_steps: opts.max_steps.max(50_000_000),
        ..opts.clone()
    };
    let start = Instant::now();
    let n = sys.model.n_dof();
    // The contact state moves at accepted steps as in `Simulation::simulate`
    // (friction anchors, raised stiffnesses, the penetration bound; CT5,
    // CT15): without the commit friction never sticks.
    let failure = std::cell::RefCell::new(None);
    let mut hooks = Callbacks::new().on_step(|info, sys: &mut RodSystem| {
        if start.elapsed().as_secs_f64() > budget {
            return Control::Stop;
        }
        let (q, qd) = info.y.as_slice().split_at(n);
        match sys.commit_contact_control(info.t, q, qd) {
            Ok(c) => c,
            Err(e) => {
                *failure.borrow_mut() = Some(format!("at t = {:e} s: {e}", info.t));
                Control::Stop
            }
        }
    });
    let sol = integrate_second_order(
        &mut sys,
        method,
        (0.0, t1),
        &built.q0,
        &built.qd0,
        &opts,
        &mut hooks,
    )
    .map_err(|e| crate::error::report(&e))?;
    let wall = start.elapsed().as_secs_f64();
    drop(hooks);
    if let Some(m) = failure.into_inner() {
        return Err(m);
    }
    if sol.status == Status::Stopped {
        return Err(format!(
            "stopped at t = {:.3e} s: over the time budget of {budget} s ({} steps)",
            sol.t_final, sol.stats.steps
        ));
    }
    let mut poses = WorldPoses::new(&sys.model);
    let mut tips = Vec::with_capacity(sol.y.len());
    for (t, y) in sol.t.iter().zip(&sol.y) {
        tips.push(tip(&mut poses, built, *t, &y.as_slice()[..n]).map_err(|e| e.report())?);
    }
    if tips.len() != times.len() {
        return Err(format!(
            "run ended at t = {} before the last comparison time",
            sol.t_final
        ));
    }
    Ok(Outcome {
        tips,
        stats: sol.stats,
        wall,
    })
}

/// `repeats` integrations; the median wall time (a failure is not repeated).
pub(super) fn simulate(
    built: &Built,
    method: Integrator,
    opts: &Options,
    times: &[f64],
    budget: f64,
    repeats: usize,
) -> std::result::Result<Outcome, String> {
    let first = simulate_once(built, method, opts, times, budget)?;
    let mut walls = vec![first.wall];
    for _ in 1..repeats {
        walls.push(simulate_once(built, method, opts, times, budget)?.wall);
    }
    Ok(Outcome {
        wall: median(walls),
        ..first
    })
}

/// The scene with every piece cut in `k` equal parts (same strains,
/// `[initial]` values repeated) and `quadrature` Gauss points per piece.
pub fn variant(scene: &Scene, k: usize, quadrature: usize) -> Result<Scene> {
    let mut s = scene.clone();
    s.run.quadrature = quadrature;
    if k == 1 {
        return Ok(s);
    }
    for r in &mut s.rods {
        r.geometry = r
            .geometry
            .subdivided(k)
            .map_err(|e| Error::Study(format!("pieces x{k}: {e}")))?;
    }
    let dup = |v: &Vec<f64>| -> Vec<f64> {
        let mut out = Vec::with_capacity(k * v.len());
        let mut off = 0;
        for r in &scene.rods {
            let c = r.geometry.pieces()[0].basis.dof();
            for _ in 0..r.geometry.n_pieces() {
                for _ in 0..k {
                    out.extend_from_slice(&v[off..off + c]);
                }
                off += c;
            }
        }
        out
    };
    s.initial.q = scene.initial.q.as_ref().map(dup);
    s.initial.qdot = scene.initial.qdot.as_ref().map(dup);
    Ok(s)
}

pub(super) fn build_variant(scene: &Scene, k: usize, quadrature: usize) -> Result<Built> {
    variant(scene, k, quadrature)?.build().map_err(|e| {
        Error::Study(format!(
            "pieces x{k}, quadrature {quadrature}: {}",
            crate::error::report(&e)
        ))
    })
}

/// Pieces over all rods of `scene`.
pub(super) fn pieces(scene: &Scene) -> usize {
    scene.rods.iter().map(|r| r.geometry.n_pieces()).sum()
}
