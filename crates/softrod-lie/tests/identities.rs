//! Algebraic identities of se(3)/SE(3) that every correct implementation
//! satisfies, checked on random inputs with proptest (64 cases each, to keep
//! the suite fast). Tolerances are a few hundred ulps of the magnitudes
//! involved: these are identities, so only rounding separates the two sides.

mod common;

use common::{Mat4, Mat6, Vec3, Vec6, ref_exp_ad};
use nalgebra as na;
use proptest::prelude::*;
use softrod_lie::{self as lie, AdOp, Pose};

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 64,
        ..ProptestConfig::default()
    }
}

fn vec6(r: f64) -> impl Strategy<Value = Vec6> {
    prop::array::uniform6(-r..r).prop_map(Vec6::from)
}

fn vec3(r: f64) -> impl Strategy<Value = Vec3> {
    prop::array::uniform3(-r..r).prop_map(Vec3::from)
}

/// A random pose: the exponential of a random twist (covers rotations up to
/// ~5 rad and translations of a few units).
fn pose() -> impl Strategy<Value = Pose> {
    vec6(3.0).prop_map(|xi| lie::exp_twist(1.0, &xi))
}

/// A random `[[A, 0], [B, A]]` with a well-conditioned `A`.
fn adop() -> impl Strategy<Value = AdOp> {
    (
        prop::array::uniform9(-1.0..1.0f64),
        prop::array::uniform9(-1.0..1.0f64),
    )
        .prop_map(|(a, b)| AdOp {
            a: na::Matrix3::from_row_slice(&a) + na::Matrix3::identity() * 3.0,
            b: na::Matrix3::from_row_slice(&b),
        })
}

fn close6(a: &Mat6, b: &Mat6, tol: f64) -> bool {
    (a - b).amax() <= tol * b.amax().max(1.0)
}

