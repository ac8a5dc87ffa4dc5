//! Rod–rod contact in runs (docs/theory-contact.md CT8–CT11) against
//! conservation laws: two free rods collide with no gravity and no other
//! load, so the total linear momentum stays what it was (the pair's forces
//! are equal and opposite) and the energy never grows (the law only
//! dissipates).

use softrod::{Flow, Observer, Sample, Settings, Simulation};
use softrod_dynamics::{Attachment, Joint, JointKind, Model, Rod};
use softrod_kinematics::Strain;
use softrod_lie::{Mat3, Pose, Vec3, Vec6, exp_twist};
use softrod_mechanics::Material;
use softrod_mechanics::contact::ContactSettings;
use softrod_scene::Integrator;

const R: f64 = 0.01;
const L: f64 = 0.2;

struct Keep(Vec<(f64, Vec<f64>, Vec<f64>)>);
impl Observer for Keep {
    fn sample(&mut self, s: Sample<'_>) -> Result<Flow, String> {
        self.0.push((s.t, s.q.to_vec(), s.qd.to_vec()));
        Ok(Flow::Continue)
    }
}

/// The centre of mass of a uniform rod: Simpson's rule over 41 points of
/// its centreline.
fn centre_of_mass(sim: &Simulation, rod: &str, q: &[f64]) -> Vec3 {
    let n = 40;
    let mut sum = Vec3::zeros();
    for i in 0..=n {
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        sum += sim
            .pose(rod, L * i as f64 / n as f64, q)
            .unwrap()
            .translation
            * w;
    }
    sum / (3.0 * n as f64)
}

/// Rod "upper" falls (no gravity: it moves at 0.5 m/s) across the resting
/// rod "lower", both free, half-elastic contact: the centre of mass of the
/// two moves on a straight line at a constant speed through the impact,
/// the energy never exceeds its start and some of it is lost, the rods
/// part, and the penetration stays under 10 % of the radius.
#[test]
fn colliding_free_rods_keep_their_momentum_and_gain_no_energy() {
    let material = Material::builder()
        .density(1000.0)
        .young(1.0e6)
        .poisson(0.5)
        .build()
        .unwrap();
    let rod = |name: &str, base: Pose| {
        Rod::builder(L)
            .name(name)
            .pieces(4)
            .strains([Strain::Ky, Strain::Kz])
            .base(base)
            .circle(R)
            .material(material)
    };
    let turn = exp_twist(
        1.0,
        &Vec6::new(0.0, 0.0, 0.5 * std::f64::consts::PI, 0.0, 0.0, 0.0),
    );
    let free = || Attachment::world_joint(Joint::new(JointKind::Free));
    let model = Model::builder()
        .rod_on(
            rod("lower", Pose::new(Mat3::identity(), Vec3::zeros())),
            free(),
        )
        .rod_on(
            rod(
                "upper",
                Pose::new(turn.rotation, Vec3::new(0.07, -0.1, 2.0 * R + 0.005)),
            ),
            free(),
        )
        .contact(ContactSettings {
            rods: true,
            restitution: 0.5,
            ..Default::default()
        })
        .build()
        .unwrap();
    let v0 = 0.5;
    let upper = model.elements()[1].joint_dofs.clone();
    let lower = model.elements()[0].joint_dofs.clone();
    let mut sim = Simulation::new(model);
    let n = sim.n_dof();
    let mut qd = vec![0.0; n];
    // Free joint: rotation coordinates first, then the translation.
    qd[upper.start + 5] = -v0;
    sim.set_initial_state(&vec![0.0; n], &qd).unwrap();
    sim.set_settings(Settings {
        integrator: Integrator::Esdirk,
        rtol: 1e-7,
        atol: 1e-9,
        output_every: Some(0.002),
        ..Settings::default()
    })
    .unwrap();
    let mut keep = Keep(Vec::new());
    sim.simulate_with(0.05, &mut keep).unwrap();
    let com = |sim: &Simulation, q: &[f64]| {
        0.5 * (centre_of_mass(sim, "lower", q) + centre_of_mass(sim, "upper", q))
    };
    let (q0, qd0) = (keep.0[0].1.clone(), keep.0[0].2.clone());
    let c0 = com(&sim, &q0);
    let velocity = Vec3::new(0.0, 0.0, -0.5 * v0);
    let e = |sim: &mut Simulation, q: &[f64], qd: &[f64]| {
        let e = sim.energies(q, qd).unwrap();
        e.kinetic + e.elastic
    };
    let e0 = e(&mut sim, &q0, &qd0);
    let mut touched = false;
    let mut deepest: f64 = 0.0;
    let mut worst_drift: f64 = 0.0;
    for (t, q, qd) in &keep.0 {
        let drift = (com(&sim, q) - c0 - velocity * *t).norm();
        assert!(
            drift < 1e-6,
            "centre of mass off its line by {drift:.3e} m at t = {t}"
        );
        let et = e(&mut sim, q, qd);
        // Kinetic and elastic only: during the impact the penalty holds the
        // rest, so this sum is below the total; the allowance is the
        // integration error of the run's tolerances (rtol 1e-7 over ~50
        // steps through the stiff contact).
        assert!(
            et <= e0 * (1.0 + 1e-5),
            "energy gained at t = {t}: {et} > {e0}"
        );
        worst_drift = worst_drift.max(drift);
        let contacts = sim.model().contacts(*t, q, qd).unwrap();
        touched |= !contacts.is_empty();
        deepest = deepest.max(sim.model().max_penetration(*t, q).unwrap());
    }
    assert!(touched, "the rods met");
    let (_, q, qd) = keep.0.last().unwrap();
    let end = e(&mut sim, q, qd);
    eprintln!(
        "energy {e0:.6e} → {end:.6e} J, deepest {deepest:.3e} m, centre of mass drift {worst_drift:.3e} m"
    );
    assert!(end < 0.95 * e0, "the half-elastic impact lost energy");
    assert!(
        qd[upper.start + 5] > qd[lower.start + 5],
        "the rods part: {} vs {}",
        qd[upper.start + 5],
        qd[lower.start + 5]
    );
    assert!(deepest < 0.1 * R, "{deepest}");
}
