//! Time integration of ODEs, written for the PCS Cosserat-rod equations of
//! motion `M(q) q̈ = τ(t, q, q̇)` but independent of them: a problem is a
//! [`SecondOrderSystem`] (accelerations `q̈ = a(t, q, q̇)`, optional Jacobians)
//! or a first-order [`OdeSystem`] (`y' = f(t, y)`). The generalized
//! coordinates (strains) form a vector space, so classical ODE theory applies;
//! shear and extension make the system stiff (`EA/EI ~ 1/r²`).
//!
//! # Methods ([`Method`])
//!
//! | method | kind | order | step | for |
//! |---|---|---|---|---|
//! | [`Method::Rk4`] | explicit RK | 4 | fixed `dt` | non-stiff, reference runs |
//! | [`Method::Dopri5`] | explicit RK 5(4), PI control, dense order 4 | 5 | adaptive | non-stiff, accurate |
//! | [`Method::Rosw34`] | Rosenbrock–W ROS34PW2, L-stable, Jacobian/LU reuse | 3 | adaptive | stiff (rods) |
//! | [`Method::GeneralizedAlpha`] | implicit structural, `ρ∞` dissipation | 2 | fixed `dt` | large fixed steps |
//!
//! # One interface
//!
//! [`integrate`] (first-order) and [`integrate_second_order`] take the system,
//! the method, `t0`, `t1`, the initial state, [`Options`] and [`Hooks`]
//! (per-step callback that may change the system or stop, an output callback
//! that streams the dense output at `t_eval` as the run proceeds, events,
//! monitors).
//! Output at [`Options::t_eval`] is produced by dense output, never by forcing
//! steps. Failures are [`IntegrateError`]s with the time, step size and check;
//! no NaN or Inf is ever written to a [`Solution`]. Runs are deterministic:
//! same input, same bits.
//!
//! ```
//! use nalgebra::{DMatrix, DVector};
//! use softrod_integrate::{integrate_second_order, Hooks, Method, Options, SecondOrderSystem};
//!
//! /// q̈ = −ω² q.
//! struct Oscillator { w2: f64 }
//! impl SecondOrderSystem for Oscillator {
//!     type Error = std::convert::Infallible;
//!     fn dim(&self) -> usize { 1 }
//!     fn accel(&mut self, _t: f64, q: &DVector<f64>, _qd: &DVector<f64>, qdd: &mut DVector<f64>)
//!         -> Result<(), Self::Error> {
//!         qdd[0] = -self.w2 * q[0];
//!         Ok(())
//!     }
//! }
//!
//! let opts = Options::tol(1e-8, 1e-10).with_t_eval(vec![0.5, 1.0]);
//! let sol = integrate_second_order(&mut Oscillator { w2: 4.0 }, Method::Dopri5, 0.0, 1.0,
//!     &DVector::from_element(1, 1.0), &DVector::zeros(1), &opts, Hooks::new()).unwrap();
//! assert!((sol.y[1][0] - (2.0f64).cos()).abs() < 1e-7);
//! ```
#![warn(missing_docs)]

mod dopri5;
mod driver;
mod error;
mod genalpha;
mod linalg;
mod options;
mod rk4;
mod rod;
mod rosw;
mod system;

pub use driver::{integrate, integrate_second_order};
pub use error::{IntegrateError, SystemError};
pub use genalpha::generalized_alpha_parameters;
pub use options::{
    Control, Direction, Event, EventRecord, Hooks, Method, Monitor, Options, OutputCallback,
    ScalarFn, Solution, Stats, Status, StepCallback, StepInfo,
};
pub use rod::{RodJacobian, RodSystem};
pub use system::{OdeSystem, SecondOrderSystem, fd_jacobian};
