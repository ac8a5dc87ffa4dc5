//! Contact on models with loop closures (docs/theory-contact.md CT16) in
//! runs, against independent references: a rod pinned by a ball closure
//! whose tip rests on a table carries the moment of its weight about the
//! pin; a rod held on a vertical line by a slider closure falls freely,
//! lands without gaining energy and rests at its radius; two rods welded
//! into one by a closure, lying across an incline, stick below the
//! friction angle and slide at `g (sin α − μ cos α)` above it.

mod common;

use common::{G, Keep, L, R, RHO, centre, material, path_along};

use softrod::{Settings, Simulation};
use softrod_dynamics::{
    Attachment, Closure, ClosureFrame, ClosureKind, Joint, JointKind, Model, Rod,
};
use softrod_kinematics::Strain;
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::contact::{Obstacle, Shape};
use softrod_scene::Integrator;

fn plane(point: Vec3, normal: Vec3) -> Shape {
    Shape::Plane { point, normal }
}

/// A free rod (bending strains only: no stretch, so arc length is
/// material length) with base pose `base`, gravity −z, `obstacle` and
/// `closure`, run by ESDIRK at rtol 1e-6.
fn held_rod(
    base: Pose,
    (young, viscosity): (f64, f64),
    obstacle: Obstacle,
    closure: Closure,
    energy_tolerance: f64,
) -> Simulation {
    let rod = Rod::builder(L)
        .name("rod")
        .pieces(4)
        .strains([Strain::Ky, Strain::Kz])
        .base(base)
        .circle(R)
        .material(material(young, viscosity));
    let model = Model::builder()
        .rod_on(rod, Attachment::world_joint(Joint::new(JointKind::Free)))
        .gravity([0.0, 0.0, -G])
        .obstacle(obstacle)
        .closure(closure)
        .build()
        .unwrap();
    let mut sim = Simulation::new(model);
    sim.set_settings(Settings {
        integrator: Integrator::Esdirk,
        rtol: 1e-6,
        atol: 1e-8,
        output_every: Some(0.01),
        energy_tolerance,
        ..Settings::default()
    })
    .unwrap();
    sim
}

fn mass() -> f64 {
    RHO * std::f64::consts::PI * R * R * L
}

/// A rod whose base is pinned to the world by a ball closure (on a free
/// joint: the pin is the closure, not a joint), tilted down so that its
/// tip just touches a frictionless table, settles under gravity. At rest
/// the table's forces balance the moment of the weight about the pin
/// (the pin's reaction has none): `Σ x_i f_z,i = m g x̄`, with `x̄` the
/// centre of mass of the bent rod (Simpson over its centreline) — and
/// the tip sinks less than 1 % of its radius (CT15 raises the stiffness
/// in closed runs too).
#[test]
fn a_pinned_rod_rests_its_tip_on_a_table_with_the_moment_of_its_weight() {
    let theta: f64 = 0.2;
    let pin = Vec3::new(0.0, 0.0, 0.1);
    let rot = *nalgebra::Rotation3::from_axis_angle(&Vec3::y_axis(), theta).matrix();
    let base = Pose::new(rot, pin);
    let tip = pin + rot * Vec3::new(L, 0.0, 0.0);
    let table = Obstacle::new("table", plane(Vec3::new(0.0, 0.0, tip.z - R), Vec3::z()));
    let closure = Closure::new(
        "pin",
        ClosureKind::Ball,
        ClosureFrame::on("rod", Some(0.0), Pose::identity()),
        ClosureFrame::world(Pose::new(Mat3::identity(), pin)),
    );
    let mut sim = held_rod(
        base,
        (2e6, 2e4),
        table,
        closure,
        Settings::default().energy_tolerance,
    );
    let mut keep = Keep(Vec::new());
    sim.simulate_with(1.0, &mut keep).unwrap();
    let (t, q, qd) = keep.0.last().unwrap().clone();
    let speed = qd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(speed < 1e-3, "at rest: {speed}");
    let contacts = sim.contacts(t, &q, &qd).unwrap();
    assert!(!contacts.is_empty());
    let moment: f64 = contacts
        .iter()
        .map(|c| (c.point.x - pin.x) * c.force.z)
        .sum();
    let n = 200;
    let xbar = (0..=n)
        .map(|i| {
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * sim
                .pose("rod", L * i as f64 / n as f64, &q)
                .unwrap()
                .translation
                .x
        })
        .sum::<f64>()
        / (3.0 * n as f64);
    let want = mass() * G * (xbar - pin.x);
    let rel = (moment - want).abs() / want;
    let total: f64 = contacts.iter().map(|c| c.force.z).sum();
    eprintln!(
        "moment {moment:.6e} N m, weight's {want:.6e} ({rel:.1e}); table carries {:.4} of the weight",
        total / (mass() * G)
    );
    assert!(rel < 1e-3, "{moment} vs {want}");
    let pen = sim.model().max_penetration(t, &q).unwrap();
    assert!(pen < 0.01 * R, "{pen}");
    let held = sim.closure_residuals(&q).unwrap();
    assert!(held.iter().all(|(_, r)| *r < 1e-6), "{held:?}");
}

