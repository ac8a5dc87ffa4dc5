//! What the contact test files share (every test file compiles this module
//! on its own, so not every item is used by each): the rod's radius,
//! length and gravity, its silicone-like material, and an observer that
//! keeps every sample. Each file keeps its own scenes and settings.
#![allow(dead_code)]

use softrod::{Flow, Observer, Sample};
use softrod_mechanics::Material;

/// Radius of the test rods \[m\].
pub const R: f64 = 0.01;
/// Length of the test rods \[m\].
pub const L: f64 = 0.2;
/// Gravity \[m/s²\].
pub const G: f64 = 9.81;
/// Density of the test rods \[kg/m³\].
pub const RHO: f64 = 1000.0;

/// An incompressible (ν = 0.5) material of density [`RHO`], Young's
/// modulus `young` \[Pa\] and Kelvin–Voigt viscosity `viscosity` \[Pa s\].
pub fn material(young: f64, viscosity: f64) -> Material {
    Material::builder()
        .density(RHO)
        .young(young)
        .poisson(0.5)
        .viscosity(viscosity)
        .build()
        .unwrap()
}

/// The silicone of most tests: E = 1 MPa, no viscosity.
pub fn silicone() -> Material {
    material(1.0e6, 0.0)
}

/// Every sample of a run: `(t, q, q̇)`.
pub struct Keep(pub Vec<(f64, Vec<f64>, Vec<f64>)>);

impl Observer for Keep {
    fn sample(&mut self, s: Sample<'_>) -> Result<Flow, String> {
        self.0.push((s.t, s.q.to_vec(), s.qd.to_vec()));
        Ok(Flow::Continue)
    }
}
