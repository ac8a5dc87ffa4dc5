//! Loop closures (docs/theory.md §11, D63–D69) against independent answers:
//! the constraint Jacobian against central differences of the residual,
//! the constrained acceleration against a second difference of `φ` along
//! the motion, the clamped-clamped beam (Euler–Bernoulli `PL³/192EI`,
//! `β₁L = 4.7300`), the propped cantilever (tip reaction `3wL/8`), a long
//! run (bounded residual, conserved energy) and the errors.

mod common;

use common::{soft_material as material, soft_rod as rod};

use nalgebra::DVector;
use softrod_dynamics::{
    Attachment, BodySpec, Closure, ClosureFrame, ClosureKind, Data, DynamicsError, Joint, Model,
    ModelBuilder, Rod, ShiftedSolver, StaticsOptions, bias_force, check_closures,
    closure_multipliers, closure_residuals, closure_statics, constraint_jacobian, constraint_rank,
    constraint_residual, energies, forward_dynamics, inverse_dynamics, mass_matrix, modes,
};
use softrod_kinematics::Strain;
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::{LoadFrame, PointLoad};

const G: f64 = 9.81;

fn rot(a: f64, b: f64, c: f64) -> Mat3 {
    *nalgebra::Rotation3::from_euler_angles(a, b, c).matrix()
}

/// Rods and bodies on joints (revolute, spherical, free), a rod clamped to
/// the world: every kind of tree column a closure frame can see.
fn open_robot() -> ModelBuilder {
    let mut hand = BodySpec::principal("hand", 0.03, [2e-5, 3e-5, 2.5e-5]);
    hand.base = Pose::new(rot(0.1, -0.2, 0.3), Vec3::new(0.01, 0.0, 0.0));
    Model::builder()
        .rod_on(
            rod("upper", 0.3, 2),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.2])),
        )
        .body(hand, Attachment::to("upper", Joint::spherical()))
        .rod_on(
            rod("finger", 0.2, 3),
            Attachment::to("hand", Joint::universal([0.0, 1.0, 0.0], [0.0, 0.0, 1.0])),
        )
        .rod_on(
            rod("drone", 0.25, 2).base(Pose::new(Mat3::identity(), Vec3::new(0.0, 0.3, 0.0))),
            Attachment::world_joint(Joint::free()),
        )
        .rod(rod("post", 0.2, 2).base(Pose::new(rot(0.0, -1.0, 0.0), Vec3::new(0.2, 0.1, 0.0))))
        .gravity([0.3, -1.0, -G])
}

fn frame(e: &str, at: Option<f64>, r: Mat3, p: [f64; 3]) -> ClosureFrame {
    ClosureFrame::on(e, at, Pose::new(r, Vec3::from(p)))
}

fn every_kind() -> Vec<Closure> {
    vec![
        // Inside pieces of two rods on different branches, with offsets.
        Closure::new(
            "weld",
            ClosureKind::Weld,
            frame("finger", Some(0.07), rot(0.2, 0.1, -0.3), [0.01, 0.02, 0.0]),
            frame("drone", Some(0.1), rot(-0.1, 0.3, 0.2), [0.0, -0.01, 0.03]),
        ),
        Closure::new(
            "ball",
            ClosureKind::Ball,
            frame("hand", None, rot(0.3, 0.0, 0.1), [0.02, 0.0, 0.01]),
            ClosureFrame::world(Pose::new(rot(0.1, 0.2, 0.0), Vec3::new(0.3, 0.0, 0.0))),
        ),
        Closure::new(
            "slider",
            ClosureKind::Slider {
                axis: Vec3::new(0.3, 1.0, -0.2),
            },
            frame("upper", Some(0.3), Mat3::identity(), [0.0; 3]),
            frame("post", Some(0.13), rot(0.0, 0.4, 0.0), [0.01, 0.0, 0.0]),
        ),
        Closure::new(
            "body-weld",
            ClosureKind::Weld,
            frame("hand", None, Mat3::identity(), [0.0; 3]),
            frame("finger", Some(0.2), rot(0.1, 0.1, 0.1), [0.0; 3]),
        ),
    ]
}

/// A reproducible state of moderate amplitude.
fn state(n: usize, seed: u64, scale: f64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            scale * (((s >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0)
        })
        .collect()
}

