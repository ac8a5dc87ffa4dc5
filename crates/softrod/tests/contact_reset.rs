//! A run or a statics solve from the initial state starts from a fresh
//! contact state (docs/theory-contact.md CT15: base stiffness, no friction
//! anchors), whatever was called before it: the reference is a second
//! `Simulation` built from the same model that has done nothing else, and
//! the results must agree bit for bit.

mod common;

use common::{across_incline, free_rod_model, plane, rope_over_cylinder_model};

use softrod::{Settings, Simulation, Trajectory};
use softrod_lie::Vec3;
use softrod_scene::Integrator;

fn settings() -> Settings {
    Settings {
        integrator: Integrator::Esdirk,
        rtol: 1e-6,
        atol: 1e-8,
        output_every: Some(0.01),
        ..Settings::default()
    }
}

/// A free rod lying across an incline of 20° with μ = 0.5 (it sticks,
/// holding its weight by the anchored springs of CT5 from the first step).
fn rod_on_incline() -> Simulation {
    let alpha = 20f64.to_radians();
    let (base, n, _) = across_incline(alpha);
    let slope = plane("slope", Vec3::zeros(), n).friction(0.5);
    let mut sim = Simulation::new(free_rod_model(base, slope, &[], 0.0));
    sim.set_settings(settings()).unwrap();
    sim
}

/// A rope clamped level on top of a cylinder with friction μ = 0.3, bent
/// over it by a tip weight far above its own: statics raises the
/// stiffness of the contacts it presses (CT15).
fn rope_over_cylinder() -> Simulation {
    let mut sim = Simulation::new(rope_over_cylinder_model(0.3));
    sim.set_settings(settings()).unwrap();
    sim
}

/// The same samples, bit for bit (times, coordinates, velocities, and the
/// contact forces the recorder kept).
fn assert_same(a: &Trajectory, b: &Trajectory, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: sample count");
    for i in 0..a.len() {
        assert_eq!(a.t[i].to_bits(), b.t[i].to_bits(), "{what}: t[{i}]");
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(a.q[i].as_slice()),
            bits(b.q[i].as_slice()),
            "{what}: q[{i}]"
        );
        assert_eq!(
            bits(a.qdot[i].as_slice()),
            bits(b.qdot[i].as_slice()),
            "{what}: qdot[{i}]"
        );
        let forces = |t: &Trajectory| {
            t.contacts[i]
                .iter()
                .map(|c| c.force.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                .collect::<Vec<_>>()
        };
        assert_eq!(forces(a), forces(b), "{what}: contact forces at sample {i}");
    }
}

#[test]
fn a_second_run_from_the_initial_state_repeats_the_first_bit_for_bit() {
    let mut fresh = rod_on_incline();
    let want = fresh.simulate(0.1).unwrap();
    let mut sim = rod_on_incline();
    let first = sim.simulate(0.1).unwrap();
    let second = sim.simulate(0.1).unwrap();
    assert_same(&first, &want, "first run");
    assert_same(&second, &want, "second run");
    // The rod touched throughout: the test is about a state that exists.
    assert!(!want.contacts.last().unwrap().is_empty());
}

#[test]
fn a_run_after_statics_is_the_run_alone() {
    let mut fresh = rope_over_cylinder();
    let want = fresh.simulate(0.01).unwrap();
    let mut sim = rope_over_cylinder();
    sim.statics().unwrap();
    let after = sim.simulate(0.01).unwrap();
    assert_same(&after, &want, "run after statics");
}

#[test]
fn statics_after_a_run_is_statics_alone() {
    let mut fresh = rope_over_cylinder();
    let want = fresh.statics().unwrap();
    let mut sim = rope_over_cylinder();
    sim.simulate(0.01).unwrap();
    let after = sim.statics().unwrap();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(after.q.as_slice()), bits(want.q.as_slice()));
    assert_eq!(after.iterations, want.iterations);
    // And `contacts` reports what each statics committed: the same forces.
    let zero = vec![0.0; want.q.len()];
    let c_want = fresh.contacts(0.0, want.q.as_slice(), &zero).unwrap();
    let c_after = sim.contacts(0.0, after.q.as_slice(), &zero).unwrap();
    assert!(!c_want.is_empty());
    let forces = |c: &[softrod_mechanics::ContactPoint]| {
        c.iter()
            .map(|p| p.force.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
            .collect::<Vec<_>>()
    };
    assert_eq!(forces(&c_after), forces(&c_want));
}

/// `step` continues: after a run, a step from the run's end state uses the
/// run's anchors and stiffness; `reset_contact` gives the step of a new
/// simulation.
#[test]
fn step_continues_and_reset_contact_forgets() {
    let mut fresh = rod_on_incline();
    let (q0, qd0) = {
        let (q, qd) = fresh.initial_state();
        (q.clone(), qd.clone())
    };
    let want = fresh
        .step(0.0, q0.as_slice(), qd0.as_slice(), 0.01)
        .unwrap();
    let mut sim = rod_on_incline();
    sim.simulate(0.1).unwrap();
    let continued = sim.step(0.0, q0.as_slice(), qd0.as_slice(), 0.01).unwrap();
    assert_ne!(
        continued.0, want.0,
        "the run's contact state is kept by step"
    );
    sim.reset_contact();
    let reset = sim.step(0.0, q0.as_slice(), qd0.as_slice(), 0.01).unwrap();
    assert_eq!(reset.0, want.0);
    assert_eq!(reset.1, want.1);
}