/// Dropped flat from 5 cm onto a frictionless, inelastic table, its centre
/// held on a vertical line by a slider closure (which does no work along
/// the line): free fall `z = z₀ − ½gt²` until the surface meets the
/// table, never more energy than at the start, at rest at centreline
/// height `r` less at most 1 % of `r` — the open test's references
/// (`tests/contact.rs`) through the constrained dynamics.
#[test]
fn a_rod_on_a_vertical_slider_falls_lands_and_rests_at_its_radius() {
    let h = 0.05;
    let base = Pose::new(Mat3::identity(), Vec3::new(0.0, 0.0, R + h));
    let table = Obstacle::new("table", plane(Vec3::zeros(), Vec3::z()));
    let closure = Closure::new(
        "guide",
        ClosureKind::Slider { axis: Vec3::z() },
        ClosureFrame::on("rod", Some(0.5 * L), Pose::identity()),
        ClosureFrame::world(Pose::new(Mat3::identity(), Vec3::new(0.5 * L, 0.0, 0.0))),
    );
    let mut sim = held_rod(
        base,
        (1e6, 0.0),
        table,
        closure,
        Settings::default().energy_tolerance,
    );
    let mut keep = Keep(Vec::new());
    sim.simulate_with(0.5, &mut keep).unwrap();
    let (q0, qd0) = (&keep.0[0].1, &keep.0[0].2);
    let e0 = sim.energies(q0, qd0).unwrap();
    let e0 = e0.kinetic + e0.elastic + e0.gravitational;
    let impact = (2.0 * h / G).sqrt();
    let mgh = mass() * G * h;
    for (t, q, qd) in &keep.0 {
        let e = sim.energies(q, qd).unwrap();
        let e = e.kinetic + e.elastic + e.gravitational;
        assert!(e - e0 < 1e-5 * mgh, "energy gained at t = {t}");
        if *t < impact - 0.005 {
            let z = centre(&sim, q).z;
            let want = R + h - 0.5 * G * t * t;
            assert!(
                (z - want).abs() < 1e-6,
                "free fall at t = {t}: {z} vs {want}"
            );
            assert!((e - e0).abs() < 1e-6 * mgh, "free fall energy");
        }
    }
    let (t, q, qd) = keep.0.last().unwrap();
    for s in [0.0, 0.25 * L, 0.5 * L, 0.75 * L, L] {
        let z = sim.pose("rod", s, q).unwrap().translation.z;
        assert!(z <= R && z > 0.99 * R, "rest height {z} at s = {s}");
    }
    let speed = qd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(speed < 1e-3, "at rest: {speed}");
    // Energy bounded by the start at every sample, and the end's lost to
    // the inelastic landing: m g h less at most the integration error.
    let e = sim.energies(q, qd).unwrap();
    let lost = e0 - (e.kinetic + e.elastic + e.gravitational);
    assert!(lost > 0.99 * mgh, "lost {lost} of {mgh} at t = {t}");
}