#[test]
fn constraint_jacobian_matches_central_differences() {
    let model = open_robot()
        .build()
        .unwrap()
        .with_closures(every_kind())
        .unwrap();
    assert_eq!(model.n_constraints(), 6 + 3 + 2 + 6);
    let mut data = Data::new(&model);
    let n = model.n_dof();
    for seed in [1, 2, 3] {
        let q = state(n, seed, 0.4);
        let j = constraint_jacobian(&model, &mut data, &q).unwrap();
        let mut fd = j.clone() * 0.0;
        let h = 1e-6;
        for c in 0..n {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[c] += h;
            qm[c] -= h;
            let d = (constraint_residual(&model, &mut data, &qp).unwrap()
                - constraint_residual(&model, &mut data, &qm).unwrap())
                / (2.0 * h);
            fd.set_column(c, &d);
        }
        let err = (&j - &fd).amax();
        assert!(
            err < 1e-7 * j.amax().max(1.0),
            "seed {seed}: |J − FD| = {err:e}"
        );
        assert!(j.amax() > 0.1);
    }
}

/// `b`'s offset such that each closure of `closures` holds at `q`: the pose
/// of each end from a weld of it to the world with identity offset.
fn assembled(builder: impl Fn() -> Model, closures: Vec<Closure>, q: &[f64]) -> Vec<Closure> {
    let pose_of = |f: &ClosureFrame| -> Pose {
        if f.element == "world" {
            return f.base;
        }
        // Twice: the rotation vector is ill-conditioned near π, the second
        // probe (relative to the first estimate) is near the identity.
        let mut est = Pose::identity();
        for _ in 0..2 {
            let probe = Closure::new(
                "probe",
                ClosureKind::Weld,
                f.clone(),
                ClosureFrame::world(est),
            );
            let m = builder().with_closures(vec![probe]).unwrap();
            let mut d = Data::new(&m);
            let phi = constraint_residual(&m, &mut d, q).unwrap();
            let r = nalgebra::Rotation3::from_scaled_axis(Vec3::new(phi[0], phi[1], phi[2]));
            let rel = Pose::new(*r.matrix(), Vec3::new(phi[3], phi[4], phi[5]));
            est = est.compose(&rel);
        }
        est
    };
    closures
        .into_iter()
        .map(|mut c| {
            let ga = pose_of(&c.a);
            let b0 = ClosureFrame::on(c.b.element.clone(), c.b.at, Pose::identity());
            let gb = if c.b.element == "world" {
                Pose::identity()
            } else {
                pose_of(&b0)
            };
            c.b.base = gb.inverse().compose(&ga);
            c
        })
        .collect()
}

#[test]
fn constrained_acceleration_obeys_the_stabilized_constraint() {
    let build = || open_robot().build().unwrap();
    let n = build().n_dof();
    let q = state(n, 7, 0.3);
    let closures = assembled(build, every_kind(), &q);
    let model = build().with_closures(closures).unwrap();
    let mut data = Data::new(&model);
    let phi0 = constraint_residual(&model, &mut data, &q).unwrap();
    assert!(phi0.amax() < 1e-12, "assembled: {phi0}");
    check_closures(&model, &mut data, &q).unwrap();
    // A velocity that violates the constraints: the stabilization acts.
    let qd = state(n, 8, 0.5);
    let qdd = forward_dynamics(&model, &mut data, 0.0, &q, &qd, None)
        .unwrap()
        .clone();
    let (lambda, rank) = closure_multipliers(&data).unwrap();
    let lambda = lambda.clone();
    assert_eq!(rank, model.n_constraints());
    assert!(lambda.amax() > 0.0);
    // φ̈ = J q̈ + ∂²φ(q̇, q̇), the second term by a second difference of φ
    // along q + t q̇ (independent of the code's J̇q̇), against
    // φ̈ = −2α φ̇ − β² φ with φ = 0 (where the velocity rows of the weld
    // are exactly ṙ) and φ̇ = J q̇.
    let j = constraint_jacobian(&model, &mut data, &q).unwrap();
    let (qdv, qddv) = (DVector::from_column_slice(&qd), qdd.clone());
    let h = 1e-4;
    let at = |t: f64| {
        let qt: Vec<f64> = (0..n).map(|i| q[i] + t * qd[i]).collect();
        constraint_residual(&model, &mut Data::new(&model), &qt).unwrap()
    };
    let curvature = (at(h) - &phi0 * 2.0 + at(-h)) / (h * h);
    let phiddot = &j * &qddv + curvature;
    let expected = -(&j * &qdv) * (2.0 * model.baumgarte_rate());
    let err = (&phiddot - &expected).amax();
    let scale = (&j * &qddv).amax();
    assert!(
        err < 1e-6 * scale,
        "φ̈ {phiddot} vs {expected}: {err:e} of {scale:e}"
    );
    // The equations of motion D67, M q̈ + b = Jᵀλ, with the dense composite
    // M and the bias b of the open tree (inverse dynamics at q̈ = 0): checks
    // the O(N) solves behind M⁻¹Jᵀ, which the constraint rows alone do
    // not see (any q̈ + z with Jz = 0 obeys them).
    let m = mass_matrix(&model, &mut data, &q).unwrap().clone();
    let b = bias_force(&model, &mut data, 0.0, &q, &qd).unwrap().clone();
    let lhs = &m * &qddv + b;
    let rhs = j.transpose() * &lambda;
    let err = (&lhs - &rhs).amax();
    assert!(
        err < 1e-10 * rhs.amax(),
        "M q̈ + b − Jᵀλ: {err:e} of {:e}",
        rhs.amax()
    );
}

