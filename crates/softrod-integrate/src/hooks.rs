//! What a run calls back: the [`Hooks`] trait (outputs, accepted steps,
//! checks, events), the empty [`NoHooks`] and the closure-based
//! [`Callbacks`].

use nalgebra::DVector;

use crate::solution::Stats;

/// What a hook returns: go on, the system changed, or stop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// Go on.
    Continue,
    /// The hook changed the system (e.g. a control law set new inputs, a
    /// contact set changed): cached derivatives and Jacobians are discarded
    /// and the event functions re-evaluated, then the run goes on from the
    /// same state.
    SystemChanged,
    /// The hook changed the forces at the current state, not how they
    /// vary with it (a contact model committed its friction anchors or
    /// healed a penalty offset, docs/theory-contact.md CT5, CT15, CT25):
    /// the derivative at the current state and the event functions are
    /// re-evaluated. A method may keep its Jacobian across it (its
    /// stepper's `forces_changed`): ESDIRK does (CT25 (a), with the stop
    /// location of CT29); the others drop it as for
    /// [`SystemChanged`](Self::SystemChanged).
    ForcesChanged,
    /// Stop here; the solution ends at the current step or output
    /// ([`Status::Stopped`](crate::Status::Stopped)).
    Stop,
}

/// What [`Hooks::step`] sees after each accepted step. Further fields may
/// come (what a method used on the step), so it is built by the driver
/// only.
#[derive(Debug, Clone, Copy)]
#[non_exhaustive]
pub struct StepInfo<'a> {
    /// Time reached.
    pub t: f64,
    /// Size of the step just taken.
    pub h: f64,
    /// State at `t` (first-order form; `(q, q̇)` for second-order systems).
    pub y: &'a DVector<f64>,
    /// Statistics so far.
    pub stats: &'a Stats,
    /// The second-order stage accelerations of the step just taken, one per
    /// stage of the method's tableau (stage 0 first), for the methods that
    /// have them (the ESDIRKs); empty otherwise. The discrete adjoint's
    /// tape keeps them as the starting points of its recomputed stages
    /// (docs/theory-control.md G34).
    pub stages: &'a [DVector<f64>],
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

/// How an event function's zeros count: the crossing direction, and
/// whether the run stops at the first one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EventKind {
    /// Which crossings count.
    pub direction: Direction,
    /// Whether the integration stops at the event ([`Status::Event`](crate::Status::Event)).
    pub terminal: bool,
}

impl EventKind {
    /// A terminal event on any sign change.
    pub const TERMINAL: Self = Self {
        direction: Direction::Either,
        terminal: true,
    };
    /// A recorded (non-terminal) event on any sign change.
    pub const RECORD: Self = Self {
        direction: Direction::Either,
        terminal: false,
    };

    /// Restricts the crossing direction.
    pub const fn direction(self, direction: Direction) -> Self {
        Self { direction, ..self }
    }
}

/// A bound a [`Hooks::check`] found exceeded (or a non-finite quantity):
/// the run ends with [`IntegrateError::BoundExceeded`](crate::IntegrateError::BoundExceeded).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exceeded {
    /// Name of the quantity.
    pub what: &'static str,
    /// Its value.
    pub value: f64,
    /// The bound on its absolute value.
    pub bound: f64,
}

