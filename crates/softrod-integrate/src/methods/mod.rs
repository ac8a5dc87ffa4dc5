//! The steppers, one per method. Each builds on the step control below it
//! (`control`, `state`, `stepper`); the driver above picks one.

mod dopri5;
mod esdirk;
mod esdirk5;
mod genalpha;
mod radau5;
mod rk4;
mod rosw;

pub(crate) use dopri5::Dopri5;
pub(crate) use esdirk::{Esdirk, Esdirk43};
pub(crate) use esdirk5::{Esdirk5, Esdirk54};
// The tableaux, for the discrete adjoint and the forward sensitivities
// (`crate::adjoint`, `crate::sensitivity`).
pub(crate) use esdirk::{
    Coefficients as EsdirkCoefficients, explicit_part as esdirk_explicit_part,
    stage_values as esdirk_stage_values,
};
pub(crate) use genalpha::GeneralizedAlpha;
pub use genalpha::generalized_alpha_parameters;
pub(crate) use radau5::{RADAU_A, RADAU_C, Radau5};
pub(crate) use rk4::Rk4;
pub(crate) use rosw::Rosw34;
