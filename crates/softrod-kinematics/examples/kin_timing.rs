//! Runs exactly what the kinematics criterion benches run
//! (`benches/benches/kinematics.rs`), for `valgrind --tool=callgrind` where
//! criterion is too slow. `BENCH=tip` is `update+tip_pose+tip_jacobian`,
//! `BENCH=gauss` is `update+gauss_poses_4`; one bench iteration is one call of
//! `tip_iteration` / `gauss_iteration` (never inlined, so
//! `callgrind_annotate --inclusive=yes` shows its count per call):
//! `BENCH=tip N_PIECES=10 N_ITER=2000 cargo run --release -p softrod-kinematics --example kin_timing`.
use nalgebra::Matrix6xX;
use softrod_kinematics::{Basis, Frame, GaussLegendre, RodGeometry, RodKinematics, straight};
use softrod_lie::Pose;
use std::hint::black_box;

fn env(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The bench's rod and configuration (`setup` in benches/benches/kinematics.rs).
fn setup(n: usize) -> (RodGeometry, Vec<f64>) {
    let rod =
        RodGeometry::uniform(1.0, n, Basis::all(), straight(), Pose::identity()).expect("rod");
    let q: Vec<f64> = (0..rod.n_dof())
        .map(|i| {
            let p = (i / 6) as f64;
            match i % 6 {
                0 => 0.5 + 0.3 * (0.7 * p).sin(),
                1 => 3.0 + 1.0 * (0.3 * p).cos(),
                2 => -1.5 + 0.5 * (1.1 * p).sin(),
                3 => 0.02 * (0.5 * p).sin(),
                _ => 0.01 * (0.9 * p).cos(),
            }
        })
        .collect();
    (rod, q)
}

#[inline(never)]
fn tip_iteration(
    rod: &RodGeometry,
    q: &[f64],
    kin: &mut RodKinematics,
    jac: &mut Matrix6xX<f64>,
) -> f64 {
    kin.update(rod, black_box(q), None, None).expect("update");
    let tip = *kin.tip_pose();
    kin.jacobian_at(rod, rod.length(), Frame::Body, jac)
        .expect("jacobian");
    black_box((tip, &*jac));
    tip.translation[0] + jac[(3, 0)]
}

#[inline(never)]
fn gauss_iteration(
    rod: &RodGeometry,
    q: &[f64],
    kin: &mut RodKinematics,
    nodes: &[f64],
    poses: &mut [Pose],
) -> f64 {
    kin.update(rod, black_box(q), None, None).expect("update");
    kin.poses_along(rod, nodes, poses).expect("poses");
    black_box(&*poses);
    poses[poses.len() - 1].translation[0]
}

fn main() {
    let n = env("N_PIECES", 10);
    let iters = env("N_ITER", 20000);
    let bench = std::env::var("BENCH").unwrap_or_else(|_| "tip".into());
    let (rod, q) = setup(n);
    let mut kin = RodKinematics::new(&rod);
    let t0 = std::time::Instant::now();
    let mut acc = 0.0;
    match bench.as_str() {
        "tip" => {
            let mut jac = Matrix6xX::zeros(rod.n_dof());
            for _ in 0..iters {
                acc += tip_iteration(&rod, &q, &mut kin, &mut jac);
            }
        }
        "gauss" => {
            let rule = GaussLegendre::new(4);
            let mut poses = vec![Pose::identity(); 4 * n];
            for _ in 0..iters {
                acc += gauss_iteration(&rod, &q, &mut kin, &rule.nodes, &mut poses);
            }
        }
        other => panic!("BENCH must be `tip` or `gauss`, not `{other}`"),
    }
    println!(
        "{bench}, N = {n}: {:.3} µs per iteration (checksum {acc:.6e})",
        t0.elapsed().as_secs_f64() / iters as f64 * 1e6
    );
}
