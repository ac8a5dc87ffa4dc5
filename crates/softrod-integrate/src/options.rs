//! Method choice, options, statistics, hooks (callback, events, monitors)
//! and the solution record.

use nalgebra::DVector;

/// The integration method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Classical 4th-order Runge–Kutta with the fixed step
    /// [`Options::dt`] (the last step is shortened to land on `t1`).
    /// Dense output: cubic Hermite (order 3 interpolant, uses the step's end
    /// derivative which the next step reuses as its first stage).
    Rk4,
    /// Dormand–Prince 5(4) (Dormand & Prince 1980; Hairer, Nørsett & Wanner,
    /// *Solving ODEs I*, §II.5, Table 5.2), FSAL, local extrapolation, the PI
    /// step-size controller of Hairer's DOPRI5 (β = 0.04) and its 4th-order
    /// continuous extension (dense output, *ODEs I* §II.6).
    Dopri5,
    /// ROS34PW2 (Rang & Angermann, BIT 45 (2005) 761–787): a 4-stage
    /// Rosenbrock–W method of order 3 with an embedded order-2 solution,
    /// L-stable and stiffly accurate. Linearly implicit: no Newton iteration;
    /// 4 solves with one LU of `I/(hγ) − J` per step.
    ///
    /// Why this one: (1) as a *W*-method it keeps order 3 with any
    /// approximation of the Jacobian, so the Jacobian may be reused across
    /// many steps and the LU across steps of equal size without losing
    /// accuracy — a plain Rosenbrock method (RODAS) needs the exact Jacobian at
    /// every step; (2) no Newton iteration, hence no convergence failure mode
    /// and bit-reproducible cost; (3) L-stability damps the shear/extension
    /// modes (EA/EI ~ 1/r²) instead of ringing; (4) stiff accuracy gives no
    /// order reduction on the elastic relaxation. Radau IIA 5 is more accurate
    /// at tight tolerances but needs a Newton iteration with a complex 2×2
    /// block system; for the rod's moderate tolerances (1e-3…1e-6) order 3 is
    /// the better trade.
    Rosw34,
    /// Generalized-α for second-order systems (Chung & Hulbert, J. Appl.
    /// Mech. 60 (1993) 371–375) in the form of Arnold & Brüls (Multibody Syst.
    /// Dyn. 18 (2007) 185–202): second-order accurate, unconditionally stable
    /// for linear problems, with high-frequency spectral radius `rho_inf ∈
    /// [0, 1]` (1: no dissipation, trapezoidal-like; 0: asymptotic
    /// annihilation). Fixed step [`Options::dt`] (halved and regrown when
    /// Newton fails), simplified Newton with Jacobian and LU reuse.
    /// Only for [`SecondOrderSystem`](crate::SecondOrderSystem).
    ///
    /// With [`Options::error_control`] the step adapts to `rtol`, `atol`
    /// (error per step, weights `atol + rtol·max(|yₙ|, |yₙ₊₁|)`, RMS norm,
    /// accepted if ≤ 1). The estimate is free — no extra evaluation or
    /// solve — and built from the two auxiliary accelerations of the step,
    /// `Δa = aₙ₊₁ − aₙ`, with `aₙ = q̈(tₙ + δh) + O(h²)`, `δ = α_m − α_f`
    /// (Arnold & Brüls 2007):
    /// * positions: `e_q = (β + δ/2 − 1/6) h² Δa`, the leading local error
    ///   `(β + δ/2 − 1/6) h³ q⃛` of the position update (Taylor expansion;
    ///   for `δ = 0` Zienkiewicz & Xie's Newmark estimator, Earthquake Eng.
    ///   Struct. Dyn. 20 (1991) 871–887);
    /// * velocities: `e_v = ½ h Δa ≈ ½ h² q⃛`, the local error of a first-order
    ///   velocity (`vₙ + h·aₙ` against the trapezoidal `vₙ + ½h(aₙ + aₙ₊₁)`):
    ///   an embedded lower-order estimate, as ROS34PW2's, since the method's
    ///   own velocity has no `h²` term to estimate (`γ = ½ − δ`).
    ///
    /// Why both: measured on the linear oscillators of the tests (t = 4,
    /// ρ∞ 0…1, rtol = atol = 1e-3…1e-7), positions alone give global errors
    /// of 15–600× the tolerance, growing like `tol^(−1/3)` (local error
    /// `O(h³)` per step, global `O(h²)`); with the velocity term the global
    /// error is tolerance-proportional: 0.4–2.2× tol in `q` and 1.6–6.3× in
    /// `(q, q̇)` for ρ∞ ≥ 0.5 (up to 8× and 23× for ρ∞ = 0), like ROS34PW2
    /// (3–9×) and DOPRI5 (0.4–4.5×) there. Step doubling would cost 50 %
    /// more work per step; filtering `Δa` by the iteration matrix
    /// (Hairer–Wanner's `(I − hγJ)⁻¹` for RADAU5) saved 2–10 % of the steps
    /// on the rod for one more solve per step, and moving `aₙ` to the new
    /// offset `δh` when `h` changes made no measurable difference on the
    /// oscillators — neither is kept.
    /// Step: the PI controller of DOPRI5 (Gustafsson; Hairer's form) for an
    /// `O(h²)` estimate, `h·0.9·err^(−0.35)·err_prev^(0.2)` within
    /// `[0.2, 5]·h`; after a rejection `h·max(0.2, 0.9·err^(−1/2))`, after a
    /// Newton failure or a non-finite trial a fresh Jacobian if it was old,
    /// else `h/2`; `h` is kept for factors in `[0.9, 1.2]` so the
    /// factorization is reused.
    ///
    /// On the undamped soft rod it resolves the physical high-frequency
    /// ringing (as the other error-controlled methods do; see the crate
    /// documentation): there the fixed-step linearly implicit scheme is the
    /// fast one, and error control is for runs whose accuracy must be
    /// guaranteed rather than checked.
    GeneralizedAlpha {
        /// Spectral radius at infinite frequency, in `[0, 1]`.
        rho_inf: f64,
    },
}

