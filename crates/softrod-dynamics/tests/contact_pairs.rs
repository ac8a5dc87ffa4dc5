//! Rod–rod and self contact (docs/theory-contact.md CT8–CT11) against
//! independent references: the closest points of two straight rods from
//! their lines' analytic geometry, the contact force of two crossing
//! cantilevers from linear beam compatibility (two springs in series),
//! no contact between neighbours of a bent rod, the refusal of an initial
//! overlap, and the contact Jacobians against central differences of the
//! forward dynamics.

use nalgebra::DVector;
use softrod_dynamics::{
    Attachment, Data, DynamicsError, FdDerivatives, Joint, JointKind, Model, Rod, StaticsOptions,
    commit_contact, forward_dynamics, forward_dynamics_derivatives, statics,
};
use softrod_kinematics::Strain;
use softrod_lie::{Pose, Vec3, Vec6, exp_twist};
use softrod_mechanics::Material;
use softrod_mechanics::contact::{ContactSettings, Contactee};

fn silicone() -> Material {
    Material::builder()
        .density(1000.0)
        .young(1.0e6)
        .poisson(0.5)
        .build()
        .unwrap()
}

fn rods_on() -> ContactSettings {
    ContactSettings {
        rods: true,
        ..Default::default()
    }
}

/// A pose rotating by `angle` about `axis` (world), placed at `at`.
fn placed(axis: Vec3, angle: f64, at: Vec3) -> Pose {
    let w = axis * angle;
    Pose::new(
        exp_twist(1.0, &Vec6::new(w.x, w.y, w.z, 0.0, 0.0, 0.0)).rotation,
        at,
    )
}

/// Two straight rods of two coarse pieces each, the upper one crossing
/// the lower at an angle, the crossing moved along both rods through many
/// places between their contact points: the contact is found every time,
/// at the arc lengths and with the gap of the two lines' common
/// perpendicular (the lines' analytic geometry).
#[test]
fn crossing_rods_touch_between_their_contact_points() {
    let (r, l) = (0.01, 0.4);
    let alpha: f64 = 0.7;
    let overlap = 0.002;
    for k in 0..23 {
        // s along both rods, not a multiple of the point spacing (≤ r).
        let sa = 0.05 + 0.0131 * k as f64;
        let sb = 0.33 - 0.0117 * k as f64;
        let dir_b = Vec3::new(alpha.cos(), alpha.sin(), 0.0);
        let cross = Vec3::new(sa, 0.0, 0.0);
        let base_b = cross - dir_b * sb + Vec3::new(0.0, 0.0, 2.0 * r - overlap);
        let rod = |name: &str, base: Pose| {
            Rod::builder(l)
                .name(name)
                .pieces(2)
                .strains([Strain::Ky, Strain::Kz])
                .base(base)
                .circle(r)
                .material(silicone())
        };
        let model = Model::builder()
            .rod(rod("lower", Pose::identity()))
            .rod(rod("upper", placed(Vec3::z(), alpha, base_b)))
            .build()
            .unwrap()
            .with_contact(Vec::new(), rods_on())
            .unwrap();
        let zero = vec![0.0; model.n_dof()];
        let contacts = model.contacts(0.0, &zero, &zero).unwrap();
        assert_eq!(contacts.len(), 1, "crossing {k}: {contacts:?}");
        let c = &contacts[0];
        assert_eq!(c.a, 0);
        let Contactee::Rod { rod: 1, s: s_b } = c.b else {
            panic!("{:?}", c.b)
        };
        assert!((c.s - sa).abs() < 1e-9, "s_a {} vs {sa}", c.s);
        assert!((s_b - sb).abs() < 1e-9, "s_b {s_b} vs {sb}");
        assert!((c.gap + overlap).abs() < 1e-12, "gap {}", c.gap);
        assert!(
            (c.normal + Vec3::z()).norm() < 1e-12,
            "normal from upper to lower"
        );
        assert!(c.force.z < 0.0, "pushes the lower rod down");
        assert!((c.point - Vec3::new(sa, 0.0, r)).norm() < 1e-12);
    }
}

