//! The recorder against the facade's own queries, computed by other paths:
//! a rod sampled along its arcs piece by piece (`poses_along`) against
//! `pose` at each abscissa (`locate` + one arc), tips and bodies against
//! `tip_pose` and `body_poses`, energies and drive forces against the
//! evaluations at the same time, and the cable power against
//! `Tᵀ(B q̇)` from the actuation matrix.

use softrod::Simulation;
use softrod::dynamics::Data;
use softrod::record::{Columns, Recorder, RodSampling};

fn example(name: &str) -> Simulation {
    let path = format!("{}/../../examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    Simulation::from_scene_file(path).unwrap().0
}

/// A smooth, non-trivial state of `n` coordinates.
fn state(n: usize) -> (Vec<f64>, Vec<f64>) {
    let q = (0..n).map(|i| 0.2 * (0.7 * i as f64 + 0.1).sin()).collect();
    let qd = (0..n).map(|i| 0.3 * (1.3 * i as f64 + 0.2).cos()).collect();
    (q, qd)
}

/// Poses agree to rounding: the two paths compose the same arcs in a
/// different order.
const POSE_TOL: f64 = 1e-12;

#[test]
fn records_agree_with_the_simulation_queries() {
    for name in [
        "cantilever_gravity",
        "cable_planar_arm",
        "oscillating_base",
        "arm_with_payload",
        "three_arm_gripper",
    ] {
        let mut sim = example(name);
        let model = sim.model().clone();
        let (q, qd) = state(model.n_dof());
        let t = 0.0625;
        let mut rec = Recorder::with_sampling(&model, RodSampling::of_model(&model, Some(3)));
        let mut data = Data::new(&model);
        model.set_time(&mut data, t);
        let r = rec.record(&model, &mut data, t, &q, &qd).unwrap().clone();
        sim.set_time(t);
        for (i, rm) in model.rods().iter().enumerate() {
            let s = &r.poses.sampling(i).s;
            assert_eq!(r.poses.samples(i).len(), s.len());
            for (g, &x) in r.poses.samples(i).iter().zip(s) {
                let p = sim.pose(i, x, &q).unwrap();
                let d = (g.translation - p.translation).norm() + (g.rotation - p.rotation).norm();
                assert!(
                    d < POSE_TOL,
                    "{name}: rod {} at s = {x}: {d:e}",
                    rm.spec.name
                );
            }
            assert_eq!(*r.poses.tip(i), sim.tip_pose(i, &q).unwrap(), "{name}");
        }
        assert_eq!(r.poses.bodies(), sim.body_poses(&q).unwrap().as_slice());
        assert_eq!(r.energies, sim.energies(&q, &qd).unwrap(), "{name}");
        let drive = sim.prescribed_forces(t, &q, &qd, None).unwrap();
        assert_eq!(r.prescribed_force, drive.as_slice(), "{name}");
        let b = sim.actuation_matrix(&q).unwrap();
        for (c, (&tension, &power)) in r.tensions.iter().zip(&r.cable_power).enumerate() {
            let rate: f64 = (0..q.len()).map(|k| b[(k, c)] * qd[k]).sum();
            assert!(
                (power - tension * rate).abs() <= 1e-12 * (tension * rate).abs().max(1e-300),
                "{name}: cable {c}"
            );
        }
        let mut row = Vec::new();
        Columns::of(&model).push_row(r.row(), &mut row);
        assert_eq!(row.len(), Columns::of(&model).width());
    }
}

/// Non-finite states are refused with the column that holds them.
#[test]
fn non_finite_states_are_refused_by_name() {
    let sim = example("cantilever_gravity");
    let model = sim.model().clone();
    let (mut q, qd) = state(model.n_dof());
    q[3] = f64::NAN;
    let mut rec = Recorder::new(&model);
    let mut data = Data::new(&model);
    let e = rec.record(&model, &mut data, 0.5, &q, &qd).unwrap_err();
    assert_eq!(e.to_string(), "non-finite q3 at t = 5e-1; output stopped");
}
