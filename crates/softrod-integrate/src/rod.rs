//! The PCS rod equations of motion as a [`SecondOrderSystem`].
//!
//! [`RodSystem`] wraps a `softrod_dynamics::Model` and its `Data`:
//! accelerations by the O(N) articulated forward dynamics, the force residual
//! by the O(N) inverse dynamics, the shifted mass matrix `M + aK + bD` by the
//! O(N) `ShiftedSolver`, and the exact Jacobians by the analytic derivatives
//! of the forward dynamics.

use nalgebra::{DMatrix, DVector, Matrix6};
use softrod_dynamics::{
    ClosedDerivatives, ClosedShiftedSolver, Data, DynamicsError, FdDerivatives, Forces,
    IdDerivatives, Model, ShiftedSolver, closed_dynamics_derivatives, closure_multipliers,
    damping_matrix, forward_dynamics, forward_dynamics_derivatives, inverse_dynamics,
    inverse_dynamics_derivatives, inverse_dynamics_inertia_vjp,
    inverse_dynamics_linearization_with, inverse_dynamics_mass_product, inverse_dynamics_vjp,
    mass_matrix, project_onto_closures, projection_tolerance, stiffness_matrix,
};
use softrod_mechanics::Tension;

use crate::integrator::Integrator;
use crate::system::SecondOrderSystem;

/// Where the projection onto the closures gave up
/// ([`RodSystem::projection_misses`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ProjectionMisses {
    /// Step ends at which it did not converge.
    pub count: usize,
    /// The time of the first \[s\] (0 when `count` is 0).
    pub first_t: f64,
    /// The largest closure residual norm (D66) left at them \[m\].
    pub largest_residual: f64,
}

/// A rod model ready for integration: `q̈ = FD(t, q, q̇, τ)`.
#[derive(Clone, Debug)]
pub struct RodSystem {
    /// The immutable model.
    pub model: Model,
    /// Its buffers.
    pub data: Data,
    /// Actuator generalized force `τ_act` (n_dof); `None` = 0. A per-step
    /// callback may change it (then return `Control::SystemChanged`).
    pub tau: Option<DVector<f64>>,
    /// Which Jacobians the stiff methods get (default [`RodJacobian::Exact`]).
    pub jacobian: RodJacobian,
    /// Models with closures (and no contact): whether the implicit methods
    /// that iterate on the shifted mass matrix (ESDIRK) get the structured
    /// KKT solve of [`SecondOrderSystem::factor_shifted_constrained`]
    /// (`softrod_dynamics::ClosedShiftedSolver`, O(N·m) per factorization,
    /// docs/theory-derivatives.md CD5–CD8) — **experimental, default
    /// `false`** — or the dense exact Jacobian of the constrained `q̈`
    /// (`n×n` LU factorizations). The structured iteration has the right
    /// fixed point (with a tight Newton tolerance whole runs agree with the
    /// dense path, `tests/closed.rs`), but on soft, ringing closed models
    /// its simplified Newton contracts slowly and unevenly and ESDIRK's
    /// stopping test (RADAU5's) accepts iterates far from it at the default
    /// tolerance: on the test models 1–30 % off at `rtol = 1e-8` where the
    /// dense path is within 2e-4 (docs/performance.md).
    pub structured_closures: bool,
    /// Models with contact: whether the structured Newton matrix
    /// `M + aK + bD` of the implicit methods also carries the contact's
    /// stiffness and damping (docs/theory-contact.md CT17; default `true`).
    /// `false` is the matrix without them, for comparisons.
    pub contact_in_shifted: bool,
    /// Whether the structured Newton matrix also carries the geometric
    /// stiffness of gravity and of the contact forces
    /// (`ShiftedSolver::set_geometric`, docs/theory-contact.md CT19–CT23;
    /// default `false`): the `T/ℓ` stiffness of a rope under tension, which
    /// the matrix without it lacks. Off by default: on the capstan benchmark
    /// it did not change the step count (docs/performance.md, "The
    /// geometric stiffness in the Newton matrix"), and on chain models it
    /// moves the factorization to the tree recursion (~1.5× its cost).
    pub geometric_in_shifted: bool,
    /// Models with closures on the structured KKT solve
    /// ([`RodSystem::structured_closures`]): whether its open-tree matrix
    /// also carries the geometric stiffness of gravity and of the closure
    /// forces at the multipliers of the last Jacobian update
    /// (`ClosedShiftedSolver::set_geometric`, docs/theory-derivatives.md
    /// CD11; **experimental, default `false`**). The terms are the exact
    /// Hessian of gravity and of a pin's force where the matrix stays
    /// positive definite, but they did not spare the cosseratbench
    /// catenary's ESDIRK run a single dense fallback (51 dense Jacobians
    /// with and without them) and made a welded twisted rod's run worse
    /// (206 steps, 198 rejected, against 90 and 38): where they are
    /// indefinite, CT23's modified factorization is a poorer Newton matrix
    /// than none (docs/performance.md).
    pub geometric_in_closures: bool,
    /// Models with contact (a tree model: joints or bodies): the structured
    /// Newton matrix takes the world-obstacle contact laws whole
    /// (`ShiftedSolver::set_contact_whole`, docs/theory-contact.md CT26)
    /// and ESDIRK re-linearizes the contact at every Newton iterate (CT27).
    /// Default `true` (with the stop location of CT29, which bounds the
    /// friction paths' dependence on the steps): on the cosseratbench
    /// capstan it cuts the dense Jacobians and the CPU time
    /// (docs/performance.md, "Contact-heavy scenes"). `false` is the
    /// symmetric CT17 blocks and a matrix kept for the step.
    pub contact_active_set: bool,
    /// Whether ESDIRK retries a step inside which a sliding contact
    /// stopped, at the stop (docs/theory-contact.md CT29; rod pairs CT30;
    /// `softrod_dynamics::friction_stop`; default `true`). `false` is the
    /// step sequence without it, for comparisons.
    pub locate_friction_stops: bool,
    /// The configuration of the last contact linearization
    /// ([`SecondOrderSystem::linearize_shifted`]); the factorizations carry
    /// it only at that `q` (a wrapper that forwards the factorization but
    /// not the linearization gets none, never a stale one).
    contact_q: Option<DVector<f64>>,
    /// Step ends where [`SecondOrderSystem::project`] gave up since the
    /// last [`reset_projection_misses`](Self::reset_projection_misses).
    projection_misses: ProjectionMisses,
    /// The factored `M(q) + aK + bD` of
    /// [`SecondOrderSystem::factor_shifted_mass`] (O(N), no `n×n` matrix).
    shifted: ShiftedSolver,
    /// The workspace of the analytic derivatives, allocated when the exact
    /// Jacobian is first asked for (it holds `n_dof × n_dof` matrices).
    derivatives: Option<Box<FdDerivatives>>,
    /// The same for a model with closures (the constrained dynamics'
    /// derivatives, `softrod_dynamics::closed_dynamics_derivatives`).
    closed: Option<Box<ClosedDerivatives>>,
    /// The workspace of [`RodSystem::force_jacobians`] (the inverse
    /// dynamics' derivatives alone), allocated on first use.
    id_derivatives: Option<Box<IdDerivatives>>,
    /// The linearizations of [`RodSystem::force_linearization`], one per
    /// slot (O(N) each, no `n×n` matrix), allocated on first use.
    products: Vec<IdDerivatives>,
    /// The KKT factorization of a closed model's implicit step, allocated
    /// on first use.
    kkt: Option<Box<ClosedShiftedSolver>>,
}