const E: f64 = 2e9;
const RHO: f64 = 1000.0;
const R: f64 = 0.005;
const L: f64 = 1.0;

/// A straight beam along x clamped at the origin, Kirchhoff strains with
/// extension (torsion, bending, stretch; no shear), `pieces` even so that
/// s = L/2 is a piece boundary; its tip held by `kind` to the world at
/// (L, 0, 0).
fn beam(pieces: usize, kind: ClosureKind, load: Option<f64>, gravity: bool) -> Model {
    beam_with(
        &[Strain::Kx, Strain::Ky, Strain::Kz, Strain::Qx],
        pieces,
        kind,
        load,
        gravity,
    )
}

/// [`beam`] with the strains `strains`.
fn beam_with(
    strains: &[Strain],
    pieces: usize,
    kind: ClosureKind,
    load: Option<f64>,
    gravity: bool,
) -> Model {
    let mut spec = Rod::builder(L)
        .name("beam")
        .pieces(pieces)
        .strains(strains.iter().copied())
        .circle(R)
        .material(material(E, RHO));
    if let Some(p) = load {
        spec = spec.point_load(PointLoad {
            s: L / 2.0,
            force: Vec3::new(0.0, 0.0, -p),
            moment: Vec3::zeros(),
            frame: LoadFrame::World,
        });
    }
    let mut b = Model::builder().rod(spec).closure(Closure::new(
        "tip",
        kind,
        ClosureFrame::on("beam", None, Pose::identity()),
        ClosureFrame::world(Pose::new(Mat3::identity(), Vec3::new(L, 0.0, 0.0))),
    ));
    if gravity {
        b = b.gravity([0.0, 0.0, -G]);
    }
    b.build().unwrap()
}

fn ei() -> f64 {
    E * std::f64::consts::PI * R.powi(4) / 4.0
}

fn z_at(model: &Model, q: &[f64], s: f64) -> f64 {
    let rod = &model.rods()[0].spec.geometry;
    let mut kin = softrod_kinematics::RodKinematics::new(rod);
    kin.update(rod, &q[model.rods()[0].dofs()], None, None)
        .unwrap();
    kin.pose_at(rod, s).unwrap().translation[2]
}

