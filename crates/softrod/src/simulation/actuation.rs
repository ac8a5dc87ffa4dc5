//! Inverse statics on the simulation's model: [`Simulation::solve_actuation`]
//! (the solver is [`crate::control`]).

use super::Simulation;
use crate::control::{Actuation, ActuationOptions, Target, solve_actuation};
use crate::error::Result;
use crate::limits::STATICS_DENSE_MATRICES;

impl Simulation {
    /// Cable tensions within `0 ≤ T ≤ max_tension` (with the actuated
    /// joints' forces within `|f| ≤ max_force`, IS14, and the unknown
    /// loads of `options`, IS13) and the static
    /// equilibrium that bring the targets' sections and bodies closest to
    /// them, the least effort among equally close ones, closed models
    /// included (docs/theory-control.md IS1–IS14; [`solve_actuation`]). Prescribed joints hold their values
    /// at `options.time`. The simulation's cable inputs
    /// ([`Self::set_cable_tensions`]) are left as they were; without
    /// `options.initial_q` the search starts from the initial `q`.
    pub fn solve_actuation(
        &mut self,
        targets: &[Target],
        options: &ActuationOptions,
    ) -> Result<Actuation> {
        // The statics' dense matrices plus the sensitivity (n_dof × n_dof
        // tangent and its factors).
        self.check_dense("inverse statics", STATICS_DENSE_MATRICES + 2)?;
        let mut options = options.clone();
        if options.initial_q.is_none() {
            options.initial_q = Some(self.q0.as_slice().to_vec());
        }
        let s = &mut self.system;
        solve_actuation(&s.model, &mut s.data, targets, &options)
    }
}
