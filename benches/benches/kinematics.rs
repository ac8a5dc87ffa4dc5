//! Criterion benches of `softrod-kinematics`: the per-step work of a
//! controller or a dynamics right-hand side.
//!
//! (a) `update` (q only) + tip pose + tip Jacobian (body frame), all six
//!     strains per piece, N = 1 … 1000 pieces (target: N = 10 ≤ 3 µs);
//! (b) `update` + poses at 4 Gauss points per piece (`poses_along`),
//!     N = 10, 100, 1000 (target: N = 100 ≤ 30 µs).
//!
//! Both should scale linearly in N (criterion reports the time per piece via
//! the element throughput).
//!
//! Regenerate (numbers in docs/performance.md):
//! `cargo bench -p softrod-benches --bench kinematics -- --warm-up-time 1 --measurement-time 2`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use nalgebra::Matrix6xX;
use softrod_kinematics::{Basis, Frame, GaussLegendre, RodGeometry, RodKinematics, straight};
use softrod_lie::Pose;
use std::hint::black_box;

/// A 1 m rod of `n` pieces with all six strains, and a fixed, reproducible
/// configuration: a curled shape (total bending of a few radians, some
/// torsion, a little shear and extension) so every piece does real work.
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

fn tip_pose_and_jacobian(c: &mut Criterion) {
    let mut group = c.benchmark_group("kinematics/update+tip_pose+tip_jacobian");
    for n in [1usize, 4, 10, 40, 100, 1000] {
        let (rod, q) = setup(n);
        let mut kin = RodKinematics::new(&rod);
        let mut jac = Matrix6xX::zeros(rod.n_dof());
        let l = rod.length();
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                kin.update(&rod, black_box(&q), None, None).expect("update");
                let tip = *kin.tip_pose();
                kin.jacobian_at(&rod, l, Frame::Body, &mut jac)
                    .expect("jacobian");
                black_box((tip, &jac));
            })
        });
    }
    group.finish();
}

fn gauss_point_poses(c: &mut Criterion) {
    let mut group = c.benchmark_group("kinematics/update+gauss_poses_4");
    let rule = GaussLegendre::new(4);
    for n in [10usize, 100, 1000] {
        let (rod, q) = setup(n);
        let mut kin = RodKinematics::new(&rod);
        let mut poses = vec![Pose::identity(); 4 * n];
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                kin.update(&rod, black_box(&q), None, None).expect("update");
                kin.poses_along(&rod, &rule.nodes, &mut poses)
                    .expect("poses");
                black_box(&poses);
            })
        });
    }
    group.finish();
}

criterion_group!(benches, tip_pose_and_jacobian, gauss_point_poses);
criterion_main!(benches);
