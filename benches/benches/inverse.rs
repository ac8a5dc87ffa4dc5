//! Criterion benches of inverse statics (`softrod::control`,
//! docs/theory-control.md IS1–IS12) on the 3-cable, 10-piece arm of
//! `examples/cable_arm_inverse.toml` (kx, ky, kz, qx: 40 DoF, gravity,
//! bounds 30 N): one tip target solved warm-started from the solution of a
//! target 1 mm away (`warm_1mm`), a tracking sequence of 100 targets 0.13 mm
//! apart on a circle, each warm-started from the last (`sequence_100`,
//! time per target = time / 100), and the same target solved cold, from
//! zero tensions and the straight arm (`cold`). The same arm with its tip
//! on a slider along the world x axis (a closed model, IS8–IS10), one
//! position target at mid-length (from a forward solve at 12, 3, 7 N):
//! `closed_warm_1mm` and `closed_cold`.
//!
//! Regenerate (numbers in docs/performance.md, section "Inverse statics"):
//! `cargo bench -p softrod-benches --bench inverse -- --warm-up-time 1 --measurement-time 3`

use criterion::{Criterion, criterion_group, criterion_main};
use softrod::Simulation;
use softrod::control::{Actuation, ActuationOptions, Target};
use std::hint::black_box;

fn arm() -> (Simulation, Vec<f64>, [f64; 3]) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/cable_arm_inverse.toml"
    );
    let (sim, scene, _) = Simulation::from_scene_file(path).unwrap();
    let bounds = scene.max_tensions().iter().map(|b| b.1).collect();
    let p = scene.targets[0].position.unwrap();
    (sim, bounds, [p.x, p.y, p.z])
}

fn solve(sim: &mut Simulation, p: [f64; 3], options: &ActuationOptions) -> Actuation {
    let a = sim
        .solve_actuation(&[Target::position(0, 0.5, p)], options)
        .unwrap();
    assert!(a.converged && a.reached, "{}", a.message);
    a
}

fn inverse(c: &mut Criterion) {
    let (mut sim, bounds, p0) = arm();
    let options = ActuationOptions {
        max_tension: bounds,
        ..ActuationOptions::default()
    };
    let first = solve(&mut sim, p0, &options);
    let p1 = [p0[0], p0[1] + 0.001, p0[2]];
    let warm = options.clone().warm_start(&first);

    let mut g = c.benchmark_group("inverse");
    g.bench_function("warm_1mm", |b| {
        b.iter(|| black_box(solve(&mut sim, black_box(p1), &warm)))
    });
    // 100 targets 0.13 mm apart on a circle of radius 2 mm in the y-z plane,
    // below the first (above it cable 0 would need more than its 30 N).
    let radius = 0.002;
    let circle: Vec<[f64; 3]> = (0..100)
        .map(|k| {
            let a = 2.0 * std::f64::consts::PI * k as f64 / 100.0;
            [
                p0[0],
                p0[1] + radius * a.sin(),
                p0[2] - radius * (1.0 - a.cos()),
            ]
        })
        .collect();
    g.bench_function("sequence_100", |b| {
        b.iter(|| {
            let mut prev = first.clone();
            for p in &circle {
                prev = solve(&mut sim, *p, &options.clone().warm_start(&prev));
            }
            black_box(prev)
        })
    });
    g.bench_function("cold", |b| {
        b.iter(|| black_box(solve(&mut sim, black_box(p1), &options)))
    });
    // The closed arm: the example with its tip on a slider along x.
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/cable_arm_inverse.toml"
    );
    let text = std::fs::read_to_string(path).unwrap()
        + "[[closure]]\ntype = \"slider\"\naxis = [1, 0, 0]\n\
           a = { element = \"arm\" }\nb = { element = \"world\" }\n";
    let (mut closed, _, _) = Simulation::from_toml(&text, "closed.toml").unwrap();
    closed.set_cable_tensions(Some(&[12.0, 3.0, 7.0])).unwrap();
    let q = closed.statics().unwrap().q;
    closed.set_cable_tensions(None).unwrap();
    let mid = closed.pose("arm", 0.25, q.as_slice()).unwrap().translation;
    let target = |p: [f64; 3]| [Target::position(0, 0.25, p)];
    let solve_closed = |sim: &mut Simulation, p: [f64; 3], o: &ActuationOptions| {
        let a = sim.solve_actuation(&target(p), o).unwrap();
        assert!(a.converged && a.reached, "{}", a.message);
        a
    };
    let m0 = [mid.x, mid.y, mid.z];
    let m1 = [mid.x, mid.y + 0.001, mid.z];
    let first = solve_closed(&mut closed, m0, &options);
    let warm = options.clone().warm_start(&first);
    g.bench_function("closed_warm_1mm", |b| {
        b.iter(|| black_box(solve_closed(&mut closed, black_box(m1), &warm)))
    });
    g.bench_function("closed_cold", |b| {
        b.iter(|| black_box(solve_closed(&mut closed, black_box(m1), &options)))
    });
    let (w, c) = (
        solve_closed(&mut closed, m1, &warm),
        solve_closed(&mut closed, m1, &options),
    );
    println!(
        "closed: warm {} Gauss-Newton / {} statics Newton, cold {} / {}",
        w.iterations, w.statics_iterations, c.iterations, c.statics_iterations
    );
    g.finish();
}

criterion_group!(benches, inverse);
criterion_main!(benches);