/// Two free rods lying across an incline of angle `alpha` with friction
/// `mu`, the first's tip welded to the second's base by a closure (one
/// straight rod of length 2L; the weld is internal, so it carries none of
/// the slope's normal load — a slider to the world would, and friction
/// would then hold less): the distance the first rod's centre travels
/// down the slope at the output times, and the run's energy balance.
fn incline(alpha: f64, mu: f64, duration: f64) -> (Vec<(f64, f64)>, softrod::EnergyBalance) {
    let n = Vec3::new(alpha.sin(), 0.0, alpha.cos());
    let down = Vec3::new(alpha.cos(), 0.0, -alpha.sin());
    let rot = Mat3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
    let rod = |name: &str, y: f64| {
        Rod::builder(L)
            .name(name)
            .pieces(4)
            .strains([Strain::Ky, Strain::Kz])
            .base(Pose::new(rot, n * R + Vec3::y() * y))
            .circle(R)
            .material(material(1e6, 0.0))
    };
    let free = || Attachment::world_joint(Joint::new(JointKind::Free));
    let model = Model::builder()
        .rod_on(rod("rod", -L), free())
        .rod_on(rod("other", 0.0), free())
        .gravity([0.0, 0.0, -G])
        .obstacle(Obstacle::new("slope", plane(Vec3::zeros(), n)).friction(mu))
        .closure(Closure::new(
            "weld",
            ClosureKind::Weld,
            ClosureFrame::on("rod", None, Pose::identity()),
            ClosureFrame::on("other", Some(0.0), Pose::identity()),
        ))
        .build()
        .unwrap();
    let mut sim = Simulation::new(model);
    sim.set_settings(Settings {
        integrator: Integrator::Esdirk,
        rtol: 1e-6,
        atol: 1e-8,
        output_every: Some(0.01),
        // The watch on, with room to report rather than stop.
        energy_tolerance: 1.0,
        ..Settings::default()
    })
    .unwrap();
    path_along(&mut sim, duration, down)
}

#[test]
fn below_the_friction_angle_welded_rods_stick_without_creep() {
    // tan 20° = 0.364 < μ = 0.5.
    let (path, energy) = incline(20f64.to_radians(), 0.5, 0.5);
    let at = |t: f64| path.iter().find(|(s, _)| (s - t).abs() < 1e-9).unwrap().1;
    eprintln!(
        "moved {:.3e} m, then {:.3e} m",
        at(0.25),
        at(0.5) - at(0.25)
    );
    // Elastic pre-slip bound (CT5): μ f_n / k ≤ μ · 1 % of r.
    assert!(at(0.5).abs() < 0.01 * R, "moved {}", at(0.5));
    assert!(
        (at(0.5) - at(0.25)).abs() < 1e-4 * R,
        "crept {}",
        at(0.5) - at(0.25)
    );
    assert!(energy.relative < 1e-3, "balance {:.3e}", energy.relative);
}

#[test]
fn above_the_friction_angle_welded_rods_slide_at_coulombs_rate() {
    let (alpha, mu) = (30f64.to_radians(), 0.2);
    let (path, energy) = incline(alpha, mu, 0.3);
    let at = |t: f64| path.iter().find(|(s, _)| (s - t).abs() < 1e-9).unwrap().1;
    let dt = 0.1;
    let a = (at(0.3) - 2.0 * at(0.2) + at(0.1)) / (dt * dt);
    let want = G * (alpha.sin() - mu * alpha.cos());
    let rel = (a - want).abs() / want;
    eprintln!("a = {a:.5} m/s², Coulomb {want:.5} ({rel:.2e})");
    assert!(rel < 1e-2, "{a} vs {want}");
    // Friction's work μ m g cos α · d, counted once by the run's balance
    // (the closures' power and the contact's kept apart).
    let friction_work = mu * 2.0 * mass() * G * alpha.cos() * at(0.3);
    eprintln!(
        "energy: change {:.4e} J, work {:.4e} J (friction {friction_work:.4e} J), closures {:.3e} J, relative error {:.2e}",
        energy.change, energy.work, energy.closure_work, energy.relative
    );
    assert!(
        (energy.work + friction_work).abs() < 1e-2 * friction_work,
        "work {} vs −{friction_work}",
        energy.work
    );
    assert!(energy.relative < 1e-3, "balance {:.3e}", energy.relative);
}
