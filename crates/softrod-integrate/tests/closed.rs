//! ESDIRK on closed chains with the structured KKT Newton solve
//! (`RodSystem::structured_closures`, docs/theory-derivatives.md CD5–CD8)
//! against the dense reference path (the exact constrained Jacobian,
//! `n×n` LU factorizations), both with the Newton iteration run to 1e-13:
//! the same motion on a four-bar of soft links, a rod pinned at both ends
//! (the cosseratbench catenary's model), a clamped–welded rod, a slider and
//! a closure on a prescribed drive — the structured iteration's fixed point
//! is the constrained dynamics — and the closures hold along both runs.
//! (At the default Newton tolerance the structured iteration stops early
//! on these ringing soft models, which is why it is off by default.)

use nalgebra::DVector;
use softrod_dynamics::{
    Attachment, Closure, ClosureFrame, ClosureKind, Curve, Data, Joint, Model, Prescribed, Rod,
    constraint_residual, max_closure_residual,
};
use softrod_integrate::{
    Integrator, Iteration, NoHooks, Options, RodSystem, Solution, Stats, integrate_second_order,
};
use softrod_kinematics::{Basis, RodGeometry, straight};
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::{Drag, Material, RodProperties, Section};

/// A soft rod along x from `x0` (all six strains).
fn rod(name: &str, length: f64, pieces: usize, x0: f64) -> Rod {
    let g = RodGeometry::uniform(
        length,
        pieces,
        Basis::all(),
        straight(),
        Pose::new(Mat3::identity(), Vec3::new(x0, 0.0, 0.0)),
    )
    .unwrap();
    let mat = Material::with_poisson(1000.0, 1e6, 0.5, 0.0).unwrap();
    let body = RodProperties::new(Section::Circle { radius: 0.01 }, mat, length).unwrap();
    Rod::new(name, g, body)
}

fn world(x: f64) -> ClosureFrame {
    ClosureFrame::world(Pose::new(Mat3::identity(), Vec3::new(x, 0.0, 0.0)))
}

fn tip(name: &str) -> ClosureFrame {
    ClosureFrame::on(name, None, Pose::identity())
}

/// The models, each holding its closures at `q = 0`.
fn models() -> Vec<(&'static str, Model)> {
    let gravity = [0.0, 0.0, -9.81];
    let four_bar = Model::builder()
        .rod_on(
            rod("a", 0.3, 2, 0.0),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
        )
        .rod_on(
            rod("b", 0.15, 2, 0.15),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
        )
        .gravity(gravity)
        .closure(Closure::new("tip", ClosureKind::Ball, tip("a"), tip("b")))
        .build()
        .unwrap();
    let mut cable = rod("cable", 0.4, 6, 0.0);
    cable.drag = Some(Drag {
        translational: 0.2,
        rotational: 1e-5,
    });
    let pinned = Model::builder()
        .rod_on(cable, Attachment::world_joint(Joint::spherical()))
        .gravity(gravity)
        .closure(Closure::new(
            "pin",
            ClosureKind::Ball,
            tip("cable"),
            world(0.4),
        ))
        .build()
        .unwrap();
    let welded = Model::builder()
        .rod(rod("beam", 0.3, 4, 0.0))
        .gravity(gravity)
        .closure(Closure::new(
            "weld",
            ClosureKind::Weld,
            tip("beam"),
            world(0.3),
        ))
        .build()
        .unwrap();
    let slider = Model::builder()
        .rod_on(
            rod("arm", 0.3, 4, 0.0),
            Attachment::world_joint(Joint::spherical()),
        )
        .gravity(gravity)
        .closure(Closure::new(
            "slide",
            ClosureKind::Slider {
                axis: Vec3::new(1.0, 0.0, 0.0),
            },
            tip("arm"),
            world(0.3),
        ))
        .build()
        .unwrap();
    let drive = Prescribed::new(vec![Curve::Sine {
        amplitude: 0.3,
        frequency: 2.0,
        phase: 0.0,
        offset: 0.0,
    }]);
    let driven = Model::builder()
        .rod_on(
            rod("shaft", 0.3, 4, 0.0),
            Attachment::world_joint(Joint::revolute([1.0, 0.0, 0.0]).with_prescribed(drive)),
        )
        .gravity(gravity)
        .closure(Closure::new(
            "bearing",
            ClosureKind::Ball,
            tip("shaft"),
            world(0.3),
        ))
        .build()
        .unwrap();
    vec![
        ("four-bar", four_bar),
        ("pinned", pinned),
        ("welded", welded),
        ("slider", slider),
        ("driven", driven),
    ]
}

