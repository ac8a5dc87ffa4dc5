//! Criterion benches of the `softrod-dynamics` algorithms on a full Cosserat
//! rod: all six strains per piece, 4 Gauss points per piece, gravity,
//! elasticity and Kelvin–Voigt damping, at a seeded, curved, moving state.
//!
//! Regenerate (numbers in docs/performance.md, section "softrod-dynamics"):
//! `cargo bench -p softrod-benches --bench dynamics -- --warm-up-time 1 --measurement-time 2`
//! (`id_vjp`: the adjoint's products of the inverse-dynamics derivatives,
//! dense against O(N), docs/performance.md "Trajectory gradients")
//! (`rod_contact`: two crossing rods with rod–rod contact;
//! `contact_derivatives`: an arm on a joint lying on a table;
//! docs/theory-contact.md).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use softrod_dynamics::{
    Data, FdDerivatives, Forces, IdDerivatives, Model, Rod, ShiftedSolver, forward_dynamics,
    forward_dynamics_derivatives, inverse_dynamics, inverse_dynamics_derivatives,
    inverse_dynamics_linearization_with, inverse_dynamics_vjp, mass_matrix,
};
use softrod_kinematics::{Basis, RodGeometry, Strain, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{Material, RodProperties, Section};
use std::hint::black_box;

/// SplitMix64 in [−1, 1), seeded: reproducible states across runs.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// The rod of derivations §8(h) (L = 0.5, r = 0.01, ρ = 1000, E = 1e7,
/// G = E/3) with viscosity μ = 1 Pa·s, all six strains on each of `n` equal
/// pieces, gravity (0, 0, −9.81), 4 Gauss points per piece.
fn model(n: usize) -> Model {
    model_with(n, Basis::all())
}

/// [`model`] with the given basis on every piece.
fn model_with(n: usize, basis: Basis) -> Model {
    let length = 0.5;
    let rod = RodGeometry::uniform(length, n, basis, straight(), Pose::identity()).unwrap();
    let material = Material::builder()
        .density(1000.0)
        .young(1e7)
        .shear_modulus(1e7 / 3.0)
        .viscosity(1.0)
        .build()
        .unwrap();
    let body = RodProperties::new(Section::Circle { radius: 0.01 }, material, length).unwrap();
    let spec = Rod::new("bench", rod, body);
    let m = Model::new(vec![spec], Some(Vec3::new(0.0, 0.0, -9.81)), 4).unwrap();
    assert!(m.terms().iter().any(|t| t == "damping"));
    m
}

/// Seeded state: curvatures and torsion in ±2 rad/m, stretch and shears in
/// ±0.02, rates in ±1 /s, accelerations in ±10 /s² (per strain component).
fn state(n_dof: usize, seed: u64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut rng = Rng(seed);
    let q = (0..n_dof)
        .map(|i| if i % 6 < 3 { 2.0 } else { 0.02 } * rng.next())
        .collect();
    let qd = (0..n_dof).map(|_| rng.next()).collect();
    let qdd = (0..n_dof).map(|_| 10.0 * rng.next()).collect();
    (q, qd, qdd)
}

/// [`state`] for the planar basis `(ky, qx, qz)`: curvature in ±2 rad/m,
/// stretch and shear in ±0.02, rates in ±1 /s.
fn planar_state(n_dof: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = Rng(seed);
    let q = (0..n_dof)
        .map(|i| if i % 3 == 0 { 2.0 } else { 0.02 } * rng.next())
        .collect();
    let qd = (0..n_dof).map(|_| rng.next()).collect();
    (q, qd)
}

fn bench_dynamics(c: &mut Criterion) {
    let mut g = c.benchmark_group("forward_dynamics");
    for n in [1usize, 4, 10, 40, 100, 1000] {
        let m = model(n);
        let mut data = Data::new(&m);
        let (q, qd, _) = state(m.n_dof(), 42);
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                forward_dynamics(&m, &mut data, 0.0, black_box(&q), black_box(&qd), None).unwrap()
                    [0]
            })
        });
    }
    g.finish();

    // The planar rod (strains ky, qx, qz on every piece) beside the 3-D one
    // of the same size: the cost per evaluation of a planar scene, on the
    // planar path (docs/theory.md §13) and, for the A/B, on the general one.
    for (group, on) in [
        ("forward_dynamics_planar", true),
        ("forward_dynamics_planar_general_path", false),
    ] {
        let mut g = c.benchmark_group(group);
        for n in [8usize, 10, 100] {
            let m = model_with(
                n,
                Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap(),
            )
            .with_planar_path(on);
            let mut data = Data::new(&m);
            let (q, qd) = planar_state(m.n_dof(), 42);
            g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                b.iter(|| {
                    forward_dynamics(&m, &mut data, 0.0, black_box(&q), black_box(&qd), None)
                        .unwrap()[0]
                })
            });
        }
        g.finish();
    }
    for (group, on) in [
        ("inverse_dynamics_planar", true),
        ("inverse_dynamics_planar_general_path", false),
    ] {
        let mut g = c.benchmark_group(group);
        for n in [10usize, 100] {
            let m = model_with(
                n,
                Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap(),
            )
            .with_planar_path(on);
            let mut data = Data::new(&m);
            let (q, qd) = planar_state(m.n_dof(), 42);
            let qdd = vec![0.5; m.n_dof()];
            g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                b.iter(|| {
                    inverse_dynamics(&m, &mut data, 0.0, black_box(&q), black_box(&qd), &qdd)
                        .unwrap()[0]
                })
            });
        }
        g.finish();
    }

    let mut g = c.benchmark_group("inverse_dynamics");
    for n in [1usize, 4, 10, 40, 100, 1000] {
        let m = model(n);
        let mut data = Data::new(&m);
        let (q, qd, qdd) = state(m.n_dof(), 42);
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                inverse_dynamics(
                    &m,
                    &mut data,
                    0.0,
                    black_box(&q),
                    black_box(&qd),
                    black_box(&qdd),
                )
                .unwrap()[0]
            })
        });
    }
    g.finish();

    // One Newton matrix of an implicit step: factor S = M + aK + bD and
    // solve once (a, b of a step of ~1e-3 s), O(N).
    let mut g = c.benchmark_group("shifted_factor_solve");
    for n in [10usize, 100, 1000] {
        let m = model(n);
        let mut solver = ShiftedSolver::new(&m);
        let (q, qd, _) = state(m.n_dof(), 42);
        let mut x = qd.clone();
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                solver.factor(&m, black_box(&q), 2.5e-7, 5e-4).unwrap();
                x.copy_from_slice(&qd);
                solver.solve(&m, &mut x).unwrap();
                x[0]
            })
        });
    }
    g.finish();

    // The analytic pair ∂τ/∂q, ∂τ/∂q̇ (docs/theory-derivatives.md) beside
    // what central differences cost: 4·n_dof inverse dynamics.
    let mut g = c.benchmark_group("id_derivatives");
    for n in [10usize, 100] {
        let m = model(n);
        let mut work = IdDerivatives::new(&m);
        let (q, qd, qdd) = state(m.n_dof(), 42);
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                inverse_dynamics_derivatives(&m, &mut work, 0.0, black_box(&q), &qd, &qdd)
                    .unwrap()
                    .dtau_dq[(0, 0)]
            })
        });
    }
    g.finish();

    // What the adjoint needs of them, u^T ∂τ/∂q and u^T ∂τ/∂q̇
    // (docs/theory-derivatives.md D81–D83): the dense pair then two
    // transposed products, against the O(N) linearization then its
    // products; and one more product on a kept linearization (what a GMRES
    // iteration adds).
    let mut g = c.benchmark_group("id_vjp");
    for n in [5usize, 20, 100] {
        let m = model(n);
        let nd = m.n_dof();
        let (q, qd, qdd) = state(nd, 42);
        let u = nalgebra::DVector::from_vec(state(nd, 7).0);
        let mut dense = IdDerivatives::new(&m);
        let (mut pq, mut pv) = (nalgebra::DVector::zeros(nd), nalgebra::DVector::zeros(nd));
        g.bench_with_input(BenchmarkId::new("dense", n), &n, |b, _| {
            b.iter(|| {
                let d = inverse_dynamics_derivatives(&m, &mut dense, 0.0, black_box(&q), &qd, &qdd)
                    .unwrap();
                pq.gemv_tr(1.0, &d.dtau_dq, &u, 0.0);
                pv.gemv_tr(1.0, &d.dtau_dqd, &u, 0.0);
                pq[0] + pv[0]
            })
        });
        let mut work = IdDerivatives::for_products(&m);
        let (mut oq, mut ov) = (vec![0.0; nd], vec![0.0; nd]);
        g.bench_with_input(BenchmarkId::new("linearization_vjp", n), &n, |b, _| {
            b.iter(|| {
                inverse_dynamics_linearization_with(
                    &m,
                    &mut work,
                    Forces::ALL,
                    0.0,
                    black_box(&q),
                    &qd,
                    &qdd,
                )
                .unwrap();
                inverse_dynamics_vjp(&m, &mut work, u.as_slice(), &mut oq, &mut ov).unwrap();
                oq[0] + ov[0]
            })
        });
        g.bench_with_input(BenchmarkId::new("vjp_only", n), &n, |b, _| {
            b.iter(|| {
                inverse_dynamics_vjp(&m, &mut work, black_box(u.as_slice()), &mut oq, &mut ov)
                    .unwrap();
                oq[0] + ov[0]
            })
        });
    }
    g.finish();

    let mut g = c.benchmark_group("id_derivatives_central_differences");
    g.sample_size(10);
    for n in [10usize, 40] {
        let m = model(n);
        let mut data = Data::new(&m);
        let (q, qd, qdd) = state(m.n_dof(), 42);
        let (mut qp, mut qdp) = (q.clone(), qd.clone());
        let mut col = vec![0.0; m.n_dof()];
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                for j in 0..m.n_dof() {
                    for which in 0..2 {
                        let x = if which == 0 { &mut qp } else { &mut qdp };
                        let x0 = x[j];
                        let h = 6e-6 * x0.abs().max(1.0);
                        x[j] = x0 + h;
                        let plus = inverse_dynamics(&m, &mut data, 0.0, &qp, &qdp, &qdd).unwrap();
                        col.copy_from_slice(plus.as_slice());
                        let x = if which == 0 { &mut qp } else { &mut qdp };
                        x[j] = x0 - h;
                        let minus = inverse_dynamics(&m, &mut data, 0.0, &qp, &qdp, &qdd).unwrap();
                        for (c, mi) in col.iter_mut().zip(minus.iter()) {
                            *c = (*c - mi) / (2.0 * h);
                        }
                        let x = if which == 0 { &mut qp } else { &mut qdp };
                        x[j] = x0;
                    }
                }
                black_box(col[0])
            })
        });
    }
    g.finish();

    let mut g = c.benchmark_group("forward_dynamics_derivatives");
    for n in [10usize, 100] {
        let m = model(n);
        let mut data = Data::new(&m);
        let mut work = FdDerivatives::new(&m);
        let (q, qd, _) = state(m.n_dof(), 42);
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                forward_dynamics_derivatives(
                    &m,
                    &mut data,
                    &mut work,
                    0.0,
                    black_box(&q),
                    &qd,
                    None,
                )
                .unwrap()
                .dqdd_dq[(0, 0)]
            })
        });
    }
    g.finish();

    let mut g = c.benchmark_group("mass_matrix");
    for n in [10usize, 40, 100] {
        let m = model(n);
        let mut data = Data::new(&m);
        let (q, _, _) = state(m.n_dof(), 42);
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| mass_matrix(&m, &mut data, black_box(&q)).unwrap()[(0, 0)])
        });
    }
    g.finish();
}

