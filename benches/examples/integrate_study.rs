//! The integrator study of issue 13 at full size (docs/performance.md,
//! section "softrod-integrate"): whole runs, wall time of the integration
//! (fastest of `REPS` runs), tip error = the largest distance over 1001
//! outputs on [0, t1] to a converged run of the same model (DOPRI5 at rtol
//! 1e-10, atol 1e-12; Radau IIA at 1e-13 for the examples, stiff and
//! damped, where DOPRI5 would need millions of steps), cached in
//! `target/integrate-study/`.
//!
//! `cargo run --release -p softrod-benches --example integrate_study` runs
//! every section; `STUDY=rtol,methods,wire,examples,big` picks some,
//! `REPS=3` sets the repetitions.
//!
//! * `rtol`: error versus rtol of the recommended setting
//!   (`Recommended::tolerance`) on the planar 8-piece release (derivations
//!   §8(h)) and the 3-D 32-piece release, rtol 1e-3 … 1e-8;
//! * `methods`: every method at settings from loose to tight, the loosest
//!   that meets the accuracy target (planar ≤ 1e-5 m, 3-D ≤ 1e-4 m) and its
//!   wall time;
//! * `wire`: the steel wire (10 pieces, all strains, undamped, 1 s) at rtol
//!   1e-3 … 1e-8;
//! * `examples`: every shipped example (`examples/*.toml`, full duration)
//!   at its own rtol and at 1e-3 … 1e-8;
//! * `big`: 0.01 s of the 3-D release with 500 pieces.

use std::path::Path;
use std::time::Instant;

use nalgebra::DVector;
use softrod_benches::rod_scenes::{
    TipProbe, cache_dir, max_error, planar_release, release_3d, steel_wire, times,
};
use softrod_dynamics::Model;
use softrod_integrate::{
    Callbacks, Control, Integrator, Options, Recommended, RodJacobian, RodSystem, Stats, Status,
    integrate_second_order,
};

fn env<T: std::str::FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

/// A model with its initial state and duration.
struct Case {
    name: String,
    model: Model,
    q0: DVector<f64>,
    qd0: DVector<f64>,
    t1: f64,
}

impl Case {
    fn rest(name: &str, model: Model, t1: f64) -> Self {
        let n = model.n_dof();
        Self {
            name: name.into(),
            model,
            q0: DVector::zeros(n),
            qd0: DVector::zeros(n),
            t1,
        }
    }
}

/// One measured run.
struct Run {
    tips: Vec<[f64; 3]>,
    stats: Stats,
    wall: f64,
}

/// Runs `setting` on `case` (fastest wall of `reps`), stopped beyond
/// `budget` wall seconds.
fn measure(case: &Case, setting: &Recommended, reps: usize, budget: f64) -> Result<Run, String> {
    let ts = times(case.t1, 1000);
    let opts = Options {
        t_eval: Some(ts),
        max_steps: usize::MAX,
        ..setting.options.clone()
    };
    let mut best: Option<Run> = None;
    for _ in 0..reps.max(1) {
        let mut sys = RodSystem::new(case.model.clone());
        setting.configure(&mut sys);
        let start = Instant::now();
        let mut hooks = Callbacks::new().on_step(move |_, _: &mut RodSystem| {
            if start.elapsed().as_secs_f64() > budget {
                Control::Stop
            } else {
                Control::Continue
            }
        });
        let sol = integrate_second_order(
            &mut sys,
            setting.integrator,
            (0.0, case.t1),
            &case.q0,
            &case.qd0,
            &opts,
            &mut hooks,
        )
        .map_err(|e| e.to_string())?;
        let wall = start.elapsed().as_secs_f64();
        if sol.status != Status::Completed {
            return Err(format!(
                "over the budget of {budget} s at t = {:.4} ({} steps)",
                sol.t_final, sol.stats.steps
            ));
        }
        if best.as_ref().is_none_or(|b| wall < b.wall) {
            let mut probe = TipProbe::new(&case.model);
            best = Some(Run {
                tips: sol.y.iter().map(|y| probe.tip(y)).collect(),
                stats: sol.stats,
                wall,
            });
        }
        if wall > 2.0 {
            break;
        }
    }
    Ok(best.unwrap())
}

fn setting(method: Integrator, options: Options, jacobian: RodJacobian) -> Recommended {
    Recommended {
        integrator: method,
        options,
        jacobian,
    }
}

