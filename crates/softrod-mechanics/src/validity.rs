//! What a rod model and a rigid body can describe: the rules every layer
//! applies to a state or an input, in one place, so that a scene check,
//! a statics result and a run's watch say the same thing in the same words.
//!
//! **Strains** ([`strain_validity`]). For each piece `n` with strain
//! `ξ_n = (κ, ν)` (angular first; D7, C9):
//! - the stretch `ν_x` must be positive: `ν_x ≤ 0` (or NaN) means the
//!   piece folded onto itself — its sections' tangents point backwards or
//!   it has no length — which no rod model describes ([`StrainProblem::Folded`],
//!   fatal for a run);
//! - linear elasticity (C7) holds for small strains: a stretch outside
//!   `1 ± STRETCH_LIMIT` or a shear `|(ν_y, ν_z)|` above [`SHEAR_LIMIT`] is
//!   beyond the model's validity ([`StrainProblem::Strain`], a warning);
//! - a bending radius `1/|(κ_y, κ_z)|` below the section's half size puts
//!   the centre of curvature inside the section, whose inner side would
//!   overlap itself ([`StrainProblem::Curvature`], a warning). The half size
//!   is taken at the piece's middle (`Section::half_size`).
//!
//! **Rigid inertia** ([`inertia_validity`]). The principal moments of inertia
//! about the centre of mass of any mass distribution satisfy the triangle
//! inequalities `I₁ ≤ I₂ + I₃` (and permutations): `I₂ + I₃ − I₁ = 2∫x₁² dm ≥ 0`.
//! Equality is a flat body (a disk, a plate); a violation is no body at all.

use std::fmt;

use nalgebra::Matrix3;
use softrod_kinematics::RodGeometry;

use crate::section::Section;

/// Stretch deviation `|ν_x − 1|` beyond which a strain is outside the
/// model's validity: extension or compression by half is far outside a
/// linear-elastic rod.
pub const STRETCH_LIMIT: f64 = 0.5;
/// Shear `|(ν_y, ν_z)|` beyond which a strain is outside the model's validity.
pub const SHEAR_LIMIT: f64 = 0.5;
/// Relative slack of the triangle inequality of principal moments
/// (`I₁ ≤ (1 + slack)(I₂ + I₃)`): a flat body meets it with equality, and
/// moments written with a few significant digits land either side of it.
pub const INERTIA_TRIANGLE_SLACK: f64 = 1e-6;

/// What is wrong with a piece's strain (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StrainProblem {
    /// The stretch `ν_x` is not positive (or not a number): the piece is
    /// folded onto itself.
    Folded {
        /// The stretch `ν_x`.
        stretch: f64,
    },
    /// The stretch is outside `1 ± STRETCH_LIMIT` or the shear above
    /// [`SHEAR_LIMIT`].
    Strain {
        /// The stretch `ν_x`.
        stretch: f64,
        /// The shear `|(ν_y, ν_z)|`.
        shear: f64,
    },
    /// The bending radius is below the section's half size.
    Curvature {
        /// Bending radius `1/|(κ_y, κ_z)|` \[m\].
        radius: f64,
        /// The section's half size at the piece's middle \[m\].
        half_size: f64,
    },
}

/// A piece whose strain breaks a rule of [`strain_validity`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrainFinding {
    /// The piece (0-based, base to tip).
    pub piece: usize,
    /// What is wrong.
    pub problem: StrainProblem,
}

impl StrainFinding {
    /// Whether no run can go on from this state (a folded piece).
    pub fn is_fatal(&self) -> bool {
        matches!(self.problem, StrainProblem::Folded { .. })
    }

    /// The headline every layer starts its message with:
    /// `"stretch not positive"`, `"strain beyond the model's validity"` or
    /// `"curvature beyond the model's validity"`. A message reads
    /// `"{headline} {when}: rod {name:?} {self}"`.
    pub fn headline(&self) -> &'static str {
        match self.problem {
            StrainProblem::Folded { .. } => "stretch not positive",
            StrainProblem::Strain { .. } => "strain beyond the model's validity",
            StrainProblem::Curvature { .. } => "curvature beyond the model's validity",
        }
    }
}

