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
    Attachment, Closure, ClosureFrame, ClosureKind, Curve, Joint, Model, Prescribed, Rod,
    max_closure_residual,
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
