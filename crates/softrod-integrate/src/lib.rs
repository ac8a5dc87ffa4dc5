//! Time integration of ODEs, written for the PCS Cosserat-rod equations of
//! motion `M(q) q̈ = τ(t, q, q̇)` but independent of them: a problem is a
//! [`SecondOrderSystem`] (accelerations `q̈ = a(t, q, q̇)`, optional Jacobians
//! and structured solves) or a first-order [`OdeSystem`] (`y' = f(t, y)`).
//! The generalized coordinates (strains) form a vector space, so classical
//! ODE theory applies; shear and extension make the system stiff
//! (`EA/EI ~ 1/r²`).
//!
//! # Which integrator
//!
//! [`Integrator`] is the one list of methods, under the names the scene
//! format (`run.integrator`), the facade and Python use.
//! [`Recommended::tolerance`] gives the integrator and options for a
//! relative tolerance, [`Recommended::fixed_step`] for a fixed step; both
//! say why, and docs/performance.md ("softrod-integrate") has the
//! measurements.
//!
//! | integrator | kind | order | steps | for |
//! |---|---|---|---|---|
//! | [`Integrator::Esdirk`] | ESDIRK4(3)6L\[2\]SA, L-stable, Newton on `M + h²γ²K + hγD` (O(N)), exact-Jacobian fallback | 4 | adaptive or fixed | stiff rods, any size: **recommended** |
//! | [`Integrator::Esdirk5`] | ESDIRK5(4)7L\[2\]SA, L-stable, the same structured Newton | 5 | adaptive or fixed | stiff rods, tighter tolerances |
//! | [`Integrator::Radau5`] | Radau IIA, RADAU5's design, exact dense Jacobian | 5 | adaptive or fixed | small stiff systems, tight tolerances |
//! | [`Integrator::Rosenbrock`] | Rosenbrock–W ROS34PW2, L-stable, no Newton | 3 | adaptive or fixed | stiff, loose tolerances |
//! | [`Integrator::GeneralizedAlpha`] | Chung–Hulbert / Arnold–Brüls, `ρ∞` dissipation | 2 | fixed, or adaptive | large fixed steps (linearly implicit: [`Iteration::LinearlyImplicit`]) |
//! | [`Integrator::Dopri5`] | explicit RK 5(4), dense order 4 | 5 | adaptive or fixed | non-stiff, references |
//! | [`Integrator::Rk4`] | explicit RK | 4 | fixed | non-stiff, reference runs |
//!
//! The ESDIRKs and generalized-α need a [`SecondOrderSystem`]; the others
//! run on first-order systems too (on `y = (q, q̇)` for a second-order one,
//! with `n×n` Schur complements instead of `2n×2n` matrices).
//!
//! # Stiff rods without dense matrices
//!
//! In PCS the elastic and viscous forces `K(q − q̄)`, `D q̇` are linear with
//! constant block-diagonal `K`, `D`, and they are what makes a rod stiff. A
//! system that provides [`SecondOrderSystem::factor_shifted_mass`] (for a
//! [`RodSystem`], the O(N) articulated recursion of
//! `softrod_dynamics::ShiftedSolver`) and the force residual
//! ([`SecondOrderSystem::force_residual`], an O(N) inverse dynamics) lets
//! the implicit methods iterate with no `n×n` matrix at all: ESDIRK's stage
//! equations, generalized-α with [`RodJacobian::ElasticOnly`]. The exact
//! dense Jacobian ([`SecondOrderSystem::jacobians`]) is evaluated only when
//! that iteration converges badly (ESDIRK), when the cheap Rosenbrock–W
//! matrix stops working (ROS34PW2 refreshes it), and always by Radau IIA,
//! whose complex Newton shift has no real-shifted structured counterpart.
//!
//! # Error control of second-order systems
//!
//! ESDIRK and Radau IIA measure the local error of `y = (q, q̇)` in
//! positions: `‖(e_q, h·e_v)‖` with the position weights — a velocity error
//! counts as the position error it makes over the step. The first-order
//! norm would make the controller resolve every high mode whose *velocity*
//! amplitude exceeds the tolerance although its displacement is far below
//! it (see [`Integrator::Esdirk`]); with the position norm the tip error of
//! the rod scenes tracks `rtol`.
//!
//! # One interface
//!
//! [`integrate`] (first-order) and [`integrate_second_order`] take the system,
//! the [`Integrator`], the time span `(t0, t1)`, the initial state,
//! [`Options`] and one [`Hooks`] object: the outputs streamed from the dense
//! output at `t_eval` as the run proceeds, each accepted step (where a
//! controller may change the system or stop the run), a check of each
//! accepted state, and event functions ([`NoHooks`] for none, [`Callbacks`]
//! for one-off closures). [`Options::validate`] checks an integrator with
//! its options without running. Output at [`Options::t_eval`] is produced by dense output, never
//! by forcing steps. Failures are [`IntegrateError`]s with the time, step size
//! and check; no NaN or Inf is ever written to a [`Solution`]. Runs are
//! deterministic: same input, same bits.
//!
//! ```
//! use nalgebra::{DMatrix, DVector};
//! use softrod_integrate::{integrate_second_order, Integrator, NoHooks, Options, SecondOrderSystem};
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
//! for method in [Integrator::Dopri5, Integrator::Esdirk, Integrator::Radau5] {
//!     let sol = integrate_second_order(&mut Oscillator { w2: 4.0 }, method, (0.0, 1.0),
//!         &DVector::from_element(1, 1.0), &DVector::zeros(1), &opts, &mut NoHooks).unwrap();
//!     assert!((sol.y[1][0] - (2.0f64).cos()).abs() < 1e-6, "{method:?}");
//! }
//! ```
//!
//! # Where things are, and adding an integrator
//!
//! The modules are floors, each importing only from those below it: the
//! plain data (`integrator`: the list; `options`, `hooks`, `solution`,
//! `error`); the user traits and the adaptors the methods run on (`system`,
//! `rod`: the one adaptor that knows rods, `problem`: first- and
//! second-order problems with their iteration matrices, `linalg`); the step
//! control every method shares (`control`: error norm, step clipping,
//! checks; `state`: the step state, its start and first step, dense
//! output; `stepper`: the `Stepper` trait a method implements); the
//! methods, one file each in `methods/`; the `driver` (one loop for every
//! method: outputs, events, checks, hooks) and `recommended`.
//!
//! A new integrator takes four steps:
//! 1. **the list**: a variant of [`Integrator`] with its scene name,
//!    description, order and kind (the compiler then points at every
//!    `match` that must place it: the driver, `Options::validate`,
//!    [`RodJacobian::recommended`], the facade's memory estimate);
//! 2. **the method**: `methods/<name>.rs`, a type implementing `Stepper`
//!    for the problems it supports: its `restart` (its own state and first
//!    evaluation; the start and the first step are shared), one accepted
//!    `step`, `system_changed`, and a dense output if the cubic Hermite of
//!    the step state is not enough;
//! 3. **the driver**: its arm in [`integrate`] and/or
//!    [`integrate_second_order`];
//! 4. **tests**: its order on the linear oscillators (`tests/order.rs`),
//!    its place in the common-interface tests (`tests/api.rs`: dense
//!    output, events, hooks, failures), and for a stiff method the stiff
//!    and rod tests (`tests/stiff.rs`, `tests/rod.rs`). Python's
//!    `softrod.INTEGRATORS` follows the list by itself; the stub's
//!    `_IntegratorName` must be extended (a Python test checks it).
#![forbid(unsafe_code)]
#![warn(missing_docs)]

