//! Contact in runs (docs/theory-contact.md) against independent
//! references: free fall before impact, no energy gained at impact, rest
//! at centreline height r; a rod on an incline sticks below the friction
//! angle (no creep) and slides with g(sin α − μ cos α) above it.

mod common;

use common::{G, Keep, L, R, across_incline, centre, free_rod_model, path_along, plane};

use softrod::{Settings, Simulation};
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::contact::{Obstacle, Shape};
use softrod_scene::Integrator;

/// A free rod (6-dof joint to the world) whose base pose is `base`, with
/// `obstacle`, gravity −z.
fn free_rod(base: Pose, obstacle: Obstacle, energy_tolerance: f64) -> Simulation {
    let model = free_rod_model(base, obstacle, &[], 0.0);
    let mut sim = Simulation::new(model);
    let settings = Settings {
        integrator: Integrator::Esdirk,
        rtol: 1e-6,
        atol: 1e-8,
        output_every: Some(0.01),
        energy_tolerance,
        ..Settings::default()
    };
    sim.set_settings(settings).unwrap();
    sim
}

/// Dropped flat from 5 cm onto a frictionless, inelastic table: free fall
/// (energy conserved, `z = z₀ − ½gt²`) until the surface meets the table,
/// never more energy than at the start, and at rest on the table at
/// centreline height `r` less at most 1 % of `r`.
#[test]
fn a_falling_rod_lands_and_rests_at_its_radius() {
    let h = 0.05;
    let base = Pose::new(Mat3::identity(), Vec3::new(0.0, 0.0, R + h));
    let table = Obstacle::new(
        "table",
        Shape::Plane {
            point: Vec3::zeros(),
            normal: Vec3::z(),
        },
    );
    let mut sim = free_rod(base, table, Settings::default().energy_tolerance);
    let mut keep = Keep(Vec::new());
    sim.simulate_with(0.5, &mut keep).unwrap();
    let (q0, qd0) = (&keep.0[0].1, &keep.0[0].2);
    let e0 = sim.energies(q0, qd0).unwrap();
    let e0 = e0.kinetic + e0.elastic + e0.gravitational;
    let mass = 1000.0 * std::f64::consts::PI * R * R * L;
    let impact = (2.0 * h / G).sqrt();
    for (t, q, qd) in &keep.0 {
        let e = sim.energies(q, qd).unwrap();
        let e = e.kinetic + e.elastic + e.gravitational;
        // Integration error at rtol 1e-6 on the energy m g h in play.
        assert!(e - e0 < 1e-5 * mass * G * h, "energy gained at t = {t}");
        if *t < impact - 0.005 {
            let z = centre(&sim, q).z;
            let want = R + h - 0.5 * G * t * t;
            assert!(
                (z - want).abs() < 1e-6,
                "free fall at t = {t}: {z} vs {want}"
            );
            assert!((e - e0).abs() < 1e-6 * mass * G * h, "free fall energy");
        }
    }
    let (_, q, qd) = keep.0.last().unwrap();
    for s in [0.0, 0.25 * L, 0.5 * L, 0.75 * L, L] {
        let z = sim.pose("rod", s, q).unwrap().translation.z;
        assert!(z <= R && z > 0.99 * R, "rest height {z} at s = {s}");
    }
    let speed = qd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(speed < 1e-3, "at rest: {speed}");
    let pen = sim.model().max_penetration(0.5, q).unwrap();
    assert!(pen < 0.01 * R, "{pen}");
}

/// A rod lying across an incline of angle `alpha` with friction `mu`:
/// the distance its centre travels down the slope at the output times,
/// and the run's energy balance (friction's dissipation counted as work).
fn incline(alpha: f64, mu: f64, duration: f64) -> (Vec<(f64, f64)>, softrod::EnergyBalance) {
    let (base, n, down) = across_incline(alpha);
    let slope = plane("slope", Vec3::zeros(), n).friction(mu);
    // The watch on, with room to report rather than stop.
    let mut sim = free_rod(base, slope, 1.0);
    path_along(&mut sim, duration, down)
}

