//! The facade against independent references: analytic beams, finite
//! differences, conservation of energy, and the contract of its errors.

use std::f64::consts::PI;

use softrod::kinematics::Frame;
use softrod::{Error, Flow, Observer, RunStatus, Sample, Settings, Simulation};
use softrod_scene::Integrator;

fn scene(rod_extra: &str, extra: &str) -> String {
    format!(
        "[[rod]]\nname = \"arm\"\nlength = 0.5\npieces = 10\n{rod_extra}\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5 }}\n{extra}"
    )
}

fn sim(text: &str) -> Simulation {
    Simulation::from_toml(text, "test.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

/// A uniform curvature κ about y is a circle arc of radius 1/κ: the pose of
/// every section is exact, whatever the number of pieces.
#[test]
fn constant_curvature_is_a_circle_arc() {
    // Tolerance: closed-form exponential, round-off of a few operations on 0.5 m.
    const ARC_TOL: f64 = 1e-13;
    let mut s = sim(&scene("strains = [\"ky\"]", ""));
    let kappa = 2.0; // rad/m, 1 rad over the rod
    let q = vec![kappa; 10];
    for x in [0.0, 0.13, 0.25, 0.5] {
        let p = s.pose("arm", x, &q).unwrap().translation;
        // Bending about +y turns the tangent x toward −z.
        let want = [
            (kappa * x).sin() / kappa,
            0.0,
            -(1.0 - (kappa * x).cos()) / kappa,
        ];
        for c in 0..3 {
            assert!(
                (p[c] - want[c]).abs() < ARC_TOL,
                "s = {x}: {p:?} vs {want:?}"
            );
        }
    }
    assert!(s.pose("arm", 0.6, &q).is_err(), "s beyond the tip");
    assert!(matches!(s.pose("nope", 0.1, &q), Err(Error::UnknownRod(_))));
    assert!(matches!(s.mass_matrix(&q[..3]), Err(Error::Dynamics(_))));
}

/// `jacobian` equals central differences of `pose` (body-frame twist of a
/// q-perturbation: vee(g⁻¹ ∂g)).
#[test]
fn jacobian_matches_finite_differences_of_pose() {
    // Central differences with h = 1e-6 on O(1) curvatures: O(h²) truncation
    // plus 1e-16/h round-off, ~1e-9.
    const FD_TOL: f64 = 1e-8;
    let s = sim(&scene("strains = \"all\"", ""));
    let n = s.n_dof();
    let q: Vec<f64> = (0..n).map(|i| 0.3 * ((i as f64) * 0.7).sin()).collect();
    let at = 0.37;
    let j = s.jacobian("arm", at, &q, Frame::Body).unwrap();
    let g0 = s.pose("arm", at, &q).unwrap();
    let h = 1e-6;
    for c in [0, 5, 17, 33, 59] {
        let mut qp = q.clone();
        qp[c] += h;
        let gp = s.pose("arm", at, &qp).unwrap();
        qp[c] -= 2.0 * h;
        let gm = s.pose("arm", at, &qp).unwrap();
        let r0t = g0.rotation.transpose();
        let dr = (gp.rotation - gm.rotation) / (2.0 * h);
        let w = r0t * dr;
        let dp = r0t * (gp.translation - gm.translation) / (2.0 * h);
        let fd = [w[(2, 1)], w[(0, 2)], w[(1, 0)], dp[0], dp[1], dp[2]];
        for r in 0..6 {
            assert!(
                (j[(r, c)] - fd[r]).abs() < FD_TOL,
                "J[{r},{c}] = {} vs {}",
                j[(r, c)],
                fd[r]
            );
        }
    }
}

/// A small dead tip load: the linear Timoshenko cantilever
/// `δ = PL³/(3EI) + PL/(GA)` (examples/tip_load_statics.toml derives it).
#[test]
fn statics_of_a_small_tip_load_is_the_timoshenko_beam() {
    // 10 pieces of constant strain: tip error ≈ δ/(4N²) = 1.3e-5 m.
    const TIP_TOL: f64 = 2e-5;
    let mut s = sim(&scene(
        "strains = \"all\"",
        "[[load]]\nrod = \"arm\"\ns = 0.5\nforce = [0.0, 0.0, -0.01]\nframe = \"world\"\n",
    ));
    let eq = s.statics().unwrap();
    let tip = s.tip_pose("arm", eq.q.as_slice()).unwrap().translation;
    let (e, g, r, l, p) = (1e7, 1e7 / 3.0, 0.01, 0.5, 0.01);
    let i = PI * r * r * r * r / 4.0;
    let delta = p * l * l * l / (3.0 * e * i) + p * l / (g * PI * r * r);
    assert!(
        (tip[2] + delta).abs() < TIP_TOL,
        "tip z {} vs {}",
        tip[2],
        -delta
    );
}

/// Modes of a slender cantilever about the rest shape: Euler–Bernoulli
/// `ω = (βL)² √(EI/ρA) / L²` with `β₁L = 1.875104`, `β₂L = 4.694091`, and
/// PCS above them by the Rayleigh–Ritz error `C_i/N²`, with
/// `C_i = (L²/24)∫φ_i‴²/∫φ_i″²` from the analytic mode shapes: 0.19366 and
/// 1.35072 (docs/validation.md, "Cantilever frequencies").
#[test]
fn modes_are_euler_bernoulli_frequencies() {
    // Bending-only rod, L/r = 1000 (rotary inertia < 1e-5): the error is
    // C_i/N² to leading order; at N = 20 the next order is < 1 % of it
    // (docs/validation.md: N²·err/C = 1.00 ± 0.5 % from N = 16 on).
    const RITZ: [f64; 2] = [0.19366, 1.35072];
    const RITZ_REL_TOL: f64 = 0.02;
    let text = "[[rod]]\nname = \"arm\"\nlength = 1.0\npieces = 20\nstrains = [\"ky\"]\n\
                section = { shape = \"circle\", radius = 0.001 }\n\
                material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }\n";
    let mut s = sim(text);
    let m = s.modes().unwrap();
    assert_eq!(m.equilibrium, softrod::Equilibrium::Rest);
    let (e, r, rho) = (1e7_f64, 1e-3_f64, 1000.0_f64);
    let (i, a) = (PI * r.powi(4) / 4.0, PI * r * r);
    let w = m.modes.omega.as_slice();
    for (k, bl) in [1.875104_f64, 4.694091].iter().enumerate() {
        let exact = bl * bl * (e * i / (rho * a)).sqrt();
        let err = w[k] / exact - 1.0;
        let ritz = RITZ[k] / 400.0;
        assert!(
            (err / ritz - 1.0).abs() < RITZ_REL_TOL,
            "mode {k}: relative error {err:.4e}, Ritz estimate {ritz:.4e}"
        );
    }
}

/// Counts samples and checks the energy of each (undamped, no actuation:
/// conserved to the integrator's tolerance).
struct EnergyWatch {
    e0: Option<f64>,
    worst: f64,
    times: Vec<f64>,
    stop_after: usize,
}

impl Observer for EnergyWatch {
    fn sample(&mut self, s: Sample<'_>) -> Result<Flow, String> {
        let e = softrod::dynamics::energies(s.model, s.data, s.q, s.qd)
            .map_err(|e| e.to_string())?
            .total();
        let e0 = *self.e0.get_or_insert(e);
        self.worst = self.worst.max((e - e0).abs());
        self.times.push(s.t);
        Ok(if self.times.len() >= self.stop_after {
            Flow::Stop
        } else {
            Flow::Continue
        })
    }
}

/// The undamped release conserves energy; samples come at the output times;
/// an observer can stop the run.
#[test]
fn simulate_conserves_energy_and_streams_samples() {
    // dopri5 at rtol 1e-9 over 0.05 s: drift ~1e-9 of the ~1e-2 J exchanged.
    const ENERGY_TOL: f64 = 1e-8;
    let mut s = sim(&scene(
        "strains = [\"ky\", \"qx\", \"qz\"]\npieces = 4",
        "[world]\ngravity = [0.0, 0.0, -9.81]\n",
    )
    .replace("pieces = 10\n", ""));
    s.set_settings(
        Settings::tolerances(1e-9, 1e-12)
            .with_integrator(Integrator::Dopri5)
            .with_output_every(0.01),
    )
    .unwrap();
    let mut w = EnergyWatch {
        e0: None,
        worst: 0.0,
        times: Vec::new(),
        stop_after: usize::MAX,
    };
    let sum = s.simulate_with(0.05, &mut w).unwrap();
    assert_eq!(sum.status, RunStatus::Completed);
    assert_eq!(sum.samples, 6);
    for (k, t) in w.times.iter().enumerate() {
        assert!((t - 0.01 * k as f64).abs() < 1e-12, "sample {k} at {t}");
    }
    assert!(w.worst < ENERGY_TOL, "energy drift {}", w.worst);
    let traj = s.simulate(0.05).unwrap();
    assert_eq!(traj.len(), 6);
    // It moved: the tip fell.
    assert!(traj.tip_position(5, 0)[2] < -1e-3);

    let mut w = EnergyWatch {
        e0: None,
        worst: 0.0,
        times: Vec::new(),
        stop_after: 3,
    };
    let sum = s.simulate_with(0.05, &mut w).unwrap();
    assert_eq!((sum.status, sum.samples), (RunStatus::Stopped, 3));
    assert!((sum.t_final - 0.02).abs() < 1e-12);
}

/// Settings that cannot run are refused before anything starts, with the
/// scene key they came from.
#[test]
fn bad_settings_are_input_errors() {
    let mut s = sim(&scene("", ""));
    let err = s.simulate(-1.0).unwrap_err();
    assert!(matches!(
        err,
        Error::InvalidSetting {
            key: "duration",
            ..
        }
    ));
    assert!(err.is_input());
    let bad = Settings {
        rtol: f64::NAN,
        ..Settings::default()
    };
    assert!(matches!(
        s.set_settings(bad),
        Err(Error::InvalidSetting { key: "rtol", .. })
    ));
    let err =
        Simulation::from_toml(&scene("", "[run]\nintegrator = \"radau\"\n"), "r.toml").unwrap_err();
    assert!(err.is_input());
    assert!(err.to_string().contains("run.integrator"), "{err}");
    assert!(matches!(
        s.set_initial_state(&[0.0; 3], &[0.0; 3]),
        Err(Error::SizeMismatch { what: "q", .. })
    ));
}

fn cable_scene(tension: &str) -> String {
    scene(
        "strains = [\"ky\", \"qx\", \"qz\"]",
        &format!(
            "[[cable]]\nrod = \"arm\"\noffset = [0.0, 0.006]\ntension = {tension}\n\
             [run]\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-12\n"
        ),
    )
    .replace("pieces = 10", "pieces = 3")
}

/// Records the tip and, from t ≥ 0.01 s, pulls the cable with 0.8 N.
struct Pull {
    last: Vec<f64>,
    switched_at: Option<f64>,
}

impl Observer for Pull {
    fn sample(&mut self, s: Sample<'_>) -> Result<Flow, String> {
        self.last = s.q.to_vec();
        Ok(Flow::Continue)
    }
    fn inputs(&mut self, t: f64, _q: &[f64], _qd: &[f64], u: &mut [f64]) -> bool {
        if t >= 0.01 && self.switched_at.is_none() {
            self.switched_at = Some(t);
            u[0] = 0.8;
            return true;
        }
        false
    }
}

/// Inputs replace the schedule: a run with u = 0.5 N equals the scene
/// whose cable holds 0.5 N; the step API chained over two halves equals one
/// run; a controller switching u mid-run ends where the step API does when
/// it switches at the same time.
#[test]
fn cable_inputs_controllers_and_steps() {
    // dopri5 at rtol 1e-10: the two integrations differ by their own
    // local errors only, ~1e-9 of the O(1) strains.
    const RUN_TOL: f64 = 1e-8;
    let mut held = sim(&cable_scene("0.5"));
    let mut input = sim(&cable_scene("{ times = [0.0, 1.0], values = [3.0, 0.0] }"));
    input.set_cable_tensions(Some(&[0.5])).unwrap();
    assert_eq!(input.cable_tensions(), Some(&[0.5][..]));
    let (a, b) = (held.simulate(0.02).unwrap(), input.simulate(0.02).unwrap());
    let last = a.len() - 1;
    assert!((&a.q[last] - &b.q[last]).amax() < RUN_TOL);
    assert!(a.q[last].amax() > 1e-3, "the cable bent the rod");

    let n = held.n_dof();
    let z = vec![0.0; n];
    let (q1, qd1) = held.step(0.0, &z, &z, 0.01).unwrap();
    let (q2, _) = held
        .step(0.01, q1.as_slice(), qd1.as_slice(), 0.01)
        .unwrap();
    assert!(
        (&q2 - &a.q[last]).amax() < RUN_TOL,
        "{}",
        (&q2 - &a.q[last]).amax()
    );

    // The controller switches at the first accepted step at or after 0.01 s,
    // which the integrator places where its error control says: compare with
    // the step API switching at the same instant.
    let mut pull = Pull {
        last: Vec::new(),
        switched_at: None,
    };
    held.simulate_with(0.02, &mut pull).unwrap();
    assert_eq!(held.cable_tensions(), None, "inputs restored after the run");
    let ts = pull.switched_at.expect("switched");
    let (q1, qd1) = held.step(0.0, &z, &z, ts).unwrap();
    held.set_cable_tensions(Some(&[0.8])).unwrap();
    let (q2, _) = held
        .step(ts, q1.as_slice(), qd1.as_slice(), 0.02 - ts)
        .unwrap();
    held.set_cable_tensions(None).unwrap();
    let pulled = nalgebra::DVector::from_vec(pull.last);
    assert!(
        (&q2 - &pulled).amax() < RUN_TOL,
        "{}",
        (&q2 - &pulled).amax()
    );
    assert!(
        (&pulled - &a.q[last]).amax() > 1e-4,
        "the pull changed the motion"
    );
    assert!(matches!(
        held.set_cable_tensions(Some(&[1.0, 2.0])),
        Err(Error::Dynamics(_))
    ));
    assert!(matches!(
        held.step(0.0, &z, &z, -1.0),
        Err(Error::InvalidSetting { key: "dt", .. })
    ));
}

/// `linearize` is the first-order model of the forward dynamics: B against
/// the forward dynamics with the input raised by 1 N (affine in u).
#[test]
fn linearize_matches_the_forward_dynamics() {
    // Affine in u: exact up to the round-off of q̈ (~1e-12 of |q̈|).
    const LIN_TOL: f64 = 1e-9;
    let mut s = sim(&cable_scene("0.5"));
    let n = s.n_dof();
    let q: Vec<f64> = (0..n).map(|i| 0.2 * (i as f64).sin()).collect();
    let qd: Vec<f64> = (0..n).map(|i| 0.1 * (i as f64).cos()).collect();
    let lin = s.linearize(0.0, &q, &qd).unwrap();
    assert_eq!((lin.a.nrows(), lin.b.ncols()), (2 * n, 1));
    let base = s.forward_dynamics(0.0, &q, &qd, None).unwrap();
    s.set_cable_tensions(Some(&[1.5])).unwrap();
    let plus = s.forward_dynamics(0.0, &q, &qd, None).unwrap();
    let fd = plus - &base;
    let b = lin.b.column(0).rows(n, n).into_owned();
    assert!((&fd - &b).amax() < LIN_TOL * base.amax().max(fd.amax()));
}

/// `q_names` says what each coordinate is: setting only the coordinate
/// named `ROD.pN.S` to a value bends exactly piece N of that rod by it —
/// checked on the poses (a circle arc over that piece alone), not on the
/// layout the names are built from.
#[test]
fn q_names_name_the_strain_each_coordinate_sets() {
    let text = "[[rod]]\nname = \"a\"\nlength = 0.4\npieces = 2\nstrains = [\"ky\", \"qx\"]\n\
         section = { shape = \"circle\", radius = 0.01 }\n\
         material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }\n\
         [[rod]]\nname = \"b\"\nlength = 0.3\npieces = 3\nstrains = \"all\"\n\
         base = { position = [0.0, 1.0, 0.0] }\n\
         section = { shape = \"circle\", radius = 0.01 }\n\
         material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }\n";
    let mut s = sim(text);
    let names = s.q_names();
    assert_eq!(names.len(), s.n_dof());
    assert_eq!(names[..4], ["a.p0.ky", "a.p0.qx", "a.p1.ky", "a.p1.qx"]);
    assert_eq!(names[4], "b.p0.kx");
    assert_eq!(names[names.len() - 1], "b.p2.qz");
    let unique: std::collections::HashSet<_> = names.iter().collect();
    assert_eq!(unique.len(), names.len());
    // "b.p1.ky" = κ: rod b straight up to s = 0.1, an arc over [0.1, 0.2].
    let kappa = 3.0;
    let mut q = vec![0.0; s.n_dof()];
    q[names.iter().position(|n| n == "b.p1.ky").unwrap()] = kappa;
    let p = |s: &mut Simulation, x: f64| s.pose("b", x, &q).unwrap().translation;
    let end = p(&mut s, 0.2);
    let want = [
        0.1 + (kappa * 0.1).sin() / kappa,
        1.0,
        -(1.0 - (kappa * 0.1).cos()) / kappa,
    ];
    for i in 0..3 {
        assert!((end[i] - want[i]).abs() < 1e-13, "{end:?} vs {want:?}");
    }
    // Rod a is untouched.
    assert!((p(&mut s, 0.05)[1] - 1.0).abs() < 1e-15);
    assert!((s.pose("a", 0.4, &q).unwrap().translation[0] - 0.4).abs() < 1e-15);
}

/// `lowest_modes` on a model large enough for Lanczos (200 bending
/// coordinates, above `LANCZOS_MIN_DOF`) has the Euler–Bernoulli
/// frequencies with the PCS Ritz error `C_i/N²` (docs/validation.md), as
/// the dense `modes` has at N = 20 above: the same analytic reference, an
/// error 100× smaller.
#[test]
fn lowest_modes_of_a_long_chain_are_euler_bernoulli_frequencies() {
    const RITZ: [f64; 2] = [0.19366, 1.35072];
    const RITZ_REL_TOL: f64 = 0.02;
    const N: usize = 200;
    const { assert!(N >= softrod::limits::LANCZOS_MIN_DOF) };
    // L/r = 10⁴: rotary inertia (∝ (r/L)²) stays far below the Ritz error.
    let text = format!(
        "[[rod]]\nname = \"arm\"\nlength = 1.0\npieces = {N}\nstrains = [\"ky\"]\n\
         section = {{ shape = \"circle\", radius = 0.0001 }}\n\
         material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5 }}\n"
    );
    let mut s = sim(&text);
    let m = s.lowest_modes(2).unwrap();
    assert_eq!(m.equilibrium, softrod::Equilibrium::Rest);
    assert_eq!(m.modes.omega.len(), 2);
    assert_eq!(m.modes.shapes.shape(), (N, 2));
    let (e, r, rho) = (1e7_f64, 1e-4_f64, 1000.0_f64);
    let (i, a) = (PI * r.powi(4) / 4.0, PI * r * r);
    for (k, bl) in [1.875104_f64, 4.694091].iter().enumerate() {
        let exact = bl * bl * (e * i / (rho * a)).sqrt();
        let err = m.modes.omega[k] / exact - 1.0;
        let ritz = RITZ[k] / (N * N) as f64;
        assert!(
            (err / ritz - 1.0).abs() < RITZ_REL_TOL,
            "mode {k}: relative error {err:.4e}, Ritz estimate {ritz:.4e}"
        );
    }
}

/// Under gravity (a sagged equilibrium, all six strains, 40 pieces = 240
/// coordinates) Lanczos and the dense eigensolver — two algorithms on the
/// same linearization — agree on the lowest frequencies; with a
/// world-frame point moment (not conservative: `K_eff` is not symmetric,
/// which Lanczos refuses) `lowest_modes` is the dense solver's symmetric
/// part, as `modes`.
#[test]
fn lowest_modes_agree_with_the_dense_modes() {
    // Lanczos converges θ = 1/ω² to a residual 1e-9 θ; the dense solver's
    // eigenvalues are exact to round-off of a 240 × 240 problem.
    const AGREE: f64 = 1e-7;
    let rod = |extra: &str| {
        format!(
            "[world]\ngravity = [0.0, 0.0, -9.81]\n\
             [[rod]]\nname = \"arm\"\nlength = 0.5\npieces = 40\n\
             section = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}\n{extra}"
        )
    };
    let moment = "[[load]]\nrod = \"arm\"\ns = 0.5\nmoment = [0.0, 0.002, 0.001]\n";
    for (text, symmetric) in [(rod(""), true), (rod(moment), false)] {
        let mut s = sim(&text);
        let dense = s.modes().unwrap();
        let lowest = s.lowest_modes(4).unwrap();
        assert!(matches!(
            lowest.equilibrium,
            softrod::Equilibrium::Statics(_)
        ));
        assert_eq!(
            symmetric,
            dense.modes.asymmetry < 1e-9,
            "{}",
            dense.modes.asymmetry
        );
        for k in 0..4 {
            let (a, b) = (lowest.modes.omega[k], dense.modes.omega[k]);
            let tol = if symmetric { AGREE * b } else { 0.0 };
            assert!((a - b).abs() <= tol, "mode {k}: {a} vs dense {b}");
        }
    }
}