/// The ordering convention, once, explicitly: twists are (ω, v), angular first.
/// A rotation about z (ω = e_z) bracketed with a velocity along x (v = e_x)
/// gives `ad_ω v = ω × v = e_y` in the linear part.
#[test]
fn angular_first_ordering() {
    assert_eq!((lie::ANGULAR, lie::LINEAR), (0, 3));
    let rot_z = Vec6::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0);
    let lin_x = Vec6::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0);
    let expect = Vec6::new(0.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    assert_eq!(lie::ad(&rot_z) * lin_x, expect);
    assert_eq!(lie::ad_vec(&rot_z, &lin_x), expect);
    // A pure translation generates a pure translation, and the hat puts it
    // in the last column.
    let g = lie::exp_twist(2.0, &lin_x);
    assert_eq!(g.rotation, na::Matrix3::identity());
    assert_eq!(g.translation, Vec3::new(2.0, 0.0, 0.0));
    assert_eq!(lie::hat(&lin_x)[(0, 3)], 1.0);
    // A quarter turn about z maps the local x axis to y.
    let q = lie::exp_twist(std::f64::consts::FRAC_PI_2, &rot_z);
    let y = q.rotation * Vec3::x();
    assert!((y - Vec3::y()).amax() < 1e-16);
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn ad_of_g_times_ad_of_inverse_is_identity(g in pose()) {
        let id = Mat6::identity();
        prop_assert!(close6(&(g.ad() * g.inverse().ad()).to_mat6(), &id, 1e-14));
        prop_assert!(close6(&(g.ad() * g.ad_inv()).to_mat6(), &id, 1e-14));
        prop_assert!(close6(&(g.ad_inv() * g.ad()).to_mat6(), &id, 1e-14));
        prop_assert!(close6(&g.ad_inv().to_mat6(), &g.inverse().ad().to_mat6(), 1e-14));
    }

    #[test]
    fn exp_of_ad_is_ad_of_exp(xi in vec6(2.0), s in 0.0..3.0f64) {
        // Ad_{exp(s ξ̂)} from the crate vs the double-double expm(s·ad_ξ).
        let lhs = lie::exp_twist(s, &xi).ad().to_mat6();
        prop_assert!(close6(&lhs, &ref_exp_ad(s, &xi), 1e-14));
        prop_assert!(close6(&lie::exp_ad(s, &xi).to_mat6(), &ref_exp_ad(s, &xi), 1e-14));
        // And the quartic relation exp(s ad_ξ) = I + ad_ξ T(s).
        let q = Mat6::identity() + lie::ad(&xi) * lie::tangent(s, &xi).to_mat6();
        prop_assert!(close6(&lhs, &q, 1e-14));
    }

    #[test]
    fn exp_is_a_one_parameter_group(xi in vec6(2.0), s in 0.0..2.0f64, t in 0.0..2.0f64) {
        let a = lie::exp_twist(s, &xi) * lie::exp_twist(t, &xi);
        let b = lie::exp_twist(s + t, &xi);
        prop_assert!((a.to_homogeneous() - b.to_homogeneous()).amax() < 1e-14 * (1.0 + b.translation.amax()));
        // RᵀR sums three products of O(1) entries: a few ulps each.
        prop_assert!(b.orthonormality_error() < 4.0 * f64::EPSILON * 4.0);
    }

    #[test]
    fn exp_at_negative_length_is_the_inverse(xi in vec6(3.0), s in 0.0..4.0f64) {
        // ψ = sθ reaches ~20: both branches, and a negative x on each.
        let g = lie::exp_twist(s, &xi);
        let a = lie::exp_twist(-s, &xi) * g;
        let scale = 1.0 + g.translation.amax();
        prop_assert!((a.to_homogeneous() - Mat4::identity()).amax() < 1e-14 * scale);
    }

    #[test]
    fn tangent_derivative_in_s_is_exp(xi in vec6(2.0), s in 0.1..3.0f64) {
        // Central difference, h = 1e-4: error ≈ h²/6·|T'''| + ε/h ≲ 1e-8.
        let h = 1e-4;
        let d = (lie::tangent(s + h, &xi).to_mat6() - lie::tangent(s - h, &xi).to_mat6()) / (2.0 * h);
        prop_assert!(close6(&d, &lie::exp_ad(s, &xi).to_mat6(), 1e-7));
        // And for T₋: d/ds T₋(s) = exp(−s ad_ξ).
        let d = (lie::tangent_minus(s + h, &xi).to_mat6()
            - lie::tangent_minus(s - h, &xi).to_mat6()) / (2.0 * h);
        prop_assert!(close6(&d, &lie::exp_twist(s, &xi).ad_inv().to_mat6(), 1e-7));
    }

    #[test]
    fn tangent_minus_is_ad_inverse_times_tangent(xi in vec6(2.0), s in 0.0..4.0f64) {
        let prod = lie::exp_twist(s, &xi).ad_inv() * lie::tangent(s, &xi);
        prop_assert!(close6(&lie::tangent_minus(s, &xi).to_mat6(), &prod.to_mat6(), 1e-14));
    }

    #[test]
    fn tangent_plus_blocks_are_transposes_of_tangent_minus(xi in vec6(3.0), s in 0.0..4.0f64) {
        // Ad_g T₋ = T₊ with T₊ = [[T_aᵀ, 0], [T_bᵀ, T_aᵀ]]: so R T_a = T_aᵀ
        // and R T_b = T_bᵀ − p̃ T_aᵀ (the dynamics' inertia sums use both).
        let (g, tm) = lie::exp_and_tangent_minus(s, &xi);
        let tp = lie::tangent(s, &xi);
        prop_assert!((tp.a - tm.a.transpose()).amax() < 1e-14 * (1.0 + tm.a.amax()));
        prop_assert!((tp.b - tm.b.transpose()).amax() < 1e-14 * (1.0 + tm.b.amax()));
        let ra = g.rotation * tm.a;
        prop_assert!((ra - tm.a.transpose()).amax() < 1e-14 * (1.0 + tm.a.amax()));
        let rb = g.rotation * tm.b;
        let pta = lie::skew(&g.translation) * tm.a.transpose();
        let scale = 1.0 + tm.b.amax() + pta.amax();
        prop_assert!((rb - (tm.b.transpose() - pta)).amax() < 1e-14 * scale);
    }

    #[test]
    fn ad_of_self_vanishes(xi in vec6(3.0)) {
        let tol = 8.0 * f64::EPSILON * xi.amax() * xi.amax();
        prop_assert!((lie::ad(&xi) * xi).amax() <= tol);
        prop_assert!(lie::ad_vec(&xi, &xi).amax() <= tol);
    }

    #[test]
    fn jacobi_identity(a in vec6(2.0), b in vec6(2.0), c in vec6(2.0)) {
        let br = lie::ad_vec;
        let s = br(&a, &br(&b, &c)) + br(&b, &br(&c, &a)) + br(&c, &br(&a, &b));
        prop_assert!(s.amax() < 1e-13);
        // Antisymmetry.
        prop_assert!((br(&a, &b) + br(&b, &a)).amax() < 1e-14);
    }

    #[test]
    fn coadjoint_duality(xi in vec6(2.0), f in vec6(2.0), eta in vec6(2.0)) {
        // ⟨ad*_ξ F, η⟩ = −⟨F, ad_ξ η⟩, i.e. ad* = −adᵀ.
        let lhs = (lie::coad(&xi) * f).dot(&eta);
        let rhs = -f.dot(&(lie::ad(&xi) * eta));
        prop_assert!((lhs - rhs).abs() < 1e-13);
        prop_assert_eq!(lie::coad(&xi), -lie::ad(&xi).transpose());
    }

    #[test]
    fn vector_forms_match_matrices(xi in vec6(2.0), f in vec6(2.0)) {
        // Sums of up to four products of size |ξ||f| ≤ 4: a few ulps of 16.
        let tol = 8.0 * f64::EPSILON * (1.0 + xi.amax() * f.amax());
        prop_assert!((lie::coad_vec(&xi, &f) - lie::coad(&xi) * f).amax() < tol);
        prop_assert!((lie::ad_vec(&xi, &f) - lie::ad(&xi) * f).amax() < tol);
        prop_assert_eq!(AdOp::ad(&xi).to_mat6(), lie::ad(&xi));
    }

    #[test]
    fn pose_coadjoint(g in pose(), f in vec6(2.0), eta in vec6(2.0)) {
        let coad = g.coad();
        let scale = 1.0 + g.translation.amax();
        prop_assert!((g.coad_vec(&f) - coad * f).amax() < 1e-14 * scale);
        // Ad*_g = Ad_g⁻ᵀ, against a dense LU inverse.
        let inv_t = g.ad().to_mat6().try_inverse().unwrap().transpose();
        prop_assert!(close6(&coad, &inv_t, 1e-13));
        // Ad_g⁻¹ η without the matrix.
        prop_assert!((g.ad_inv_vec(&eta) - g.ad_inv().to_mat6() * eta).amax() < 1e-14 * scale);
    }

    #[test]
    fn adjoint_conjugates_ad(g in pose(), eta in vec6(2.0)) {
        // Ad_g ad_η Ad_g⁻¹ = ad_{Ad_g η}.
        let lhs = g.ad().to_mat6() * lie::ad(&eta) * g.ad_inv().to_mat6();
        let rhs = lie::ad(&(g.ad().mul_vec(&eta)));
        prop_assert!(close6(&lhs, &rhs, 1e-13));
    }

    #[test]
    fn hat_vee_roundtrip(xi in vec6(5.0), w in vec3(5.0)) {
        prop_assert_eq!(lie::vee(&lie::hat(&xi)), xi);
        prop_assert_eq!(lie::unskew(&lie::skew(&w)), w);
        let h: Mat4 = lie::hat(&xi);
        prop_assert_eq!(h.row(3).into_owned(), na::RowVector4::zeros());
        prop_assert_eq!(lie::skew(&w) * Vec3::new(1.0, -2.0, 0.5), w.cross(&Vec3::new(1.0, -2.0, 0.5)));
    }

    #[test]
    fn pose_isometry_roundtrip(g in pose(), x in vec3(2.0)) {
        let iso: na::Isometry3<f64> = g.into();
        let back = Pose::from(iso);
        prop_assert!((back.rotation - g.rotation).amax() < 1e-14);
        prop_assert!((back.translation - g.translation).amax() < 1e-14);
        prop_assert!((iso.transform_point(&na::Point3::from(x)).coords - g.transform_point(&x)).amax() < 1e-13);
        let h = Pose::from_homogeneous(&g.to_homogeneous());
        prop_assert_eq!(h, g);
        let id = g * g.inverse();
        prop_assert!((id.to_homogeneous() - Mat4::identity()).amax() < 1e-14);
    }

    #[test]
    fn adop_matches_dense(a in adop(), b in adop(), v in vec6(2.0), s in -2.0..2.0f64) {
        let (da, db) = (a.to_mat6(), b.to_mat6());
        prop_assert!(close6(&(a * b).to_mat6(), &(da * db), 1e-15));
        prop_assert!(close6(&(a + b).to_mat6(), &(da + db), 1e-15));
        prop_assert!(close6(&(a - b).to_mat6(), &(da - db), 1e-15));
        prop_assert!(close6(&a.scale(s).to_mat6(), &(da * s), 1e-15));
        prop_assert!((a.mul_vec(&v) - da * v).amax() < 1e-14);
        prop_assert!((a * v - da * v).amax() < 1e-14);
        prop_assert!((a.tr_mul_vec(&v) - da.transpose() * v).amax() < 1e-14);
        let (w, u) = a.mul_parts(&lie::angular(&v), &lie::linear(&v));
        prop_assert!((lie::join(&w, &u) - da * v).amax() < 1e-14);
        let inv = a.try_inverse().unwrap();
        prop_assert!(close6(&inv.to_mat6(), &da.try_inverse().unwrap(), 1e-13));
        prop_assert!(close6(&(a * inv).to_mat6(), &Mat6::identity(), 1e-14));
        prop_assert_eq!(AdOp::from_mat6(&da), a);
        prop_assert_eq!(Mat6::from(a), da);
    }

    #[test]
    fn d_tangent_minus_self_is_matrix_times_delta(xi in vec6(2.0), d in vec6(2.0), s in 0.0..4.0f64) {
        let m = lie::d_tangent_minus(s, &xi, &d);
        let v = lie::d_tangent_minus_self(s, &xi, &d);
        prop_assert!((m.mul_vec(&d) - v).amax() < 1e-14 * (1.0 + m.to_mat6().amax() * d.amax()));
    }
}

#[test]
fn singular_adop_has_no_inverse() {
    assert!(AdOp::zeros().try_inverse().is_none());
    assert_eq!(AdOp::identity().try_inverse(), Some(AdOp::identity()));
}
