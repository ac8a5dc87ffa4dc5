//! Issue 24's step-size target (docs/performance.md, "A rod resting on a
//! table"): a free 20-piece rod lying on a table integrates with steps no
//! smaller than those of the same rod free in the air — the contact's
//! stiffness and damping are in the implicit integrator's Newton matrix
//! (docs/theory-contact.md CT17), so the contact frequency does not set
//! the step. Counted in accepted steps (the default integrator, ESDIRK,
//! and `Simulation`'s default tolerances), not in time.

use softrod::Simulation;
use softrod_dynamics::{Attachment, Joint, JointKind, Model, Rod};
use softrod_kinematics::Strain;
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::Material;
use softrod_mechanics::contact::{Obstacle, Shape};

const R: f64 = 0.01;

/// The depth at which each contact point of the rod carries its own
/// weight (docs/theory-contact.md CT2–CT3): `k = max(m g / (0.005 r),
/// m (v₀ / (0.1 r))²)` per point of mass `m`, `δ = m g / k + ε/2` on the
/// penalty's linear branch, `ε = 10⁻³ r` — the same for every point of a
/// uniform rod (`k ∝ m`).
fn rest_depth() -> f64 {
    let g = 9.81;
    let k_per_mass = (g / (0.005 * R)).max((1.0 / (0.1 * R)).powi(2));
    g / k_per_mass + 0.5e-3 * R
}

/// A free 20-piece rod, its centreline at `height`, on a table or not.
fn rod(table: bool, height: f64) -> Simulation {
    let rod = Rod::builder(0.5)
        .name("rod")
        .pieces(20)
        .strains([Strain::Ky, Strain::Kz])
        .base(Pose::new(Mat3::identity(), Vec3::new(0.0, 0.0, height)))
        .circle(R)
        .material(
            Material::builder()
                .density(1000.0)
                .young(1.0e6)
                .poisson(0.5)
                .build()
                .unwrap(),
        );
    let mut b = Model::builder()
        .rod_on(rod, Attachment::world_joint(Joint::new(JointKind::Free)))
        .gravity([0.0, 0.0, -9.81]);
    if table {
        b = b.obstacle(Obstacle::new(
            "table",
            Shape::Plane {
                point: Vec3::zeros(),
                normal: Vec3::z(),
            },
        ));
    }
    Simulation::new(b.build().unwrap())
}

/// Resting: the rod lies where it settles on the table (a first run of
/// 0.5 s from its rest depth, CT3, velocities then set to zero), against
/// the same rod straight and free (the kindest comparison: a rigid free
/// fall, smooth for any step).
#[test]
fn a_rod_resting_on_a_table_takes_no_smaller_steps_than_the_free_rod() {
    let duration = 0.5;
    let height = R - rest_depth();
    let free_stats = rod(false, height).simulate(duration).unwrap().summary.stats;
    let mut table = rod(true, height);
    let settled = table.simulate(duration).unwrap();
    let q = settled.q.last().unwrap().clone();
    let v = vec![0.0; q.len()];
    table.set_initial_state(q.as_slice(), &v).unwrap();
    let run = table.simulate(duration).unwrap();
    let table_stats = run.summary.stats;
    eprintln!("free: {free_stats:?}\ntable: {table_stats:?}");
    assert!(
        table_stats.steps <= free_stats.steps,
        "on the table {} steps, free {}",
        table_stats.steps,
        free_stats.steps
    );
    // And the structured Newton matrix, with the contact in it (CT17),
    // carries every step: no dense Jacobian, no rejected step (without the
    // contact in it, the first step's Newton iteration fails and falls back
    // to the dense exact Jacobian).
    assert_eq!(table_stats.jacobian_evaluations, 0, "{table_stats:?}");
    assert_eq!(table_stats.rejected_steps, 0, "{table_stats:?}");
    // It rests: the free joint's height stays within a hundredth of the
    // rest depth of where it was.
    let z = run.q.last().unwrap()[5];
    assert!(
        (z - q[5]).abs() < 0.01 * rest_depth(),
        "z = {z:e}, from {:e}",
        q[5]
    );
}