/// What a run calls back, as one object: the outputs as they are produced,
/// each accepted step (where a controller may change the system or stop the
/// run), a check of each accepted state, and event functions located on the
/// dense output. One object, so that an observer, a controller and a check
/// share their state as fields, with no cells. `S` is the user's system
/// type; every method has a default that does nothing, and [`NoHooks`] is
/// the object with no hooks.
///
/// Per accepted step the driver calls, in order: [`check`](Self::check),
/// the [`event`](Self::event) functions (located in the step), the
/// [`output`](Self::output)s in the step, then [`step`](Self::step). States
/// are in first-order form, `y = (q, q̇)` for a second-order system.
///
/// ```
/// use nalgebra::DVector;
/// use softrod_integrate::{
///     Control, Hooks, Integrator, Options, SecondOrderSystem, StepInfo, integrate_second_order,
/// };
///
/// /// q̈ = −k q with a stiffness a controller may change.
/// struct Spring { k: f64 }
/// impl SecondOrderSystem for Spring {
///     type Error = std::convert::Infallible;
///     fn dim(&self) -> usize { 1 }
///     fn accel(&mut self, _t: f64, q: &DVector<f64>, _qd: &DVector<f64>, qdd: &mut DVector<f64>)
///         -> Result<(), Self::Error> {
///         qdd[0] = -self.k * q[0];
///         Ok(())
///     }
/// }
///
/// /// Counts the outputs and doubles the stiffness once, after t = 1.
/// #[derive(Default)]
/// struct Stiffen { outputs: usize, switched_at: Option<f64> }
/// impl Hooks<Spring> for Stiffen {
///     fn output(&mut self, _t: f64, _y: &DVector<f64>, _sys: &mut Spring) -> Control {
///         self.outputs += 1;
///         Control::Continue
///     }
///     fn step(&mut self, info: &StepInfo<'_>, sys: &mut Spring) -> Control {
///         if info.t >= 1.0 && self.switched_at.is_none() {
///             self.switched_at = Some(info.t);
///             sys.k *= 2.0;
///             return Control::SystemChanged;
///         }
///         Control::Continue
///     }
/// }
///
/// let mut hooks = Stiffen::default();
/// let opts = Options::tol(1e-8, 1e-10).with_t_eval(vec![0.0, 1.0, 2.0]);
/// let one = DVector::from_element(1, 1.0);
/// integrate_second_order(&mut Spring { k: 1.0 }, Integrator::Dopri5, (0.0, 2.0), &one,
///     &DVector::zeros(1), &opts, &mut hooks).unwrap();
/// assert_eq!(hooks.outputs, 3);
/// assert!(hooks.switched_at.unwrap() >= 1.0);
/// ```
pub trait Hooks<S> {
    /// Whether outputs are also stored in the [`Solution`](crate::Solution)
    /// (default `true`). `false` leaves `Solution::t`/`y` empty, so that a
    /// long run streamed through [`output`](Self::output) keeps O(1)
    /// memory.
    fn keep_outputs(&self) -> bool {
        true
    }

    /// Called at each output time as the integration proceeds: every
    /// [`Options::t_eval`](crate::Options::t_eval) time (the method's dense
    /// output, exact at step ends; `t0` first), or `t0` and every accepted
    /// step when `t_eval` is `None` — the same `(t, y)` that go into
    /// [`Solution::t`](crate::Solution::t)/[`Solution::y`](crate::Solution::y),
    /// in the same order, before the step's [`step`](Self::step). `sys`
    /// evaluates derived quantities. [`Control::Stop`] ends the run at that
    /// output time (`t_final`, `y_final` are that output;
    /// [`Status::Stopped`](crate::Status::Stopped));
    /// [`Control::SystemChanged`] takes effect at the end of the current
    /// step.
    fn output(&mut self, t: f64, y: &DVector<f64>, sys: &mut S) -> Control {
        let _ = (t, y, sys);
        Control::Continue
    }

    /// Called after each accepted step, after its outputs: may change the
    /// system (return [`Control::SystemChanged`]) or stop the run
    /// ([`Control::Stop`]; the solution ends at this step).
    fn step(&mut self, info: &StepInfo<'_>, sys: &mut S) -> Control {
        let _ = (info, sys);
        Control::Continue
    }

    /// Checks the state `y` at `t` after each accepted step (e.g. a bound
    /// on the energy): `Err` ends the run with
    /// [`IntegrateError::BoundExceeded`](crate::IntegrateError::BoundExceeded).
    fn check(&mut self, t: f64, y: &DVector<f64>) -> Result<(), Exceeded> {
        let _ = (t, y);
        Ok(())
    }

    /// The event functions, one [`EventKind`] each (default none), read
    /// once when the run starts; their indices are those of
    /// [`EventRecord::index`](crate::EventRecord::index) and
    /// [`Status::Event`](crate::Status::Event).
    fn events(&self) -> &[EventKind] {
        &[]
    }

    /// The value of event function `i < events().len()` at `(t, y)`; its
    /// sign changes are located on the dense output (Illinois regula falsi,
    /// to a few ulps of `t`).
    fn event(&mut self, i: usize, t: f64, y: &DVector<f64>) -> f64 {
        let _ = (i, t, y);
        f64::NAN
    }
}

/// No hooks: every output is stored, nothing else happens.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoHooks;

impl<S> Hooks<S> for NoHooks {}

/// A scalar function of `(t, y)`.
pub type ScalarFn<'a> = Box<dyn FnMut(f64, &DVector<f64>) -> f64 + 'a>;

/// An event function with its [`EventKind`], for [`Callbacks::event`].
pub struct Event<'a> {
    g: ScalarFn<'a>,
    kind: EventKind,
}