#[test]
fn clamped_clamped_beam_deflection_is_pl3_over_192ei() {
    let p = 0.01;
    let exact = -p * L.powi(3) / (192.0 * ei());
    let err = |pieces: usize| {
        let model = beam(pieces, ClosureKind::Weld, Some(p), false);
        let mut data = Data::new(&model);
        let q0 = vec![0.0; model.n_dof()];
        check_closures(&model, &mut data, &q0).unwrap();
        let (st, lambda) =
            closure_statics(&model, &mut data, &q0, &StaticsOptions::default()).unwrap();
        assert!(closure_residuals(&model, &mut data, st.q.as_slice()).unwrap()[0] < 1e-12);
        // The far clamp carries half the load (symmetry): force z row.
        assert!((lambda[5] - p / 2.0).abs() < 1e-6 * p, "{lambda}");
        (z_at(&model, st.q.as_slice(), L / 2.0) - exact).abs() / exact.abs()
    };
    let (e8, e16, e32) = (err(8), err(16), err(32));
    // Piecewise-constant curvature: O(N⁻²), and Richardson's extrapolation
    // of the two finest removes it.
    assert!(e32 < 5e-3, "relative error {e32} at 32 pieces");
    assert!(
        e8 / e16 > 3.5 && e16 / e32 > 3.5,
        "{e8} → {e16} → {e32} is not second order"
    );
    let z = |pieces: usize| {
        let model = beam(pieces, ClosureKind::Weld, Some(p), false);
        let mut data = Data::new(&model);
        let q0 = vec![0.0; model.n_dof()];
        let (st, _) = closure_statics(&model, &mut data, &q0, &StaticsOptions::default()).unwrap();
        z_at(&model, st.q.as_slice(), L / 2.0)
    };
    let richardson = (4.0 * z(32) - z(16)) / 3.0;
    let rel = (richardson - exact).abs() / exact.abs();
    assert!(rel < 2e-4, "extrapolated {richardson} vs {exact}: {rel:e}");
}

/// A weld on a planar rod (bending in the x–z plane and stretch) has six
/// rows of which three are independent: the out-of-plane rotations and
/// the y translation cannot move. Statics drops the redundant rows (D69,
/// the pivoted Cholesky of the dynamics) and finds the equilibrium of the
/// model with out-of-plane strains, where the in-plane load leaves them at
/// zero (a second model), and Euler–Bernoulli's PL³/192EI to the
/// discretization error of the full model; its modes are the full model's
/// in-plane ones.
#[test]
fn a_planar_weld_closure_has_redundant_rows_and_the_full_answer() {
    let p = 0.01;
    let planar = [Strain::Ky, Strain::Qx];
    let solve = |model: &Model| {
        let mut data = Data::new(model);
        let q0 = vec![0.0; model.n_dof()];
        let (st, lambda) =
            closure_statics(model, &mut data, &q0, &StaticsOptions::default()).unwrap();
        assert!(closure_residuals(model, &mut data, st.q.as_slice()).unwrap()[0] < 1e-12);
        (z_at(model, st.q.as_slice(), L / 2.0), lambda)
    };
    let flat = beam_with(&planar, 16, ClosureKind::Weld, Some(p), false);
    let mut data = Data::new(&flat);
    assert_eq!(
        constraint_rank(&flat, &mut data, &vec![0.0; flat.n_dof()]).unwrap(),
        3
    );
    let (z_flat, lambda) = solve(&flat);
    let (z_full, _) = solve(&beam(16, ClosureKind::Weld, Some(p), false));
    let exact = -p * L.powi(3) / (192.0 * ei());
    assert!(
        (z_flat - z_full).abs() < 1e-9 * exact.abs(),
        "{z_flat} vs {z_full}"
    );
    // 16 pieces: the full model's O(N⁻²) error (< 2e-2, see above).
    assert!(
        (z_flat - exact).abs() < 2e-2 * exact.abs(),
        "{z_flat} vs {exact}"
    );
    // The far clamp carries half the load; the dropped rows carry nothing.
    assert!((lambda[5] - p / 2.0).abs() < 1e-6 * p, "{lambda}");
    for row in [0, 2, 4] {
        assert!(lambda[row].abs() < 1e-12 * p, "{lambda}");
    }
    // Modes about it: the full model's first (in-plane) frequency.
    let q0 = vec![0.0; flat.n_dof()];
    let w_flat = modes(&flat, &mut Data::new(&flat), &q0, 0.0).unwrap();
    let full = beam(16, ClosureKind::Weld, None, false);
    let w_full = modes(&full, &mut Data::new(&full), &vec![0.0; full.n_dof()], 0.0).unwrap();
    assert_eq!(w_flat.omega.len(), flat.n_dof() - 3);
    let e = (w_flat.omega[0] - w_full.omega[0]).abs() / w_full.omega[0];
    assert!(e < 1e-8, "{} vs {}", w_flat.omega[0], w_full.omega[0]);
}