/// Integration options. `Default` gives `rtol = 1e-6`, `atol = 1e-9`, no
/// output times (every step is output), `max_steps = 100_000`.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Relative tolerance (adaptive methods; Newton tolerance scale for
    /// generalized-α).
    pub rtol: f64,
    /// Absolute tolerance, same units as the state.
    pub atol: f64,
    /// Step size of the fixed-step methods ([`Method::Rk4`],
    /// [`Method::GeneralizedAlpha`]) and of adaptive methods run with
    /// `adaptive = false`. Required there; for adaptive runs it is the initial
    /// step (`None`: Hairer's starting-step heuristic).
    pub dt: Option<f64>,
    /// Adaptive methods only: `false` takes fixed steps `dt` and accepts every
    /// step (for convergence studies or fixed-rate control loops).
    pub adaptive: bool,
    /// Largest step (default `∞`).
    pub h_max: f64,
    /// Smallest step before [`IntegrateError::StepSizeUnderflow`](crate::IntegrateError)
    /// (default 0: only the resolution of `t` limits).
    pub h_min: f64,
    /// Maximum number of accepted steps.
    pub max_steps: usize,
    /// Output times (sorted, within `[t0, t1]`), filled by dense output — the
    /// steps are not forced to hit them. `None`: output `t0` and every accepted
    /// step.
    pub t_eval: Option<Vec<f64>>,
    /// Bound on the max-norm of the state; exceeding it is an error
    /// (default `∞`).
    pub max_norm: f64,
    /// Rosenbrock–W and generalized-α: re-evaluate the Jacobian at the latest
    /// after this many accepted steps (it is also re-evaluated after every
    /// rejected step / Newton failure that used an older one). 1: every step.
    /// Default 20: on Van der Pol (μ = 1000) it saves ~90 % of the Jacobians
    /// for ~4 % more steps than 1.
    pub jacobian_max_age: usize,
    /// Generalized-α: Newton tolerance on the weighted increment norm
    /// (weights `atol + rtol·|y|`).
    pub newton_tol: f64,
    /// Generalized-α: maximum Newton iterations per attempt.
    pub newton_max_iter: usize,
    /// Generalized-α: control the local error to `rtol`, `atol` and adapt the
    /// step (then [`Options::dt`] is only the first step; `None`: Hairer's
    /// starting-step heuristic). Default `false`: fixed step `dt`. The
    /// estimate and controller are described at [`Method::GeneralizedAlpha`].
    /// The other methods ignore it (their error control is
    /// [`Options::adaptive`]).
    pub error_control: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            rtol: 1e-6,
            atol: 1e-9,
            dt: None,
            adaptive: true,
            h_max: f64::INFINITY,
            h_min: 0.0,
            max_steps: 100_000,
            t_eval: None,
            max_norm: f64::INFINITY,
            jacobian_max_age: 20,
            newton_tol: 1e-2,
            newton_max_iter: 8,
            error_control: false,
        }
    }
}

impl Options {
    /// Fixed step `dt` (for [`Method::Rk4`] and [`Method::GeneralizedAlpha`]).
    pub fn fixed(dt: f64) -> Self {
        Self {
            dt: Some(dt),
            ..Self::default()
        }
    }