// Floors, bottom up (each imports only from below); see "Where things are"
// in the crate documentation.
mod error;
mod hooks;
mod integrator;
mod options;
mod solution;

mod linalg;
mod problem;
mod rod;
mod system;

mod control;
mod state;
mod stepper;

mod methods;

mod adjoint;
mod driver;
mod krylov;
mod radau_adjoint;
mod recommended;
mod sensitivity;

pub use adjoint::{
    ADJOINT_INTEGRATORS, AdjointGradient, AdjointSolver, ParameterSystem, Seed, Tape,
    adjoint_second_order, adjoint_second_order_with,
};
pub use driver::{integrate, integrate_second_order};
pub use error::{IntegrateError, SystemError};
pub use hooks::{
    Callbacks, Control, Direction, Event, EventKind, Exceeded, Hooks, NoHooks, ScalarFn, StepInfo,
};
pub use integrator::{Integrator, UnknownIntegrator};
pub use methods::generalized_alpha_parameters;
pub use options::{Iteration, Options, StepControl};
pub use recommended::Recommended;
pub use rod::{ProjectionMisses, RodJacobian, RodSystem};
pub use sensitivity::forward_sensitivity_second_order;
pub use solution::{EventRecord, Solution, Stats, Status};
pub use system::{OdeSystem, SecondOrderSystem, fd_jacobian};

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