/// Two rods crossing exactly at a piece boundary of both — the symmetric
/// crossing at mid-span of rods with an even number of pieces, a contact
/// point of both: the four segment pairs that meet there each refine to
/// that one contact, which must be reported once (four reports would be
/// four springs, a contact four times as stiff). The lower rod is bent with
/// a curvature jump at the boundary; the upper, straight, passes its point
/// at `s = L/2` along the common perpendicular `n = t × d` of its tangent
/// `t` and the upper direction `d`, so the exact closest points are both
/// `L/2` and the gap is `−overlap` (the geometry, independent of the code).
#[test]
fn a_crossing_at_a_piece_boundary_of_both_rods_is_one_contact() {
    let (r, l, overlap) = (0.01, 0.4, 0.002);
    let rod = |name: &str, base: Pose| {
        Rod::builder(l)
            .name(name)
            .pieces(2)
            .strains([Strain::Ky])
            .base(base)
            .circle(r)
            .material(silicone())
    };
    let cases = [
        (0.7, 0.0, 0.0),
        (1.2, 1.5, -1.0),
        (0.7, -2.5, 0.5),
        (std::f64::consts::FRAC_PI_2, 3.0, 3.0),
    ];
    for (alpha, b0, b1) in cases {
        let probe = Model::builder()
            .rod(rod("lower", Pose::identity()))
            .build()
            .unwrap();
        let geometry = &probe.rods()[0].spec.geometry;
        let mut kin = softrod_kinematics::RodKinematics::new(geometry);
        kin.update(geometry, &[b0, b1], None, None).unwrap();
        let g = kin.pose_at(geometry, 0.5 * l).unwrap();
        let t = g.rotation * Vec3::x();
        let d = t * alpha.cos() + Vec3::y() * alpha.sin();
        let n = t.cross(&d).normalize();
        let y = n.cross(&d);
        let base_b = g.translation + n * (2.0 * r - overlap) - d * (0.5 * l);
        let frame = softrod_lie::Mat3::from_columns(&[d, y, n]);
        let model = Model::builder()
            .rod(rod("lower", Pose::identity()))
            .rod(rod("upper", Pose::new(frame, base_b)))
            .build()
            .unwrap()
            .with_contact(Vec::new(), rods_on())
            .unwrap();
        let q = [b0, b1, 0.0, 0.0];
        let zero = vec![0.0; model.n_dof()];
        let contacts = model.contacts(0.0, &q, &zero).unwrap();
        assert_eq!(
            contacts.len(),
            1,
            "alpha {alpha}, bends {b0}, {b1}: {contacts:?}"
        );
        let c = &contacts[0];
        let Contactee::Rod { rod: 1, s: s_b } = c.b else {
            panic!("{:?}", c.b)
        };
        assert!((c.s - 0.5 * l).abs() < 1e-9, "s_a {}", c.s);
        assert!((s_b - 0.5 * l).abs() < 1e-9, "s_b {s_b}");
        assert!((c.gap + overlap).abs() < 1e-12, "gap {}", c.gap);
    }
}

/// The crossing at a corner: the lower rod sheared up on its first piece
/// and down on its second (tangents `(1, 0, ±0.2)`, an apex at the piece
/// boundary `s = L/2`), the upper rod straight along y just above the apex.
/// The closest points are the apex and the upper rod's middle, gap
/// `−overlap` (the geometry), but the distance is not stationary there on
/// either side: the refinement from the four segment pairs at the apex
/// crosses the boundary back and forth. Still one contact, at the apex.
#[test]
fn a_crossing_at_a_corner_between_pieces_is_one_contact() {
    let (r, l, overlap, shear) = (0.01, 0.4, 0.002, 0.2);
    let lower = Rod::builder(l)
        .name("lower")
        .pieces(2)
        .strains([Strain::Qz])
        .circle(r)
        .material(silicone());
    let apex = Vec3::new(0.5 * l, 0.0, 0.5 * l * shear);
    let along_y = softrod_lie::Mat3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
    let upper = Rod::builder(l)
        .name("upper")
        .pieces(2)
        .strains([Strain::Ky])
        .base(Pose::new(
            along_y,
            apex + Vec3::new(0.0, -0.5 * l, 2.0 * r - overlap),
        ))
        .circle(r)
        .material(silicone());
    let model = Model::builder()
        .rod(lower)
        .rod(upper)
        .build()
        .unwrap()
        .with_contact(Vec::new(), rods_on())
        .unwrap();
    let q = [shear, -shear, 0.0, 0.0];
    let zero = vec![0.0; model.n_dof()];
    let contacts = model.contacts(0.0, &q, &zero).unwrap();
    assert_eq!(contacts.len(), 1, "{contacts:?}");
    let c = &contacts[0];
    let Contactee::Rod { rod: 1, s: s_b } = c.b else {
        panic!("{:?}", c.b)
    };
    assert!((c.s - 0.5 * l).abs() < 1e-9, "s_a {}", c.s);
    assert!((s_b - 0.5 * l).abs() < 1e-9, "s_b {s_b}");
    assert!((c.gap + overlap).abs() < 1e-9, "gap {}", c.gap);
}

