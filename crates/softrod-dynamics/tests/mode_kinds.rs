//! Rigid, stable and unstable modes (docs/theory.md E7), against
//! independent answers: a free body that nothing holds has exactly six
//! rigid modes and leaves the rod's frequencies as the bare rod has them (a
//! free joint transmits nothing: a second model); a stiff rod on a revolute
//! joint carrying a heavy tip body is a rigid pendulum, stable hanging with
//! `ω² = g (m l + ρA L²/2) / I_pivot` and unstable upright with `−ω²`.

mod common;

use common::{soft_material, soft_rod};
use softrod_dynamics::{
    Attachment, BodySpec, Data, Joint, ModeKind, Model, StaticsOptions, modes, statics,
};
use softrod_kinematics::Strain;

#[test]
fn a_free_body_has_six_rigid_modes_and_changes_nothing_else() {
    let rod = || soft_rod("a", 0.2, 2).strains([Strain::Ky, Strain::Kz, Strain::Qx]);
    let with_body = Model::builder()
        .rod(rod())
        .body(
            BodySpec::principal("b0", 0.01, [1e-6, 1e-6, 1e-6]),
            Attachment::to("a", Joint::free()),
        )
        .build()
        .unwrap();
    let bare = Model::builder().rod(rod()).build().unwrap();
    let n = with_body.n_dof();
    let m = modes(&with_body, &mut Data::new(&with_body), &vec![0.0; n], 0.0).unwrap();
    let b = modes(&bare, &mut Data::new(&bare), &vec![0.0; bare.n_dof()], 0.0).unwrap();
    assert_eq!(m.n_rigid(), 6, "{}", m.omega);
    assert_eq!(m.n_unstable(), 0, "{}", m.omega);
    assert!(m.rigid_tolerance > 0.0 && m.rigid_tolerance.is_finite());
    // Rigid modes come after any unstable one and before the stable ones,
    // and are exactly zero.
    for i in 0..6 {
        assert_eq!(m.kind(i), ModeKind::Rigid);
        assert_eq!(m.omega[i], 0.0);
    }
    // The elastic modes are the bare rod's.
    assert_eq!(m.omega.len() - 6, b.omega.len());
    for (i, w) in b.omega.iter().enumerate() {
        assert_eq!(m.kind(6 + i), ModeKind::Stable);
        let e = (m.omega[6 + i] - w).abs() / w;
        assert!(e < 1e-8, "mode {i}: {} vs {w}", m.omega[6 + i]);
    }
}

/// The pendulum: a stiff rod (E = 1e11 Pa, so that its bending adds a
/// relative compliance of ~1e-5) on a revolute joint about y at the world
/// origin, along +x at rest, a 1 kg body fixed at its tip; gravity along
/// `±x` makes it hang or stand.
fn pendulum(g: f64) -> Model {
    let rod = soft_rod("link", 0.3, 2)
        .strains([Strain::Ky, Strain::Qx, Strain::Qz])
        .material(soft_material(1e11, 1000.0));
    Model::builder()
        .rod_on(
            rod,
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
        )
        .body(
            BodySpec::principal("bob", 1.0, [1e-4, 1e-4, 1e-4]),
            Attachment::to("link", Joint::fixed()),
        )
        .gravity([g, 0.0, 0.0])
        .build()
        .unwrap()
}

#[test]
fn an_upright_pendulum_is_unstable_and_a_hanging_one_is_not() {
    let (l, m_b, i_b): (f64, f64, f64) = (0.3, 1.0, 1e-4);
    // Rod: ρA = 1000 π 0.01² kg/m; its moment of inertia about the pivot
    // ρA L³/3 (the section's own rotary inertia ρI L, 2.4e-6 of it, is
    // below the test's tolerance).
    let rho_a = 1000.0 * std::f64::consts::PI * 1e-4;
    let i_pivot = i_b + m_b * l * l + rho_a * l.powi(3) / 3.0;
    let w2 = 9.81 * (m_b * l + rho_a * l * l / 2.0) / i_pivot;
    for (g, sign) in [(9.81, 1.0), (-9.81, -1.0)] {
        let model = pendulum(g);
        let n = model.n_dof();
        let mut data = Data::new(&model);
        // The straight shape is an equilibrium either way (up to the rod's
        // axial sag); statics finds it, modes linearize about it.
        let eq = statics(&model, &mut data, &vec![0.0; n], &StaticsOptions::default()).unwrap();
        let md = modes(&model, &mut data, eq.q.as_slice(), 0.0).unwrap();
        assert_eq!(md.n_rigid(), 0, "{}", md.omega);
        let lowest = md.omega[0];
        let got = lowest.signum() * lowest * lowest;
        let e = (got - sign * w2).abs() / w2;
        assert!(e < 1e-3, "g = {g}: ω² = {got}, pendulum {}", sign * w2);
        assert_eq!(md.n_unstable(), usize::from(sign < 0.0), "{}", md.omega);
        assert_eq!(
            md.kind(0),
            if sign < 0.0 {
                ModeKind::Unstable
            } else {
                ModeKind::Stable
            }
        );
        // The pendulum's |ω²| stands far above the rigid tolerance (which
        // the stiff rod's differenced stiffness sets, ~4e-5 of it here).
        assert!(md.rigid_tolerance < 1e-3 * w2, "{}", md.rigid_tolerance);
    }
}
