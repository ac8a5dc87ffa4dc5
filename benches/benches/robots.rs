//! Criterion benches of the tree path (docs/theory.md §11): the rod of the
//! `dynamics` benches (all six strains, 4 Gauss points, gravity, damping)
//! on a revolute joint (the tree recursion), on a prescribed prismatic base
//! (D59), and with its tip welded to the world (a closed chain, D63–D69:
//! the tree's forward dynamics plus one O(N) solve with `M` per constraint
//! row); the O(N) shifted factorization and solve on the tree; the analytic
//! derivatives on the tree; the Jacobian of a closed chain's constrained
//! `q̈` (a rod pinned at both ends: spherical joint and ball closure, the
//! cosseratbench catenary) by `closed_dynamics_derivatives` (CD1–CD4) and
//! by forward differences of the constrained `q̈` (what the integrators
//! used before: `2n` constrained forward dynamics); the Newton matrix of a
//! closed chain's implicit step (the same pinned rod): the structured KKT
//! factorization and solve (`ClosedShiftedSolver`, CD5–CD7) with its two
//! residuals, against what the dense path pays (an `n×n` LU of the
//! iteration matrix and the constrained forward dynamics per iteration).
//! Compare with `forward_dynamics/N` and `shifted_factor_solve/N` of the
//! `dynamics` benches.
//!
//! Regenerate (numbers in docs/performance.md, section "Articulated models"):
//! `cargo bench -p softrod-benches --bench robots -- --warm-up-time 1 --measurement-time 2`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use softrod_dynamics::{
    Attachment, ClosedDerivatives, ClosedShiftedSolver, Closure, ClosureFrame, ClosureKind, Curve,
    Data, Element, IdDerivatives, Joint, Model, Prescribed, Rod, ShiftedSolver,
    closed_dynamics_derivatives, forward_dynamics, inverse_dynamics_derivatives,
};
use softrod_kinematics::{Basis, RodGeometry, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{Material, RodProperties, Section};
use std::hint::black_box;

const LENGTH: f64 = 0.5;

fn spec(n: usize) -> Rod {
    let rod = RodGeometry::uniform(LENGTH, n, Basis::all(), straight(), Pose::identity()).unwrap();
    let material = Material::builder()
        .density(1000.0)
        .young(1e7)
        .shear_modulus(1e7 / 3.0)
        .viscosity(1.0)
        .build()
        .unwrap();
    let body = RodProperties::new(Section::Circle { radius: 0.01 }, material, LENGTH).unwrap();
    Rod::new("bench", rod, body)
}

fn on(n: usize, joint: Joint) -> Model {
    Model::with_elements(
        vec![Element::Rod(spec(n), Attachment::world_joint(joint))],
        Some(Vec3::new(0.0, 0.0, -9.81)),
        4,
    )
    .unwrap()
}

/// A smooth, curved, moving state (deterministic).
fn state(n: usize) -> (Vec<f64>, Vec<f64>) {
    let q = (0..n)
        .map(|i| if i % 6 < 3 { 1.5 } else { 0.01 } * (0.7 * i as f64 + 0.3).sin())
        .collect();
    let qd = (0..n).map(|i| (1.3 * i as f64).cos()).collect();
    (q, qd)
}

fn bench(c: &mut Criterion, group: &str, make: impl Fn(usize) -> Model, sizes: &[usize]) {
    let mut g = c.benchmark_group(group);
    for &n in sizes {
        let m = make(n);
        let mut data = Data::new(&m);
        let (q, qd) = state(m.n_dof());
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                forward_dynamics(&m, &mut data, 0.1, black_box(&q), black_box(&qd), None).unwrap()
                    [0]
            })
        });
    }
    g.finish();
}