/// Two curved rods (rest curvature in two planes, coarse pieces) crossing
/// over each other: the contact's arc lengths and gap against a brute-force
/// search over 2000 × 2000 centreline points, zoomed in — the refinement finds the
/// closest points of the arcs, not of the polylines through the contact
/// points.
#[test]
fn curved_rods_touch_at_the_closest_points_of_their_arcs() {
    let r = 0.01;
    let rod = |name: &str, base: Pose, rest: Vec6| {
        Rod::builder(0.4)
            .name(name)
            .pieces(2)
            .strains([Strain::Ky])
            .rest_strain(rest)
            .base(base)
            .circle(r)
            .material(silicone())
    };
    let model = Model::builder()
        .rod(rod(
            "a",
            Pose::identity(),
            Vec6::new(0.0, 0.0, 2.5, 1.0, 0.0, 0.0),
        ))
        .rod(rod(
            "b",
            // Rising from below a's plane to cross over it near s = 0.3.
            placed(Vec3::z(), 1.3, Vec3::new(0.25, -0.12, -0.0163)),
            Vec6::new(0.0, -0.8, 0.0, 1.0, 0.0, 0.0),
        ))
        .build()
        .unwrap()
        .with_contact(Vec::new(), rods_on())
        .unwrap();
    let q = vec![0.0; model.n_dof()];
    let contacts = model.contacts(0.0, &q, &q).unwrap();
    assert_eq!(contacts.len(), 1, "{contacts:?}");
    let c = &contacts[0];
    let Contactee::Rod { s: sb, .. } = c.b else {
        panic!()
    };
    let mut data = Data::new(&model);
    let n = 2000;
    let points = |rod: usize, data: &mut Data| -> Vec<(f64, Vec3)> {
        (0..=n)
            .map(|i| {
                let s = 0.4 * i as f64 / n as f64;
                let (pose, _) =
                    softrod_dynamics::section_jacobian(&model, data, &q, rod, s).unwrap();
                (s, pose.translation)
            })
            .collect()
    };
    let (pa, pb) = (points(0, &mut data), points(1, &mut data));
    let mut best = (f64::INFINITY, 0.0, 0.0);
    for (sa, xa) in &pa {
        for (sb, xb) in &pb {
            let d = (xa - xb).norm();
            if d < best.0 {
                best = (d, *sa, *sb);
            }
        }
    }
    // Zoom: 201 × 201 points within two coarse steps of the best pair.
    let (ca, cb) = (best.1, best.2);
    for i in 0..=200 {
        let sa = (ca - 4e-4 + 4e-6 * i as f64).clamp(0.0, 0.4);
        let (ga, _) = softrod_dynamics::section_jacobian(&model, &mut data, &q, 0, sa).unwrap();
        for j in 0..=200 {
            let sb = (cb - 4e-4 + 4e-6 * j as f64).clamp(0.0, 0.4);
            let (gb, _) = softrod_dynamics::section_jacobian(&model, &mut data, &q, 1, sb).unwrap();
            let d = (ga.translation - gb.translation).norm();
            if d < best.0 {
                best = (d, sa, sb);
            }
        }
    }
    let gap = best.0 - 2.0 * r;
    eprintln!(
        "code: gap {:.6e} at ({:.6}, {sb:.6}); brute force {gap:.6e} at ({:.6}, {:.6})",
        c.gap, c.s, best.1, best.2
    );
    // The sampled minimum lies above the true one by at most
    // |Δ|²/(2d) for the offset |Δ| ≤ √2 · 2 µm of the zoomed grid and the
    // centreline distance d ≈ 1.85 cm: ~2e-10 m.
    assert!(
        c.gap <= gap + 1e-12 && c.gap > gap - 1e-9,
        "{} vs {gap}",
        c.gap
    );
    assert!((c.s - best.1).abs() < 1e-5 && (sb - best.2).abs() < 1e-5);
}