#[test]
fn clamped_clamped_first_frequency_from_beta_l_4_73() {
    let rho_a = RHO * std::f64::consts::PI * R * R;
    let exact = (4.730_040_744_862_704 / L).powi(2) * (ei() / rho_a).sqrt();
    let first = |pieces: usize| {
        let model = beam(pieces, ClosureKind::Weld, None, false);
        let mut data = Data::new(&model);
        let q0 = vec![0.0; model.n_dof()];
        assert_eq!(constraint_rank(&model, &mut data, &q0).unwrap(), 6);
        let m = modes(&model, &mut data, &q0, 0.0).unwrap();
        assert_eq!(m.omega.len(), model.n_dof() - 6);
        // Two bending planes: the first two modes are the same frequency.
        assert!((m.omega[0] - m.omega[1]).abs() < 1e-6 * m.omega[0]);
        m.omega[0]
    };
    let (w16, w32) = (first(16), first(32));
    let (e16, e32) = ((w16 - exact) / exact, (w32 - exact) / exact);
    assert!(e32.abs() < 3e-3, "ω = {w32}, exact {exact}");
    assert!(e16 / e32 > 3.5, "{e16} → {e32} is not second order");
    // Richardson's extrapolation; what is left is rotary inertia, which
    // Euler–Bernoulli neglects: a relative ~(β₁r/L)²/4 ~ 1e-4.
    let rich = (4.0 * w32 - w16) / 3.0;
    let rel = (rich - exact).abs() / exact;
    assert!(rel < 5e-4, "extrapolated {rich} vs {exact}: {rel:e}");
}

#[test]
fn propped_cantilever_tip_reaction_is_3wl_over_8() {
    // Tip on a slider along the rod axis: held in y and z, free along x
    // and in rotation.
    let model = beam(
        16,
        ClosureKind::Slider {
            axis: Vec3::new(2.0, 0.0, 0.0),
        },
        None,
        true,
    );
    let mut data = Data::new(&model);
    let q0 = vec![0.0; model.n_dof()];
    let (st, lambda) = closure_statics(&model, &mut data, &q0, &StaticsOptions::default()).unwrap();
    let w = RHO * std::f64::consts::PI * R * R * G;
    // Rows: the normals z (= x × y) and −y of the axis x (model/closure.rs).
    let reaction = lambda[0];
    let exact = 3.0 * w * L / 8.0;
    assert!(
        (reaction - exact).abs() < 2e-3 * exact,
        "reaction {reaction}, exact {exact}"
    );
    assert!(lambda[1].abs() < 1e-9 * exact);
    assert!(z_at(&model, st.q.as_slice(), L).abs() < 1e-12);
    assert!(z_at(&model, st.q.as_slice(), L / 2.0) < -1e-4);
}

/// A soft rod on a revolute joint about y (a pin), horizontal, its tip on a
/// slider along the horizontal line through (L, 0, 0) along x (a roller):
/// a simply supported beam that sags and swings in the xz plane (the
/// slider's y row is redundant in the plane: rank handling).
fn swinging_loop() -> Model {
    Model::builder()
        .rod_on(
            Rod::builder(0.3)
                .name("arm")
                .pieces(4)
                .strains([Strain::Ky])
                .circle(0.01)
                .material(material(1e5, 1000.0)),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
        )
        .gravity([0.0, 0.0, -G])
        .closure(Closure::new(
            "rail",
            ClosureKind::Slider {
                axis: Vec3::new(1.0, 0.0, 0.0),
            },
            ClosureFrame::on("arm", None, Pose::identity()),
            ClosureFrame::world(Pose::new(Mat3::identity(), Vec3::new(0.3, 0.0, 0.0))),
        ))
        .build()
        .unwrap()
}