fn run(model: &Model, structured: bool, t1: f64) -> (Solution, Stats, f64) {
    let mut sys = RodSystem::new(model.clone());
    sys.structured_closures = structured;
    let n = model.n_dof();
    let z = DVector::zeros(n);
    let mut opts = Options::tol(1e-8, 1e-10);
    opts.iteration = Iteration::Newton {
        tol: 1e-13,
        max_iter: 400,
    };
    opts.t_eval = Some((0..=20).map(|k| t1 * k as f64 / 20.0).collect());
    let sol = integrate_second_order(
        &mut sys,
        Integrator::Esdirk,
        (0.0, t1),
        &z,
        &z,
        &opts,
        &mut NoHooks,
    )
    .unwrap();
    let mut residual: f64 = 0.0;
    for (t, y) in sol.t.iter().zip(&sol.y) {
        sys.model.set_time(&mut sys.data, *t);
        residual = residual
            .max(max_closure_residual(&sys.model, &mut sys.data, &y.as_slice()[..n]).unwrap());
    }
    let stats = sol.stats;
    (sol, stats, residual)
}

#[test]
fn structured_and_dense_newton_give_the_same_motion() {
    let t1 = 0.1;
    for (name, model) in models() {
        let (a, sa, ra) = run(&model, true, t1);
        let (b, sb, rb) = run(&model, false, t1);
        let scale = b.y_final.amax();
        assert!(scale > 1e-3, "{name}: the model moved ({scale:e})");
        let diff = (&a.y_final - &b.y_final).amax();
        // Measured 8e-5–3.3e-4 of 29–65 (the two paths take other steps).
        assert!(diff < 2e-5 * scale, "{name}: {diff:e} of {scale:e}");
        // The structured path ran: it evaluates a dense Jacobian only when
        // its Newton iteration fails, the dense path one per update.
        assert!(
            sa.jacobian_evaluations < sb.jacobian_evaluations,
            "{name}: {} dense Jacobians structured, {} dense",
            sa.jacobian_evaluations,
            sb.jacobian_evaluations
        );
        // The closures hold (Baumgarte-stabilized) along both runs.
        for r in [ra, rb] {
            assert!(r < 1e-6, "{name}: closure residual {r:e} m");
        }
    }
}

