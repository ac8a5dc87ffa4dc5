//! The energy watch's false alarms (issue 26) and what it must still catch.
//!
//! The rule (crates/softrod/src/watch.rs, module documentation): errors below
//! the round-off floor `10³ ε (T + V_e + |V_g| + |E(0)| + ∫|P| + F L)` count
//! as zero, `F L` the model's work scale (weights, loads and cable tensions
//! times the rods' total length, plus the loads' moments); with closures the
//! power of the closure forces `q̇ᵀJᵀλ` (nonzero only through the Baumgarte
//! stabilization) is part of the balance; the advice names an abrupt drive
//! when one moved in the failing span.

use softrod::{Error, Flow, Observer, Sample, Settings, Simulation};
use softrod_scene::Integrator;

const D02A: &str = include_str!("fixtures/D02a_energy_guard_false_fail_motionless_closed.toml");

struct Discard;
impl Observer for Discard {
    fn sample(&mut self, _: Sample<'_>) -> Result<Flow, String> {
        Ok(Flow::Continue)
    }
}

fn sim(text: &str) -> Simulation {
    Simulation::from_toml(text, "test.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

fn with(s: &mut Simulation, f: impl FnOnce(&mut Settings)) {
    let mut set = s.settings().clone();
    f(&mut set);
    s.set_settings(set).unwrap();
}

/// The reproducing scene: a rod welded at both ends that cannot move, every
/// energy at round-off (1.7e-23 J), failed the run as "1.0 of the energy
/// scale". It passes, silently, with every integrator, and the floor is the
/// one the rule states, computed here by hand.
#[test]
fn a_motionless_welded_rod_is_not_flagged() {
    // Weight ρ π r² L g of the 0.2 m rod times its length.
    let weight = 1100.0 * std::f64::consts::PI * 0.008f64.powi(2) * 0.2 * 9.81;
    let floor = 1e3 * f64::EPSILON * weight * 0.2;
    for integrator in [
        Integrator::Esdirk,
        Integrator::Dopri5,
        Integrator::Rk4,
        Integrator::Radau5,
    ] {
        let mut s = sim(D02A);
        with(&mut s, |x| x.integrator = integrator);
        let sum = s
            .simulate_with(0.1, &mut Discard)
            .unwrap_or_else(|e| panic!("{integrator:?}: {e}"));
        let b = sum.energy.unwrap();
        assert!(
            sum.warnings.is_empty(),
            "{integrator:?}: {:?}",
            sum.warnings
        );
        // Every energy is round-off: far below the floor.
        assert!(b.change.abs() < 1e-3 * floor, "{integrator:?}: {b:?}");
        // The floor is the work scale's (the energies add ~1e-20 of it).
        assert!(
            (b.floor - floor).abs() < 1e-6 * floor,
            "{integrator:?}: {} vs {floor}",
            b.floor
        );
    }
}

/// Both ends welded, 2 pieces of ky, kz, qx: a locked structure. A large
/// load on it moves by the stabilization's noise only, but that noise times
/// the load is work the load does — and the closure forces take it back.
/// Counted, the balance closes; the closure work is many times the energy
/// change, so without it the run would fail.
#[test]
fn a_locked_structure_under_a_large_load_is_not_flagged() {
    let text = D02A.replace("[world]\ngravity = [0.0, 0.0, -9.81]\n", "")
        + "[[load]]\nrod = \"a\"\ns = 0.1\nforce = [0, 0, -1e7]\n";
    let mut s = sim(&text);
    let sum = s.simulate_with(0.1, &mut Discard).unwrap();
    let b = sum.energy.unwrap();
    assert!(sum.warnings.is_empty(), "{:?}", sum.warnings);
    assert!(b.closure_work.abs() > 1e3 * b.change.abs(), "{b:?}");
    // The load's own work is the closure work's opposite.
    let load_work = b.work - b.closure_work;
    assert!(
        (load_work + b.closure_work).abs() < 1e-3 * b.closure_work.abs(),
        "{b:?}"
    );
}

/// A genuine error is still one: the same closed rod, loaded so that it
/// moves, under rk4 with a fixed step far beyond its stability limit, fails
/// on the balance, and the advice is the step's.
#[test]
fn an_unstable_step_on_a_closed_chain_still_fails() {
    let text = D02A.replace("strains = [\"ky\", \"kz\", \"qx\"]", "strains = \"all\"")
        + "[[load]]\nrod = \"a\"\ns = 0.1\nforce = [0, 0, -5]\n";
    let mut s = sim(&text);
    with(&mut s, |x| {
        x.integrator = Integrator::Rk4;
        x.dt = 1e-2;
    });
    let e = s.simulate_with(0.1, &mut Discard).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, Error::EnergyBalance { .. }), "{msg}");
    assert!(
        msg.ends_with("reduce dt or the tolerances, or use a stiff integrator"),
        "{msg}"
    );
    // At a stable step the same run passes.
    with(&mut s, |x| {
        x.integrator = Integrator::Esdirk;
    });
    s.simulate_with(0.1, &mut Discard).unwrap();
}

const DRIVE: &str = r#"
[[rod]]
name = "tentacle"
length = 0.3
pieces = 6
strains = ["ky", "kz", "qx"]
base = { position = [0.0, 0.0, 0.0], rotation = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]] }
joint = { type = "prismatic", axis = [0, 0, 1], prescribed = { times = [0, 0.005, 0.01], values = [0, 0.01, 0.03] } }
section = { shape = "circle", radius = 0.008 }
material = { density = 1100.0, young = 5.0e5, poisson = 0.5 }
[run]
output_every = 0.01
"#;

/// A drive that stops at 5 m/s is an impulse: the balance breaks at the
/// stop whatever the step, and the advice says so instead of "reduce dt".
#[test]
fn an_abrupt_drive_stop_is_called_an_impulse() {
    for integrator in [Integrator::Dopri5, Integrator::Esdirk, Integrator::Rk4] {
        let mut s = sim(DRIVE);
        with(&mut s, |x| integrator_and_step(x, integrator, 1e-5));
        let e = s.simulate_with(0.05, &mut Discard).unwrap_err();
        let msg = e.to_string();
        let Error::EnergyBalance { t, advice, .. } = &e else {
            panic!("{integrator:?}: {msg}")
        };
        assert!(*t >= 0.01, "{integrator:?}: {msg}");
        assert!(
            advice.starts_with(
                "the drive of \"tentacle\" (coordinate 0) stops abruptly at t = 1e-2 s"
            ) && advice.contains("an impulse"),
            "{integrator:?}: {msg}"
        );
        assert!(!msg.contains("reduce dt"), "{msg}");
    }
}

fn integrator_and_step(x: &mut Settings, integrator: Integrator, dt: f64) {
    x.integrator = integrator;
    x.dt = dt;
    x.rtol = 1e-8;
    x.atol = 1e-10;
}

/// The same stage driven by a sine, smooth everywhere, at the same
/// settings: no impulse, and the balance holds to 1e-4.
#[test]
fn a_smooth_drive_runs_clean() {
    let text = DRIVE.replace(
        "prescribed = { times = [0, 0.005, 0.01], values = [0, 0.01, 0.03] }",
        "prescribed = { sine = { amplitude = 0.01, frequency = 20.0 } }",
    );
    let mut s = sim(&text);
    with(&mut s, |x| integrator_and_step(x, Integrator::Dopri5, 1e-5));
    let sum = s.simulate_with(0.05, &mut Discard).unwrap();
    let b = sum.energy.unwrap();
    assert!(b.relative < 1e-4, "{b:?}");
}