/// Two clamped cantilevers crossing at right angles, the upper tilted down
/// onto the lower, no gravity: statics finds the contact force of linear
/// beam compatibility. Each rod acts as the spring `k_i = 3EI/a_i³` of a
/// cantilever loaded at distance `a_i` from its clamp; in series they take
/// up the interference `Δ` of the undeformed rods less the penetration,
/// `F = (Δ + gap) / (a_A³/3EI + a_B³/3EI)`.
#[test]
fn crossing_cantilevers_press_with_the_force_of_beam_compatibility() {
    let (r, la, lb) = (0.01, 0.5, 0.4);
    let (ca, cb) = (0.35, 0.25);
    let theta: f64 = 0.004;
    let h = 2.0 * r;
    let upper = Rod::builder(la)
        .name("upper")
        .pieces(36)
        .strains([Strain::Ky, Strain::Kz])
        .base(placed(Vec3::y(), theta, Vec3::new(0.0, 0.0, h)))
        .circle(r)
        .material(silicone());
    let lower = Rod::builder(lb)
        .name("lower")
        .pieces(36)
        .strains([Strain::Ky, Strain::Kz])
        .base(placed(
            Vec3::z(),
            0.5 * std::f64::consts::PI,
            Vec3::new(ca, -cb, 0.0),
        ))
        .circle(r)
        .material(silicone());
    let model = Model::builder()
        .rod(upper)
        .rod(lower)
        .build()
        .unwrap()
        .with_contact(Vec::new(), rods_on())
        .unwrap();
    let mut data = Data::new(&model);
    let rest = vec![0.0; model.n_dof()];
    let res = statics(&model, &mut data, &rest, &StaticsOptions::default()).unwrap();
    let q = res.q.as_slice();
    let zero = vec![0.0; q.len()];
    let contacts = model.contacts(0.0, q, &zero).unwrap();
    assert_eq!(contacts.len(), 1, "{contacts:?}");
    let c = &contacts[0];
    // The undeformed lines: A through (0,0,h) along (cos θ, 0, −sin θ),
    // B through (ca, ·, 0) along y; common normal (sin θ, 0, cos θ).
    let interference = 2.0 * r - (h * theta.cos() - ca * theta.sin());
    let a_upper = ca * theta.cos() + h * theta.sin();
    let ei = silicone().young() * std::f64::consts::PI * r.powi(4) / 4.0;
    let compliance = (a_upper.powi(3) + cb.powi(3)) / (3.0 * ei);
    let expected = (interference + c.gap) / compliance;
    let normal = Vec3::new(theta.sin(), 0.0, theta.cos());
    let f = c.force.dot(&normal);
    let rel = (f - expected).abs() / expected;
    eprintln!(
        "F = {f:.6e} N, beam compatibility {expected:.6e} N ({rel:.2e}); gap {:.3e} m, at s = {:.4}, {:?}",
        c.gap, c.s, c.b
    );
    // Linear theory drops terms of order (deflection/length)² ~ 1e-5; what
    // remains is the PCS discretization of the linear moment by constant
    // curvature per piece: 4.2e-3 with 12 pieces, 9e-4 with 36.
    assert!(rel < 2e-3, "{rel}");
    assert!((c.s - a_upper).abs() < 2e-3, "{}", c.s);
    // Penetration within the 1 % bound of the pair's law (CT3, CT11).
    assert!(-c.gap < 0.01 * r, "{}", c.gap);
}

