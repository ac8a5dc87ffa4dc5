//! Linear elastic, Kelvin–Voigt viscous material.

use crate::error::{MechanicsError, non_negative, positive};

/// Material constants (SI): density `ρ` [kg/m³], Young's modulus `E` [Pa],
/// shear modulus `G` [Pa] and Kelvin–Voigt shear viscosity `μ` [Pa·s].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Density `ρ` [kg/m³].
    pub density: f64,
    /// Young's modulus `E` [Pa].
    pub young: f64,
    /// Shear modulus `G` [Pa].
    pub shear: f64,
    /// Shear viscosity `μ` [Pa·s] (0: no internal damping).
    pub viscosity: f64,
}

impl Material {
    /// Material with `G = E / (2(1 + ν))`, Poisson ratio `ν ∈ (−1, 0.5]`.
    pub fn with_poisson(
        density: f64,
        young: f64,
        poisson: f64,
        viscosity: f64,
    ) -> Result<Self, MechanicsError> {
        if !(poisson > -1.0 && poisson <= 0.5) {
            return Err(MechanicsError::PoissonRatio { value: poisson });
        }
        let m = Self {
            density,
            young,
            shear: young / (2.0 * (1.0 + poisson)),
            viscosity,
        };
        m.validate()?;
        Ok(m)
    }

    /// Checks `ρ, E, G > 0` and `μ ≥ 0`, all finite.
    pub fn validate(&self) -> Result<(), MechanicsError> {
        positive("density [kg/m^3]", self.density)?;
        positive("Young's modulus [Pa]", self.young)?;
        positive("shear modulus [Pa]", self.shear)?;
        non_negative("viscosity [Pa s]", self.viscosity)
    }

    /// The Poisson ratio implied by `E` and `G`: `ν = E/(2G) − 1`.
    pub fn poisson(&self) -> f64 {
        self.young / (2.0 * self.shear) - 1.0
    }
}