impl fmt::Display for StrainFinding {
    /// The details after the rod's name: `piece 2 has stretch -1e0 (the rod
    /// folded onto itself)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.piece;
        match self.problem {
            StrainProblem::Folded { stretch } => write!(
                f,
                "piece {n} has stretch {stretch:e} (the rod folded onto itself)"
            ),
            StrainProblem::Strain { stretch, shear } => write!(
                f,
                "piece {n} has stretch {stretch:.3} and shear {shear:.3} (linear elasticity holds \
                 for small strains; warned beyond stretch 1 ± {STRETCH_LIMIT}, shear {SHEAR_LIMIT})"
            ),
            StrainProblem::Curvature { radius, half_size } => write!(
                f,
                "piece {n} bends with radius {radius:.3e} m, less than the section's half size \
                 {half_size:.3e} m (the section would overlap itself)"
            ),
        }
    }
}

/// The first piece breaking each rule of a rod's strains (see the module
/// documentation); `None` where no piece does. `Copy` and allocation-free:
/// a run's watch evaluates it at every step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrainValidity {
    /// The first folded piece (fatal for a run).
    pub folded: Option<StrainFinding>,
    /// The first piece with a stretch or shear beyond the limits.
    pub strain: Option<StrainFinding>,
    /// The first piece bent tighter than its section.
    pub curvature: Option<StrainFinding>,
}

impl StrainValidity {
    /// Whether every piece keeps every rule.
    pub fn is_valid(&self) -> bool {
        self.folded.is_none() && self.strain.is_none() && self.curvature.is_none()
    }

    /// The findings, fatal first.
    pub fn findings(&self) -> impl Iterator<Item = StrainFinding> + '_ {
        [self.folded, self.strain, self.curvature]
            .into_iter()
            .flatten()
    }
}

/// The validity of a rod's strains at its coordinates `q` (the rod's own
/// `n_dof` values; the strain of piece `n` is `B_n q_n + ξ̄_n`, rest strain
/// included), with its cross-section `section` (for the bending radius).
///
/// # Panics
/// If `q` is shorter than the rod's `n_dof`.
pub fn strain_validity(rod: &RodGeometry, section: &Section, q: &[f64]) -> StrainValidity {
    let mut out = StrainValidity::default();
    let length = rod.length();
    for (n, piece) in rod.pieces().iter().enumerate() {
        let xi = piece.strain(q);
        let stretch = xi[3];
        if out.folded.is_none() && (stretch.is_nan() || stretch <= 0.0) {
            out.folded = Some(StrainFinding {
                piece: n,
                problem: StrainProblem::Folded { stretch },
            });
        }
        let shear = xi[4].hypot(xi[5]);
        if out.strain.is_none() && ((stretch - 1.0).abs() > STRETCH_LIMIT || shear > SHEAR_LIMIT) {
            out.strain = Some(StrainFinding {
                piece: n,
                problem: StrainProblem::Strain { stretch, shear },
            });
        }
        let half_size = section.half_size((piece.start + 0.5 * piece.length) / length);
        let bend = xi[1].hypot(xi[2]);
        if out.curvature.is_none() && bend * half_size > 1.0 {
            out.curvature = Some(StrainFinding {
                piece: n,
                problem: StrainProblem::Curvature {
                    radius: 1.0 / bend,
                    half_size,
                },
            });
        }
    }
    out
}

/// Why a rigid body's inertia cannot be one (see [`inertia_validity`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InertiaProblem {
    /// The principal moments break the triangle inequality: `largest`
    /// exceeds the sum of the other two, `others`.
    Triangle {
        /// The principal moments, ascending \[kg m²\].
        moments: [f64; 3],
    },
}

impl fmt::Display for InertiaProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            InertiaProblem::Triangle { moments: [a, b, c] } => write!(
                f,
                "principal moments [{a:e}, {b:e}, {c:e}] kg m² break the triangle inequality: \
                 {c:e} > {a:e} + {b:e}, which no mass distribution has (I₂ + I₃ − I₁ = 2∫x₁² dm ≥ 0)"
            ),
        }
    }
}

