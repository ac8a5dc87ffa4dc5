//! Integration options: tolerances, step control, the implicit iteration,
//! limits and output times, and the one check of a method with its options.

// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::error::IntegrateError;
use crate::integrator::Integrator;

/// How the step size is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepControl {
    /// Fixed step `dt` (s): every step is accepted (the last one is shortened
    /// to land on `t1`). For convergence studies and fixed-rate control loops,
    /// and the only mode of [`Integrator::Rk4`](crate::Integrator::Rk4). A step whose
    /// trial state is not finite is an error; generalized-α halves a step
    /// whose Newton iteration fails and regrows it by doubling up to `dt`.
    Fixed(f64),
    /// Error control: the local error estimate of each step is kept below 1
    /// in the weighted RMS norm with weights `atol + rtol·max(|yₙ|, |yₙ₊₁|)`
    /// ([`Options::rtol`], [`Options::atol`]) and the step adapts.
    Adaptive {
        /// First step (s); `None`: Hairer's starting-step heuristic (one
        /// extra right-hand side).
        h0: Option<f64>,
    },
}

/// How the implicit methods solve their step equations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Iteration {
    /// Simplified Newton with Jacobian and factorization reuse, stopped when
    /// the estimated distance to the solution is below `tol` in the weighted
    /// norm of the error test (weights `atol + rtol·|y|`); a step whose
    /// iteration diverges, is too slow or needs more than `max_iter`
    /// iterations is retried with a fresh Jacobian, then a smaller step.
    Newton {
        /// Stopping tolerance, relative to the error weights (Hairer's κ).
        tol: f64,
        /// Iterations per attempt, ≥ 1.
        max_iter: usize,
    },
    /// Generalized-α only: one Newton iteration per step, always accepted —
    /// a linearly implicit scheme. With a [`RodSystem`](crate::RodSystem)
    /// whose Jacobians are [`RodJacobian::ElasticOnly`](crate::RodJacobian)
    /// this is an IMEX scheme: the constant elastic/viscous `K`, `D` (through
    /// `M(q)⁻¹K`, `M(q)⁻¹D`) implicit, gravity, Coriolis and loads explicit —
    /// one evaluation and one solve per step. Use it with `rho_inf < 1` (the
    /// explicitly treated remainder needs a little high-frequency
    /// dissipation; with `rho_inf = 1` the rod release blows up) and, with a
    /// fixed step, a step that resolves the motion (its error is then not
    /// controlled). Non-finite states are still detected and reported.
    LinearlyImplicit,
}

impl Iteration {
    /// The default Newton iteration: `tol = 1e-2`, at most 8 iterations.
    pub const NEWTON: Self = Self::Newton {
        tol: 1e-2,
        max_iter: 8,
    };

    /// Iterations per attempt (1 for the linearly implicit mode).
    pub fn max_iter(self) -> usize {
        match self {
            Self::Newton { max_iter, .. } => max_iter.max(1),
            Self::LinearlyImplicit => 1,
        }
    }
}