#[test]
fn long_run_keeps_the_residual_bounded_and_conserves_energy() {
    let model = swinging_loop();
    let mut data = Data::new(&model);
    let n = model.n_dof();
    assert_eq!(
        constraint_rank(&model, &mut data, &vec![0.0; n]).unwrap(),
        1
    );
    let mut q = DVector::zeros(n);
    let mut v = DVector::zeros(n);
    let e0 = energies(&model, &mut data, q.as_slice(), v.as_slice()).unwrap();
    let total = |e: &softrod_dynamics::Energies| e.kinetic + e.elastic + e.gravitational;
    let (t_end, dt) = (6.0, 1e-3);
    let mut max_res: f64 = 0.0;
    let mut max_de: f64 = 0.0;
    let mut max_ke: f64 = 0.0;
    for _ in 0..(t_end / dt) as usize {
        common::rk4_step(&model, &mut data, 0.0, &mut q, &mut v, dt);
        let (_, rank) = closure_multipliers(&data).unwrap();
        assert_eq!(rank, 1, "the in-plane row only");
        let res = closure_residuals(&model, &mut data, q.as_slice()).unwrap()[0];
        max_res = max_res.max(res);
        let e = energies(&model, &mut data, q.as_slice(), v.as_slice()).unwrap();
        max_de = max_de.max((total(&e) - total(&e0)).abs());
        max_ke = max_ke.max(e.kinetic);
    }
    // It moves: the loop sags and swings.
    assert!(max_ke > 1e-4, "kinetic energy {max_ke}");
    // RK4 at 1 ms over about five periods of the first mode: the drift the
    // integrator leaves is held by the stabilization at ~5e-8 m (bounded,
    // not growing); the constraint forces do no work, so the energy drifts
    // only by what RK4 and the stabilization leave, ~1e-6 of the kinetic.
    assert!(max_res < 2e-7, "residual {max_res:e} m");
    assert!(
        max_de < 1e-5 * max_ke,
        "energy drift {max_de:e} vs kinetic {max_ke:e}"
    );
}