/// The Jacobians [`RodSystem`] hands to the stiff methods.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RodJacobian {
    /// `∂q̈/∂q`, `∂q̈/∂q̇` of the full forward dynamics
    /// (`softrod_dynamics::forward_dynamics_derivatives`, analytic).
    #[default]
    Exact,
    /// Only the stiff linear part: `−M(q)⁻¹K` and `−M(q)⁻¹D` (one `M(q)`, no
    /// derivatives). The integrators get it in mass-matrix form
    /// ([`SecondOrderSystem::mass_form_jacobians`]) and never form `M⁻¹K`:
    /// generalized-α factors `M + β'K + γ'D` by the O(N)
    /// [`SecondOrderSystem::factor_shifted_mass`], ROS34PW2 `c²M + cD + K`
    /// by a dense Cholesky ([`RodSystem::elastic_jacobians`] gives the dense
    /// `−M⁻¹K`, `−M⁻¹D` for comparisons; [`SecondOrderSystem::jacobians`]
    /// stays exact, for the methods to refresh to). The elastic and viscous forces
    /// `K(q − q̄)`, `D q̇` are linear with constant `K`, `D` in PCS, and they
    /// are what makes the rod stiff; gravity, Coriolis and loads are soft and
    /// left out. With the Rosenbrock–W method (order 3 for any `W`) this is a
    /// linearly implicit IMEX splitting: stiff elastic/viscous part implicit,
    /// the rest explicit. Generalized-α still converges to the same step
    /// solution (its simplified Newton just takes an iteration more when the
    /// geometric part matters). [`Integrator::Esdirk`](crate::Integrator::Esdirk)
    /// does not look at it: it iterates on the shifted mass matrix and falls
    /// back to the exact [`SecondOrderSystem::jacobians`].
    ElasticOnly,
}

impl RodJacobian {
    /// The Jacobian `integrator` gets on a rod. ESDIRK and Radau IIA
    /// iterate Newton to convergence and get the exact one (from the
    /// analytic derivatives, docs/theory-derivatives.md): with only `−M⁻¹K`,
    /// `−M⁻¹D` their Newton iterations stall on fast 3-D motion, where
    /// gyroscopic and geometric-stiffness terms matter. Rosenbrock–W and
    /// generalized-α get [`RodJacobian::ElasticOnly`] (O(N), no `n×n`
    /// matrix): Rosenbrock–W keeps its order with any Jacobian and
    /// refreshes to the exact one itself when its steps collapse. The
    /// explicit methods use none (`ElasticOnly`, never evaluated).
    pub fn recommended(integrator: Integrator) -> Self {
        match integrator {
            Integrator::Esdirk | Integrator::Esdirk5 | Integrator::Radau5 => RodJacobian::Exact,
            Integrator::Rk4
            | Integrator::Dopri5
            | Integrator::Rosenbrock
            | Integrator::GeneralizedAlpha => RodJacobian::ElasticOnly,
        }
    }
}

impl RodSystem {
    /// A system for `model`, no actuator force.
    pub fn new(model: Model) -> Self {
        let data = Data::new(&model);
        let shifted = ShiftedSolver::new(&model);
        Self {
            model,
            data,
            tau: None,
            jacobian: RodJacobian::Exact,
            structured_closures: false,
            contact_in_shifted: true,
            geometric_in_shifted: false,
            geometric_in_closures: false,
            contact_active_set: true,
            locate_friction_stops: true,
            contact_q: None,
            projection_misses: ProjectionMisses::default(),
            shifted,
            derivatives: None,
            closed: None,
            id_derivatives: None,
            products: Vec::new(),
            kkt: None,
        }
    }
}