/// A quasi-static settle on a closed chain (docs/theory-derivatives.md
/// CD10): a soft cable pinned at both ends (spherical joint, ball
/// closure: the cosseratbench catenary's model) sagging under gravity with
/// heavy drag, ESDIRK at the loose tolerances of a settle (`rtol = 1e-3`,
/// `atol = 1e-5`) against Radau IIA at `rtol = 1e-10`. Its steps grow to
/// seconds once the drag has damped the motion; with
/// `Options::steps_to_outputs` the outputs are step ends (CD10), not the
/// quintic Hermite across such a step: once settled they
/// follow the reference to a few tenths of a micrometre and the end stays
/// on its pin.
#[test]
fn esdirk_settles_a_pinned_cable_like_a_tight_radau_run() {
    let mut cable = rod("cable", 0.8, 10, 0.0);
    // Critical for the first sag mode or so: settled within ~3 s.
    cable.drag = Some(Drag {
        translational: 3.0,
        rotational: 1e-5,
    });
    let model = Model::builder()
        .rod_on(cable, Attachment::world_joint(Joint::spherical()))
        .gravity([0.0, 0.0, -9.81])
        .closure(Closure::new(
            "pin",
            ClosureKind::Ball,
            tip("cable"),
            world(0.7),
        ))
        .build()
        .unwrap();
    let n = model.n_dof();
    // Start bent so the cable spans 0.7 m: a uniform curvature in the
    // vertical plane found by a few secant steps on the chord.
    let chord = |k: f64| 2.0 * (0.4 * k).sin() / k;
    let (mut a, mut b) = (1.0, 2.0);
    for _ in 0..60 {
        let c = b - (chord(b) - 0.7) * (b - a) / (chord(b) - chord(a));
        (a, b) = (b, c);
        if (chord(b) - 0.7).abs() < 1e-15 {
            break;
        }
    }
    let mut q0 = DVector::zeros(n);
    // Spherical joint first (3 coordinates), then six strains per piece
    // (kx, ky, kz, qx, qy, qz): ky bends in the x-z plane; the base is
    // turned down by half the arc's angle about y.
    q0[1] = 0.4 * b;
    for p in 0..10 {
        q0[3 + 6 * p + 1] = -b;
    }
    let t1 = 4.0;
    let times: Vec<f64> = (0..=80).map(|k| t1 * k as f64 / 80.0).collect();
    let solve = |integrator, rtol: f64, atol: f64, steps_to_outputs: bool| {
        let mut sys = RodSystem::new(model.clone());
        let mut opts = Options::tol(rtol, atol);
        opts.t_eval = Some(times.clone());
        opts.steps_to_outputs = steps_to_outputs;
        let z = DVector::zeros(n);
        let sol = integrate_second_order(
            &mut sys,
            integrator,
            (0.0, t1),
            &q0,
            &z,
            &opts,
            &mut NoHooks,
        )
        .unwrap();
        let mut gaps = Vec::new();
        for y in &sol.y {
            gaps.push(max_closure_residual(&sys.model, &mut sys.data, &y.as_slice()[..n]).unwrap());
        }
        (sol, gaps)
    };
    // The cable's points at s = 0.2, 0.4, 0.6 m, read as the residuals of
    // ball "probes" to the world origin on a copy of the model that serves
    // only to measure.
    let mut probes = Model::builder()
        .rod_on(
            rod("cable", 0.8, 10, 0.0),
            Attachment::world_joint(Joint::spherical()),
        )
        .closure(Closure::new(
            "pin",
            ClosureKind::Ball,
            tip("cable"),
            world(0.7),
        ));
    for (name, s) in [("p1", 0.2), ("p2", 0.4), ("p3", 0.6)] {
        probes = probes.closure(Closure::new(
            name,
            ClosureKind::Ball,
            ClosureFrame::on("cable", Some(s), Pose::identity()),
            world(0.0),
        ));
    }
    let probes = probes.build().unwrap();
    let mut probe_data = Data::new(&probes);
    let mut points = |y: &DVector<f64>| -> DVector<f64> {
        constraint_residual(&probes, &mut probe_data, &y.as_slice()[..n]).unwrap()
    };
    let (reference, _) = solve(Integrator::Radau5, 1e-10, 1e-12, false);
    let (esdirk, gaps) = solve(Integrator::Esdirk, 1e-3, 1e-5, true);
    assert!(
        gaps[0] < 1e-12,
        "the start holds the closure: {:e}",
        gaps[0]
    );
    let (mut late, mut late_gap): (f64, f64) = (0.0, 0.0);
    for (k, (a, b)) in esdirk.y.iter().zip(&reference.y).enumerate() {
        if times[k] >= 2.0 {
            late = late.max((points(a) - points(b)).amax());
            late_gap = late_gap.max(gaps[k]);
        }
    }
    // Settled: the points' speed over the last output interval [m/s]
    // (cosseratbench's settling residual), the reference's 3.4e-8.
    let last = esdirk.y.len() - 1;
    let dt = times[last] - times[last - 1];
    let speed = (points(&esdirk.y[last]) - points(&esdirk.y[last - 1])).amax() / dt;
    // Measured: 4.2e-7 m after t = 2 s, a speed of 5.7e-9 m/s in 363 steps;
    // with the outputs taken from the Hermite across the steps (before
    // CD10) 4.4e-5 m.
    assert!(
        late < 2e-6,
        "after t = 2 s the points are {late:e} m off the reference"
    );
    assert!(speed < 1e-7, "settling speed {speed:e} m/s");
    assert!(late_gap < 1e-6, "closure gap after t = 2 s {late_gap:e} m");
}

