//! Rigid poses `g ∈ SE(3)`.

use crate::adop::AdOp;
use crate::ops::skew;
use crate::types::{Mat3, Mat4, Mat6, Vec3, Vec6, angular, join, linear};
use nalgebra as na;

/// A pose `g = (R, p) ∈ SE(3)`, `g = [[R, p], [0, 1]]`.
///
/// For a rod section, `R` maps the section's local frame (x = tangent) to the
/// reference frame and `p` is the section centre \[m\] in the reference frame.
/// `R` is stored as a plain matrix (kept orthonormal by construction through
/// [`crate::exp_twist`] and products) because the hot loops need it as one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Rotation matrix `R` (local → reference).
    pub rotation: Mat3,
    /// Translation `p` \[m\].
    pub translation: Vec3,
}

impl Default for Pose {
    fn default() -> Self {
        Self::identity()
    }
}

impl Pose {
    /// The identity pose.
    #[inline]
    pub fn identity() -> Self {
        Self {
            rotation: Mat3::identity(),
            translation: Vec3::zeros(),
        }
    }

    /// Pose from rotation and translation (the rotation is taken as given).
    #[inline]
    pub fn new(rotation: Mat3, translation: Vec3) -> Self {
        Self {
            rotation,
            translation,
        }
    }

    /// `g⁻¹ = (Rᵀ, −Rᵀp)`.
    #[inline]
    pub fn inverse(&self) -> Self {
        let rt = self.rotation.transpose();
        Self {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }

    /// Composition `self · other = (R₁R₂, R₁p₂ + p₁)`.
    #[inline]
    pub fn compose(&self, other: &Pose) -> Pose {
        Pose {
            rotation: self.rotation * other.rotation,
            translation: self.rotation * other.translation + self.translation,
        }
    }

    /// Maps a point given in the local frame: `R x + p`.
    #[inline]
    pub fn transform_point(&self, x: &Vec3) -> Vec3 {
        self.rotation * x + self.translation
    }

    /// Adjoint `Ad_g = [[R, 0], [p̃R, R]]`: maps body twists of the frame `g`
    /// to twists of the reference frame.
    #[inline]
    pub fn ad(&self) -> AdOp {
        AdOp {
            a: self.rotation,
            b: skew(&self.translation) * self.rotation,
        }
    }

    /// `Ad_g⁻¹ = Ad_{g⁻¹} = [[Rᵀ, 0], [−Rᵀp̃, Rᵀ]]`.
    #[inline]
    pub fn ad_inv(&self) -> AdOp {
        // −Rᵀp̃ = (p̃R)ᵀ: row j is p × (column j of R), 18 multiplications
        // instead of a 27-multiplication product with the skew matrix.
        let p = &self.translation;
        let r = &self.rotation;
        let c0 = p.cross(&r.column(0));
        let c1 = p.cross(&r.column(1));
        let c2 = p.cross(&r.column(2));
        AdOp {
            a: r.transpose(),
            b: Mat3::new(
                c0[0], c0[1], c0[2], c1[0], c1[1], c1[2], c2[0], c2[1], c2[2],
            ),
        }
    }

    /// `Ad_g⁻¹ η` without forming the matrix: `(Rᵀω, Rᵀ(v − p × ω))`.
    #[inline]
    pub fn ad_inv_vec(&self, eta: &Vec6) -> Vec6 {
        let w = angular(eta);
        let v = linear(eta);
        join(
            &self.rotation.tr_mul(&w),
            &self.rotation.tr_mul(&(v - self.translation.cross(&w))),
        )
    }

    /// Coadjoint `Ad*_g = Ad_g⁻ᵀ = [[R, p̃R], [0, R]]` (dense): maps wrenches of
    /// the frame `g` to wrenches of the reference frame.
    pub fn coad(&self) -> Mat6 {
        self.ad_inv().to_mat6().transpose()
    }

    /// `Ad*_g 𝓕 = (R M + p × R N, R N)`.
    #[inline]
    pub fn coad_vec(&self, f: &Vec6) -> Vec6 {
        let rn = self.rotation * linear(f);
        join(
            &(self.rotation * angular(f) + self.translation.cross(&rn)),
            &rn,
        )
    }

    /// 4×4 homogeneous matrix.
    pub fn to_homogeneous(&self) -> Mat4 {
        let mut m = Mat4::identity();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.rotation);
        m.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.translation);
        m
    }

    /// From a 4×4 homogeneous matrix (last row ignored).
    pub fn from_homogeneous(m: &Mat4) -> Self {
        Self {
            rotation: m.fixed_view::<3, 3>(0, 0).into_owned(),
            translation: m.fixed_view::<3, 1>(0, 3).into_owned(),
        }
    }

    /// Unit quaternion of the rotation (re-orthonormalised by nalgebra).
    pub fn quaternion(&self) -> na::UnitQuaternion<f64> {
        na::UnitQuaternion::from_rotation_matrix(&na::Rotation3::from_matrix_unchecked(
            self.rotation,
        ))
    }

    /// Conversion to nalgebra's `Isometry3`.
    pub fn to_isometry(&self) -> na::Isometry3<f64> {
        na::Isometry3::from_parts(na::Translation3::from(self.translation), self.quaternion())
    }

    /// Conversion from nalgebra's `Isometry3`.
    pub fn from_isometry(iso: &na::Isometry3<f64>) -> Self {
        Self {
            rotation: iso.rotation.to_rotation_matrix().into_inner(),
            translation: iso.translation.vector,
        }
    }

    /// Largest deviation of `RᵀR` from the identity: a cheap check that the
    /// rotation is still orthonormal after many compositions.
    pub fn orthonormality_error(&self) -> f64 {
        (self.rotation.transpose() * self.rotation - Mat3::identity()).amax()
    }
}

impl std::ops::Mul for Pose {
    type Output = Pose;
    #[inline]
    fn mul(self, rhs: Pose) -> Pose {
        self.compose(&rhs)
    }
}

impl From<na::Isometry3<f64>> for Pose {
    fn from(iso: na::Isometry3<f64>) -> Self {
        Pose::from_isometry(&iso)
    }
}

impl From<Pose> for na::Isometry3<f64> {
    fn from(p: Pose) -> Self {
        p.to_isometry()
    }
}