impl RodSystem {
    /// The linearization of the equation of motion in force form,
    /// `r(t, q, q̇, q̈) = ID(t, q, q̇, q̈) − τ_act = M(q) q̈ − f(t, q, q̇)`, at
    /// a given `q̈`: `M(q)` into `mass`, `∂r/∂q` (at fixed `q̇`, `q̈`;
    /// with the change of `M(q) q̈`) into `dr_dq`, `∂r/∂q̇` into `dr_dqd`
    /// (all n_dof × n_dof; `softrod_dynamics::mass_matrix` and
    /// `softrod_dynamics::inverse_dynamics_derivatives`, analytic, O(N·n_dof),
    /// no allocation after the first call). At `q̈ = a(t, q, q̇)` the
    /// Jacobians of [`SecondOrderSystem::jacobians`] are
    /// `∂a/∂q = −M⁻¹ ∂r/∂q`, `∂a/∂q̇ = −M⁻¹ ∂r/∂q̇` — which this leaves
    /// unformed (they cost `2·n_dof` O(N) mass solves; the adjoint's
    /// transposed stage solves need only `M` and `∂r`, docs/theory-control.md
    /// G11). Returns `Ok(false)` (nothing written) for models with closures
    /// (their `q̈` carries closure forces, `r` is not their equation) or
    /// contact (its friction anchors are the run's state).
    #[allow(clippy::too_many_arguments)]
    pub fn force_jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
        dr_dq: &mut DMatrix<f64>,
        dr_dqd: &mut DMatrix<f64>,
    ) -> Result<bool, DynamicsError> {
        if self.model.has_closures() || self.model.has_contact() {
            return Ok(false);
        }
        self.model.set_time(&mut self.data, t);
        mass.copy_from(mass_matrix(&self.model, &mut self.data, q.as_slice())?);
        let work = self
            .id_derivatives
            .get_or_insert_with(|| Box::new(IdDerivatives::new(&self.model)));
        work.copy_inputs(&self.data);
        let d = inverse_dynamics_derivatives(
            &self.model,
            work,
            t,
            q.as_slice(),
            qd.as_slice(),
            qdd.as_slice(),
        )?;
        dr_dq.copy_from(&d.dtau_dq);
        dr_dqd.copy_from(&d.dtau_dqd);
        Ok(true)
    }
}

impl RodSystem {
    /// [`RodSystem::force_jacobians`] without the dense derivatives: `M(q)`
    /// into `mass`, and `∂r/∂q`, `∂r/∂q̇` kept as an operator in `slot`
    /// (any index; one O(N) workspace each) for
    /// [`RodSystem::force_vjp`] — `softrod_dynamics::
    /// inverse_dynamics_linearization_with`, O(N), no allocation after a
    /// slot's first use (docs/theory-derivatives.md D81–D83,
    /// docs/theory-control.md G12). Returns `Ok(false)` (nothing written)
    /// where `force_jacobians` does (closures, contact).
    #[allow(clippy::too_many_arguments)]
    pub fn force_linearization(
        &mut self,
        slot: usize,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
    ) -> Result<bool, DynamicsError> {
        if self.model.has_closures() || self.model.has_contact() {
            return Ok(false);
        }
        self.model.set_time(&mut self.data, t);
        mass.copy_from(mass_matrix(&self.model, &mut self.data, q.as_slice())?);
        self.force_operators(slot, t, q, qd, qdd)
    }

    /// [`RodSystem::force_linearization`] without forming `M(q)`: `M` is
    /// kept in `slot` too, as the O(N) products of
    /// [`RodSystem::force_mass_product`] (docs/theory-derivatives.md D86,
    /// docs/theory-control.md G15). Returns `Ok(false)` (nothing kept)
    /// where `force_jacobians` does (closures, contact).
    pub fn force_operators(
        &mut self,
        slot: usize,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
    ) -> Result<bool, DynamicsError> {
        if self.model.has_closures() || self.model.has_contact() {
            return Ok(false);
        }
        while self.products.len() <= slot {
            self.products.push(IdDerivatives::for_products(&self.model));
        }
        let work = &mut self.products[slot];
        work.copy_inputs(&self.data);
        inverse_dynamics_linearization_with(
            &self.model,
            work,
            Forces::ALL,
            t,
            q.as_slice(),
            qd.as_slice(),
            qdd.as_slice(),
        )?;
        Ok(true)
    }

    /// `M(q) v` into `out` (dim n_dof) at the linearization of `slot`
    /// ([`RodSystem::force_operators`] or
    /// [`RodSystem::force_linearization`]); O(N)
    /// (`softrod_dynamics::inverse_dynamics_mass_product`). An error for a
    /// slot without a successful linearization.
    pub fn force_mass_product(
        &mut self,
        slot: usize,
        v: &DVector<f64>,
        out: &mut DVector<f64>,
    ) -> Result<(), DynamicsError> {
        let Some(work) = self.products.get_mut(slot) else {
            return Err(DynamicsError::NotLinearized {
                what: "RodSystem::force_mass_product",
            });
        };
        inverse_dynamics_mass_product(&self.model, work, v.as_slice(), out.as_mut_slice())
    }

    /// `(∂r/∂q)ᵀu` into `out_q`, `(∂r/∂q̇)ᵀu` into `out_qd` (dim n_dof) at
    /// the linearization of `slot` ([`RodSystem::force_linearization`]);
    /// O(N) (`softrod_dynamics::inverse_dynamics_vjp`). An error for a slot
    /// without a successful linearization.
    pub fn force_vjp(
        &mut self,
        slot: usize,
        u: &DVector<f64>,
        out_q: &mut DVector<f64>,
        out_qd: &mut DVector<f64>,
    ) -> Result<(), DynamicsError> {
        let Some(work) = self.products.get_mut(slot) else {
            return Err(DynamicsError::NotLinearized {
                what: "RodSystem::force_vjp",
            });
        };
        inverse_dynamics_vjp(
            &self.model,
            work,
            u.as_slice(),
            out_q.as_mut_slice(),
            out_qd.as_mut_slice(),
        )
    }
}

impl RodSystem {
    /// The inertia products of [`RodSystem::force_inertia_vjp`] at the
    /// point of the last [`RodSystem::force_jacobians`] (its dense
    /// derivatives keep the same per-piece sums, D85). An error before any.
    pub fn force_jacobians_inertia_vjp(
        &mut self,
        z: &DVector<f64>,
        rods: &mut [f64],
        bodies: &mut [Matrix6<f64>],
    ) -> Result<(), DynamicsError> {
        let Some(work) = self.id_derivatives.as_deref_mut() else {
            return Err(DynamicsError::NotLinearized {
                what: "RodSystem::force_jacobians_inertia_vjp",
            });
        };
        inverse_dynamics_inertia_vjp(&self.model, work, z.as_slice(), rods, bodies)
    }