/// A rod bent into a quarter circle and a straight rod, with self contact
/// on: neighbours along the rod never touch (CT9), however finely it is
/// cut; a rod rolled into more than a full turn of a flat spiral touches
/// itself where its turns come within two radii.
#[test]
fn self_contact_spares_neighbours_and_finds_turns_that_touch() {
    let r = 0.01;
    let settings = ContactSettings {
        self_contact: true,
        ..Default::default()
    };
    let zero = |m: &Model| vec![0.0; m.n_dof()];
    for (pieces, curvature) in [(4, 0.0), (30, 0.0), (30, 0.5 * std::f64::consts::PI / 0.5)] {
        let model = Model::builder()
            .rod(
                Rod::builder(0.5)
                    .pieces(pieces)
                    .strains([Strain::Ky])
                    .rest_strain(Vec6::new(0.0, curvature, 0.0, 1.0, 0.0, 0.0))
                    .circle(r)
                    .material(silicone()),
            )
            .build()
            .unwrap()
            .with_contact(Vec::new(), settings)
            .unwrap();
        let q = zero(&model);
        assert!(model.contacts(0.0, &q, &q).unwrap().is_empty());
    }
    // A circle of radius ρ = 0.05 m a little over one turn long: the tip
    // comes back next to the base, 1.5 r off the circle's plane by a
    // small twist... (a planar circle would overlap end to end): rest
    // curvature κ = 1/ρ about y and a torsion that lifts the second turn
    // by less than 2 r.
    let rho = 0.05;
    let length = 2.0 * std::f64::consts::PI * rho * 1.25;
    // Helix of radius ~ρ and pitch p: κ = ρ/(ρ² + c²), τ = c/(ρ² + c²),
    // c = p/2π.
    let pitch = 1.5 * r;
    let c = pitch / (2.0 * std::f64::consts::PI);
    let (kappa, tau) = (rho / (rho * rho + c * c), c / (rho * rho + c * c));
    let model = Model::builder()
        .rod(
            Rod::builder(length)
                .pieces(20)
                .strains([Strain::Ky])
                .rest_strain(Vec6::new(tau, kappa, 0.0, 1.0, 0.0, 0.0))
                .circle(r)
                .material(silicone()),
        )
        .build()
        .unwrap()
        .with_contact(Vec::new(), settings)
        .unwrap();
    let q = zero(&model);
    let contacts = model.contacts(0.0, &q, &q).unwrap();
    assert!(!contacts.is_empty());
    // The turns touch a full turn apart along the rod, the gap of a helix
    // is its pitch less the two radii.
    let turn = 2.0 * std::f64::consts::PI * (rho * rho + c * c).sqrt();
    for c in &contacts {
        let Contactee::Rod { rod: 0, s } = c.b else {
            panic!()
        };
        assert!(((s - c.s) - turn).abs() < 0.05 * turn, "{} {s}", c.s);
        assert!(c.gap < 0.0 && c.gap > -0.6 * r, "{}", c.gap);
    }
    let err = model.check_initial_contact(&q).unwrap_err();
    assert!(matches!(err, DynamicsError::InitialOverlap { .. }));
}

/// Rods that start overlapping more than 1 % of the smaller radius are
/// refused with both names, both arc lengths and the depth.
#[test]
fn an_initial_overlap_of_two_rods_names_both() {
    let r = 0.01;
    let rod = |name: &str, base: Pose| {
        Rod::builder(0.3)
            .name(name)
            .pieces(3)
            .strains([Strain::Ky])
            .base(base)
            .circle(r)
            .material(silicone())
    };
    let build = |z: f64| {
        Model::builder()
            .rod(rod("left", Pose::identity()))
            .rod(rod(
                "right",
                placed(
                    Vec3::z(),
                    0.5 * std::f64::consts::PI,
                    Vec3::new(0.1, -0.2, z),
                ),
            ))
            .build()
            .unwrap()
            .with_contact(Vec::new(), rods_on())
            .unwrap()
    };
    let model = build(0.015);
    let q = vec![0.0; model.n_dof()];
    let text = model.check_initial_contact(&q).unwrap_err().to_string();
    eprintln!("{text}");
    assert!(
        text.contains("'left'")
            && text.contains("'right'")
            && text.contains("s = 0.100000")
            && text.contains("s = 0.200000")
            && text.contains("5.000e-3"),
        "{text}"
    );
    // Within 1 % of the radius: accepted.
    build(0.01995).check_initial_contact(&q).unwrap();
}