#[test]
fn closure_errors_name_the_closure_and_what() {
    let base = || Model::builder().rod(rod("arm", 0.3, 2)).build().unwrap();
    let c = |a: ClosureFrame, kind: ClosureKind| {
        base().with_closures(vec![Closure::new(
            "c1",
            kind,
            a,
            ClosureFrame::world(Pose::identity()),
        )])
    };
    match c(
        ClosureFrame::on("nope", None, Pose::identity()),
        ClosureKind::Ball,
    ) {
        Err(e @ DynamicsError::ClosureFrame { .. }) => {
            let s = e.to_string();
            assert!(s.contains("c1") && s.contains("nope"), "{s}");
        }
        other => panic!("{other:?}"),
    }
    match c(
        ClosureFrame::on("arm", Some(0.5), Pose::identity()),
        ClosureKind::Ball,
    ) {
        Err(e @ DynamicsError::ClosureFrame { .. }) => {
            assert!(e.to_string().contains("outside"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    match c(
        ClosureFrame::on("arm", None, Pose::identity()),
        ClosureKind::Slider {
            axis: Vec3::zeros(),
        },
    ) {
        Err(DynamicsError::ClosureAxis { closure, .. }) => assert_eq!(closure, "c1"),
        other => panic!("{other:?}"),
    }
    // Does not hold at q = 0 (the tip is at (0.3, 0, 0), not the origin).
    let model = c(
        ClosureFrame::on("arm", None, Pose::identity()),
        ClosureKind::Ball,
    )
    .unwrap();
    let mut data = Data::new(&model);
    match check_closures(&model, &mut data, &vec![0.0; model.n_dof()]) {
        Err(DynamicsError::ClosureNotHeld {
            closure, residual, ..
        }) => {
            assert_eq!(closure, "c1");
            assert!((residual - 0.3).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
    // A workspace made before the closures is refused, not a panic.
    let open = base();
    let mut stale = Data::new(&open);
    let z = vec![0.0; model.n_dof()];
    assert!(matches!(
        forward_dynamics(&model, &mut stale, 0.0, &z, &z, None),
        Err(DynamicsError::WorkspaceMismatch { .. })
    ));
    assert!(matches!(
        constraint_residual(&model, &mut stale, &z),
        Err(DynamicsError::WorkspaceMismatch { .. })
    ));
    // What is not implemented says so.
    let z = vec![0.0; model.n_dof()];
    assert!(matches!(
        inverse_dynamics(&model, &mut data, 0.0, &z, &z, &z),
        Err(DynamicsError::UnsupportedClosed { .. })
    ));
}

/// Rod `b` hanging from rod `a`'s tip (the tree, no closure) and the same
/// rod on a free joint from the world welded to `a`'s tip (a closure):
/// two algorithms for one mechanism.
fn split_beam(welded: bool) -> Model {
    let half = 0.25;
    let a = rod("a", half, 3);
    let mut b = Model::builder()
        .rod(a)
        .gravity([0.0, -2.0, -G])
        .quadrature(4);
    b = if welded {
        b.rod_on(
            rod("b", half, 3).base(Pose::new(Mat3::identity(), Vec3::new(half, 0.0, 0.0))),
            Attachment::world_joint(Joint::free()),
        )
        .closure(Closure::new(
            "joint",
            ClosureKind::Weld,
            ClosureFrame::on("b", Some(0.0), Pose::identity()),
            ClosureFrame::on("a", None, Pose::identity()),
        ))
    } else {
        b.rod_on(rod("b", half, 3), Attachment::to("a", Joint::fixed()))
    };
    b.build().unwrap()
}

#[test]
fn a_weld_to_a_floating_rod_is_the_rigid_attachment() {
    let (tree, closed) = (split_beam(false), split_beam(true));
    let n = tree.n_dof();
    assert_eq!(closed.n_dof(), n + 6);
    // Closed layout: a's strains, b's free joint (6), b's strains.
    let na = tree.rods()[0].n_dof();
    let strains =
        |qc: &[f64]| -> Vec<f64> { qc[..na].iter().chain(&qc[na + 6..]).copied().collect() };
    // Statics: the same strains.
    let opts = StaticsOptions::default();
    let st = softrod_dynamics::statics(&tree, &mut Data::new(&tree), &vec![0.0; n], &opts).unwrap();
    let (sc, _) =
        closure_statics(&closed, &mut Data::new(&closed), &vec![0.0; n + 6], &opts).unwrap();
    let qc = strains(sc.q.as_slice());
    let err = (0..n).map(|i| (qc[i] - st.q[i]).abs()).fold(0.0, f64::max);
    assert!(err < 1e-8 * st.q.amax(), "statics differ by {err:e}");
    // Dynamics at q = 0 (the loop holds) with a strain velocity and the
    // joint velocity that keeps the weld (J q̇ = 0): the stabilization is
    // idle, so the strains accelerate as in the tree.
    let mut dc = Data::new(&closed);
    let qc0 = vec![0.0; n + 6];
    let v = state(n, 11, 0.8);
    let mut qdc = vec![0.0; n + 6];
    for i in 0..n {
        qdc[if i < na { i } else { i + 6 }] = v[i];
    }
    let j = constraint_jacobian(&closed, &mut dc, &qc0).unwrap();
    let jj = j.columns(na, 6).into_owned();
    let rest = &j * DVector::from_column_slice(&qdc);
    let vj = jj.lu().solve(&(-rest)).unwrap();
    for k in 0..6 {
        qdc[na + k] = vj[k];
    }
    let jq = &j * DVector::from_column_slice(&qdc);
    assert!(jq.amax() < 1e-12, "{jq}");
    let a_tree = forward_dynamics(&tree, &mut Data::new(&tree), 0.0, &vec![0.0; n], &v, None)
        .unwrap()
        .clone();
    let a_closed = forward_dynamics(&closed, &mut dc, 0.0, &qc0, &qdc, None)
        .unwrap()
        .clone();
    let ac = strains(a_closed.as_slice());
    let err = (0..n)
        .map(|i| (ac[i] - a_tree[i]).abs())
        .fold(0.0, f64::max);
    assert!(
        err < 1e-7 * a_tree.amax(),
        "q̈ differ by {err:e} of {:e}",
        a_tree.amax()
    );
}

/// The O(N) shifted solve does not cover closed chains (their Newton
/// matrix carries the constraints): a clear error, not a wrong answer.
#[test]
fn shifted_solver_refuses_closed_chains() {
    let model = beam(4, ClosureKind::Weld, None, true);
    let q = vec![0.0; model.n_dof()];
    let mut solver = ShiftedSolver::new(&model);
    let e = solver.factor(&model, &q, 1.0, 0.0).unwrap_err();
    assert!(matches!(e, DynamicsError::UnsupportedClosed { .. }), "{e}");
}
