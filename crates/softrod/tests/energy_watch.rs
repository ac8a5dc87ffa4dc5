//! The energy-balance watch (issue 15): a run that breaks `dE/dt = P_nc`
//! fails or warns; a correct one passes. The balance compares two
//! independent computations: the energies (`T + V_e + V_g`, from the
//! kinematics and the constitutive law) and the power of the
//! non-conservative forces (from the bias forces of the full and the
//! conservative model).

use softrod::{Error, Flow, Observer, Sample, Settings, Simulation};
use softrod_scene::Integrator;

const FAST_WHIRL: &str = include_str!("../../../examples/extreme/fast_whirl.toml");

fn cantilever(extra_rod: &str, extra: &str) -> String {
    format!(
        "[world]\ngravity = [0.0, 0.0, -9.81]\n\
         [[rod]]\nname = \"arm\"\nlength = 0.5\npieces = 8\nstrains = [\"ky\", \"qx\", \"qz\"]\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n{extra_rod}\n{extra}"
    )
}

const RUBBER: &str = "material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }";

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

struct Discard;
impl Observer for Discard {
    fn sample(&mut self, _: Sample<'_>) -> Result<Flow, String> {
        Ok(Flow::Continue)
    }
}

/// The case: rk4 with dt = 1 s over 0.05 s, one unstable step
/// (energy 1.4e28 J): the run fails, it is not reported as ok.
#[test]
fn one_unstable_rk4_step_fails_the_run() {
    let mut s = sim(&cantilever(RUBBER, ""));
    with(&mut s, |x| {
        x.integrator = Integrator::Rk4;
        x.dt = 1.0;
        x.output_every = Some(0.01);
    });
    let e = s.simulate_with(0.05, &mut Discard).unwrap_err();
    assert!(!e.is_input(), "{e}");
    // The step also folds the rod (stretch −12 in piece 2); the balance,
    // checked first, names the cause.
    let msg = e.to_string();
    assert!(matches!(e, Error::EnergyBalance { .. }), "{msg}");
    assert!(
        msg.starts_with("energy balance violated at t = 5e-2 s"),
        "{msg}"
    );
}

/// Released cantilever, undamped: the exact flow conserves `E`. At
/// rtol 1e-8 the balance holds to far below the bound, and nothing warns.
#[test]
fn a_tight_conservative_run_is_not_flagged() {
    let mut s = sim(&cantilever(RUBBER, ""));
    with(&mut s, |x| {
        x.integrator = Integrator::Dopri5;
        x.rtol = 1e-9;
        x.atol = 1e-12;
        x.output_every = Some(0.01);
    });
    let sum = s.simulate_with(0.05, &mut Discard).unwrap();
    let b = sum.energy.unwrap();
    println!("{b:?} {:?}", sum.warnings);
    assert!(!b.non_conservative && b.work == 0.0);
    assert!(b.relative < 1e-5, "{b:?}");
    assert!(sum.warnings.is_empty(), "{:?}", sum.warnings);
}

/// Damping, a cable, a point load and drag: the energy changes by the
/// work of the non-conservative forces, which must be a sizeable part of
/// the balance for the test to say anything.
#[test]
fn a_tight_damped_actuated_run_balances_its_work() {
    let text = cantilever(
        "material = { density = 1000.0, young = 1.0e7, poisson = 0.5, viscosity = 300.0 }\n\
         drag = { translational = 0.5, rotational = 0.001 }",
        "[[cable]]\nrod = \"arm\"\noffset = [0.0, 0.006]\ntension = 3.0\n\
         [[load]]\nrod = \"arm\"\ns = 0.5\nforce = [0.0, 0.0, 0.4]\nframe = \"world\"\n",
    );
    let mut s = sim(&text);
    with(&mut s, |x| {
        x.integrator = Integrator::Dopri5;
        x.rtol = 1e-9;
        x.atol = 1e-12;
        x.output_every = Some(0.01);
    });
    let sum = s.simulate_with(0.1, &mut Discard).unwrap();
    let b = sum.energy.unwrap();
    assert!(b.non_conservative);
    // The work term matters: without it the balance would be off by the
    // whole energy change, over 1000 times the largest error measured.
    assert!(b.work.abs() > 1e3 * b.error, "{b:?}");
    // The largest error is 1e-5 of the scale at most (7e-7 measured with
    // the trapezoidal work over dopri5's accepted steps at rtol 1e-9;
    // Simpson's work is closer still).
    assert!(b.relative < 1e-5, "{b:?}");
    assert!(sum.warnings.is_empty(), "{:?}", sum.warnings);
}