/// Integration options. `Default` gives `rtol = 1e-6`, `atol = 1e-9`,
/// adaptive steps from Hairer's starting step, Newton with `tol = 1e-2`, no
/// output times (every step is output), `max_steps = 100_000`.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Relative tolerance: the error test of adaptive steps and the weights
    /// of the Newton test of implicit methods (in either step mode).
    pub rtol: f64,
    /// Absolute tolerance, same units as the state (as `rtol`).
    pub atol: f64,
    /// Fixed or adaptive steps.
    pub step: StepControl,
    /// How implicit methods solve their step equations.
    pub iteration: Iteration,
    /// Rosenbrock–W and generalized-α: re-evaluate the Jacobian at the latest
    /// after this many accepted steps (it is also re-evaluated after every
    /// rejected step / Newton failure that used an older one). 1: every step.
    /// Default 20: on a stiff problem it saves most Jacobian evaluations for
    /// a few percent more steps than 1 (docs/performance.md).
    pub jacobian_max_age: usize,
    /// Largest step (default `∞`).
    pub h_max: f64,
    /// Smallest step before [`IntegrateError::StepSizeUnderflow`](crate::IntegrateError)
    /// (default 0: only the resolution of `t` limits).
    pub h_min: f64,
    /// Maximum number of accepted steps.
    pub max_steps: usize,
    /// Output times (sorted, within `[t0, t1]`), filled by dense output — the
    /// steps are not forced to hit them unless [`steps_to_outputs`](Self::steps_to_outputs).
    /// `None`: output `t0` and every accepted step.
    pub t_eval: Option<Vec<f64>>,
    /// Adaptive steps end on the output times ([`t_eval`](Self::t_eval)), so
    /// every output is a step end rather than a dense-output value
    /// (docs/theory-derivatives.md CD10). Off by default: it costs at least
    /// one step per output, and the dense output is accurate to the
    /// tolerance; it pays where steps grow far beyond the decay of modes the
    /// method damps (a quasi-static settle under drag), where the
    /// interpolant across them does not follow the decay that the step ends
    /// do. Fixed steps ignore it.
    pub steps_to_outputs: bool,
    /// After each accepted step, the state is projected onto the system's
    /// constraint manifold ([`SecondOrderSystem::project`](crate::SecondOrderSystem::project):
    /// a closed chain's loops, docs/theory.md D121) and the step-start
    /// derivative re-evaluated there; the method keeps its Jacobian. For
    /// runs whose loops the stabilization alone lets drift apart at the
    /// tolerance asked (a loose quasi-static run, a loop at self contact).
    /// ESDIRK and ESDIRK5 only; the other methods ignore it. Off by
    /// default.
    pub project_state: bool,
    /// Bound on the max-norm of the state; exceeding it is an error
    /// (default `∞`).
    pub max_norm: f64,
    /// Generalized-α only: the spectral radius at infinite frequency
    /// `ρ∞ ∈ [0, 1]` ([`Integrator::GeneralizedAlpha`]; default
    /// [`Options::DEFAULT_RHO_INF`]).
    pub rho_inf: f64,
    /// Times the adaptive steps never cross: each is the end of a step
    /// (any order; those outside `(t0, t1)` are ignored). Where a drive
    /// stops, starts or changes its rate (a prescribed curve's ends, the
    /// knots of a piecewise-linear tension table) the right-hand side or its
    /// derivatives jump: a step across such a time meets a solution that is
    /// not smooth, which its error estimate and dense output assume. Fixed
    /// steps keep their grid and ignore these. Default: none.
    pub breakpoints: Vec<f64>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            rtol: 1e-6,
            atol: 1e-9,
            step: StepControl::Adaptive { h0: None },
            iteration: Iteration::NEWTON,
            jacobian_max_age: 20,
            h_max: f64::INFINITY,
            h_min: 0.0,
            max_steps: 100_000,
            t_eval: None,
            steps_to_outputs: false,
            project_state: false,
            max_norm: f64::INFINITY,
            rho_inf: Self::DEFAULT_RHO_INF,
            breakpoints: Vec::new(),
        }
    }
}

impl Options {
    /// The default `ρ∞` of generalized-α, 0.9: it damps the unresolved
    /// shear/extension modes of a rod a little (the explicit remainder of
    /// the linearly implicit scheme needs some dissipation: `ρ∞ = 1` blows
    /// up on the release) while leaving resolved bending modes almost
    /// undamped (period error and damping of a mode with `ω·dt ≪ 1` are
    /// second order either way).
    pub const DEFAULT_RHO_INF: f64 = 0.9;

    /// Fixed step `dt` ([`StepControl::Fixed`]); the Newton weights of the
    /// implicit methods are the default `rtol`, `atol`.
    pub fn fixed(dt: f64) -> Self {
        Self {
            step: StepControl::Fixed(dt),
            ..Self::default()
        }
    }

    /// Adaptive steps to the tolerances `rtol`, `atol`.
    pub fn tol(rtol: f64, atol: f64) -> Self {
        Self {
            rtol,
            atol,
            ..Self::default()
        }
    }

    /// Linearly implicit generalized-α ([`Iteration::LinearlyImplicit`]) with
    /// the fixed step `dt`.
    pub fn linearly_implicit(dt: f64) -> Self {
        Self {
            iteration: Iteration::LinearlyImplicit,
            ..Self::fixed(dt)
        }
    }

    /// Linearly implicit generalized-α ([`Iteration::LinearlyImplicit`])
    /// with error control to `rtol`, `atol` (see
    /// [`Integrator::GeneralizedAlpha`]), first
    /// step by Hairer's heuristic.
    pub fn linearly_implicit_tol(rtol: f64, atol: f64) -> Self {
        Self {
            iteration: Iteration::LinearlyImplicit,
            ..Self::tol(rtol, atol)
        }
    }