/// Two 20-piece rods (Ky, Kz; r = 1 cm, L = 0.4 m) crossing at 1.2 rad,
/// pressed together 0.5 mm at the start, at rest: the forward dynamics
/// with `[contact] rods` (broadphase, closest points, the pair's force and
/// its generalized force, docs/theory-contact.md CT7–CT8) against the same
/// model without contact, and the contact Jacobian (central differences of
/// the pair, CT11) within the forward-dynamics derivatives.
fn bench_rod_contact(c: &mut Criterion) {
    use softrod_lie::{Mat3, exp_twist};
    use softrod_mechanics::contact::ContactSettings;
    let rod = |name: &str, base: Pose| {
        let material = Material::builder()
            .density(1000.0)
            .young(1e6)
            .poisson(0.5)
            .build()
            .unwrap();
        Rod::builder(0.4)
            .name(name)
            .pieces(20)
            .strains([Strain::Ky, Strain::Kz])
            .base(base)
            .circle(0.01)
            .material(material)
    };
    let turn = exp_twist(1.0, &softrod_lie::Vec6::new(0.0, 0.0, 1.2, 0.0, 0.0, 0.0)).rotation;
    let build = |contact: bool| {
        let m = Model::builder()
            .rod(rod("a", Pose::new(Mat3::identity(), Vec3::zeros())))
            .rod(rod("b", Pose::new(turn, Vec3::new(0.2, -0.15, 0.0195))))
            .gravity([0.0, 0.0, -9.81])
            .build()
            .unwrap();
        if contact {
            m.with_contact(
                Vec::new(),
                ContactSettings {
                    rods: true,
                    ..Default::default()
                },
            )
            .unwrap()
        } else {
            m
        }
    };
    let mut g = c.benchmark_group("rod_contact");
    for (name, contact) in [
        ("forward_dynamics_without", false),
        ("forward_dynamics", true),
    ] {
        let m = build(contact);
        let mut data = Data::new(&m);
        let q = vec![0.0; m.n_dof()];
        g.bench_function(name, |b| {
            b.iter(|| forward_dynamics(&m, &mut data, 0.0, black_box(&q), &q, None).unwrap()[0])
        });
    }
    for (name, contact) in [
        ("forward_dynamics_derivatives_without", false),
        ("forward_dynamics_derivatives", true),
    ] {
        let m = build(contact);
        let mut data = Data::new(&m);
        let mut work = FdDerivatives::new(&m);
        let q = vec![0.0; m.n_dof()];
        assert_eq!(m.contacts(0.0, &q, &q).unwrap().len(), usize::from(contact));
        g.bench_function(name, |b| {
            b.iter(|| {
                forward_dynamics_derivatives(&m, &mut data, &mut work, 0.0, black_box(&q), &q, None)
                    .unwrap()
                    .dqdd_dq[(0, 0)]
            })
        });
    }
    g.finish();
}