/// The other case: an undamped large-strain run (the fast whirl,
/// 0.154 J conserved by the exact flow) at a loose tolerance drifts by
/// tens of percent: flagged, as a failure or at least a warning.
#[test]
fn an_undamped_large_strain_run_at_a_loose_tolerance_is_flagged() {
    let mut s = sim(FAST_WHIRL);
    with(&mut s, |x| {
        x.integrator = Integrator::Dopri5;
        x.rtol = 1e-1;
        x.atol = 1e-1;
    });
    match s.simulate_with(0.05, &mut Discard) {
        Err(e) => {
            println!("{e}");
            assert!(matches!(e, Error::EnergyBalance { .. }), "{e}");
        }
        Ok(sum) => {
            println!("{:?} {:?}", sum.energy, sum.warnings);
            assert!(
                sum.warnings.iter().any(|w| w.starts_with("energy balance")),
                "{sum:?}"
            );
        }
    }
    // The same run at a tight tolerance keeps its energy.
    with(&mut s, |x| {
        x.rtol = 1e-9;
        x.atol = 1e-12;
    });
    let sum = s.simulate_with(0.05, &mut Discard).unwrap();
    let b = sum.energy.unwrap();
    println!("tight: {b:?} {:?}", sum.warnings);
    assert!(b.relative < 1e-5, "{b:?}");
}

/// A bound can be set: an absurdly tight one fails a correct run at the
/// default settings, the default does not.
#[test]
fn the_bound_is_a_setting() {
    let mut s = sim(&cantilever(RUBBER, ""));
    with(&mut s, |x| x.output_every = Some(0.01));
    let sum = s.simulate_with(0.05, &mut Discard).unwrap();
    println!("default: {:?}", sum.energy);
    with(&mut s, |x| x.energy_tolerance = 1e-14);
    let e = s.simulate_with(0.05, &mut Discard).unwrap_err();
    assert!(
        e.to_string().starts_with("energy balance violated at t = "),
        "{e}"
    );
    let mut bad = s.settings().clone();
    bad.energy_tolerance = 0.0;
    assert!(s.set_settings(bad).unwrap_err().is_input());
}

/// The shipped examples, at their own settings over their first 0.05 s,
/// keep the balance well inside the default bound.
#[test]
fn shipped_examples_are_not_flagged() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples");
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    assert!(!paths.is_empty());
    for p in paths {
        let (mut s, scene, _) = Simulation::from_scene_file(&p).unwrap();
        if scene.run.mode != softrod_scene::Mode::Dynamics {
            continue;
        }
        let sum = s
            .simulate_with(0.05, &mut Discard)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let b = sum.energy.unwrap();
        println!("{}: {b:?} {:?}", p.display(), sum.warnings);
        assert!(
            b.relative < softrod_scene::Run::DEFAULT_ENERGY_TOLERANCE,
            "{}: {b:?}",
            p.display()
        );
    }
}

/// Stretch `ξ_x = 1 + q_qx`: a state with a piece folded (stretch −0.5)
/// fails the run at once; one stretched by 1.7 runs and warns.
#[test]
fn folded_pieces_fail_and_overstretched_ones_warn() {
    let mut s = sim(&cantilever(RUBBER, ""));
    with(&mut s, |x| {
        x.integrator = Integrator::Dopri5;
        x.rtol = 1e-6;
        x.output_every = Some(1e-4);
    });
    let n = s.n_dof();
    // Coordinates per piece: ky, qx, qz; piece 3's qx is q[3·3 + 1].
    let mut q = vec![0.0; n];
    q[10] = -1.5;
    s.set_initial_state(&q, &vec![0.0; n]).unwrap();
    match s.simulate_with(1e-3, &mut Discard).unwrap_err() {
        Error::Stretch { piece, stretch, .. } => {
            assert_eq!(piece, 3);
            assert!((stretch + 0.5).abs() < 1e-12, "{stretch}");
        }
        e => panic!("{e}"),
    }
    q[10] = 0.7;
    s.set_initial_state(&q, &vec![0.0; n]).unwrap();
    let sum = s.simulate_with(1e-4, &mut Discard).unwrap();
    assert!(
        sum.warnings
            .iter()
            .any(|w| w.starts_with("strain beyond the model's validity") && w.contains("piece 3")),
        "{:?}",
        sum.warnings
    );
}

/// Regression (found by the CLI's cable-power test): a tension ramping from
/// zero makes `P ∝ t³` on the first step, which the trapezoid overestimates
/// twice while the energy scale is 1e-15 J; the work's own uncertainty is
/// not held against the run.
#[test]
fn a_tension_ramp_from_zero_is_not_flagged() {
    let mut s = sim(
        "[[rod]]\nname = \"arm\"\nlength = 0.3\npieces = 4\nstrains = [\"ky\", \"qx\", \"qz\"]\n\
         section = { shape = \"circle\", radius = 0.01 }\n\
         material = { density = 1100.0, young = 1.0e6, poisson = 0.5 }\n\
         [[cable]]\nrod = \"arm\"\noffset = [0.0, 0.008]\n\
         tension = { times = [0.0, 0.02], values = [0.0, 1.0] }\n\
         [run]\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-13\noutput_every = 0.001\n",
    );
    let sum = s.simulate_with(0.04, &mut Discard).unwrap();
    let b = sum.energy.unwrap();
    assert!(b.non_conservative && b.work > 0.0, "{b:?}");
    assert!(b.relative < 1e-5, "{b:?}");
    assert!(sum.warnings.is_empty(), "{:?}", sum.warnings);
}
