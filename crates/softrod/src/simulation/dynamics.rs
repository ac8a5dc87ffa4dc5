//! Evaluations of the equations of motion `M(q) q̈ + b(t, q, q̇) = τ`
//! (D17–D27) and of their terms, with the simulation's buffers.

use nalgebra::{DMatrix, DVector};
use softrod_dynamics::{
    Data, Energies, FdDerivatives, Linearization, actuation_matrix, bias_force, coriolis_matrix,
    damping_matrix, energies, forward_dynamics, generalized_gravity, inverse_dynamics, linearize,
    mass_matrix, stiffness_matrix,
};

use super::Simulation;
use crate::error::Result;

impl Simulation {
    /// Forward dynamics `q̈(t, q, q̇)` under actuator force `tau` (n_dof,
    /// `None`: 0) by the O(N) articulated recursion (D23–D27).
    pub fn forward_dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        qdot: &[f64],
        tau: Option<&[f64]>,
    ) -> Result<DVector<f64>> {
        let s = &mut self.system;
        Ok(forward_dynamics(&s.model, &mut s.data, t, q, qdot, tau)?.clone())
    }

    /// The generalized forces the prescribed joints' drives apply (D60;
    /// N·m or N, in the order of [`Self::prescribed_names`]) at
    /// `(t, q, q̇)` under actuator force `tau`, from the forward dynamics;
    /// empty without prescribed joints.
    pub fn prescribed_forces(
        &mut self,
        t: f64,
        q: &[f64],
        qdot: &[f64],
        tau: Option<&[f64]>,
    ) -> Result<DVector<f64>> {
        let s = &mut self.system;
        forward_dynamics(&s.model, &mut s.data, t, q, qdot, tau)?;
        Ok(s.data.prescribed_force.clone())
    }

    /// The closures' names and residuals at `q` (one per `[[closure]]`, in
    /// order): `max(‖d‖, ℓ‖r‖)` \[m\], the misfit of the held frames
    /// (docs/theory.md D66); empty without closures.
    pub fn closure_residuals(&mut self, q: &[f64]) -> Result<Vec<(String, f64)>> {
        self.check("q", q)?;
        let (model, data) = self.at_time();
        if !model.has_closures() {
            return Ok(Vec::new());
        }
        let r = softrod_dynamics::closure_residuals(model, data, q)?;
        Ok(model.closures().map(|c| c.name.clone()).zip(r).collect())
    }

    /// Inverse dynamics: the actuator force `τ_act` that gives `q̈` at
    /// `(t, q, q̇)` (D17–D18).
    pub fn inverse_dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        qdot: &[f64],
        qddot: &[f64],
    ) -> Result<DVector<f64>> {
        let s = &mut self.system;
        Ok(inverse_dynamics(&s.model, &mut s.data, t, q, qdot, qddot)?.clone())
    }

    /// The active contacts at `(t, q, q̇)` with their forces
    /// (docs/theory-contact.md), friction as the run's committed state
    /// leaves it; empty for a model without contact.
    pub fn contacts(
        &mut self,
        t: f64,
        q: &[f64],
        qdot: &[f64],
    ) -> Result<Vec<softrod_mechanics::ContactPoint>> {
        let s = &mut self.system;
        Ok(s.model.contacts_with(&mut s.data, t, q, qdot)?)
    }

    /// Forgets the contact state the last run, statics or step committed
    /// (docs/theory-contact.md CT5 anchors, CT15 raised stiffnesses): the
    /// next [`Simulation::step`] or [`Simulation::contacts`] sees the base
    /// stiffness and no friction history, as a new simulation would.
    /// [`Simulation::simulate_with`] and [`Simulation::statics`] do this
    /// themselves.
    pub fn reset_contact(&mut self) {
        self.system.data.reset_contact();
    }

    /// Copies the contact state this simulation holds (the friction anchors
    /// of CT5 and the raised stiffnesses of CT15, docs/theory-contact.md)
    /// into `data`, a workspace of this simulation's model: a front end
    /// that integrates with its own workspace (Python `step` with tensions
    /// as inputs) continues from the state the last run, statics or step
    /// committed. Nothing for a model without contact; no allocation once
    /// `data` has held as many rod–rod anchors.
    pub fn contact_state_into(&self, data: &mut Data) {
        data.copy_friction_state_from(&self.system.data);
    }

    /// Takes the contact state `data` (a workspace of this model) committed
    /// as this simulation's, so that [`Simulation::contacts`] and the next
    /// [`Simulation::step`] continue from it: the counterpart of
    /// [`Simulation::contact_state_into`].
    pub fn contact_state_from(&mut self, data: &Data) {
        self.system.data.copy_friction_state_from(data);
    }

    /// Mass matrix `M(q)` (n_dof × n_dof, symmetric positive definite; D19–D20).
    pub fn mass_matrix(&mut self, q: &[f64]) -> Result<DMatrix<f64>> {
        let (model, data) = self.at_time();
        Ok(mass_matrix(model, data, q)?.clone())
    }

    /// Kinetic, elastic and gravitational energy at `(q, q̇)` \[J\]; with
    /// prescribed joints the kinetic energy includes their motion at
    /// [`Self::time`] (it is not `½q̇ᵀMq̇` then).
    pub fn energies(&mut self, q: &[f64], qdot: &[f64]) -> Result<Energies> {
        let (model, data) = self.at_time();
        Ok(energies(model, data, q, qdot)?)
    }

    /// Bias force `b(q, q̇) = C q̇ + G + τ_e + D q̇ − τ_c − Q_ext` at time `t`
    /// (n_dof): `M q̈ + b = τ_act` (D21–D22).
    pub fn bias_force(&mut self, t: f64, q: &[f64], qdot: &[f64]) -> Result<DVector<f64>> {
        let s = &mut self.system;
        Ok(bias_force(&s.model, &mut s.data, t, q, qdot)?.clone())
    }

    /// Coriolis matrix `C(q, q̇)` (n_dof × n_dof, D21), with `Ṁ − 2C`
    /// skew-symmetric.
    pub fn coriolis_matrix(&self, q: &[f64], qdot: &[f64]) -> Result<DMatrix<f64>> {
        Ok(coriolis_matrix(self.model(), q, qdot)?)
    }

    /// Generalized gravity `G(q) = ∂V_g/∂q` (n_dof, D22).
    pub fn gravity_force(&mut self, q: &[f64]) -> Result<DVector<f64>> {
        let (model, data) = self.at_time();
        Ok(generalized_gravity(model, data, q)?)
    }

    /// Stiffness matrix `K` (n_dof × n_dof, block-diagonal per piece, D13).
    pub fn stiffness_matrix(&self) -> DMatrix<f64> {
        stiffness_matrix(self.model())
    }

    /// Damping matrix `D` (n_dof × n_dof, block-diagonal per piece, D13).
    pub fn damping_matrix(&self) -> DMatrix<f64> {
        damping_matrix(self.model())
    }

    /// Actuation matrix `∂τ_c/∂u` at `q` (n_dof × n_cables): the
    /// generalized force of each cable per newton of tension (D15).
    pub fn actuation_matrix(&self, q: &[f64]) -> Result<DMatrix<f64>> {
        Ok(actuation_matrix(self.model(), q)?)
    }

    /// Linearization `ẋ ≈ f(x₀, u₀) + A (x − x₀) + B (u − u₀)` of the
    /// dynamics about `(q, q̇)` at `t`, `x = (q, q̇)` (2·n_dof), `u` the cable
    /// tensions (the inputs, or the schedules at `t`), from the analytic
    /// derivatives (D30–D49): what LQR, MPC and trajectory optimization need.
    /// On a model with loop closures, of the constrained (Baumgarte-
    /// stabilized) dynamics in the model's coordinates
    /// (docs/theory-derivatives.md CD9).
    pub fn linearize(&mut self, t: f64, q: &[f64], qdot: &[f64]) -> Result<Linearization> {
        let s = &mut self.system;
        let mut work = FdDerivatives::new(&s.model);
        Ok(linearize(
            &s.model,
            &mut s.data,
            &mut work,
            t,
            q,
            qdot,
            None,
        )?)
    }
}