    /// The inertia products at the linearization of `slot`
    /// ([`RodSystem::force_linearization`]): `rods[r] = zᵀ ∂r/∂s_r` for a
    /// factor `s_r` on rod `r`'s inertia, `bodies[b]` the 6×6 `G_b` with
    /// `zᵀ ∂r/∂𝓜_b [δ𝓜] = Σ G_b,ij δ𝓜ᵢⱼ` for body `b`'s screw inertia
    /// (`softrod_dynamics::inverse_dynamics_inertia_vjp`, O(N), no
    /// allocation; docs/theory-derivatives.md D85). An error for a slot
    /// without a successful linearization.
    pub fn force_inertia_vjp(
        &mut self,
        slot: usize,
        z: &DVector<f64>,
        rods: &mut [f64],
        bodies: &mut [Matrix6<f64>],
    ) -> Result<(), DynamicsError> {
        let Some(work) = self.products.get_mut(slot) else {
            return Err(DynamicsError::NotLinearized {
                what: "RodSystem::force_inertia_vjp",
            });
        };
        inverse_dynamics_inertia_vjp(&self.model, work, z.as_slice(), rods, bodies)
    }
}

impl RodSystem {
    /// The dense elastic/viscous Jacobian approximation `∂q̈/∂q ≈ −M(q)⁻¹K`,
    /// `∂q̈/∂q̇ ≈ −M(q)⁻¹D` (n_dof × n_dof each; one mass matrix, one dense
    /// Cholesky, `n_dof` solves; allocates). The integrators never form it
    /// (they use the mass-matrix form of [`RodJacobian::ElasticOnly`]); it is
    /// here for comparisons.
    pub fn elastic_jacobians(
        &mut self,
        q: &DVector<f64>,
        dqdd_dq: &mut DMatrix<f64>,
        dqdd_dqd: &mut DMatrix<f64>,
    ) -> Result<(), DynamicsError> {
        let m = mass_matrix(&self.model, &mut self.data, q.as_slice())?;
        let chol = m.clone().cholesky().ok_or(DynamicsError::Singular {
            rod: 0,
            piece: 0,
            what: "mass matrix",
        })?;
        let mut k = stiffness_matrix(&self.model);
        chol.solve_mut(&mut k);
        dqdd_dq.copy_from(&k);
        dqdd_dq.neg_mut();
        let mut d = damping_matrix(&self.model);
        if d.iter().all(|&v| v == 0.0) {
            // Undamped: skip the n_dof-column solve.
            dqdd_dqd.fill(0.0);
        } else {
            chol.solve_mut(&mut d);
            dqdd_dqd.copy_from(&d);
            dqdd_dqd.neg_mut();
        }
        Ok(())
    }
}

impl RodSystem {
    /// After an accepted step to `(t, q, q̇)`: commits the contact friction
    /// anchors and stiffnesses and checks the penetration
    /// (`softrod_dynamics::commit_contact`, docs/theory-contact.md CT5,
    /// CT15). Returns whether the system changed (a stiffness rose, or a
    /// model with friction: the
    /// cached derivatives no longer hold, the caller returns
    /// [`Control::SystemChanged`](crate::Control::SystemChanged)). Call it
    /// from the `step` hook only: a rejected step must leave the anchors
    /// alone.
    pub fn commit_contact(&mut self, t: f64, q: &[f64], qd: &[f64]) -> Result<bool, DynamicsError> {
        if !self.model.has_contact() {
            return Ok(false);
        }
        Ok(self.commit_contact_control(t, q, qd)? != crate::Control::Continue)
    }

    /// Forgets the contact linearization the structured Newton matrix keeps
    /// between evaluations (CT17, CT27). It is keyed by `q` only, so one
    /// taken at the end of an integration (the last Newton iterate of a
    /// stiffly accurate step is its end state) would be reused by the next
    /// integration starting there although the commit that ended the step
    /// moved the anchors. An integration that starts afresh calls this, so
    /// that it is a function of its state, contact state and inputs alone,
    /// whatever this workspace integrated before; its first Jacobian update
    /// linearizes the contact anyway. No allocation.
    pub fn forget_contact_linearization(&mut self) {
        if self.contact_q.take().is_some() {
            self.shifted.clear_contact();
        }
    }

    /// The step ends at which the projection onto the closures
    /// ([`Options::project_state`](crate::Options::project_state),
    /// docs/theory.md D121) did not converge since the last
    /// [`reset_projection_misses`](Self::reset_projection_misses): there the
    /// state was left as the step ended it, held by the stabilization alone.
    /// A run reports them rather than passing over them.
    pub fn projection_misses(&self) -> ProjectionMisses {
        self.projection_misses
    }

    /// Starts counting [`projection_misses`](Self::projection_misses) anew.
    pub fn reset_projection_misses(&mut self) {
        self.projection_misses = ProjectionMisses::default();
    }

    /// [`commit_contact`](Self::commit_contact) as what the step hook
    /// returns (CT25): a stiffness that rose changes the law's slope
    /// ([`Control::SystemChanged`](crate::Control::SystemChanged): the
    /// Jacobians are dropped); friction anchors and healing offsets change
    /// only the forces at the current state
    /// ([`Control::ForcesChanged`](crate::Control::ForcesChanged): the
    /// step-start acceleration is re-evaluated); nothing else,
    /// [`Control::Continue`](crate::Control::Continue).
    pub fn commit_contact_control(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
    ) -> Result<crate::Control, DynamicsError> {
        if !self.model.has_contact() {
            return Ok(crate::Control::Continue);
        }
        let c = softrod_dynamics::commit_contact_change(&self.model, &mut self.data, t, q, qd)?;
        let friction = self.model.obstacles().iter().any(|o| o.friction > 0.0)
            || self.model.contact_settings().friction > 0.0;
        Ok(if c.scale_rose {
            crate::Control::SystemChanged
        } else if c.offset_moved || friction {
            crate::Control::ForcesChanged
        } else {
            crate::Control::Continue
        })
    }
}

