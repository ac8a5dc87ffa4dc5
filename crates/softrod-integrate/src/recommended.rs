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
    /// Why: on the rod scenes its tip error tracks `rtol` and it reaches a
    /// given tip error faster than the other methods, being the only
    /// adaptive implicit method whose Newton matrix `M + h²γ²K + hγD` is
    /// solved in O(N) with no `n×n` matrix (measurements: docs/performance.md,
    /// "softrod-integrate"). [`Integrator::Radau5`] can be faster on small
    /// models at tight tolerances (order 5), but its complex Newton shift
    /// needs dense `n×n` factorizations; [`Integrator::Rosenbrock`] and
    /// [`Integrator::Dopri5`] resolve the undamped high-frequency modes the
    /// release excites.
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
    /// bending modes almost undamped (its accuracy at a given `dt`:
    /// docs/performance.md, "softrod-integrate").
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