/// Two crossing 3-D rods pressed together and moving, with friction
/// anchors committed a moment before so that the pair sticks or slides:
/// `∂q̈/∂q`, `∂q̈/∂q̇` with the pair's terms against central differences
/// of the forward dynamics, on a chain model and on a tree (b free).
#[test]
fn pair_jacobians_match_central_differences() {
    let cases = [
        (0.0, 0.0, false),
        (0.6, 1e-5, false),
        (0.05, 3e-4, false),
        (0.6, 1e-5, true),
    ];
    for (friction, shift, tree) in cases {
        let r = 0.01;
        let rod = |name: &str, base: Pose| {
            Rod::builder(0.3)
                .name(name)
                .pieces(3)
                .strains(Strain::ALL)
                .base(base)
                .circle(r)
                .material(silicone())
        };
        let settings = ContactSettings {
            rods: true,
            friction,
            restitution: 0.4,
            ..Default::default()
        };
        let b = rod("b", placed(Vec3::z(), 1.2, Vec3::new(0.2, -0.15, 0.0195)));
        let builder = Model::builder().rod(rod("a", Pose::identity()));
        // A free rod b makes a tree model (the pair's Jacobian through the
        // points' paths on the tree, CT12–CT14).
        let builder = if tree {
            builder.rod_on(b, Attachment::world_joint(Joint::new(JointKind::Free)))
        } else {
            builder.rod(b)
        };
        let model = builder
            .gravity([0.0, 0.0, -9.81])
            .build()
            .unwrap()
            .with_contact(Vec::new(), settings)
            .unwrap();
        let n = model.n_dof();
        let q: Vec<f64> = (0..n).map(|i| 1e-3 * ((i as f64) * 1.3).sin()).collect();
        let qd: Vec<f64> = (0..n).map(|i| 0.02 * ((i as f64) * 0.7).cos()).collect();
        let mut data = Data::new(&model);
        let q_before: Vec<f64> = q
            .iter()
            .enumerate()
            .map(|(i, v)| v - shift * ((i as f64) * 2.1).cos())
            .collect();
        commit_contact(&model, &mut data, 0.0, &q_before, &qd).unwrap();
        let contacts = model.contacts_with(&mut data, 0.0, &q, &qd).unwrap();
        assert_eq!(contacts.len(), 1, "{contacts:?}");
        eprintln!("friction {friction}: sticking {}", contacts[0].sticking);
        let mut work = FdDerivatives::new(&model);
        let j =
            forward_dynamics_derivatives(&model, &mut data, &mut work, 0.0, &q, &qd, None).unwrap();
        let (dq, dqd) = (j.dqdd_dq.clone(), j.dqdd_dqd.clone());
        let mut acc = |q: &[f64], qd: &[f64]| -> DVector<f64> {
            forward_dynamics(&model, &mut data, 0.0, q, qd, None)
                .unwrap()
                .clone()
        };
        let mut worst: f64 = 0.0;
        for l in 0..n {
            for (which, analytic) in [(0, &dq), (1, &dqd)] {
                let h = if which == 0 { 1e-7 } else { 1e-4 };
                let (mut a, mut b) = ((q.clone(), qd.clone()), (q.clone(), qd.clone()));
                if which == 0 {
                    a.0[l] += h;
                    b.0[l] -= h;
                } else {
                    a.1[l] += h;
                    b.1[l] -= h;
                }
                let fd = (acc(&a.0, &a.1) - acc(&b.0, &b.1)) / (2.0 * h);
                let col = analytic.column(l);
                let err = (&fd - col).norm() / (col.norm() + 1.0);
                worst = worst.max(err);
                // The tree model without the pair (rods apart) already
                // agrees only to 1.1e-5 here (its free joint's Coriolis
                // terms against the q̇ step): the bound of the chain case
                // times five.
                let bound = if tree { 5e-5 } else { 1e-5 };
                assert!(
                    err < bound,
                    "friction {friction}, tree {tree}, column {l} of d/d{which}: {err:.3e}"
                );
            }
        }
        eprintln!("friction {friction}, tree {tree}: worst relative column error {worst:.3e}");
    }
}

