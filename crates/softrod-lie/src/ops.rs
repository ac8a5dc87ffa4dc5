//! Hat/vee and the small adjoint operators of se(3).

use crate::types::{Mat3, Mat4, Mat6, Vec3, Vec6, angular, join, linear};

/// Skew-symmetric matrix `ṽ` with `ṽ w = v × w`.
#[inline(always)]
pub fn skew(v: &Vec3) -> Mat3 {
    Mat3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// Inverse of [`skew`]: the axial vector of the skew-symmetric part of `m`
/// (`(m − mᵀ)/2`, so it is exact for skew `m` and a projection otherwise).
#[inline]
pub fn unskew(m: &Mat3) -> Vec3 {
    Vec3::new(
        0.5 * (m[(2, 1)] - m[(1, 2)]),
        0.5 * (m[(0, 2)] - m[(2, 0)]),
        0.5 * (m[(1, 0)] - m[(0, 1)]),
    )
}

/// se(3) hat: `ξ = (k, q) ↦ ξ̂ = [[k̃, q], [0, 0]]` (4×4), seed eq. (1).
pub fn hat(xi: &Vec6) -> Mat4 {
    let k = skew(&angular(xi));
    let mut m = Mat4::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&k);
    m[(0, 3)] = xi[3];
    m[(1, 3)] = xi[4];
    m[(2, 3)] = xi[5];
    m
}

/// se(3) vee, inverse of [`hat`]: reads `k` from the skew part of the
/// rotation block and `q` from the translation column.
pub fn vee(m: &Mat4) -> Vec6 {
    let r: Mat3 = m.fixed_view::<3, 3>(0, 0).into_owned();
    join(&unskew(&r), &Vec3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]))
}

/// Adjoint of se(3): `ad_ξ = [[k̃, 0], [q̃, k̃]]` (6×6), so that
/// `ad_a b = [a, b]` (the Lie bracket of twists).
pub fn ad(xi: &Vec6) -> Mat6 {
    let k = skew(&angular(xi));
    let q = skew(&linear(xi));
    let mut m = Mat6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&k);
    m.fixed_view_mut::<3, 3>(3, 0).copy_from(&q);
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(&k);
    m
}

/// Coadjoint `ad*_ξ = [[k̃, q̃], [0, k̃]] = −ad_ξᵀ` (6×6), the seed's sign
/// convention: `⟨ad*_ξ 𝓕, η⟩ = −⟨𝓕, ad_ξ η⟩`.
pub fn coad(xi: &Vec6) -> Mat6 {
    let k = skew(&angular(xi));
    let q = skew(&linear(xi));
    let mut m = Mat6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&k);
    m.fixed_view_mut::<3, 3>(0, 3).copy_from(&q);
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(&k);
    m
}

/// `ad_a b = (k_a × k_b, q_a × k_b + k_a × q_b)` without forming a matrix.
#[inline]
pub fn ad_vec(a: &Vec6, b: &Vec6) -> Vec6 {
    let (ka, qa) = (angular(a), linear(a));
    let (kb, qb) = (angular(b), linear(b));
    join(&ka.cross(&kb), &(qa.cross(&kb) + ka.cross(&qb)))
}

/// `ad*_ξ 𝓕 = (k × M + q × N, k × N)` for `ξ = (k, q)`, `𝓕 = (M, N)`, without
/// forming a matrix.
#[inline]
pub fn coad_vec(xi: &Vec6, f: &Vec6) -> Vec6 {
    let (k, q) = (angular(xi), linear(xi));
    let (m, n) = (angular(f), linear(f));
    join(&(k.cross(&m) + q.cross(&n)), &k.cross(&n))
}