impl SecondOrderSystem for RodSystem {
    type Error = DynamicsError;

    fn dim(&self) -> usize {
        self.model.n_dof()
    }

    fn accel(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), DynamicsError> {
        let tau = self.tau.as_ref().map(|v| v.as_slice());
        let a = forward_dynamics(
            &self.model,
            &mut self.data,
            t,
            q.as_slice(),
            qd.as_slice(),
            tau,
        )?;
        qdd.copy_from(a);
        Ok(())
    }

    /// The exact `∂q̈/∂q`, `∂q̈/∂q̇` (the analytic derivatives of
    /// `softrod_dynamics::forward_dynamics_derivatives`, of
    /// `softrod_dynamics::closed_dynamics_derivatives` for a model with
    /// closures; no allocation after the first call)
    /// whatever [`RodSystem::jacobian`] says: the cheap approximation of
    /// [`RodJacobian::ElasticOnly`] is the mass-matrix form, and this is what
    /// the methods refresh to when it stops working.
    fn jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        dqdd_dq: &mut DMatrix<f64>,
        dqdd_dqd: &mut DMatrix<f64>,
    ) -> Result<(), DynamicsError> {
        let tau = self.tau.as_ref().map(|v| v.as_slice());
        if self.model.has_closures() {
            // The constrained q̈'s derivatives (docs/theory-derivatives.md
            // (CD1)–(CD4)): the open tree's analytic ones projected through
            // the multiplier system, the closure rows differenced alone.
            let work = self
                .closed
                .get_or_insert_with(|| Box::new(ClosedDerivatives::new(&self.model)));
            let j = closed_dynamics_derivatives(
                &self.model,
                &mut self.data,
                work,
                t,
                q.as_slice(),
                qd.as_slice(),
                tau,
            )?;
            dqdd_dq.copy_from(&j.dqdd_dq);
            dqdd_dqd.copy_from(&j.dqdd_dqd);
            return Ok(());
        }
        let work = self
            .derivatives
            .get_or_insert_with(|| Box::new(FdDerivatives::new(&self.model)));
        let j = forward_dynamics_derivatives(
            &self.model,
            &mut self.data,
            work,
            t,
            q.as_slice(),
            qd.as_slice(),
            tau,
        )?;
        dqdd_dq.copy_from(&j.dqdd_dq);
        dqdd_dqd.copy_from(&j.dqdd_dqd);
        Ok(())
    }

    /// [`RodJacobian::ElasticOnly`]: `M(q)` and the constant `K`, `D` (the
    /// methods then factor `M + β'K + γ'D` or `c²M + cD + K` by Cholesky
    /// instead of forming `M⁻¹K`). [`RodJacobian::Exact`]: not provided.
    fn mass_form_jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        _qd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
        constant: Option<(&mut DMatrix<f64>, &mut DMatrix<f64>)>,
    ) -> Result<bool, DynamicsError> {
        if self.jacobian != RodJacobian::ElasticOnly {
            return Ok(false);
        }
        self.model.set_time(&mut self.data, t);
        mass.copy_from(mass_matrix(&self.model, &mut self.data, q.as_slice())?);
        if let Some((k, d)) = constant {
            k.copy_from(&stiffness_matrix(&self.model));
            d.copy_from(&damping_matrix(&self.model));
        }
        Ok(true)
    }

    fn has_mass_form(&self) -> bool {
        // The mass form M q̈ = f has no room for closure multipliers
        // (docs/theory.md D67): closed models use the constrained q̈.
        self.jacobian == RodJacobian::ElasticOnly && !self.model.has_closures()
    }

    /// `r = ID(t, q, q̇, q̈) − τ_act = M(q) q̈ − f` by the O(N) inverse
    /// dynamics.
    fn force_residual(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        r: &mut DVector<f64>,
    ) -> Result<bool, DynamicsError> {
        if self.model.has_closures() {
            // M q̈ − f leaves out the closure forces Jᵀλ (docs/theory.md
            // D67): the methods use the constrained q̈ instead.
            return Ok(false);
        }
        r.copy_from(inverse_dynamics(
            &self.model,
            &mut self.data,
            t,
            q.as_slice(),
            qd.as_slice(),
            qdd.as_slice(),
        )?);
        if let Some(tau) = &self.tau {
            *r -= tau;
        }
        Ok(true)
    }

    /// With contact: the contact's stiffness and damping at `(t, q, q̇)`
    /// with the run's contact state (`ShiftedSolver::linearize_contact`,
    /// docs/theory-contact.md CT17), for the factorizations that follow.
    /// Nothing without contact.
    fn linearize_shifted(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
    ) -> Result<(), DynamicsError> {
        if self.n_constraints() > 0 {
            if !self.geometric_in_closures {
                return Ok(());
            }
            // The closure forces whose geometric stiffness the KKT matrix
            // holds (docs/theory-derivatives.md CD11): the constrained
            // forward dynamics' multipliers at the update's state.
            let tau = self.tau.as_ref().map(|v| v.as_slice());
            forward_dynamics(
                &self.model,
                &mut self.data,
                t,
                q.as_slice(),
                qd.as_slice(),
                tau,
            )?;
            let kkt = self
                .kkt
                .get_or_insert_with(|| Box::new(ClosedShiftedSolver::new(&self.model)));
            if let Some((lambda, _)) = closure_multipliers(&self.data) {
                kkt.set_multipliers(lambda.as_slice())?;
            }
            return Ok(());
        }
        if !self.model.has_contact() || self.model.has_closures() {
            return Ok(());
        }
        if self.contact_in_shifted {
            self.shifted.set_contact_whole(self.contact_active_set);
            self.shifted.linearize_contact(
                &self.model,
                &mut self.data,
                t,
                q.as_slice(),
                qd.as_slice(),
            )?;
            match &mut self.contact_q {
                Some(at) => at.copy_from(q),
                None => self.contact_q = Some(q.clone()),
            }
        } else {
            self.shifted.clear_contact();
            self.contact_q = None;
        }
        Ok(())
    }

    /// A slide that stopped inside the step (docs/theory-contact.md CT29,
    /// `softrod_dynamics::friction_stop`).
    fn step_event_fraction(
        &mut self,
        h: f64,
        t0: f64,
        q0: &DVector<f64>,
        qd0: &DVector<f64>,
        t1: f64,
        q1: &DVector<f64>,
        qd1: &DVector<f64>,
    ) -> Result<Option<f64>, DynamicsError> {
        if !self.locate_friction_stops {
            return Ok(None);
        }
        softrod_dynamics::friction_stop(
            &self.model,
            &mut self.data,
            h,
            t0,
            q0.as_slice(),
            qd0.as_slice(),
            t1,
            q1.as_slice(),
            qd1.as_slice(),
        )
    }

    /// With contact in the structured matrix: the contact set and its
    /// stick/slide branches change within a step, so ESDIRK re-linearizes
    /// the contact at every Newton iterate (docs/theory-contact.md CT27).
    fn relinearize_in_newton(&self) -> bool {
        self.contact_active_set
            && self.contact_in_shifted
            && self.model.has_contact()
            && !self.model.has_closures()
    }

    /// `M(q) + aK + bD` by the O(N) articulated recursion
    /// (`softrod_dynamics::ShiftedSolver`, on the tree for models with
    /// joints and bodies, prescribed joints where they stand at `t`), with
    /// the contact of the last [`SecondOrderSystem::linearize_shifted`].
    fn factor_shifted_mass(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        a: f64,
        b: f64,
    ) -> Result<bool, DynamicsError> {
        if self.model.has_closures() {
            // The constrained Newton matrix is not a shifted mass matrix:
            // dense matrices.
            return Ok(false);
        }
        if self.contact_q.as_ref().is_some_and(|at| at != q) {
            self.shifted.clear_contact();
            self.contact_q = None;
        }
        // Cheap when unchanged (a chain model's tree is built once).
        self.shifted
            .set_geometric(&self.model, self.geometric_in_shifted)?;
        self.shifted.factor_at(&self.model, t, q.as_slice(), a, b)?;
        Ok(true)
    }

    fn solve_shifted_mass(&mut self, x: &mut DVector<f64>) -> Result<(), DynamicsError> {
        self.shifted.solve(&self.model, x.as_mut_slice())
    }

    /// A closed model's loops: `softrod_dynamics::project_onto_closures`
    /// (docs/theory.md D121) to `1e-11 ℓ` (`projection_tolerance`).
    /// `Ok(false)` for a model without closures, and when the Newton
    /// iteration on the positions did not converge (the state is then left
    /// as it was: the stabilization alone goes on holding it).
    fn project(
        &mut self,
        t: f64,
        q: &mut DVector<f64>,
        qd: &mut DVector<f64>,
    ) -> Result<bool, DynamicsError> {
        if !self.model.has_closures() {
            return Ok(false);
        }
        let tol = projection_tolerance(&self.model);
        let p = project_onto_closures(
            &self.model,
            &mut self.data,
            t,
            q.as_mut_slice(),
            qd.as_mut_slice(),
            tol,
        )?;
        if !p.converged {
            let m = &mut self.projection_misses;
            if m.count == 0 {
                m.first_t = t;
            }
            m.count += 1;
            m.largest_residual = m.largest_residual.max(p.residual_before);
        }
        Ok(p.converged)
    }

    /// The closure rows `m` for a model with closures and without contact
    /// when [`RodSystem::structured_closures`] is on, else 0.
    fn n_constraints(&self) -> usize {
        if self.structured_closures && self.model.has_closures() && !self.model.has_contact() {
            self.model.n_constraints()
        } else {
            0
        }
    }

    /// The KKT matrix of the closed model's implicit step,
    /// `[M + aK + bD, −Jᵀ; s·J, 0]` (`softrod_dynamics::ClosedShiftedSolver`:
    /// the open tree's O(N) shifted factorization, `m` solves for
    /// `S⁻¹Jᵀ`, an `m×m` Cholesky; docs/theory-derivatives.md CD6–CD7).
    fn factor_shifted_constrained(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        a: f64,
        b: f64,
    ) -> Result<bool, DynamicsError> {
        if self.n_constraints() == 0 {
            return Ok(false);
        }
        let kkt = self
            .kkt
            .get_or_insert_with(|| Box::new(ClosedShiftedSolver::new(&self.model)));
        kkt.set_geometric(self.geometric_in_closures);
        kkt.factor_at(&self.model, t, q.as_slice(), a, b)?;
        Ok(true)
    }

    fn solve_shifted_constrained(
        &mut self,
        x: &mut DVector<f64>,
        d: &DVector<f64>,
    ) -> Result<(), DynamicsError> {
        let Some(kkt) = self.kkt.as_mut() else {
            return Err(DynamicsError::NotFactored {
                what: "ClosedShiftedSolver",
            });
        };
        kkt.solve(&self.model, x.as_mut_slice(), d.as_slice())
    }

    /// The open tree's force residual `ID(t, q, q̇, q̈) − τ_act` and the
    /// Baumgarte-stabilized closure rows at `q̈` (docs/theory-derivatives.md
    /// CD5).
    fn constrained_residual(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        r: &mut DVector<f64>,
        c: &mut DVector<f64>,
    ) -> Result<bool, DynamicsError> {
        if self.n_constraints() == 0 {
            return Ok(false);
        }
        let kkt = self
            .kkt
            .get_or_insert_with(|| Box::new(ClosedShiftedSolver::new(&self.model)));
        kkt.residuals(
            &self.model,
            &mut self.data,
            t,
            q.as_slice(),
            qd.as_slice(),
            qdd.as_slice(),
            self.tau.as_ref().map(|v| v.as_slice()),
            r.as_mut_slice(),
            c.as_mut_slice(),
        )?;
        Ok(true)
    }

    /// Time enters through prescribed joints (D59) and cable tension
    /// tables (unless `data` overrides the tensions).
    fn is_autonomous(&self) -> bool {
        self.model.n_prescribed() == 0
            && (self.data.cable_tensions().is_some()
                || !self.model.rods().iter().any(|r| {
                    r.spec
                        .cables
                        .iter()
                        .any(|c| matches!(c.tension, Tension::Table { .. }))
                }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Integrator, NoHooks, Options, integrate_second_order};
    use softrod_dynamics::{Rod, energies};
    use softrod_kinematics::{Basis, RodGeometry};
    use softrod_lie::{Pose, Vec3};
    use softrod_mechanics::{Material, RodProperties, Section};

    /// A clamped 0.2 m rubber rod (r = 1 cm, E = 1e5 Pa, ν = 0.5, all six
    /// strains) of `pieces` pieces and viscosity `mu` \[Pa·s\] under gravity.
    fn clamped_rod(pieces: usize, mu: f64) -> RodSystem {
        let l = 0.2;
        let rod = RodGeometry::uniform(
            l,
            pieces,
            Basis::all(),
            softrod_kinematics::straight(),
            Pose::identity(),
        )
        .unwrap();
        let mat = Material::with_poisson(1000.0, 1e5, 0.5, mu).unwrap();
        let body = RodProperties::new(Section::Circle { radius: 0.01 }, mat, l).unwrap();
        let model = Model::new(
            vec![Rod::new("r", rod, body)],
            Some(Vec3::new(0.0, 0.0, -9.81)),
            4,
        )
        .unwrap();
        RodSystem::new(model)
    }

    #[test]
    fn released_rod_conserves_energy_with_dopri5() {
        let mut sys = clamped_rod(1, 0.0);
        assert!(sys.is_autonomous());
        let n = sys.dim();
        let q0 = DVector::zeros(n);
        let v0 = DVector::zeros(n);
        let e0 = energies(&sys.model, &mut sys.data, q0.as_slice(), v0.as_slice())
            .unwrap()
            .total();
        let opts = Options::tol(1e-11, 1e-13);
        let sol = integrate_second_order(
            &mut sys,
            Integrator::Dopri5,
            (0.0, 0.05),
            &q0,
            &v0,
            &opts,
            &mut NoHooks,
        )
        .unwrap();
        let mut scale = e0.abs();
        let mut worst: f64 = 0.0;
        for y in &sol.y {
            let e = energies(
                &sys.model,
                &mut sys.data,
                &y.as_slice()[..n],
                &y.as_slice()[n..],
            )
            .unwrap();
            scale = scale.max(e.kinetic.abs()).max(e.gravitational.abs());
            worst = worst.max((e.total() - e0).abs());
        }
        // The rod moved: kinetic energy appeared.
        assert!(scale > 0.0);
        assert!(
            worst / scale < 1e-8,
            "relative energy drift {}",
            worst / scale
        );
    }

    /// The structured error filter (Shampine's `(I − hγJ)⁻¹ e` through the
    /// shifted matrix): `ẽ_v = (M + h²γ²K + hγD)⁻¹ (M e_v − hγ K̃ e_q)`,
    /// `ẽ_q = e_q + hγ ẽ_v`, with `M e_v` and the static stiffness `K̃ e_q`
    /// as differences of the O(N) force residual at `(q_J, 0, ·)`, against
    /// the same formula on dense matrices: `M` of the composite recursion,
    /// `K̃ = ∂ID/∂q` at `(q_J, 0, 0)` from the analytic derivatives, the
    /// elastic `K` and `D`. At the update's own time (the residual at
    /// `(q_J, 0, 0)` evaluated) and at a later step's time of the same update
    /// (that residual held, the system being autonomous).
    #[test]
    fn structured_error_filter_with_held_residual_equals_the_dense_filter() {
        use crate::problem::{JacKind, SecondOrderProblem};
        let mut sys = clamped_rod(2, 50.0);
        assert!(sys.is_autonomous());
        let n = sys.dim();
        let q = DVector::from_fn(n, |i, _| 0.3 * ((i as f64) * 0.7).sin());
        let zero = DVector::zeros(n);
        let hg = 0.25 * 2e-3;
        // Dense reference.
        let m = mass_matrix(&sys.model, &mut sys.data, q.as_slice())
            .unwrap()
            .clone();
        let mut work = IdDerivatives::new(&sys.model);
        let kt = inverse_dynamics_derivatives(
            &sys.model,
            &mut work,
            0.0,
            q.as_slice(),
            zero.as_slice(),
            zero.as_slice(),
        )
        .unwrap()
        .dtau_dq
        .clone();
        let shifted =
            &m + stiffness_matrix(&sys.model) * (hg * hg) + damping_matrix(&sys.model) * hg;
        let eq0 = DVector::from_fn(n, |i, _| 1e-4 * (1.0 + ((i as f64) * 1.3).cos()));
        let ev0 = DVector::from_fn(n, |i, _| 1e-3 * ((i as f64) * 0.9).sin());
        let want_v = shifted.lu().solve(&(&m * &ev0 - &kt * &eq0 * hg)).unwrap();
        let want_q = &eq0 + &want_v * hg;
        let mut p = SecondOrderProblem::new(&mut sys);
        assert_eq!(p.update_jacobians_qv(0.0, &q, &zero, true).unwrap(), None);
        assert_eq!(p.kind(), JacKind::Structured);
        assert!(p.factor_newmark(hg * hg, hg).unwrap());
        for t in [0.0, 0.37] {
            let (mut eq, mut ev) = (eq0.clone(), ev0.clone());
            p.filter_error(t, hg, &mut eq, &mut ev).unwrap();
            // K̃ e_q is a directional difference with a √ε-sized step.
            let dv = (&ev - &want_v).amax() / want_v.amax();
            let dq = (&eq - &want_q).amax() / want_q.amax();
            assert!(dv < 1e-6 && dq < 1e-6, "t = {t}: {dv:e}, {dq:e}");
        }
    }

    /// Time enters through a prescribed joint and a tension table, not
    /// through a table that the data's tensions override.
    #[test]
    fn autonomy_follows_prescribed_joints_and_tension_tables() {
        use softrod_dynamics::{Attachment, Curve, Joint, Prescribed};
        use softrod_mechanics::{Cable, Routing};
        let spec = |table: bool| {
            let rod = RodGeometry::uniform(
                0.2,
                2,
                Basis::all(),
                softrod_kinematics::straight(),
                Pose::identity(),
            )
            .unwrap();
            let mat = Material::with_poisson(1000.0, 1e5, 0.5, 0.0).unwrap();
            let body = RodProperties::new(Section::Circle { radius: 0.01 }, mat, 0.2).unwrap();
            let mut spec = Rod::new("r", rod, body);
            if table {
                spec.cables.push(Cable::new(
                    Routing::Offset { y: 0.005, z: 0.0 },
                    Tension::Table {
                        times: vec![0.0, 1.0],
                        values: vec![0.0, 1.0],
                    },
                ));
            }
            spec
        };
        let clamped = Model::new(vec![spec(false)], None, 4).unwrap();
        assert!(RodSystem::new(clamped).is_autonomous());
        let driven = Model::builder()
            .rod_on(
                spec(false),
                Attachment::world_joint(Joint::prismatic([0.0, 0.0, 1.0]).with_prescribed(
                    Prescribed::new(vec![Curve::Sine {
                        amplitude: 0.01,
                        frequency: 1.0,
                        phase: 0.0,
                        offset: 0.0,
                    }]),
                )),
            )
            .build()
            .unwrap();
        assert!(!RodSystem::new(driven).is_autonomous());
        let tabled = Model::new(vec![spec(true)], None, 4).unwrap();
        let mut sys = RodSystem::new(tabled);
        assert!(!sys.is_autonomous());
        sys.data
            .set_cable_tensions(&sys.model, Some(&[0.5]))
            .unwrap();
        assert!(sys.is_autonomous());
    }

    /// A four-bar of two soft rods (revolute joints, ball closure at the
    /// tips), released under gravity, undamped: with the exact closed-chain
    /// Jacobians (CD1–CD4) ESDIRK and Radau IIA land where they land with
    /// forward differences of the constrained q̈ (the Jacobian only steers
    /// Newton), and the energy stays constant (an independent check: the
    /// closure forces do no work on the manifold).
    #[test]
    fn closed_chain_runs_agree_with_difference_jacobians_and_conserve_energy() {
        use softrod_dynamics::{Attachment, Closure, ClosureFrame, ClosureKind, Joint};
        struct Differences(RodSystem);
        impl SecondOrderSystem for Differences {
            type Error = DynamicsError;
            fn dim(&self) -> usize {
                self.0.dim()
            }
            fn accel(
                &mut self,
                t: f64,
                q: &DVector<f64>,
                qd: &DVector<f64>,
                qdd: &mut DVector<f64>,
            ) -> Result<(), DynamicsError> {
                self.0.accel(t, q, qd, qdd)
            }
        }
        let mat = Material::with_poisson(1000.0, 1e6, 0.5, 0.0).unwrap();
        let rod = |name: &str, l: f64, x: f64| {
            let g = RodGeometry::uniform(
                l,
                2,
                Basis::all(),
                softrod_kinematics::straight(),
                Pose::new(softrod_lie::Mat3::identity(), Vec3::new(x, 0.0, 0.0)),
            )
            .unwrap();
            let body = RodProperties::new(Section::Circle { radius: 0.01 }, mat, l).unwrap();
            Rod::new(name, g, body)
        };
        // Both rods along x, tips together at x = 0.3: the loop holds at q = 0.
        let model = Model::builder()
            .rod_on(
                rod("a", 0.3, 0.0),
                Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
            )
            .rod_on(
                rod("b", 0.15, 0.15),
                Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
            )
            .gravity([0.0, 0.0, -9.81])
            .closure(Closure::new(
                "tip",
                ClosureKind::Ball,
                ClosureFrame::on("a", None, Pose::identity()),
                ClosureFrame::on("b", None, Pose::identity()),
            ))
            .build()
            .unwrap();
        let n = model.n_dof();
        let (q0, v0) = (DVector::zeros(n), DVector::zeros(n));
        let opts = Options::tol(1e-8, 1e-10);
        for method in [Integrator::Esdirk, Integrator::Radau5] {
            let mut exact = RodSystem::new(model.clone());
            let a = integrate_second_order(
                &mut exact,
                method,
                (0.0, 0.1),
                &q0,
                &v0,
                &opts,
                &mut NoHooks,
            )
            .unwrap();
            let mut fd = Differences(RodSystem::new(model.clone()));
            let b =
                integrate_second_order(&mut fd, method, (0.0, 0.1), &q0, &v0, &opts, &mut NoHooks)
                    .unwrap();
            let scale = b.y_final.amax();
            assert!(scale > 1e-3, "{method:?}: the loop moved");
            let diff = (&a.y_final - &b.y_final).amax();
            assert!(diff < 1e-5 * scale, "{method:?}: {diff:e} of {scale:e}");
            let e = |y: &DVector<f64>, sys: &mut RodSystem| {
                energies(
                    &sys.model,
                    &mut sys.data,
                    &y.as_slice()[..n],
                    &y.as_slice()[n..],
                )
                .unwrap()
            };
            let e0 = e(&a.y[0], &mut exact).total();
            let mut kinetic: f64 = 0.0;
            let mut drift: f64 = 0.0;
            for y in &a.y {
                let en = e(y, &mut exact);
                kinetic = kinetic.max(en.kinetic);
                drift = drift.max((en.total() - e0).abs());
            }
            assert!(kinetic > 0.0);
            assert!(
                drift < 1e-4 * kinetic,
                "{method:?}: energy drift {drift:e} of {kinetic:e}"
            );
        }
    }
}