impl<'a> Event<'a> {
    /// A terminal event on any sign change of `g`.
    pub fn terminal(g: impl FnMut(f64, &DVector<f64>) -> f64 + 'a) -> Self {
        Self {
            g: Box::new(g),
            kind: EventKind::TERMINAL,
        }
    }

    /// A recorded (non-terminal) event on any sign change of `g`.
    pub fn record(g: impl FnMut(f64, &DVector<f64>) -> f64 + 'a) -> Self {
        Self {
            g: Box::new(g),
            kind: EventKind::RECORD,
        }
    }

    /// Restricts the crossing direction.
    pub fn direction(mut self, direction: Direction) -> Self {
        self.kind = self.kind.direction(direction);
        self
    }
}

/// A quantity checked after each accepted step: `|f(t, y)| ≤ bound`.
struct Monitor<'a> {
    name: &'static str,
    f: ScalarFn<'a>,
    bound: f64,
}

/// A per-step callback.
type StepFn<'a, S> = Box<dyn FnMut(&StepInfo<'_>, &mut S) -> Control + 'a>;
/// An output callback.
type OutputFn<'a, S> = Box<dyn FnMut(f64, &DVector<f64>, &mut S) -> Control + 'a>;

/// [`Hooks`] from closures, for one-off hooks that share no state (a
/// terminal event, a progress counter): closures for
/// [`output`](Hooks::output) and [`step`](Hooks::step), events, and
/// monitors `|f(t, y)| ≤ bound` as the [`check`](Hooks::check). Hooks that
/// share state implement [`Hooks`] on one struct instead.
pub struct Callbacks<'a, S> {
    on_step: Option<StepFn<'a, S>>,
    on_output: Option<OutputFn<'a, S>>,
    keep_outputs: bool,
    events: Vec<ScalarFn<'a>>,
    kinds: Vec<EventKind>,
    monitors: Vec<Monitor<'a>>,
}

impl<S> Default for Callbacks<'_, S> {
    fn default() -> Self {
        Self {
            on_step: None,
            on_output: None,
            keep_outputs: true,
            events: Vec::new(),
            kinds: Vec::new(),
            monitors: Vec::new(),
        }
    }
}

impl<'a, S> Callbacks<'a, S> {
    /// No callbacks.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets the per-step callback ([`Hooks::step`]).
    pub fn on_step(mut self, f: impl FnMut(&StepInfo<'_>, &mut S) -> Control + 'a) -> Self {
        self.on_step = Some(Box::new(f));
        self
    }

    /// Sets the output callback ([`Hooks::output`]); outputs are still
    /// stored in the solution.
    pub fn on_output(mut self, f: impl FnMut(f64, &DVector<f64>, &mut S) -> Control + 'a) -> Self {
        self.on_output = Some(Box::new(f));
        self
    }

    /// Sets the output callback and stops storing outputs in the solution
    /// ([`Hooks::keep_outputs`] `false`): outputs are only streamed to `f`.
    pub fn stream_outputs(
        mut self,
        f: impl FnMut(f64, &DVector<f64>, &mut S) -> Control + 'a,
    ) -> Self {
        self.on_output = Some(Box::new(f));
        self.keep_outputs = false;
        self
    }

    /// Adds an event (index: the number added before it).
    pub fn event(mut self, e: Event<'a>) -> Self {
        self.events.push(e.g);
        self.kinds.push(e.kind);
        self
    }

    /// Adds a monitor `|f(t, y)| ≤ bound` (a non-finite `f` fails it too).
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

impl<S> Hooks<S> for Callbacks<'_, S> {
    fn keep_outputs(&self) -> bool {
        self.keep_outputs
    }

    fn output(&mut self, t: f64, y: &DVector<f64>, sys: &mut S) -> Control {
        self.on_output
            .as_mut()
            .map_or(Control::Continue, |f| f(t, y, sys))
    }

    fn step(&mut self, info: &StepInfo<'_>, sys: &mut S) -> Control {
        self.on_step
            .as_mut()
            .map_or(Control::Continue, |f| f(info, sys))
    }

    // Negated comparison: a NaN quantity fails the check.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn check(&mut self, t: f64, y: &DVector<f64>) -> Result<(), Exceeded> {
        for m in &mut self.monitors {
            let value = (m.f)(t, y);
            if !(value.abs() <= m.bound) {
                return Err(Exceeded {
                    what: m.name,
                    value,
                    bound: m.bound,
                });
            }
        }
        Ok(())
    }

    fn events(&self) -> &[EventKind] {
        &self.kinds
    }

    fn event(&mut self, i: usize, t: f64, y: &DVector<f64>) -> f64 {
        (self.events[i])(t, y)
    }
}