fn bench_robots(c: &mut Criterion) {
    let sizes = [10usize, 40];
    bench(
        c,
        "forward_dynamics_tree",
        |n| on(n, Joint::revolute([0.0, 1.0, 0.0])),
        &sizes,
    );
    bench(
        c,
        "forward_dynamics_prescribed",
        |n| {
            on(
                n,
                Joint::prismatic([0.0, 0.0, 1.0]).with_prescribed(Prescribed::new(vec![
                    Curve::Sine {
                        amplitude: 0.01,
                        frequency: 2.0,
                        phase: 0.0,
                        offset: 0.0,
                    },
                ])),
            )
        },
        &sizes,
    );
    bench(
        c,
        "forward_dynamics_closed",
        |n| {
            on(n, Joint::fixed())
                .with_closures(vec![Closure::new(
                    "tip",
                    ClosureKind::Weld,
                    ClosureFrame::on("bench", None, Pose::identity()),
                    ClosureFrame::world(Pose::new(
                        nalgebra::Matrix3::identity(),
                        Vec3::new(LENGTH, 0.0, 0.0),
                    )),
                )])
                .unwrap()
        },
        &sizes,
    );
    // One factorization and solve of M + aK + bD on the tree (the implicit
    // integrators' Newton matrix), integrator-sized shifts.
    let mut g = c.benchmark_group("shifted_factor_solve_tree");
    for n in [10usize, 40, 160] {
        let m = on(n, Joint::revolute([0.0, 1.0, 0.0]));
        let mut solver = ShiftedSolver::new(&m);
        let (q, r) = state(m.n_dof());
        let mut x = r.clone();
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                solver.factor(&m, black_box(&q), 1e-6, 1e-3).unwrap();
                x.copy_from_slice(&r);
                solver.solve(&m, &mut x).unwrap();
                x[0]
            })
        });
    }
    g.finish();
    // The analytic pair ∂τ/∂q, ∂τ/∂q̇ on the tree (D76–D80); compare with
    // `id_derivatives/N` of the dynamics benches (the clamped rod).
    let mut g = c.benchmark_group("id_derivatives_tree");
    for n in [10usize, 40] {
        let m = on(n, Joint::revolute([0.0, 1.0, 0.0]));
        let mut work = IdDerivatives::new(&m);
        let (q, qd) = state(m.n_dof());
        let qdd = vec![0.5; m.n_dof()];
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                inverse_dynamics_derivatives(&m, &mut work, 0.1, black_box(&q), &qd, &qdd)
                    .unwrap()
                    .dtau_dq[(0, 0)]
            })
        });
    }
    g.finish();
    // The Jacobian ∂q̈/∂q, ∂q̈/∂q̇ of the pinned–pinned rod (CD1–CD4)
    // against forward differences of the constrained q̈.
    let pinned = |n: usize| {
        on(n, Joint::spherical())
            .with_closures(vec![Closure::new(
                "pin",
                ClosureKind::Ball,
                ClosureFrame::on("bench", None, Pose::identity()),
                ClosureFrame::world(Pose::new(
                    nalgebra::Matrix3::identity(),
                    Vec3::new(LENGTH, 0.0, 0.0),
                )),
            )])
            .unwrap()
    };
    let mut g = c.benchmark_group("closed_jacobian");
    for n in [10usize, 50] {
        let m = pinned(n);
        let mut data = Data::new(&m);
        let mut work = ClosedDerivatives::new(&m);
        let (q, qd) = state(m.n_dof());
        g.bench_with_input(BenchmarkId::new("analytic", n), &n, |b, _| {
            b.iter(|| {
                closed_dynamics_derivatives(&m, &mut data, &mut work, 0.1, black_box(&q), &qd, None)
                    .unwrap()
                    .dqdd_dq[(0, 0)]
            })
        });
    }
    for n in [10usize, 50] {
        let m = pinned(n);
        let mut data = Data::new(&m);
        let (q, qd) = state(m.n_dof());
        let nd = m.n_dof();
        let (mut qx, mut qdx) = (q.clone(), qd.clone());
        let mut jac = nalgebra::DMatrix::<f64>::zeros(nd, 2 * nd);
        g.bench_with_input(BenchmarkId::new("differences", n), &n, |b, _| {
            b.iter(|| {
                let a0 = forward_dynamics(&m, &mut data, 0.1, black_box(&q), &qd, None)
                    .unwrap()
                    .clone_owned();
                for j in 0..2 * nd {
                    let (x, k) = if j < nd {
                        (&mut qx, j)
                    } else {
                        (&mut qdx, j - nd)
                    };
                    let h = 1.5e-8 * x[k].abs().max(1.0);
                    x[k] += h;
                    let a = forward_dynamics(&m, &mut data, 0.1, &qx, &qdx, None).unwrap();
                    for i in 0..nd {
                        jac[(i, j)] = (a[i] - a0[i]) / h;
                    }
                    let x = if j < nd { &mut qx } else { &mut qdx };
                    x[k] = if j < nd { q[k] } else { qd[k] };
                }
                jac[(0, 0)]
            })
        });
    }
    g.finish();
    bench_closed_newton(c, &pinned);
}

/// One Newton iteration's pieces on the pinned rod (CD5–CD7), structured
/// and dense.
fn bench_closed_newton(c: &mut Criterion, pinned: &dyn Fn(usize) -> Model) {
    let mut g = c.benchmark_group("closed_newton");
    let (a, b) = (1e-6, 1e-3);
    for n in [10usize, 50] {
        let m = pinned(n);
        let (nd, rows) = (m.n_dof(), m.n_constraints());
        let mut data = Data::new(&m);
        let mut kkt = ClosedShiftedSolver::new(&m);
        let (q, qd) = state(nd);
        let qdd = vec![0.5; nd];
        g.bench_with_input(BenchmarkId::new("kkt_factor", n), &n, |bch, _| {
            bch.iter(|| kkt.factor_at(&m, 0.1, black_box(&q), a, b).unwrap())
        });
        let (mut r, mut cr) = (vec![0.0; nd], vec![0.0; rows]);
        g.bench_with_input(BenchmarkId::new("residuals", n), &n, |bch, _| {
            bch.iter(|| {
                kkt.residuals(
                    &m,
                    &mut data,
                    0.1,
                    black_box(&q),
                    &qd,
                    &qdd,
                    None,
                    &mut r,
                    &mut cr,
                )
                .unwrap();
                r[0]
            })
        });
        let mut x = r.clone();
        g.bench_with_input(BenchmarkId::new("kkt_solve", n), &n, |bch, _| {
            bch.iter(|| {
                x.copy_from_slice(&r);
                kkt.solve(&m, black_box(&mut x), &cr).unwrap();
                x[0]
            })
        });
        g.bench_with_input(BenchmarkId::new("constrained_forward", n), &n, |bch, _| {
            bch.iter(|| forward_dynamics(&m, &mut data, 0.1, black_box(&q), &qd, None).unwrap()[0])
        });
        // The dense path's factorization: an LU of an n×n iteration matrix
        // (ESDIRK's real one; Radau IIA factors a real and a complex one).
        let dense = nalgebra::DMatrix::<f64>::from_fn(nd, nd, |i, j| {
            if i == j {
                nd as f64
            } else {
                ((i * 7 + j * 3) % 11) as f64 / 11.0
            }
        });
        g.bench_with_input(BenchmarkId::new("dense_lu", n), &n, |bch, _| {
            bch.iter(|| black_box(dense.clone()).lu().determinant())
        });
    }
    g.finish();
}

criterion_group!(benches, bench_robots);
criterion_main!(benches);
