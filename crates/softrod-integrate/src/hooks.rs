//! Hooks of a run: per-step and output callbacks, events, monitors.

use nalgebra::DVector;

use crate::solution::Stats;

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
    /// ([`Status::Stopped`](crate::Status::Stopped)).
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
    /// Whether the integration stops at the event ([`Status::Event`](crate::Status::Event)).
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
    /// [`Options::t_eval`](crate::Options::t_eval) time (the method's dense output, exact at step
    /// ends; `t0` first), or `t0` and every accepted step when `t_eval` is
    /// `None` — the same `(t, y)` that go into [`Solution::t`](crate::Solution::t)/[`Solution::y`](crate::Solution::y),
    /// in the same order, before the step's `on_step`. Returning
    /// [`Control::Stop`] ends the run at that output time (`t_final`,
    /// `y_final` are that output; [`Status::Stopped`](crate::Status::Stopped));
    /// [`Control::SystemChanged`] takes effect at the end of the current step
    /// (as from `on_step`).
    pub on_output: Option<OutputCallback<'a, S>>,
    /// Whether outputs are also stored in the [`Solution`](crate::Solution) (default `true`).
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
