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
//! | [`Method::GeneralizedAlpha`] | implicit structural, `ρ∞` dissipation | 2 | fixed `dt`, or adaptive ([`StepControl::Adaptive`]) | large fixed steps |
//!
//! # Stiff rods: the linearly implicit (IMEX) path
//!
//! In PCS the elastic and viscous forces `K(q − q̄)`, `D q̇` are linear with
//! constant `K`, `D`, and they are what makes a rod stiff (shear and
//! extension, `EA/EI ~ 1/r²`). [`RodJacobian::ElasticOnly`] hands the stiff
//! methods `W = (−M(q)⁻¹K, −M(q)⁻¹D)` instead of the full Jacobian: one
//! mass matrix, no finite differences (at 5 pieces ~10× cheaper than
//! `dynamics_jacobians`), in mass-matrix form
//! ([`SecondOrderSystem::mass_form_jacobians`]): the iteration matrix
//! `I − β'W_q − γ'W_v = M⁻¹(M + β'K + γ'D)` is solved by a Cholesky of the
//! SPD bracket and one product with `M` per solve, `M⁻¹K` is never formed. [`Options::linearly_implicit`] then
//! makes generalized-α take exactly one Newton iteration per step: the
//! elastic/viscous part is implicit, gravity, Coriolis and loads explicit —
//! one evaluation and one solve per step. With the mass-matrix form the
//! evaluation is the force residual `M(q) x − f` by the O(N) inverse
//! dynamics ([`SecondOrderSystem::force_residual`]) rather than a forward
//! dynamics. [`Options::linearly_implicit_tol`] adds error control (a free
//! local error estimate from the step's two auxiliary accelerations, PI step
//! control; see [`Method::GeneralizedAlpha`]).
//!
//! Measured (`benches/benches/integrate.rs`, docs/performance.md): 1 s of the
//! undamped release of a soft cantilever (L = 0.5 m, E = 1e7, all strains)
//! with the tip within 1e-4 m of a converged run.
//!
//! | 5 pieces | setting | wall |
//! |---|---|---|
//! | DOPRI5 | rtol 1e-3 (looser fails) | ~0.8–1.3 s |
//! | RK4 | `dt` = 2.7/ω_max (its stability limit) | ~0.2–0.3 s |
//! | ROS34PW2, exact J | rtol 5e-3 | ~0.13–0.2 s |
//! | ROS34PW2, `ElasticOnly` | rtol 5e-3 | 40–60 ms |
//! | generalized-α, Newton, `ElasticOnly` | ρ∞ 0.8, dt 1.5e-3 | 25–41 ms |
//! | **linearly implicit generalized-α, `ElasticOnly`** | ρ∞ 0.8, dt 1.5e-3 | **5–9 ms** |
//!
//! At 20 pieces the linearly implicit generalized-α (ρ∞ 0.8, dt 1.5e-3,
//! tip error 9.4e-5 m at t = 1) takes 36–40 ms (callgrind: 230 M
//! instructions, 55 % of them inverse dynamics), against ~100–125 ms
//! before the mass-matrix form and the force residual. The wall times are
//! from a shared VM (±30 %); docs/performance.md has the bench's numbers.
//!
//! Why the linearly implicit generalized-α wins on the undamped rod: (1) the
//! error-controlled methods must resolve the undamped shear/extension ringing
//! the release excites (their error estimators see it; ROS34PW2 needs ~550
//! steps where 667 fixed steps of a second-order method suffice for 1e-4 m);
//! (2) a full Newton iteration costs ~4 evaluations per step against one;
//! (3) the exact Jacobian costs `4·n_dof` inverse dynamics where `M⁻¹K` costs
//! one mass matrix, and it changes the accuracy at 1e-4 m not at all.
//! Use `rho_inf < 1` with it (the explicit remainder needs a little
//! high-frequency dissipation: with ρ∞ = 1 the release blows up) and a step
//! that resolves the motion — its error is not controlled; check with a
//! halved step, with ROS34PW2 or with [`Options::linearly_implicit_tol`]
//! when accuracy matters (on this undamped scene error control resolves the
//! ringing like the other error-controlled methods: ~6400 steps at rtol 1e-2
//! for 20 pieces, against 667 fixed steps).
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

// Floors, bottom up (each imports only from below): errors and the plain
// data (options, method, hooks, solution); the user traits and the
// adaptors the methods run on; the step control shared by all methods; the
// steppers; the driver.
mod error;
mod hooks;
mod method;
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

mod driver;

pub use driver::{integrate, integrate_second_order};
pub use error::{IntegrateError, SystemError};
pub use hooks::{
    Control, Direction, Event, Hooks, Monitor, OutputCallback, ScalarFn, StepCallback, StepInfo,
};
pub use method::Method;
pub use methods::generalized_alpha_parameters;
pub use options::{Iteration, Options, StepControl};
pub use rod::{RodJacobian, RodSystem};
pub use solution::{EventRecord, Solution, Stats, Status};
pub use system::{OdeSystem, SecondOrderSystem, fd_jacobian};