/// `Options::project_state` (docs/theory.md D121): ESDIRK at a loose
/// tolerance with the state projected onto the closures after each step.
/// At every step end each closure holds to the projection's tolerance
/// (`1e-11 ℓ`, measured by `max_closure_residual`, not by the projection),
/// where the same run without it drifts by what Baumgarte's stabilization
/// leaves; and the projected run ends no farther from the tight reference
/// (`run`: rtol 1e-8, Newton to 1e-13) than twice the unprojected one.
#[test]
fn projected_esdirk_holds_the_closures_at_every_step_end() {
    let t1 = 0.1;
    for (name, model) in models() {
        let n = model.n_dof();
        let (reference, _, _) = run(&model, false, t1);
        let loose = |project: bool| {
            let mut sys = RodSystem::new(model.clone());
            let mut opts = Options::tol(1e-3, 1e-5);
            opts.project_state = project;
            let z = DVector::zeros(n);
            let sol = integrate_second_order(
                &mut sys,
                Integrator::Esdirk,
                (0.0, t1),
                &z,
                &z,
                &opts,
                &mut NoHooks,
            )
            .unwrap();
            let mut worst: f64 = 0.0;
            for (t, y) in sol.t.iter().zip(&sol.y) {
                sys.model.set_time(&mut sys.data, *t);
                let r = max_closure_residual(&sys.model, &mut sys.data, &y.as_slice()[..n]);
                worst = worst.max(r.unwrap());
            }
            let error = (&sol.y_final - &reference.y_final).amax();
            (sol.t.len(), worst, error)
        };
        let (steps, held, projected) = loose(true);
        let (_, drift, plain) = loose(false);
        assert!(steps > 5, "{name}: {steps} step ends");
        let length = model
            .rods()
            .iter()
            .map(|r| r.spec.geometry.length())
            .fold(0.0, f64::max);
        assert!(
            held <= 1e-11 * length,
            "{name}: {held:e} m after projection"
        );
        assert!(
            drift > held,
            "{name}: unprojected {drift:e} m, projected {held:e} m"
        );
        assert!(
            projected <= 2.0 * plain + 1e-9,
            "{name}: end error {projected:e} projected, {plain:e} not"
        );
    }
}

/// A projection that cannot converge is counted, not passed over: a
/// Kirchhoff rod (no stretch) of length 0.3 m pinned at its base, its tip
/// asked by a ball closure to reach a point 0.5 m away. No bent shape
/// reaches it (the tip is at most 0.3 m from the base), so the positions'
/// Newton iteration gives up; the state is left as it was and
/// `projection_misses` says when and how far apart the loop was: the
/// residual there is the tip's distance from the point, 0.2 m in the
/// straight start.
#[test]
fn a_projection_that_cannot_converge_is_counted() {
    use softrod_integrate::{ProjectionMisses, SecondOrderSystem};
    let g = RodGeometry::uniform(0.3, 3, Basis::kirchhoff(), straight(), Pose::identity()).unwrap();
    let mat = Material::with_poisson(1000.0, 1e6, 0.5, 0.0).unwrap();
    let body = RodProperties::new(Section::Circle { radius: 0.01 }, mat, 0.3).unwrap();
    let model = Model::builder()
        .rod_on(
            Rod::new("r", g, body),
            Attachment::world_joint(Joint::spherical()),
        )
        .closure(Closure::new("far", ClosureKind::Ball, tip("r"), world(0.5)))
        .build()
        .unwrap();
    let n = model.n_dof();
    let mut sys = RodSystem::new(model);
    assert_eq!(sys.projection_misses(), ProjectionMisses::default());
    let (mut q, mut qd) = (DVector::zeros(n), DVector::from_element(n, 0.1));
    let (q0, qd0) = (q.clone(), qd.clone());
    for t in [0.25, 0.5] {
        let moved = sys.project(t, &mut q, &mut qd).unwrap();
        assert!(!moved);
    }
    assert_eq!((q, qd), (q0, qd0), "the state is left as it was");
    let m = sys.projection_misses();
    assert_eq!((m.count, m.first_t), (2, 0.25));
    assert!((m.largest_residual - 0.2).abs() < 1e-12, "{m:?}");
    sys.reset_projection_misses();
    assert_eq!(sys.projection_misses().count, 0);
}
