//! Cost against the number of pieces (issue 30; docs/performance.md,
//! "Scaling to 10 000 pieces"): one forward dynamics, the analytic
//! derivatives, the factor + solve of `M + aK + bD` (the implicit step's
//! linear algebra), a statics solve and the lowest 10 modes of a clamped
//! soft rod under gravity, at N = 10, 100, 1 000, 10 000 pieces.
//!
//! `cargo run --release -p softrod-benches --example scaling`
//! (`SIZES=10,100 BASIS=all|planar WHAT=step,statics,modes REPS=3`). Each
//! figure is the fastest of `REPS` repetitions \[s\]. The derivatives
//! (`n × n` outputs) are skipped above `DERIV_MAX` pieces (default 1 000),
//! the dense statics and modes (for comparison, `DENSE=1`) above 200.

use softrod_dynamics::{
    Data, IdDerivatives, Model, Rod, ShiftedSolver, StaticsOptions, StaticsSolver,
    forward_dynamics, inverse_dynamics_derivatives, lowest_modes, modes, statics,
};
use softrod_kinematics::Strain;
use softrod_lie::Vec3;
use softrod_mechanics::Material;
use std::time::Instant;

fn env<T: std::str::FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

/// A 1 m silicone-like rod (E = 5 MPa, ρ = 1 000 kg/m³, r = 1 cm),
/// clamped, under gravity: gravity parameter `ρgAL³/EI` = 7.8, a large
/// sag that Newton reaches without continuation.
fn rod_model(pieces: usize, planar: bool) -> Model {
    let material = Material::with_poisson(1000.0, 5e6, 0.5, 0.0).unwrap();
    let strains: Vec<Strain> = if planar {
        vec![Strain::Ky, Strain::Qx, Strain::Qz]
    } else {
        Strain::ALL.to_vec()
    };
    let rod = Rod::builder(1.0)
        .name("rod")
        .pieces(pieces)
        .strains(strains)
        .circle(0.01)
        .material(material)
        .build()
        .unwrap();
    Model::builder()
        .rod(rod)
        .gravity(Vec3::new(0.0, 0.0, -9.81))
        .quadrature(3)
        .build()
        .unwrap()
}

fn best<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..reps {
        let t = Instant::now();
        let v = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(v);
    }
    (best, out.unwrap())
}

fn main() {
    let sizes: Vec<usize> = std::env::var("SIZES")
        .unwrap_or_else(|_| "10,100,1000,10000".into())
        .split(',')
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let planar = env("BASIS", String::from("all")) == "planar";
    let what = env("WHAT", String::from("step,statics,modes"));
    let reps = env("REPS", 3usize);
    let deriv_max = env("DERIV_MAX", 1000usize);
    let dense = env("DENSE", 0usize) == 1;
    println!(
        "basis {}, fastest of {reps}",
        if planar {
            "planar (ky, qx, qz)"
        } else {
            "all six"
        }
    );
    println!(
        "| N | n_dof | FD [s] | derivatives [s] | factor+solve [s] | statics [s] (its) | modes [s] | ω₁ [rad/s] |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for &n in &sizes {
        let model = rod_model(n, planar);
        let nd = model.n_dof();
        let mut data = Data::new(&model);
        let q: Vec<f64> = (0..nd).map(|i| 0.01 * ((i as f64) * 0.7).sin()).collect();
        let qd: Vec<f64> = (0..nd).map(|i| 0.1 * ((i as f64) * 1.3).cos()).collect();
        let mut cells = vec![String::from("–"); 6];
        if what.contains("step") {
            let (t, _) = best(reps, || {
                forward_dynamics(&model, &mut data, 0.0, &q, &qd, None)
                    .unwrap()
                    .amax()
            });
            cells[0] = format!("{t:.2e}");
            if n <= deriv_max {
                let mut w = IdDerivatives::new(&model);
                let qdd = vec![0.0; nd];
                let (t, _) = best(reps, || {
                    inverse_dynamics_derivatives(&model, &mut w, 0.0, &q, &qd, &qdd).unwrap();
                });
                cells[1] = format!("{t:.2e}");
            }
            let mut solver = ShiftedSolver::new(&model);
            let mut x = vec![1.0; nd];
            let (t, _) = best(reps, || {
                solver.factor(&model, &q, 1e-6, 1e-3).unwrap();
                solver.solve(&model, &mut x).unwrap();
            });
            cells[2] = format!("{t:.2e}");
        }
        let zero = vec![0.0; nd];
        let mut q_eq = zero.clone();
        if what.contains("statics") {
            let solver = match env("SOLVER", String::from("auto")).as_str() {
                _ if dense && n <= 200 => StaticsSolver::Dense,
                "structured" => StaticsSolver::Structured,
                _ => StaticsSolver::Auto,
            };
            let options = StaticsOptions {
                solver,
                ..StaticsOptions::default()
            };
            let (t, r) = best(reps, || {
                statics(&model, &mut data, &zero, &options).unwrap()
            });
            cells[3] = format!("{t:.2e} ({})", r.iterations);
            q_eq = r.q.as_slice().to_vec();
        }
        if what.contains("modes") {
            // The lowest 10 modes about the sagged equilibrium (or the
            // straight rod without WHAT=statics).
            let (t, m) = best(reps, || {
                if dense && n <= 200 {
                    modes(&model, &mut data, &q_eq, 0.0).unwrap()
                } else {
                    lowest_modes(&model, &mut data, &q_eq, 0.0, 10).unwrap()
                }
            });
            cells[4] = format!("{t:.2e}");
            cells[5] = format!("{:.4}", m.omega[0]);
        }
        println!(
            "| {n} | {nd} | {} | {} | {} | {} | {} | {} |",
            cells[0], cells[1], cells[2], cells[3], cells[4], cells[5]
        );
    }
}
