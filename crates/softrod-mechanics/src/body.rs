//! The mechanical description of one rod: section, material, length.

use crate::error::{MechanicsError, Quantity, positive};
use crate::material::Material;
use crate::section::{Section, SectionProperties};
use softrod_kinematics::RodGeometry;
use softrod_lie::Vec6;

/// Section + material + length of one rod: everything that turns strains and
/// velocities into internal wrenches and inertia ((C5), (C7)).
///
/// Valid by construction ([`RodProperties::new`]). All per-`s` queries take the
/// material abscissa `s ∈ [0, L]` \[m\] (clamped); only a tapered section
/// depends on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RodProperties {
    section: Section,
    material: Material,
    length: f64,
}

impl RodProperties {
    /// Relative tolerance of [`Self::check_rod`]: the body and the kinematic
    /// rod describe the same length when they agree to 1e-9 (a rod of `n`
    /// equal pieces sums to its length within `n` ulps; a million pieces
    /// stay inside).
    pub const LENGTH_RTOL: f64 = 1e-9;

    /// A body of undeformed length `length > 0` \[m\]; checks the length and
    /// the section ([`Section::validate`]). The material is valid by
    /// construction.
    pub fn new(section: Section, material: Material, length: f64) -> Result<Self, MechanicsError> {
        positive(Quantity::RodLength, length)?;
        section.validate()?;
        Ok(Self {
            section,
            material,
            length,
        })
    }

    /// Cross-section (possibly varying along `s`).
    #[inline]
    pub fn section(&self) -> &Section {
        &self.section
    }

    /// Material.
    #[inline]
    pub fn material(&self) -> &Material {
        &self.material
    }

    /// Undeformed length `L` \[m\]; equals the kinematic rod's length.
    #[inline]
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Checks that `rod` has this body's length (to [`Self::LENGTH_RTOL`] relative).
    pub fn check_rod(&self, rod: &RodGeometry) -> Result<(), MechanicsError> {
        if (rod.length() - self.length).abs() > Self::LENGTH_RTOL * self.length.max(rod.length()) {
            return Err(MechanicsError::LengthMismatch {
                body: self.length,
                rod: rod.length(),
            });
        }
        Ok(())
    }

    /// Section properties at abscissa `s` \[m\].
    #[inline]
    pub fn properties(&self, s: f64) -> SectionProperties {
        self.section.properties(s / self.length)
    }

    /// Diagonal of the screw inertia per unit length (C5)
    /// `𝓜(s) = diag(ρJx, ρJy, ρJz, ρA, ρA, ρA)` [kg·m, kg·m, kg·m, kg/m ×3],
    /// body frame at the section centre.
    #[inline]
    pub fn screw_inertia(&self, s: f64) -> Vec6 {
        let p = self.properties(s);
        let r = self.material.density();
        Vec6::new(
            r * p.jx,
            r * p.jy,
            r * p.jz,
            r * p.area,
            r * p.area,
            r * p.area,
        )
    }

    /// Diagonal of the stiffness `Γ(s) = diag(GJx, EJy, EJz, EA, GA, GA)`
    /// [N·m², N·m², N·m², N, N, N] (C7); bending takes `E`, docs/theory.md §9 erratum 2.
    /// No shear correction factor is applied.
    #[inline]
    pub fn stiffness(&self, s: f64) -> Vec6 {
        let p = self.properties(s);
        let (e, g) = (self.material.young(), self.material.shear_modulus());
        Vec6::new(
            g * p.jx,
            e * p.jy,
            e * p.jz,
            e * p.area,
            g * p.area,
            g * p.area,
        )
    }

    /// Diagonal of the Kelvin–Voigt viscosity
    /// `γ(s) = diag(μJx, 3μJy, 3μJz, 3μA, μA, μA)` [N·m²·s, …, N·s] (C7).
    #[inline]
    pub fn viscosity(&self, s: f64) -> Vec6 {
        let p = self.properties(s);
        let m = self.material.viscosity();
        Vec6::new(
            m * p.jx,
            3.0 * m * p.jy,
            3.0 * m * p.jz,
            3.0 * m * p.area,
            m * p.area,
            m * p.area,
        )
    }

    /// Mass per unit length `ρA(s)` [kg/m].
    #[inline]
    pub fn mass_per_length(&self, s: f64) -> f64 {
        self.material.density() * self.properties(s).area
    }

    /// True when every property is constant along the rod.
    #[inline]
    pub fn is_uniform(&self) -> bool {
        self.section.is_uniform()
    }
}
