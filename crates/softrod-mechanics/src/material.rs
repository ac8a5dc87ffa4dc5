//! Linear elastic, Kelvin–Voigt viscous material.

use crate::error::{MechanicsError, Quantity, non_negative, positive};

/// Material constants (SI): density `ρ` [kg/m³], Young's modulus `E` \[Pa\],
/// shear modulus `G` \[Pa\] and Kelvin–Voigt shear viscosity `μ` [Pa·s].
///
/// Valid by construction (built by [`Material::builder`]): `ρ, E, G > 0`,
/// `μ ≥ 0`, all finite.
///
/// ```
/// use softrod_mechanics::Material;
///
/// let silicone = Material::builder()
///     .density(1000.0)
///     .young(1.0e6)
///     .poisson(0.5)
///     .viscosity(50.0)
///     .build()
///     .unwrap();
/// assert_eq!(silicone.shear_modulus(), 1.0e6 / 3.0);
/// assert!(Material::builder().density(1000.0).young(-1.0).poisson(0.3).build().is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    density: f64,
    young: f64,
    shear: f64,
    viscosity: f64,
    /// The Poisson ratio `G` was derived from, when it was.
    poisson: Option<f64>,
}

impl Material {
    /// A builder: [`MaterialBuilder::density`], [`MaterialBuilder::young`],
    /// then [`MaterialBuilder::poisson`] or [`MaterialBuilder::shear_modulus`],
    /// optionally [`MaterialBuilder::viscosity`] (default 0).
    pub fn builder() -> MaterialBuilder {
        MaterialBuilder::default()
    }

    /// Material with `G = E / (2(1 + ν))`, Poisson ratio `ν ∈ (−1, 0.5]`.
    ///
    /// Positional; kept for the callers not yet moved to [`Material::builder`].
    #[doc(hidden)]
    pub fn with_poisson(
        density: f64,
        young: f64,
        poisson: f64,
        viscosity: f64,
    ) -> Result<Self, MechanicsError> {
        Self::builder()
            .density(density)
            .young(young)
            .poisson(poisson)
            .viscosity(viscosity)
            .build()
    }

    /// Density `ρ` [kg/m³].
    #[inline]
    pub fn density(&self) -> f64 {
        self.density
    }

    /// Young's modulus `E` \[Pa\].
    #[inline]
    pub fn young(&self) -> f64 {
        self.young
    }

    /// Shear modulus `G` \[Pa\]: as given, or `E / (2(1 + ν))`.
    #[inline]
    pub fn shear_modulus(&self) -> f64 {
        self.shear
    }

    /// Shear viscosity `μ` [Pa·s] (0: no internal damping).
    #[inline]
    pub fn viscosity(&self) -> f64 {
        self.viscosity
    }

    /// The Poisson ratio implied by `E` and `G`: `ν = E/(2G) − 1`.
    pub fn poisson(&self) -> f64 {
        self.young / (2.0 * self.shear) - 1.0
    }

    /// The Poisson ratio the material was specified with; `None` when it was
    /// specified by its shear modulus.
    pub fn specified_poisson(&self) -> Option<f64> {
        self.poisson
    }
}

/// Builder of a [`Material`] (see [`Material::builder`]). Every value is
/// checked once, in [`MaterialBuilder::build`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[must_use]
pub struct MaterialBuilder {
    density: Option<f64>,
    young: Option<f64>,
    poisson: Option<f64>,
    shear: Option<f64>,
    viscosity: Option<f64>,
}

impl MaterialBuilder {
    /// Density `ρ > 0` [kg/m³] (required).
    pub fn density(mut self, density: f64) -> Self {
        self.density = Some(density);
        self
    }

    /// Young's modulus `E > 0` \[Pa\] (required).
    pub fn young(mut self, young: f64) -> Self {
        self.young = Some(young);
        self
    }

    /// Poisson ratio `ν ∈ (−1, 0.5]`: `G = E / (2(1 + ν))`. Give this or
    /// [`Self::shear_modulus`].
    pub fn poisson(mut self, poisson: f64) -> Self {
        self.poisson = Some(poisson);
        self
    }

    /// Shear modulus `G > 0` \[Pa\]. Give this or [`Self::poisson`].
    pub fn shear_modulus(mut self, shear: f64) -> Self {
        self.shear = Some(shear);
        self
    }

    /// Kelvin–Voigt shear viscosity `μ ≥ 0` [Pa·s] (default 0: none).
    pub fn viscosity(mut self, viscosity: f64) -> Self {
        self.viscosity = Some(viscosity);
        self
    }

    /// The material, or the first value that is missing or out of range
    /// (in the order density, Young's modulus, Poisson ratio or shear
    /// modulus, viscosity).
    pub fn build(self) -> Result<Material, MechanicsError> {
        let required = |v: Option<f64>, quantity| v.ok_or(MechanicsError::Missing { quantity });
        let density = required(self.density, Quantity::Density)?;
        positive(Quantity::Density, density)?;
        let young = required(self.young, Quantity::YoungsModulus)?;
        positive(Quantity::YoungsModulus, young)?;
        let shear = match (self.poisson, self.shear) {
            (Some(nu), None) => {
                if !(nu > -1.0 && nu <= 0.5) {
                    return Err(MechanicsError::PoissonRatio { value: nu });
                }
                young / (2.0 * (1.0 + nu))
            }
            (None, Some(g)) => {
                positive(Quantity::ShearModulus, g)?;
                g
            }
            (None, None) => {
                return Err(MechanicsError::Missing {
                    quantity: Quantity::PoissonRatio,
                });
            }
            (Some(_), Some(_)) => {
                return Err(MechanicsError::Conflict {
                    quantity: Quantity::ShearModulus,
                    other: Quantity::PoissonRatio,
                });
            }
        };
        let viscosity = self.viscosity.unwrap_or(0.0);
        non_negative(Quantity::Viscosity, viscosity)?;
        Ok(Material {
            density,
            young,
            shear,
            viscosity,
            poisson: self.poisson,
        })
    }
}