#[test]
fn below_the_friction_angle_a_rod_sticks_without_creep() {
    // tan 20° = 0.364 < μ = 0.5.
    let (path, _) = incline(20f64.to_radians(), 0.5, 0.5);
    let at = |t: f64| path.iter().find(|(s, _)| (s - t).abs() < 1e-9).unwrap().1;
    // Elastic pre-slip bound (CT5): μ f_n / k ≤ μ · 1 % of r.
    assert!(at(0.5).abs() < 0.01 * R, "moved {}", at(0.5));
    // No creep: nothing more after the first quarter second.
    assert!(
        (at(0.5) - at(0.25)).abs() < 1e-4 * R,
        "crept {}",
        at(0.5) - at(0.25)
    );
}

#[test]
fn above_the_friction_angle_a_rod_slides_at_coulombs_rate() {
    let (alpha, mu) = (30f64.to_radians(), 0.2);
    let (path, energy) = incline(alpha, mu, 0.3);
    let at = |t: f64| path.iter().find(|(s, _)| (s - t).abs() < 1e-9).unwrap().1;
    let dt = 0.1;
    let a = (at(0.3) - 2.0 * at(0.2) + at(0.1)) / (dt * dt);
    let want = G * (alpha.sin() - mu * alpha.cos());
    let rel = (a - want).abs() / want;
    eprintln!("a = {a:.5} m/s², Coulomb {want:.5} ({rel:.2e})");
    assert!(rel < 1e-2, "{a} vs {want}");
    // The energy the slide loses is friction's work μ m g cos α · d: the
    // run's balance counts it (the watch evaluates friction with the run's
    // anchors; with a fresh workspace's it missed all of it).
    let m = 1000.0 * std::f64::consts::PI * R * R * L;
    let d = at(0.3);
    let friction_work = mu * m * G * alpha.cos() * d;
    eprintln!(
        "energy: change {:.4e} J, work {:.4e} J (friction μ m g cos α d = {friction_work:.4e} J), \
         relative error {:.2e}",
        energy.change, energy.work, energy.relative
    );
    assert!(
        (energy.work + friction_work).abs() < 1e-2 * friction_work,
        "work {} vs −{friction_work}",
        energy.work
    );
    assert!(energy.relative < 1e-3, "balance {:.3e}", energy.relative);
}

/// `Simulation::simulate` keeps each sample's contacts (what the recorder
/// gives `contacts.csv`): on a frictionless table, the contacts of each
/// sample are those the model computes at that state (their forces with
/// the run's contact stiffness, CT15), and the trajectory's
/// `max_penetration` and `max_contacts` are those of its samples.
#[test]
fn a_trajectory_keeps_the_contacts_of_its_samples() {
    let base = Pose::new(Mat3::identity(), Vec3::new(0.0, 0.0, R + 0.002));
    let table = Obstacle::new(
        "table",
        Shape::Plane {
            point: Vec3::zeros(),
            normal: Vec3::z(),
        },
    );
    let mut sim = free_rod(base, table, Settings::default().energy_tolerance);
    let traj = sim.simulate(0.1).unwrap();
    assert_eq!(traj.contacts.len(), traj.len());
    let mut deepest = 0.0f64;
    for i in 0..traj.len() {
        let (q, qd) = (traj.q[i].as_slice(), traj.qdot[i].as_slice());
        let want = sim.model().contacts(traj.t[i], q, qd).unwrap();
        // The same contacts and geometry; the forces are the run's, whose
        // stiffness a load raised (CT15), not a fresh workspace's.
        assert_eq!(traj.contacts[i].len(), want.len(), "sample {i}");
        for (c, w) in traj.contacts[i].iter().zip(&want) {
            assert_eq!(
                (c.a, c.s, c.b, c.point, c.normal, c.gap),
                (w.a, w.s, w.b, w.point, w.normal, w.gap),
                "sample {i}"
            );
            assert!(c.force.dot(&c.normal) > 0.0, "sample {i}: pushes");
        }
        deepest = traj.contacts[i].iter().fold(deepest, |m, c| m.max(-c.gap));
    }
    assert!(deepest > 0.0, "the rod landed");
    assert_eq!(traj.max_penetration, deepest);
    let most = traj.contacts.iter().map(Vec::len).max().unwrap();
    assert_eq!(traj.max_contacts, most);
}
