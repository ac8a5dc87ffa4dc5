//! Analytic derivatives on articulated models (docs/theory-derivatives.md
//! §7, D76–D80) against fourth-order central differences of the production
//! tree inverse and forward dynamics (independent code paths): every joint
//! type with springs and dampers, bodies with offset centres of mass and
//! loads, branches, children inside pieces, a prescribed joint, every rod
//! force term; straight, curved and several-turn states.

mod common;

use common::id_differences as fd;
use common::{
    Lcg, Shape, Terms, bases, rel, richardson_jacobians, robot, rod_spec, state, tilted_base,
};
use softrod_dynamics::*;
use softrod_kinematics::Basis;
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::LoadFrame;

/// See `id_derivatives.rs`: the differences are good to ~1e-13 of the
/// largest entry once the exact `K`, `D` are removed; a missing or wrong
/// term of the derivation shows at O(1e-4 … 1).
const FD_TOL: f64 = 1e-8;

/// A tree with every kind of node and attachment: a rod with `terms` on a
/// sprung, damped revolute joint; a body inside its second piece (dead and
/// follower loads when `terms.dead_point`); a rod with mixed bases on a
/// universal joint inside its first piece, carrying a body on a spherical
/// joint inside its piece; at its tip a rod on a prescribed prismatic joint
/// (a sine) with a body on a free joint at its tip.
fn loaded_tree(terms: Terms) -> Model {
    let spring = |j: Joint, k: usize| {
        j.with_stiffness(&vec![0.2; k])
            .with_damping(&vec![if terms.damping { 0.01 } else { 0.0 }; k])
            .with_rest(&vec![0.05; k])
    };
    let trunk = rod_spec(
        "trunk",
        &Shape::new(3, vec![Basis::all()]),
        terms,
        tilted_base(),
    );
    let mut branch_shape = Shape::new(2, bases());
    branch_shape.length = 0.2;
    branch_shape.tapered = true;
    let branch = rod_spec("branch", &branch_shape, terms, Pose::identity());
    let mut tail_shape = Shape::new(2, vec![Basis::all()]);
    tail_shape.length = 0.15;
    let tail = rod_spec("tail", &tail_shape, terms, Pose::identity());
    let mut mid = BodySpec::new(
        "mid",
        0.02,
        Mat3::new(1e-6, 2e-7, 0.0, 2e-7, 2e-6, 1e-7, 0.0, 1e-7, 3e-6),
    );
    mid.center_of_mass = Vec3::new(0.004, -0.01, 0.003);
    mid.base = Pose::new(
        *nalgebra::Rotation3::from_euler_angles(0.3, 0.1, -0.2).matrix(),
        Vec3::new(0.0, 0.01, 0.0),
    );
    if terms.dead_point {
        mid.loads = vec![
            BodyLoad {
                force: Vec3::new(0.02, -0.01, 0.03),
                moment: Vec3::new(0.001, 0.0, -0.002),
                frame: LoadFrame::World,
            },
            BodyLoad {
                force: Vec3::new(-0.01, 0.02, 0.0),
                moment: Vec3::new(0.0, 0.001, 0.0),
                frame: LoadFrame::Body,
            },
        ];
    }
    let mut bud = BodySpec::principal("bud", 0.01, [1e-6, 1.5e-6, 2e-6]);
    bud.center_of_mass = Vec3::new(0.0, 0.0, 0.005);
    let mut cap = BodySpec::principal("cap", 0.015, [2e-6, 1e-6, 1.5e-6]);
    cap.center_of_mass = Vec3::new(0.003, 0.0, 0.0);
    let drive =
        Joint::prismatic([0.0, 1.0, 0.3]).with_prescribed(Prescribed::new(vec![Curve::Sine {
            amplitude: 0.02,
            frequency: 1.3,
            phase: 0.4,
            offset: 0.01,
        }]));
    Model::with_elements(
        vec![
            Element::Rod(
                trunk,
                Attachment::world_joint(spring(Joint::revolute([0.0, 1.0, 0.3]), 1)),
            ),
            Element::Body(mid, Attachment::to("trunk", Joint::fixed()).at(0.21)),
            Element::Rod(
                branch,
                Attachment::to(
                    "trunk",
                    spring(Joint::universal([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]), 2),
                )
                .at(0.05),
            ),
            Element::Body(
                bud,
                Attachment::to("branch", spring(Joint::spherical(), 3)).at(0.13),
            ),
            Element::Rod(tail, Attachment::to("trunk", drive)),
            Element::Body(cap, Attachment::to("tail", spring(Joint::free(), 6))),
        ],
        common::gravity(terms),
        4,
    )
    .unwrap()
}

