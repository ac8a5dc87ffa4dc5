//! The recommended settings for rods, chosen by measurement
//! (docs/performance.md, section "softrod-integrate"), so that front ends take
//! them from the library.

use crate::integrator::Integrator;
use crate::options::{Iteration, Options};
use crate::rod::{RodJacobian, RodSystem};

/// A method, its options and the Jacobian choice for a [`RodSystem`].
///
/// ```
/// use softrod_integrate::Recommended;
/// let r = Recommended::tolerance(1e-8);
/// assert_eq!((r.options.rtol, r.options.atol), (1e-8, 1e-8));
/// let r = Recommended::tolerance(1e-3);
/// assert_eq!((r.options.rtol, r.options.atol), (1e-3, 1e-6));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Recommended {
    /// The integrator.
    pub integrator: Integrator,
    /// Its options (no output times: set [`Options::t_eval`]).
    pub options: Options,
    /// What [`RodSystem::jacobian`] should be.
    pub jacobian: RodJacobian,
}

impl Recommended {
    /// Steps allowed to a recommended run: enough for any run a callback
    /// does not stop first (1e7 steps of the 3-D release at 32 pieces are
    /// about an hour).
    pub const MAX_STEPS: usize = 50_000_000;

    /// The absolute tolerance that goes with `rtol`: the smaller of `1e-6`
    /// and `rtol`. Strains and strain rates are O(1) in their units for a
    /// rod of metre scale, so an `atol` above `rtol` would cap the accuracy
    /// `rtol` asks for; `1e-6` is the measured default at the default
    /// `rtol = 1e-3` (docs/defaults.md). The scene format's rule for a
    /// `[run]` that sets only `rtol` is the same.
    pub fn atol(rtol: f64) -> f64 {
        1e-6_f64.min(rtol)
    }

    /// Adaptive steps to the relative tolerance `rtol`:
    /// [`Integrator::Esdirk`] with `atol =` [`Recommended::atol`]`(rtol)`,
    /// Newton tolerance `1e-2` of the error weights, the exact Jacobian.
    ///
    /// Why (measured, docs/performance.md): on the undamped release of the
    /// soft cantilever (docs/theory.md §8(h); planar with 8 pieces, 3-D
    /// with 32) the largest tip error over the second falls with every
    /// tighter `rtol` and stays within 0.06–8× `rtol` in metres from
    /// `rtol = 1e-3` to `1e-8` (below `rtol` at loose tolerances, where
    /// `atol` dominates; above it at tight ones, where the global error of
    /// a local-error controller grows like `rtol^{p/(p+1)}`); it reaches 1e-5 m on the planar scene and
    /// 1e-4 m on the 32-piece one faster than every other method here, and
    /// it is the only adaptive implicit method whose Newton matrix
    /// `M + h²γ²K + hγD` is solved in O(N) with no `n×n` matrix (0.01 s of
    /// 500 pieces in well under a second). [`Integrator::Radau5`] is faster on
    /// small models (up to ~50 coordinates: order 5, three stages) and at
    /// tight tolerances there, but its complex Newton shift needs dense
    /// `n×n` factorizations; [`Integrator::Rosenbrock`] and [`Integrator::Dopri5`]
    /// resolve the undamped high-frequency modes the release excites and
    /// take 10–100× longer at equal tip error.
    pub fn tolerance(rtol: f64) -> Self {
        Self {
            integrator: Integrator::Esdirk,
            options: Options {
                max_steps: Self::MAX_STEPS,
                iteration: Iteration::NEWTON,
                ..Options::tol(rtol, Self::atol(rtol))
            },
            jacobian: RodJacobian::recommended(Integrator::Esdirk),
        }
    }

    /// Fixed steps `dt`: the linearly implicit generalized-α
    /// ([`Iteration::LinearlyImplicit`]) with `ρ∞ = 0.9`
    /// ([`Options::DEFAULT_RHO_INF`]) and the elastic
    /// Jacobian ([`RodJacobian::ElasticOnly`], O(N) per step): one
    /// inverse dynamics and one structured solve per step, no error control
    /// (check a run by halving `dt`). `ρ∞ = 0.9` damps the unresolved
    /// shear/extension modes a little (the explicit remainder needs some
    /// dissipation: `ρ∞ = 1` blows up on the release) while leaving resolved
    /// bending modes almost undamped. Measured: `dt = 1e-3` keeps the tip of
    /// the 32-piece 3-D release within ~1.5e-4 m over the second in ~70 ms.
    pub fn fixed_step(dt: f64) -> Self {
        Self {
            integrator: Integrator::GeneralizedAlpha,
            options: Options {
                max_steps: Self::MAX_STEPS,
                rho_inf: Options::DEFAULT_RHO_INF,
                ..Options::linearly_implicit(dt)
            },
            jacobian: RodJacobian::recommended(Integrator::GeneralizedAlpha),
        }
    }

    /// Sets the Jacobian choice on `sys`.
    pub fn configure(&self, sys: &mut RodSystem) {
        sys.jacobian = self.jacobian;
    }
}