/// The cached converged tip trajectory of `case`.
fn reference(case: &Case, radau: bool) -> Vec<[f64; 3]> {
    let file = cache_dir().join(format!(
        "{}_{}_{}_{}.json",
        case.name,
        case.model.n_dof(),
        case.t1,
        if radau {
            "radau5_1e-13"
        } else {
            "dopri5_1e-10"
        }
    ));
    if let Ok(text) = std::fs::read_to_string(&file)
        && let Ok(tips) = serde_json::from_str::<Vec<[f64; 3]>>(&text)
    {
        return tips;
    }
    let s = if radau {
        setting(
            Integrator::Radau5,
            Options::tol(1e-13, 1e-13),
            RodJacobian::Exact,
        )
    } else {
        setting(
            Integrator::Dopri5,
            Options::tol(1e-10, 1e-12),
            RodJacobian::Exact,
        )
    };
    let r = measure(case, &s, 1, f64::INFINITY).unwrap();
    println!(
        "(reference for {}: {} steps, {:.1} s)",
        case.name, r.stats.steps, r.wall
    );
    std::fs::create_dir_all(cache_dir()).unwrap();
    std::fs::write(&file, serde_json::to_string(&r.tips).unwrap()).unwrap();
    r.tips
}

fn row(label: &str, setting: &str, r: &Result<Run, String>, reference: &[[f64; 3]]) -> String {
    match r {
        Ok(r) => format!(
            "| {label} | {setting} | {:.2e} | {} | {} | {} | {} | {:.3} |",
            max_error(&r.tips, reference),
            r.stats.steps,
            r.stats.rejected_steps,
            r.stats.rhs_evaluations,
            r.stats.jacobian_evaluations,
            r.wall
        ),
        Err(e) => format!("| {label} | {setting} | failed: {e} | | | | | |"),
    }
}

const HEADER: &str = "| scene | setting | tip error [m] | steps | rejected | evaluations | Jacobians | wall [s] |\n|---|---|---|---|---|---|---|---|";

const RTOLS: [f64; 6] = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8];

fn study_rtol(reps: usize) {
    println!("\n### Error versus rtol, recommended setting\n\n{HEADER}");
    for case in [
        Case::rest("planar", planar_release(), 1.0),
        Case::rest("3d", release_3d(32), 1.0),
    ] {
        let rf = reference(&case, false);
        for rtol in RTOLS {
            let r = measure(&case, &Recommended::tolerance(rtol), reps, 300.0);
            println!("{}", row(&case.name, &format!("rtol {rtol:e}"), &r, &rf));
        }
    }
}

fn study_methods(reps: usize) {
    let budget = env("BUDGET", 120.0);
    for (case, target) in [
        (Case::rest("planar", planar_release(), 1.0), 1e-5),
        (Case::rest("3d", release_3d(32), 1.0), 1e-4),
    ] {
        let rf = reference(&case, false);
        println!(
            "\n### {} release, target {target:e} m: the loosest setting of each method that meets it\n\n{HEADER}",
            case.name
        );
        let tol = |m: Integrator, j: RodJacobian, r: f64, a: f64| setting(m, Options::tol(r, a), j);
        let e = RodJacobian::Exact;
        let el = RodJacobian::ElasticOnly;
        let rtols = [
            1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7,
        ];
        let dts = [4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4, 6e-5];
        let families: Vec<(&str, Vec<(String, Recommended)>)> = vec![
            (
                "ESDIRK4(3)6L[2]SA (recommended)",
                rtols
                    .iter()
                    .map(|&r| (format!("rtol = atol = {r:e}"), Recommended::tolerance(r)))
                    .collect(),
            ),
            (
                "Radau IIA 5, exact J",
                rtols
                    .iter()
                    .map(|&r| {
                        (
                            format!("rtol = atol = {r:e}"),
                            tol(Integrator::Radau5, e, r, r),
                        )
                    })
                    .collect(),
            ),
            (
                "ROS34PW2, W = M⁻¹K (refreshed)",
                rtols
                    .iter()
                    .map(|&r| {
                        (
                            format!("rtol {r:e}, atol {:e}", r * 1e-2),
                            tol(Integrator::Rosenbrock, el, r, r * 1e-2),
                        )
                    })
                    .collect(),
            ),
            (
                "DOPRI5",
                [1e-3, 1e-4, 1e-5, 1e-6]
                    .iter()
                    .map(|&r| {
                        (
                            format!("rtol {r:e}, atol {:e}", r * 1e-3),
                            tol(Integrator::Dopri5, e, r, r * 1e-3),
                        )
                    })
                    .collect(),
            ),
            (
                "linearly implicit gen-α ρ∞ 0.9, W = M⁻¹K (fixed step)",
                dts.iter()
                    .map(|&dt| (format!("dt {dt:e}"), Recommended::fixed_step(dt)))
                    .collect(),
            ),
            (
                "ESDIRK, fixed step",
                dts.iter()
                    .map(|&dt| {
                        (
                            format!("dt {dt:e}"),
                            Recommended {
                                options: Options {
                                    step: softrod_integrate::StepControl::Fixed(dt),
                                    ..Recommended::tolerance(1e-6).options
                                },
                                ..Recommended::tolerance(1e-6)
                            },
                        )
                    })
                    .collect(),
            ),
        ];
        for (family, settings) in families {
            let mut met = false;
            for (label, s) in settings {
                let r = measure(&case, &s, reps, budget);
                let ok = r.as_ref().is_ok_and(|r| max_error(&r.tips, &rf) <= target);
                let over = matches!(&r, Err(e) if e.contains("budget"));
                println!(
                    "{}",
                    row(
                        family,
                        &format!("{label}{}", if ok { " ✓" } else { "" }),
                        &r,
                        &rf
                    )
                );
                if ok || over {
                    met = ok;
                    break;
                }
            }
            if !met {
                println!(
                    "| {family} | (target not met within the budget of {budget} s) | | | | | | |"
                );
            }
        }
    }
}