/// The analytic pair against differences, `K` and `D` removed; `work.tau`
/// against the production `τ`.
fn check(m: &Model, t: f64, q: &[f64], qd: &[f64], qdd: &[f64], label: &str) -> f64 {
    let mut work = IdDerivatives::new(m);
    inverse_dynamics_derivatives(m, &mut work, t, q, qd, qdd).unwrap();
    let tau = inverse_dynamics(m, &mut Data::new(m), t, q, qd, qdd)
        .unwrap()
        .clone();
    let e_tau = (&work.tau - &tau).amax() / tau.amax();
    assert!(e_tau < 1e-12, "{label}: τ {e_tau:e}");
    let (fq, fv) = fd(m, t, q, qd, qdd);
    let (k, d) = (stiffness_matrix(m), damping_matrix(m));
    let e1 = rel(&(&work.dtau_dq - &k), &(&fq - &k));
    let e2 = rel(&(&work.dtau_dqd - &d), &(&fv - &d));
    assert!(e1 < FD_TOL, "{label}: ∂τ/∂q − K: {e1:e}");
    assert!(e2 < FD_TOL, "{label}: ∂τ/∂q̇ − D: {e2:e}");
    e1.max(e2)
}

#[test]
fn every_joint_type_bodies_and_branches() {
    // common::robot: revolute, spherical, universal, prismatic (inside a
    // piece), free joints with springs and dampers, bodies with offset
    // centres of mass and a follower load, a second branch, a rod at
    // another's base, a body welded to a body.
    let mut rng = Lcg(5);
    for (gravity, damping, tree, loads) in [
        (true, true, true, true),
        (false, false, false, false),
        (true, false, true, false),
    ] {
        let m = robot(gravity, damping, tree, loads);
        let n = m.n_dof();
        let (q, qd, qdd) = state(&mut rng, n, 0.4, 1.5, 3.0);
        let label = format!("robot g{gravity} d{damping} tree{tree} loads{loads}");
        let e = check(&m, 0.0, &q, &qd, &qdd, &label);
        println!("{label}: {e:.1e}");
    }
}

#[test]
fn inside_attachments_prescribed_joint_and_every_rod_term() {
    let mut rng = Lcg(9);
    for (terms, label) in [
        (Terms::NONE, "no forces"),
        (
            Terms {
                gravity: true,
                ..Terms::NONE
            },
            "gravity",
        ),
        (Terms::ALL, "every term"),
    ] {
        let m = loaded_tree(terms);
        let n = m.n_dof();
        assert!(m.n_prescribed() == 1 && m.is_articulated());
        for t in [0.0, 0.37] {
            let (q, qd, qdd) = state(&mut rng, n, 0.3, 1.0, 2.0);
            let e = check(&m, t, &q, &qd, &qdd, &format!("{label}, t = {t}"));
            println!("{label}, t = {t}: {e:.1e}");
        }
    }
}