/// A 20-piece arm (Ky, Kz, 40 coordinates) on a revolute joint, lying on a
/// table 0.2 mm into it along its whole length (41 contact points touching,
/// friction 0.5, anchors committed: sticking): the forward-dynamics
/// derivatives with the contact's linearization on a tree
/// (docs/theory-contact.md CT12) against the same arm without the table.
fn bench_contact_derivatives(c: &mut Criterion) {
    use softrod_dynamics::{Attachment, Joint, JointKind, commit_contact};
    use softrod_lie::Mat3;
    use softrod_mechanics::contact::{ContactSettings, Obstacle, Shape};
    let build = |table: bool| {
        let material = Material::builder()
            .density(1000.0)
            .young(1e6)
            .poisson(0.5)
            .build()
            .unwrap();
        let arm = Rod::builder(0.4)
            .name("arm")
            .pieces(20)
            .strains([Strain::Ky, Strain::Kz])
            .base(Pose::new(Mat3::identity(), Vec3::new(0.0, 0.0, 0.0098)))
            .circle(0.01)
            .material(material);
        let m = Model::builder()
            .rod_on(
                arm,
                Attachment::world_joint(Joint::new(JointKind::Revolute { axis: Vec3::y() })),
            )
            .gravity([0.0, 0.0, -9.81])
            .build()
            .unwrap();
        if table {
            let plane = Shape::Plane {
                point: Vec3::zeros(),
                normal: Vec3::z(),
            };
            m.with_contact(
                vec![Obstacle::new("table", plane).friction(0.5)],
                ContactSettings::default(),
            )
            .unwrap()
        } else {
            m
        }
    };
    let mut g = c.benchmark_group("contact_derivatives");
    for (name, table) in [("arm_on_table_without", false), ("arm_on_table", true)] {
        let m = build(table);
        let mut data = Data::new(&m);
        let q = vec![0.0; m.n_dof()];
        if table {
            commit_contact(&m, &mut data, 0.0, &q, &q).unwrap();
            assert_eq!(m.contacts_with(&mut data, 0.0, &q, &q).unwrap().len(), 41);
        }
        let mut work = FdDerivatives::new(&m);
        g.bench_function(name, |b| {
            b.iter(|| {
                forward_dynamics_derivatives(&m, &mut data, &mut work, 0.0, black_box(&q), &q, None)
                    .unwrap()
                    .dqdd_dq[(0, 0)]
            })
        });
    }
    g.finish();
}

criterion_group!(
    benches,
    bench_dynamics,
    bench_rod_contact,
    bench_contact_derivatives
);
criterion_main!(benches);