/// Checks that a symmetric positive-definite inertia about the centre of
/// mass \[kg m²\] is one a body can have: its principal moments keep the
/// triangle inequality (up to [`INERTIA_TRIANGLE_SLACK`]). Symmetry and
/// positive definiteness are the caller's to check first.
pub fn inertia_validity(inertia: &Matrix3<f64>) -> Result<(), InertiaProblem> {
    let sym = 0.5 * (inertia + inertia.transpose());
    let mut m: Vec<f64> = sym.symmetric_eigenvalues().iter().copied().collect();
    m.sort_by(f64::total_cmp);
    let moments = [m[0], m[1], m[2]];
    if moments[2] > (1.0 + INERTIA_TRIANGLE_SLACK) * (moments[0] + moments[1]) {
        return Err(InertiaProblem::Triangle { moments });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};
    use softrod_kinematics::{Basis, Strain, straight};
    use softrod_lie::Pose;

    fn rod(pieces: usize) -> RodGeometry {
        RodGeometry::uniform(
            0.4,
            pieces,
            Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qy]).unwrap(),
            straight(),
            Pose::identity(),
        )
        .unwrap()
    }

    const CIRCLE: Section = Section::Circle { radius: 0.01 };

    #[test]
    fn rest_is_valid() {
        let v = strain_validity(&rod(4), &CIRCLE, &[0.0; 12]);
        assert!(v.is_valid(), "{v:?}");
    }

    #[test]
    fn each_rule_finds_its_first_piece() {
        let r = rod(4);
        // Piece 1 folded (stretch 1 − 1.5), piece 2 sheared 0.6, piece 3
        // bent at 150 1/m (radius 6.7 mm < 10 mm).
        let q = [
            0.0, 0.0, 0.0, 0.0, -1.5, 0.0, 0.0, 0.0, 0.6, 150.0, 0.0, 0.0,
        ];
        let v = strain_validity(&r, &CIRCLE, &q);
        let folded = v.folded.unwrap();
        assert_eq!(folded.piece, 1);
        assert!(folded.is_fatal());
        assert_eq!(
            folded.to_string(),
            "piece 1 has stretch -5e-1 (the rod folded onto itself)"
        );
        // The folded piece is also far outside 1 ± 0.5: it is the first
        // piece beyond the strain limits.
        assert_eq!(v.strain.unwrap().piece, 1);
        let c = v.curvature.unwrap();
        assert_eq!(c.piece, 3);
        assert!(!c.is_fatal());
        assert_eq!(c.headline(), "curvature beyond the model's validity");
        assert_eq!(v.findings().count(), 3);
    }

    #[test]
    fn limits_are_sharp() {
        let r = rod(1);
        // At the limits: valid; just beyond: not.
        let at = |q: [f64; 3]| strain_validity(&r, &CIRCLE, &q);
        assert!(at([100.0, 0.5, 0.0]).is_valid());
        assert!(at([0.0, -0.5, 0.5]).is_valid());
        assert!(at([100.1, 0.0, 0.0]).curvature.is_some());
        assert!(at([0.0, 0.5001, 0.0]).strain.is_some());
        assert!(at([0.0, 0.0, 0.5001]).strain.is_some());
        assert!(at([0.0, -1.0, 0.0]).folded.is_some());
        assert!(at([0.0, f64::NAN, 0.0]).folded.is_some());
    }

    #[test]
    fn triangle_inequality_of_inertia() {
        // A thin disk of mass m, radius a: (¼, ¼, ½) m a² — equality.
        let disk = Matrix3::from_diagonal(&Vector3::new(0.25, 0.25, 0.5));
        assert!(inertia_validity(&disk).is_ok());
        // Rotated, it is the same body.
        let r = Rotation3::from_euler_angles(0.3, -0.7, 1.1).into_inner();
        assert!(inertia_validity(&(r * disk * r.transpose())).is_ok());
        // A sphere and a box are bodies.
        assert!(inertia_validity(&Matrix3::identity()).is_ok());
        let b = Matrix3::from_diagonal(&Vector3::new(5.0, 10.0, 13.0));
        assert!(inertia_validity(&b).is_ok());
        // 1, 1, 3: no body.
        let bad = Matrix3::from_diagonal(&Vector3::new(1.0, 3.0, 1.0));
        let e = inertia_validity(&(r * bad * r.transpose())).unwrap_err();
        let InertiaProblem::Triangle { moments } = e;
        assert!((moments[2] - 3.0).abs() < 1e-12, "{moments:?}");
        assert!(e.to_string().contains("triangle inequality"), "{e}");
    }
}