/// Each dead load's own part (the `𝒴` composites and receivers): the model
/// with the term minus the model without it, analytic against differences.
#[test]
fn dead_loads_own_contribution() {
    let with = loaded_tree(Terms {
        gravity: true,
        dead_point: true,
        distributed: true,
        ..Terms::NONE
    });
    let without = loaded_tree(Terms {
        gravity: true,
        ..Terms::NONE
    });
    let n = with.n_dof();
    let (q, qd, qdd) = state(&mut Lcg(3), n, 0.3, 1.0, 2.0);
    let analytic = |m: &Model| {
        let mut work = IdDerivatives::new(m);
        inverse_dynamics_derivatives(m, &mut work, 0.2, &q, &qd, &qdd).unwrap();
        work.dtau_dq.clone()
    };
    let own_a = analytic(&with) - analytic(&without);
    let own_f = fd(&with, 0.2, &q, &qd, &qdd).0 - fd(&without, 0.2, &q, &qd, &qdd).0;
    assert!(own_f.amax() > 1e-4, "the loads matter: {:e}", own_f.amax());
    let e = rel(&own_a, &own_f);
    assert!(e < FD_TOL, "dead loads' own ∂τ/∂q: {e:e}");
}

#[test]
fn straight_rest_and_several_turns() {
    let m = loaded_tree(Terms::ALL);
    let n = m.n_dof();
    let zero = vec![0.0; n];
    // At q = 0 every joint is at its zero and the rods at their (curved)
    // rest strain offset; at rest, with and without acceleration.
    check(&m, 0.0, &zero, &zero, &zero, "q = q̇ = q̈ = 0");
    let mut rng = Lcg(21);
    let (q, qd, qdd) = state(&mut rng, n, 1e-9, 1e-9, 1e-9);
    check(&m, 0.1, &q, &qd, &qdd, "near zero");
    // Large curvatures: strains up to 12 1/m on 0.13 m pieces (~1.5 turns).
    let (q, qd, qdd) = state(&mut rng, n, 12.0, 2.0, 3.0);
    check(&m, 0.1, &q, &qd, &qdd, "several turns");
}

/// `∂q̈/∂q`, `∂q̈/∂q̇` of the O(N) tree forward dynamics (a second
/// algorithm: the articulated recursion) and the linearization.
#[test]
fn forward_derivatives_and_linearization_on_trees() {
    let mut rng = Lcg(13);
    for m in [robot(true, true, true, true), loaded_tree(Terms::ALL)] {
        let n = m.n_dof();
        let (q, qd, _) = state(&mut rng, n, 0.3, 1.0, 0.0);
        let t = 0.25;
        let mut data = Data::new(&m);
        let mut work = FdDerivatives::new(&m);
        forward_dynamics_derivatives(&m, &mut data, &mut work, t, &q, &qd, None).unwrap();
        let mut fdata = Data::new(&m);
        let (fq, fv) = richardson_jacobians(&q, &qd, |q, qd| {
            forward_dynamics(&m, &mut fdata, t, q, qd, None)
                .unwrap()
                .clone()
        });
        let eq = rel(&work.dqdd_dq, &fq);
        let ev = rel(&work.dqdd_dqd, &fv);
        println!("forward: {eq:.1e} {ev:.1e}");
        assert!(eq < 1e-7 && ev < 1e-7, "∂q̈/∂q {eq:e}, ∂q̈/∂q̇ {ev:e}");
        let lin = linearize(&m, &mut data, &mut work, t, &q, &qd, None).unwrap();
        assert_eq!(lin.a.view((n, 0), (n, n)), work.dqdd_dq);
        let j = dynamics_jacobians(&m, &mut data, t, &q, &qd, None).unwrap();
        assert!(rel(&j.dqdd_dq, &fq) < 1e-7);
    }
}

#[test]
fn closed_chains_are_refused() {
    // The force a closed loop needs is not unique (docs/theory.md D67):
    // no inverse dynamics, so no derivatives of it.
    let m = robot(true, false, false, false)
        .with_closures(vec![Closure::new(
            "pin",
            ClosureKind::Ball,
            ClosureFrame::on("upper", None, Pose::identity()),
            ClosureFrame::world(Pose::identity()),
        )])
        .unwrap();
    let n = m.n_dof();
    let z = vec![0.0; n];
    let mut work = IdDerivatives::new(&m);
    let e = inverse_dynamics_derivatives(&m, &mut work, 0.0, &z, &z, &z).unwrap_err();
    assert!(matches!(e, DynamicsError::UnsupportedClosed { .. }), "{e}");
}