    /// Preset for interactive/real-time use: `rtol = 1e-3`, `atol = 1e-6`
    /// (millimetre-scale accuracy on a metre-scale rod is what a control loop
    /// or a plot needs; the stiff method then takes few, large steps).
    pub fn coarse() -> Self {
        Self::tol(1e-3, 1e-6)
    }

    /// Preset for validation against references: `rtol = 1e-9`, `atol =
    /// 1e-12` (well below the PCS discretization errors being measured).
    pub fn accurate() -> Self {
        Self::tol(1e-9, 1e-12)
    }

    /// Sets the output times.
    pub fn with_t_eval(mut self, t_eval: Vec<f64>) -> Self {
        self.t_eval = Some(t_eval);
        self
    }

    /// Sets the first step of an adaptive run (no effect on a fixed one).
    pub fn with_h0(mut self, h0: f64) -> Self {
        if let StepControl::Adaptive { h0: h } = &mut self.step {
            *h = Some(h0);
        }
        self
    }

    /// Whether the steps are error-controlled.
    pub fn is_adaptive(&self) -> bool {
        matches!(self.step, StepControl::Adaptive { .. })
    }

    /// The fixed step, if the steps are fixed.
    pub fn fixed_dt(&self) -> Option<f64> {
        match self.step {
            StepControl::Fixed(dt) => Some(dt),
            StepControl::Adaptive { .. } => None,
        }
    }
}

impl Options {
    /// Checks that `integrator` can run with these options — the checks that do
    /// not depend on the problem, its time span or its initial state (those
    /// come when the run starts). A front end calls this to reject a setting
    /// before running it; [`integrate`](crate::integrate) and
    /// [`integrate_second_order`](crate::integrate_second_order) call it
    /// first.
    ///
    /// Rejected ([`IntegrateError::InvalidInput`]): negative or NaN
    /// tolerances or both zero; a fixed step or first step that is not
    /// positive and finite; `h_min`, `h_max` out of order; unsorted `t_eval`;
    /// a Newton `tol` that is not positive or `max_iter = 0`;
    /// [`Integrator::Rk4`] with adaptive steps (it has no error estimate);
    /// [`Iteration::LinearlyImplicit`] with a method other than
    /// generalized-α; `rho_inf` outside `[0, 1]`.
    pub fn validate(&self, integrator: Integrator) -> Result<(), IntegrateError> {
        let bad = |what: String| Err(IntegrateError::InvalidInput { what });
        if !(self.rtol >= 0.0 && self.atol >= 0.0 && self.rtol + self.atol > 0.0) {
            return bad(format!(
                "tolerances rtol = {}, atol = {} must be >= 0 and not both 0",
                self.rtol, self.atol
            ));
        }
        match self.step {
            StepControl::Fixed(dt) if !(dt > 0.0 && dt.is_finite()) => {
                return bad(format!("fixed step dt = {dt} must be positive and finite"));
            }
            StepControl::Adaptive { h0: Some(h0) } if !(h0 > 0.0 && h0.is_finite()) => {
                return bad(format!("first step h0 = {h0} must be positive and finite"));
            }
            _ => {}
        }
        if !(self.h_max > 0.0) || !(self.h_min >= 0.0) || self.h_min > self.h_max {
            return bad(format!(
                "need 0 <= h_min ({}) <= h_max ({}), h_max > 0",
                self.h_min, self.h_max
            ));
        }
        if let Some(te) = &self.t_eval
            && te.windows(2).any(|w| !(w[0] <= w[1]))
        {
            return bad("t_eval must be sorted".into());
        }
        if let Iteration::Newton { tol, max_iter } = self.iteration
            && (!(tol > 0.0) || max_iter == 0)
        {
            return bad(format!(
                "Newton tol = {tol} must be > 0 and max_iter = {max_iter} >= 1"
            ));
        }
        if !(0.0..=1.0).contains(&self.rho_inf) {
            return bad(format!("rho_inf = {} is not in [0, 1]", self.rho_inf));
        }
        if self.is_adaptive() && !integrator.has_error_estimate() {
            return bad(format!(
                "{integrator} has no error estimate: it needs a fixed step (StepControl::Fixed)"
            ));
        }
        if self.iteration == Iteration::LinearlyImplicit
            && integrator != Integrator::GeneralizedAlpha
        {
            return bad(format!(
                "Iteration::LinearlyImplicit applies to generalized-alpha only, not {integrator}"
            ));
        }
        Ok(())
    }
}
