//! What the driver needs from a method: its state between steps and one
//! accepted step at a time.

use nalgebra::DVector;

use crate::error::IntegrateError;
use crate::options::Options;
use crate::problem::Problem;
use crate::solution::Stats;
use crate::state::StepState;

/// One method's state between steps.
pub(crate) trait Stepper<P: Problem> {
    /// The order `p` the starting-step heuristic assumes (the first step
    /// aims at a local error `~ h^(p+1)` of the tolerance).
    const START_ORDER: i32;
    /// Resets the method's own state for a run from the step state's
    /// `(t, y)` (just set by [`init`](Self::init)) and evaluates what its
    /// first step needs, the derivative `f` at least.
    fn restart(
        &mut self,
        p: &mut P,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError>;
    /// Starts a run at `(t0, y0)`, the same for every method: the step
    /// state, the method's [`restart`](Self::restart), then the first step
    /// ([`StepState::first_step`]).
    fn init(
        &mut self,
        p: &mut P,
        t0: f64,
        y0: &DVector<f64>,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        self.state_mut().start(t0, y0);
        self.restart(p, opts, stats)?;
        let h = self.state().first_step(p, Self::START_ORDER, opts, stats)?;
        self.state_mut().h_next = h;
        Ok(())
    }
    /// Takes one accepted step, never beyond `t_end` (landing on it exactly
    /// when it is reached).
    fn step(
        &mut self,
        p: &mut P,
        t_end: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError>;
    /// The shared time/state/derivative bookkeeping.
    fn state(&self) -> &StepState;
    /// The same, to write.
    fn state_mut(&mut self) -> &mut StepState;
    /// Current time.
    fn t(&self) -> f64 {
        self.state().t
    }
    /// Time at the start of the last step.
    fn t_prev(&self) -> f64 {
        self.state().t_prev
    }
    /// Current state.
    fn y(&self) -> &DVector<f64> {
        &self.state().y
    }
    /// Size of the last step.
    fn h_last(&self) -> f64 {
        self.state().h
    }
    /// The second-order stage accelerations of the last accepted step (one
    /// per stage, stage 0 first; [`StepInfo::stages`](crate::StepInfo)).
    /// Empty by default (methods without second-order stages).
    fn stage_accelerations(&self) -> &[DVector<f64>] {
        &[]
    }
    /// Dense output at `t ∈ [t_prev, t]` into `out` (cubic Hermite unless
    /// the method has its own).
    fn dense(&self, t: f64, out: &mut DVector<f64>) {
        self.state().hermite_dense(t, out);
    }
    /// The user changed the system: drop cached derivatives/Jacobians.
    fn system_changed(&mut self, p: &mut P, stats: &mut Stats) -> Result<(), IntegrateError>;
    /// The user changed the forces at the current state but not their
    /// linearization much ([`Control::ForcesChanged`](crate::Control::ForcesChanged)):
    /// re-evaluate the derivative at the current state. By default, as
    /// [`system_changed`](Self::system_changed).
    fn forces_changed(&mut self, p: &mut P, stats: &mut Stats) -> Result<(), IntegrateError> {
        self.system_changed(p, stats)
    }
    /// [`Options::project_state`](crate::Options::project_state): projects
    /// the current state onto the system's constraints and, if that moved
    /// it, re-evaluates the derivative there as
    /// [`forces_changed`](Self::forces_changed) does. `Ok(true)` if the
    /// state moved. By default (methods that do not support it) nothing.
    fn project(&mut self, p: &mut P, stats: &mut Stats) -> Result<bool, IntegrateError> {
        let _ = (p, stats);
        Ok(false)
    }
    /// A step has just ended on one of [`Options::breakpoints`](crate::Options::breakpoints),
    /// where the right-hand side jumps: the next step starts from the
    /// derivative and Jacobian just after it (evaluated at the next
    /// representable time), not from the values the step that ended there
    /// used, which belong to the side before.
    fn restart_after_breakpoint(
        &mut self,
        p: &mut P,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let t = self.t();
        self.state_mut().t = next_after(t);
        let restarted = self.system_changed(p, stats);
        self.state_mut().t = t;
        restarted
    }
}

/// The smallest `f64` greater than `t` (finite `t`).
fn next_after(t: f64) -> f64 {
    if t == 0.0 {
        f64::from_bits(1)
    } else if t > 0.0 {
        f64::from_bits(t.to_bits() + 1)
    } else {
        f64::from_bits(t.to_bits() - 1)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn next_after_is_the_next_representable_time() {
        for t in [0.0, -0.0, 1.0, -1.0, 6.0, 1e-300, -1e-300, 123.456] {
            let n = super::next_after(t);
            assert!(n > t, "{t}");
            // Nothing lies between: the midpoint rounds to one of the two.
            let mid = t + (n - t) / 2.0;
            assert!(mid == t || mid == n, "{t}");
        }
    }
}