/// A cantilever coiled into a helix by a dead tip moment `M` tilted by φ
/// from the bending axis: without contact the turns of the helix of
/// Kirchhoff's constant-moment solution (radius `EI cos φ/M`, pitch
/// `2π EI sin φ/M`, here one radius) pass through each other; with self
/// contact statics stops them touching. Checked by brute force over the
/// centreline (points `π(r_a + r_b)/2` or more apart along the rod), not
/// by the code's closest points: without contact the surfaces overlap by
/// about a radius, with it by no more than the penalty's penetration.
#[test]
fn a_coiled_rod_stops_at_its_own_surface() {
    use softrod_mechanics::{LoadFrame, PointLoad};
    let (r, l): (f64, f64) = (0.01, 0.5);
    let ei = silicone().young() * std::f64::consts::PI * r.powi(4) / 4.0;
    let turns = 1.3;
    let m = turns * 2.0 * std::f64::consts::PI * ei / l;
    let pitch = r;
    let sin_phi = pitch * m / (2.0 * std::f64::consts::PI * ei);
    let phi = sin_phi.asin();
    let build = |self_contact: bool| {
        Model::builder()
            .rod(
                Rod::builder(l)
                    .pieces(24)
                    .strains([Strain::Kx, Strain::Ky, Strain::Kz])
                    .circle(r)
                    .material(silicone())
                    .point_load(PointLoad {
                        s: l,
                        force: Vec3::zeros(),
                        moment: Vec3::new(m * sin_phi, 0.0, m * phi.cos()),
                        frame: LoadFrame::World,
                    }),
            )
            .build()
            .unwrap()
            .with_contact(
                Vec::new(),
                ContactSettings {
                    self_contact,
                    ..Default::default()
                },
            )
            .unwrap()
    };
    // The smallest surface distance between points at least the exclusion
    // apart, over 400 points of the centreline.
    let closest = |model: &Model, q: &[f64]| {
        let n = 400;
        let mut data = Data::new(model);
        let pts: Vec<(f64, Vec3)> = (0..=n)
            .map(|i| {
                let s = l * i as f64 / n as f64;
                let (pose, _) =
                    softrod_dynamics::section_jacobian(model, &mut data, q, 0, s).unwrap();
                (s, pose.translation)
            })
            .collect();
        let reach = 0.5 * std::f64::consts::PI * 2.0 * r;
        let mut best = f64::INFINITY;
        for (i, (si, pi)) in pts.iter().enumerate() {
            for (sj, pj) in &pts[i + 1..] {
                if sj - si >= reach {
                    best = best.min((pi - pj).norm() - 2.0 * r);
                }
            }
        }
        best
    };
    let options = StaticsOptions::default();
    let free = build(false);
    let mut data = Data::new(&free);
    let rest = vec![0.0; free.n_dof()];
    let q_free = statics(&free, &mut data, &rest, &options).unwrap().q;
    let through = closest(&free, q_free.as_slice());
    eprintln!("without contact: surfaces {through:.3e} m apart");
    assert!(
        through < -0.5 * r,
        "the coil should pass through itself: {through}"
    );
    let touching = build(true);
    let mut data = Data::new(&touching);
    let res = statics(&touching, &mut data, &rest, &options).unwrap();
    let q = res.q.as_slice();
    let gap = closest(&touching, q);
    let contacts = touching.contacts(0.0, q, &vec![0.0; q.len()]).unwrap();
    let deepest = touching.max_penetration(0.0, q).unwrap();
    eprintln!(
        "with self contact: surfaces {gap:.3e} m apart, {} contacts, deepest {deepest:.3e} m",
        contacts.len()
    );
    assert!(!contacts.is_empty());
    // Sampling at 1.25 mm can miss the closest points by at most the
    // sagitta-like error (1.25 mm)²/(8 ρ) ≈ 5e-6 m, far below r.
    assert!(gap > -deepest - 1e-5 && gap < 0.05 * r, "{gap}");
    assert!(deepest < 0.1 * r, "{deepest}");
}
