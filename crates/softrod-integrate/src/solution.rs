//! What a run returns: outputs, events, final state, status, work counters.

use nalgebra::DVector;

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

/// How an integration ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// `t1` was reached.
    Completed,
    /// The callback returned [`Control::Stop`](crate::Control::Stop).
    Stopped,
    /// Terminal event number `index` (in [`Hooks::events`](crate::Hooks::events)) fired.
    Event {
        /// Index of the event.
        index: usize,
    },
}

/// An event occurrence.
#[derive(Debug, Clone, PartialEq)]
pub struct EventRecord {
    /// Index in [`Hooks::events`](crate::Hooks::events).
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
    /// and every accepted step); empty when [`Hooks::keep_outputs`](crate::Hooks::keep_outputs) is
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
    /// The step the method would take next from `(t_final, y_final)` \[s\]
    /// (its controller's proposal for an adaptive method, the step for a
    /// fixed-step one; `0` if no step was taken; if the last step was cut
    /// short to land on the end of the span, the larger of the proposal
    /// before it and after it). A continuation of the run with the same
    /// right-hand side can start with it
    /// ([`StepControl::Adaptive`](crate::StepControl::Adaptive) `{ h0:
    /// Some(h_next) }`) instead of ramping up again from a small first
    /// step. Not after a jump of the inputs: the transient it starts needs
    /// the small first step again (measured on 20 Hz control periods of a
    /// cable arm, docs/performance.md "Learning environments": the carried
    /// step is rejected ~5 times a period).
    pub h_next: f64,
}
