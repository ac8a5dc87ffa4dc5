//! Resource limits (issue 15): a task that cannot fit in memory is refused
//! before it allocates, with an input error naming the key and the
//! estimate; nothing aborts.

use softrod::limits::dense_bytes;
use softrod::{Error, Flow, Limits, Observer, Sample, Settings, Simulation};
use softrod_scene::Integrator;

fn scene(pieces: usize, integrator: &str) -> String {
    format!(
        "[world]\ngravity = [0.0, 0.0, -9.81]\n\
         [[rod]]\nname = \"arm\"\nlength = 0.5\npieces = {pieces}\nstrains = [\"ky\", \"qx\", \"qz\"]\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5 }}\n\
         [run]\nduration = 0.01\nintegrator = \"{integrator}\"\ndt = 1e-4\n"
    )
}

fn sim(text: &str) -> Simulation {
    Simulation::from_toml(text, "test.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

struct Discard;
impl Observer for Discard {
    fn sample(&mut self, _: Sample<'_>) -> Result<Flow, String> {
        Ok(Flow::Continue)
    }
}

fn too_large(e: Error, key: &str) -> (u64, u64) {
    assert!(e.is_input(), "{e}");
    match e {
        Error::TooLarge {
            key: k,
            estimate,
            limit,
            ..
        } => {
            assert_eq!(k, key);
            (estimate, limit)
        }
        other => panic!("expected TooLarge, got {other}"),
    }
}

/// 100 000 pieces × 3 strains: one dense matrix is 300 000² · 8 B = 720 GB,
/// more than any machine running the tests. Modes and a Rosenbrock run are
/// refused with the estimate; nothing is allocated. Statics needs no dense
/// matrix on an open rod (GMRES on the tangent, docs/theory.md E8–E10): it
/// converges, and its curvature over the middle thirtieth of the rod
/// averages to the coarse 30-piece equilibrium's (solved densely) there, to
/// the coarse model's discretization error (O(h²) ≈ 1e-3).
#[test]
fn a_hundred_thousand_pieces_solve_statics_and_refuse_dense_work() {
    let mut s = sim(&scene(100_000, "rosenbrock"));
    assert_eq!(s.n_dof(), 300_000);
    let one = dense_bytes(1, 300_000);
    assert_eq!(one, 720_000_000_000);
    let fine = s.statics().unwrap();
    assert!(fine.residual < 1e-8, "residual {}", fine.residual);
    let coarse = sim(&scene(30, "rosenbrock")).statics().unwrap();
    // Piece 15 of 30 spans s ∈ [0.25, 0.2667]: pieces 50 000..53 333 of the fine rod.
    let (a, b) = (50_000, 53_333);
    let mean = (a..b).map(|p| fine.q[3 * p]).sum::<f64>() / (b - a) as f64;
    let want = coarse.q[3 * 15];
    eprintln!("ky over [0.25, 0.2667]: fine {mean:.6}, coarse {want:.6}");
    assert!((mean - want).abs() < 1e-3 * want.abs(), "{mean} vs {want}");
    let (est, _) = too_large(s.modes().unwrap_err(), "rod[0].pieces");
    assert!(est >= one);
    let e = s.simulate_with(1e-3, &mut Discard).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("rod[0].pieces") && msg.contains("rosenbrock"),
        "{msg}"
    );
    too_large(e, "rod[0].pieces");
}

/// Explicit methods and generalized-α (structured solve only) allocate no
/// dense matrix: under a limit that refuses one 30×30 matrix, they still run.
#[test]
fn explicit_and_structured_methods_need_no_dense_matrix() {
    // 10 pieces × 3 strains; one dense matrix: 30² · 8 = 7200 B.
    let limits = Limits { memory: 7000 };
    for integrator in ["rk4", "dopri5", "generalized-alpha"] {
        let mut s = sim(&scene(10, integrator));
        s.set_limits(limits);
        s.set_settings(Settings {
            output_every: Some(1e-3),
            ..s.settings().clone()
        })
        .unwrap();
        s.simulate_with(2e-3, &mut Discard)
            .unwrap_or_else(|e| panic!("{integrator}: {e}"));
    }
    let mut s = sim(&scene(10, "rosenbrock"));
    s.set_limits(limits);
    too_large(
        s.simulate_with(2e-3, &mut Discard).unwrap_err(),
        "rod[0].pieces",
    );
    too_large(s.statics().unwrap_err(), "rod[0].pieces");
}

/// `output_every = 1e-9` over 1 s is 10⁹ samples: the output times alone
/// are 8 GB, refused (here under a 1 GB limit) before they are made.
#[test]
fn absurd_output_spacing_is_refused() {
    let mut s = sim(&scene(4, "rk4"));
    s.set_limits(Limits { memory: 1 << 30 });
    s.set_settings(Settings {
        output_every: Some(1e-9),
        ..s.settings().clone()
    })
    .unwrap();
    let (est, _) = too_large(
        s.simulate_with(1.0, &mut Discard).unwrap_err(),
        "run.output_every",
    );
    assert!(est >= 8_000_000_000, "{est}");
    // Kept in memory, every sample costs its q and q̇ as well.
    let (kept, _) = too_large(s.simulate(1.0).unwrap_err(), "run.output_every");
    assert!(kept >= 1_000_000_000 * (2 * 8 * 12), "{kept}");
}

/// `duration = 1e300` with a fixed step: an input error, not a wrapped
/// step budget ("maximum number of steps (98) exceeded").
#[test]
fn absurd_durations_with_a_fixed_step_are_input_errors() {
    let mut s = sim(&scene(4, "rk4"));
    for every in [None, Some(1e299)] {
        s.set_settings(Settings {
            integrator: Integrator::Rk4,
            output_every: every,
            ..s.settings().clone()
        })
        .unwrap();
        let e = s.simulate_with(1e300, &mut Discard).unwrap_err();
        assert!(e.is_input(), "{e}");
        assert!(!e.to_string().contains("maximum number of steps"), "{e}");
    }
}

/// `[run] memory_limit_gib` is the budget: 100 pieces with rosenbrock need
/// 8 dense 300×300 matrices (5.76 MB), refused under 5 MiB and admitted
/// under 6 MiB; the refusal names the setting that raises it.
#[test]
fn the_scene_sets_the_memory_budget() {
    let need = 8 * dense_bytes(1, 300);
    assert_eq!(need, 5_760_000);
    let with = |gib: f64| scene(100, "rosenbrock") + &format!("memory_limit_gib = {gib:e}\n");
    let small = sim(&with(5.0 / 1024.0));
    assert_eq!(small.limits().memory, 5 << 20);
    let e = small.check_run(0.01).unwrap_err();
    assert!(e.to_string().contains("run.memory_limit_gib"), "{e}");
    too_large(e, "rod[0].pieces");
    sim(&with(6.0 / 1024.0)).check_run(0.01).unwrap();
    let bad = Simulation::from_toml(&with(-1.0), "bad.toml").unwrap_err();
    assert!(bad.to_string().contains("run.memory_limit_gib"), "{bad}");
}