    /// Linearly implicit generalized-α with fixed step `dt`: one Newton
    /// iteration per step, always accepted (`newton_max_iter = 1`,
    /// `newton_tol = ∞`). With a [`RodSystem`](crate::RodSystem) whose
    /// Jacobians are [`RodJacobian::ElasticOnly`](crate::RodJacobian) this is
    /// an IMEX scheme: the constant elastic/viscous `K`, `D` (through
    /// `M(q)⁻¹K`, `M(q)⁻¹D`) implicit, gravity, Coriolis and loads explicit —
    /// one acceleration evaluation and one LU solve per step. Use it with
    /// `rho_inf < 1` (the explicitly treated remainder needs a little
    /// high-frequency dissipation; with `rho_inf = 1` the rod release blows
    /// up) and a step that resolves the motion (its error is not
    /// controlled). Non-finite states are still detected and reported.
    pub fn linearly_implicit(dt: f64) -> Self {
        Self {
            newton_tol: f64::INFINITY,
            newton_max_iter: 1,
            ..Self::fixed(dt)
        }
    }

    /// Linearly implicit generalized-α (as [`Options::linearly_implicit`])
    /// with error control: local error to `rtol`, `atol`, adaptive step
    /// ([`Options::error_control`]), first step by Hairer's heuristic.
    pub fn linearly_implicit_tol(rtol: f64, atol: f64) -> Self {
        Self {
            rtol,
            atol,
            dt: None,
            error_control: true,
            ..Self::linearly_implicit(1.0)
        }
    }

    /// Tolerances `rtol`, `atol`.
    pub fn tol(rtol: f64, atol: f64) -> Self {
        Self {
            rtol,
            atol,
            ..Self::default()
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
}

/// Work counters of one integration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected steps (error test failed, non-finite trial, Newton failure).
    pub rejected_steps: usize,
    /// Right-hand-side / acceleration evaluations made by the integrator
    /// (finite-difference Jacobian calls are not included).
    pub rhs_evaluations: usize,
    /// Jacobian evaluations.
    pub jacobian_evaluations: usize,
    /// LU factorizations.
    pub factorizations: usize,
    /// Linear solves with an LU.
    pub lu_solves: usize,
    /// Newton iterations (generalized-α).
    pub newton_iterations: usize,
}

/// What the per-step callback returns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// Go on.
    Continue,
    /// The callback changed the system (e.g. a control law set new
    /// parameters): cached derivatives and Jacobians are discarded, then go
    /// on.
    SystemChanged,
    /// Stop here; the solution ends at the current step
    /// ([`Status::Stopped`]).
    Stop,
}

/// What the per-step callback sees after each accepted step.
#[derive(Debug, Clone, Copy)]
pub struct StepInfo<'a> {
    /// Time reached.
    pub t: f64,
    /// Size of the step just taken.
    pub h: f64,
    /// State at `t` (first-order form; `(q, q̇)` for second-order systems).
    pub y: &'a DVector<f64>,
    /// Statistics so far.
    pub stats: &'a Stats,
}

/// Which sign changes of an event function count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// From negative to positive.
    Rising,
    /// From positive to negative.
    Falling,
    /// Both.
    Either,
}

/// A per-step callback: sees the step and may change the system.
pub type StepCallback<'a, S> = Box<dyn FnMut(&StepInfo<'_>, &mut S) -> Control + 'a>;

/// An output callback: called with each output time `t`, the state `y` there
/// (from the method's dense output, or the step end itself) and the user's
/// system (for evaluating derived quantities). It may stop the run.
pub type OutputCallback<'a, S> = Box<dyn FnMut(f64, &DVector<f64>, &mut S) -> Control + 'a>;

/// A scalar function of `(t, y)`.
pub type ScalarFn<'a> = Box<dyn FnMut(f64, &DVector<f64>) -> f64 + 'a>;

/// A stop event: a zero of `g(t, y)` located on the dense output.
pub struct Event<'a> {
    /// The event function.
    pub g: ScalarFn<'a>,
    /// Which crossings count.
    pub direction: Direction,
    /// Whether the integration stops at the event ([`Status::Event`]).
    pub terminal: bool,
}

impl<'a> Event<'a> {
    /// A terminal event on any sign change of `g`.
    pub fn terminal(g: impl FnMut(f64, &DVector<f64>) -> f64 + 'a) -> Self {
        Self {
            g: Box::new(g),
            direction: Direction::Either,
            terminal: true,
        }
    }

    /// A recorded (non-terminal) event on any sign change of `g`.
    pub fn record(g: impl FnMut(f64, &DVector<f64>) -> f64 + 'a) -> Self {
        Self {
            g: Box::new(g),
            direction: Direction::Either,
            terminal: false,
        }
    }

    /// Restricts the crossing direction.
    pub fn direction(mut self, direction: Direction) -> Self {
        self.direction = direction;
        self
    }
}