fn study_wire(reps: usize) {
    println!(
        "\n### Steel wire (10 pieces, all strains, undamped, 1 s), recommended setting\n\n{HEADER}"
    );
    let case = Case::rest("wire", steel_wire(10), 1.0);
    // Radau IIA at 1e-13: DOPRI5 at 1e-10 did not finish in 20 min (the
    // shear-rotation modes near 4e6 rad/s hold it below 1e-6 s); Radau IIA at
    // 1e-11 is within the distance printed here of it.
    let rf = reference(&case, true);
    let coarse = measure(
        &case,
        &setting(
            Integrator::Radau5,
            Options::tol(1e-11, 1e-11),
            RodJacobian::Exact,
        ),
        1,
        f64::INFINITY,
    )
    .unwrap();
    println!(
        "(Radau IIA at 1e-11 against the reference at 1e-13: {:.2e} m)",
        max_error(&coarse.tips, &rf)
    );
    for rtol in RTOLS {
        let r = measure(&case, &Recommended::tolerance(rtol), reps, 300.0);
        println!("{}", row("steel wire", &format!("rtol {rtol:e}"), &r, &rf));
    }
}

fn study_examples(reps: usize) {
    println!("\n### Shipped examples (full duration), recommended setting\n\n{HEADER}");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    let extreme = dir.join("extreme");
    if let Ok(rd) = std::fs::read_dir(&extreme) {
        paths.extend(
            rd.map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "toml")),
        );
    }
    paths.sort();
    for path in paths {
        let (scene, _) = softrod_scene::Scene::from_path(&path).unwrap();
        if scene.run.mode != softrod_scene::Mode::Dynamics {
            continue;
        }
        let built = scene.build().unwrap();
        let name = path
            .strip_prefix(&dir)
            .unwrap()
            .to_string_lossy()
            .replace('/', "_")
            .replace(".toml", "");
        let case = Case {
            name: name.clone(),
            model: built.model,
            q0: built.q0,
            qd0: built.qd0,
            t1: scene.run.duration,
        };
        let rf = reference(&case, true);
        let mut rtols = vec![scene.run.rtol];
        rtols.extend(RTOLS);
        for rtol in rtols {
            let r = measure(&case, &Recommended::tolerance(rtol), reps, 300.0);
            println!("{}", row(&name, &format!("rtol {rtol:e}"), &r, &rf));
        }
    }
}

fn study_big(reps: usize) {
    println!(
        "\n### 0.01 s of the 3-D release, 500 pieces (n_dof 3000), recommended setting\n\n{HEADER}"
    );
    let case = Case::rest("3d500", release_3d(500), 0.01);
    let rf = reference(&case, false);
    for rtol in [1e-3, 1e-6] {
        let r = measure(&case, &Recommended::tolerance(rtol), reps, 300.0);
        println!(
            "{}",
            row("3-D, 500 pieces", &format!("rtol {rtol:e}"), &r, &rf)
        );
    }
}

fn main() {
    let which: String = env("STUDY", "rtol,methods,wire,examples,big".to_string());
    let reps: usize = env("REPS", 3);
    for s in which.split(',') {
        match s {
            "rtol" => study_rtol(reps),
            "methods" => study_methods(reps),
            "wire" => study_wire(reps),
            "examples" => study_examples(reps),
            "big" => study_big(reps),
            other => panic!("unknown study {other}"),
        }
    }
}
