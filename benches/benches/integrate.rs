//! Criterion benches of the integrators on the rod scenes of issue 13
//! (`softrod_benches::rod_scenes`):
//!
//! * `implicit_step/{esdirk,imex}/N`: ten implicit steps of `h = 1e-4` from
//!   a moving state of the 3-D release with all six strains on N = 10, 100,
//!   1000 pieces — ESDIRK4(3)6L\[2\]SA with its structured Newton matrix,
//!   and the linearly implicit generalized-α — throughput in steps: the
//!   cost of one step, which must grow linearly in N;
//! * `release/…`: whole runs with the recommended setting
//!   ([`Recommended::tolerance`]) on the full-size scenes the default must
//!   never fail on, at the loosest and tightest rtol of issue 13 and at the
//!   rtol that meets each accuracy target (planar 8-piece release ≤ 1e-5 m
//!   over 1 s at rtol 1e-5, 3-D 32-piece release ≤ 1e-4 m at the default
//!   1e-3, the same at rtol 1e-6), the undamped steel wire, and 0.01 s of
//!   the 500-piece release at the default. The accuracies are measured by
//!   `scripts/integrator_defaults.py --rtol-only` (docs/performance.md).
//!
//! `cargo bench -p softrod-benches --bench integrate -- --warm-up-time 1 --measurement-time 5`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use nalgebra::DVector;
use softrod_benches::rod_scenes::{planar_release, release_3d, steel_wire};
use softrod_dynamics::Model;
use softrod_integrate::{NoHooks, Options, Recommended, RodSystem, integrate_second_order};

/// The state after 5 ms of the release (the rod moving, the fast modes
/// rung up), by the recommended setting at rtol 1e-6.
fn moving_state(model: &Model) -> (DVector<f64>, DVector<f64>) {
    let r = Recommended::tolerance(1e-6);
    let mut sys = RodSystem::new(model.clone());
    r.configure(&mut sys);
    let n = model.n_dof();
    let z = DVector::zeros(n);
    let sol = integrate_second_order(
        &mut sys,
        r.integrator,
        (0.0, 5e-3),
        &z,
        &z,
        &r.options,
        &mut NoHooks,
    )
    .unwrap();
    let y = sol.y_final;
    (y.rows(0, n).into_owned(), y.rows(n, n).into_owned())
}

const STEPS: usize = 10;
const H: f64 = 1e-4;

fn bench_step(c: &mut Criterion) {
    let mut g = c.benchmark_group("implicit_step");
    g.throughput(Throughput::Elements(STEPS as u64));
    for pieces in [10usize, 100, 1000] {
        let model = release_3d(pieces);
        let (q0, v0) = moving_state(&model);
        for (name, setting) in [
            (
                "esdirk",
                Recommended {
                    options: Options {
                        step: softrod_integrate::StepControl::Fixed(H),
                        ..Recommended::tolerance(1e-6).options
                    },
                    ..Recommended::tolerance(1e-6)
                },
            ),
            ("imex", Recommended::fixed_step(H)),
        ] {
            let mut sys = RodSystem::new(model.clone());
            setting.configure(&mut sys);
            g.bench_with_input(BenchmarkId::new(name, pieces), &setting, |b, s| {
                b.iter(|| {
                    integrate_second_order(
                        &mut sys,
                        s.integrator,
                        (0.0, STEPS as f64 * H),
                        &q0,
                        &v0,
                        &s.options,
                        &mut NoHooks,
                    )
                    .unwrap()
                })
            });
        }
    }
    g.finish();
}

fn bench_release(c: &mut Criterion) {
    let mut g = c.benchmark_group("release");
    g.sample_size(10);
    let cases: [(&str, Model, f64, f64); 9] = [
        ("planar_8_1s_rtol1e-3", planar_release(), 1.0, 1e-3),
        ("planar_8_1s_rtol1e-5", planar_release(), 1.0, 1e-5),
        ("planar_8_1s_rtol1e-8", planar_release(), 1.0, 1e-8),
        ("3d_32_1s_rtol1e-3", release_3d(32), 1.0, 1e-3),
        ("3d_32_1s_rtol1e-6", release_3d(32), 1.0, 1e-6),
        ("3d_32_1s_rtol1e-8", release_3d(32), 1.0, 1e-8),
        ("steel_wire_10_1s_rtol1e-3", steel_wire(10), 1.0, 1e-3),
        ("steel_wire_10_1s_rtol1e-8", steel_wire(10), 1.0, 1e-8),
        ("3d_500_0.01s_rtol1e-3", release_3d(500), 0.01, 1e-3),
    ];
    for (name, model, t1, rtol) in cases {
        let r = Recommended::tolerance(rtol);
        let z = DVector::zeros(model.n_dof());
        let mut sys = RodSystem::new(model);
        r.configure(&mut sys);
        g.bench_function(name, |b| {
            b.iter(|| {
                integrate_second_order(
                    &mut sys,
                    r.integrator,
                    (0.0, t1),
                    &z,
                    &z,
                    &r.options,
                    &mut NoHooks,
                )
                .unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_step, bench_release);
criterion_main!(benches);