/// A quantity checked after each accepted step (e.g. total energy): its
/// absolute value above `bound` (or non-finite) is an error.
pub struct Monitor<'a> {
    /// Name used in the error.
    pub name: &'static str,
    /// The quantity.
    pub f: ScalarFn<'a>,
    /// The bound on its absolute value.
    pub bound: f64,
}

/// Optional hooks of an integration: per-step callback, output callback,
/// events, monitors. `S` is the user's system type.
pub struct Hooks<'a, S> {
    /// Called after each accepted step (after output and events).
    pub on_step: Option<StepCallback<'a, S>>,
    /// Called at each output time as the integration proceeds: every
    /// [`Options::t_eval`] time (the method's dense output, exact at step
    /// ends; `t0` first), or `t0` and every accepted step when `t_eval` is
    /// `None` — the same `(t, y)` that go into [`Solution::t`]/[`Solution::y`],
    /// in the same order, before the step's `on_step`. Returning
    /// [`Control::Stop`] ends the run at that output time (`t_final`,
    /// `y_final` are that output; [`Status::Stopped`]);
    /// [`Control::SystemChanged`] takes effect at the end of the current step
    /// (as from `on_step`).
    pub on_output: Option<OutputCallback<'a, S>>,
    /// Whether outputs are also stored in the [`Solution`] (default `true`).
    /// `false` (see [`Hooks::stream_outputs`]) leaves `Solution::t`/`y` empty
    /// so a long run streamed through `on_output` keeps O(1) memory.
    pub keep_outputs: bool,
    /// Events, located by root finding on the dense output.
    pub events: Vec<Event<'a>>,
    /// Monitors (blow-up checks).
    pub monitors: Vec<Monitor<'a>>,
}

impl<S> Default for Hooks<'_, S> {
    fn default() -> Self {
        Self {
            on_step: None,
            on_output: None,
            keep_outputs: true,
            events: Vec::new(),
            monitors: Vec::new(),
        }
    }
}

impl<'a, S> Hooks<'a, S> {
    /// No hooks.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets the per-step callback.
    pub fn on_step(mut self, f: impl FnMut(&StepInfo<'_>, &mut S) -> Control + 'a) -> Self {
        self.on_step = Some(Box::new(f));
        self
    }

    /// Sets the output callback (see [`Hooks::on_output`](Hooks#structfield.on_output));
    /// outputs are still stored in the solution.
    pub fn on_output(mut self, f: impl FnMut(f64, &DVector<f64>, &mut S) -> Control + 'a) -> Self {
        self.on_output = Some(Box::new(f));
        self
    }

    /// Sets the output callback and stops storing outputs in the solution
    /// (`keep_outputs = false`): outputs are only streamed to `f`.
    pub fn stream_outputs(
        mut self,
        f: impl FnMut(f64, &DVector<f64>, &mut S) -> Control + 'a,
    ) -> Self {
        self.on_output = Some(Box::new(f));
        self.keep_outputs = false;
        self
    }

    /// Adds an event.
    pub fn event(mut self, e: Event<'a>) -> Self {
        self.events.push(e);
        self
    }

    /// Adds a monitor `|f(t, y)| ≤ bound`.
    pub fn monitor(
        mut self,
        name: &'static str,
        bound: f64,
        f: impl FnMut(f64, &DVector<f64>) -> f64 + 'a,
    ) -> Self {
        self.monitors.push(Monitor {
            name,
            f: Box::new(f),
            bound,
        });
        self
    }
}

/// How an integration ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// `t1` was reached.
    Completed,
    /// The callback returned [`Control::Stop`].
    Stopped,
    /// Terminal event number `index` (in [`Hooks::events`]) fired.
    Event {
        /// Index of the event.
        index: usize,
    },
}

/// An event occurrence.
#[derive(Debug, Clone, PartialEq)]
pub struct EventRecord {
    /// Index in [`Hooks::events`].
    pub index: usize,
    /// Located time.
    pub t: f64,
    /// State there (dense output).
    pub y: DVector<f64>,
}

/// The result of an integration.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// Output times (the requested `t_eval` up to where the run ended, or `t0`
    /// and every accepted step); empty when [`Hooks::keep_outputs`] is
    /// `false`.
    pub t: Vec<f64>,
    /// States at `t` (first-order form; `(q, q̇)` for second-order systems).
    pub y: Vec<DVector<f64>>,
    /// Event occurrences, in time order.
    pub events: Vec<EventRecord>,
    /// Final time (`t1`, or where it stopped).
    pub t_final: f64,
    /// Final state.
    pub y_final: DVector<f64>,
    /// How it ended.
    pub status: Status,
    /// Work counters.
    pub stats: Stats,
}
