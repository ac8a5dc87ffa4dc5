//! Static equilibrium by Newton's method with line search and load continuation.

use super::krylov::{BlockStiffness, Tangent, gmres};
use crate::algorithms::{check_vec, inverse_dynamics_with};
use crate::derivatives::{IdDerivatives, inverse_dynamics_derivatives_with};
use crate::error::DynamicsError;
use crate::forces::{Drives, Forces};
use crate::model::Model;
use crate::model::data::Data;
use nalgebra::{DMatrix, DVector};

/// Settings of [`statics`].
#[derive(Clone, Debug)]
pub struct StaticsOptions {
    /// Converged when `‖r‖∞ ≤ tolerance · max(‖r(q₀)‖∞, ‖K q‖∞)`: the
    /// residual generalized force relative to the load it balances.
    pub tolerance: f64,
    /// Newton iterations per continuation step.
    pub max_iterations: usize,
    /// Maximum number of continuation steps (load increments).
    pub max_load_steps: usize,
    /// Time at which time-dependent loads (cable tensions) are evaluated \[s\].
    pub time: f64,
    /// How the Newton systems are solved ([`StaticsSolver`]).
    pub solver: StaticsSolver,
}

/// How [`statics`] solves the Newton system `K_t Δq = −r` of each
/// iteration (docs/theory.md E8–E10).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StaticsSolver {
    /// [`StaticsSolver::Structured`] on open models with at least
    /// [`StaticsSolver::STRUCTURED_MIN_DOF`] coordinates whose `K` is
    /// positive definite (no joint without a spring), else
    /// [`StaticsSolver::Dense`]; a structured solve that fails is retried
    /// dense up to [`StaticsSolver::DENSE_FALLBACK_MAX_DOF`] coordinates.
    #[default]
    Auto,
    /// The analytic `K_t = ∂τ/∂q` (D37–D47) as an `n × n` matrix and its
    /// LU: O(n²) memory, O(n³) time; every model, closed ones included.
    Dense,
    /// Matrix-free: GMRES on `K_t Δq = −r` with products `K_t v` by a
    /// central difference of two O(N) inverse dynamics (E9),
    /// preconditioned by the block-diagonal `K` (E10). O(N) memory and
    /// time per product; open models whose `K` is positive definite
    /// ([`DynamicsError::NotPositiveDefinite`] otherwise,
    /// [`DynamicsError::UnsupportedClosed`] with closures).
    Structured,
}

impl StaticsSolver {
    /// Below this many coordinates [`StaticsSolver::Auto`] is dense: the
    /// LU of a small `K_t` costs less than the Krylov iterations
    /// (docs/performance.md, "Scaling").
    pub const STRUCTURED_MIN_DOF: usize = 120;
    /// [`StaticsSolver::Auto`] retries a failed structured solve dense up
    /// to this many coordinates (an `n × n` LU of 2 000 is ~0.5 s).
    pub const DENSE_FALLBACK_MAX_DOF: usize = 2000;

    /// Whether [`statics`] of `model` with this setting runs structured
    /// (no `n × n` matrix): `Structured`, or `Auto` on an open model with
    /// at least [`Self::STRUCTURED_MIN_DOF`] coordinates and a positive
    /// definite `K`.
    pub fn is_structured(self, model: &Model) -> bool {
        match self {
            Self::Dense => false,
            Self::Structured => true,
            Self::Auto => {
                !model.has_closures()
                    && model.n_dof() >= Self::STRUCTURED_MIN_DOF
                    && BlockStiffness::new(model).is_definite()
            }
        }
    }
}

impl Default for StaticsOptions {
    /// `tolerance = 1e-12`: Newton converges quadratically, so the last step
    /// typically lands near round-off (~1e-15 of the balanced force); 1e-10
    /// could stop one step early with a 1e-10-relative error in the strains.
    /// 30 iterations, 64 load steps, [`StaticsSolver::Auto`].
    fn default() -> Self {
        Self {
            tolerance: 1e-12,
            max_iterations: 30,
            max_load_steps: 64,
            time: 0.0,
            solver: StaticsSolver::Auto,
        }
    }
}

/// A converged equilibrium (failures are [`DynamicsError::StaticsFailed`],
/// never a result).
#[derive(Clone, Debug)]
pub struct StaticsResult {
    /// Equilibrium coordinates (n_dof).
    pub q: DVector<f64>,
    /// Newton iterations over all continuation steps.
    pub iterations: usize,
    /// Final residual `‖r‖∞` [N or N·m per coordinate].
    pub residual: f64,
    /// Load increments used (1 when the full load converged directly).
    pub load_steps: usize,
}

/// Static equilibrium `r(q) = ID(q, 0, 0) = G + τ_e − τ_c − Q_ext = 0` under
/// every static term of the model (gravity, elasticity, cables at
/// `options.time`, point and distributed loads), starting from `q0`.
///
/// Newton's method with the analytic tangent stiffness `K_t = ∂r/∂q`
/// (dense, or matrix-free by Krylov iterations on large open models:
/// [`StaticsOptions::solver`], docs/theory.md E8–E10) and a backtracking
/// line search on `‖r‖`. If the full load does not converge from `q0`, the loads are
/// ramped (`λ` from 0 to 1, step halved on failure, grown on success) —
/// large curls and follower loads need it. Never returns an unconverged
/// state: failure is [`DynamicsError::StaticsFailed`] with the load fraction
/// reached and the residual.
pub fn statics(
    model: &Model,
    data: &mut Data,
    q0: &[f64],
    options: &StaticsOptions,
) -> Result<StaticsResult, DynamicsError> {
    check_vec(model, "q0", q0)?;
    // Prescribed joints (D59) hold their values at `options.time`, at rest
    // (`Forces::at_rest` in every evaluation).
    if let (true, Some(tree)) = (model.has_closures(), &model.tree) {
        if options.solver == StaticsSolver::Structured {
            return Err(DynamicsError::UnsupportedClosed {
                what: "the structured statics",
            });
        }
        // Closed chains: Newton on [τ − Jᵀλ; φ] (docs/theory.md D69).
        crate::constraints::queries::check_workspace(model, data)?;
        return super::closed::statics(model, tree, data, q0, options).map(|(r, _)| r);
    }
    let mut result = statics_open(model, data, q0, options)?;
    // Contact (docs/theory-contact.md CT15): resting contacts whose spring
    // carries its force deeper than its target have their stiffness raised,
    // and the equilibrium is solved again from where it was, until none is.
    let mut rounds = 0;
    while model.has_contact()
        && rounds < MAX_STIFFNESS_ROUNDS
        && super::raise_for_rest(model, data, options.time, result.q.as_slice())
    {
        let again = statics_open(model, data, result.q.as_slice(), options)?;
        result = StaticsResult {
            iterations: result.iterations + again.iterations,
            load_steps: result.load_steps.max(again.load_steps),
            ..again
        };
        rounds += 1;
    }
    Ok(result)
}

/// Rounds of contact stiffness raises in [`statics`] (CT15); each raises a
/// scale by at least [`crate::model::contact::RAISE_HEADROOM`], so a
/// contact settles in one or two.
pub(crate) const MAX_STIFFNESS_ROUNDS: usize = 20;

/// [`statics`] of an open model with the contact stiffness `data` holds.
fn statics_open(
    model: &Model,
    data: &mut Data,
    q0: &[f64],
    options: &StaticsOptions,
) -> Result<StaticsResult, DynamicsError> {
    let stiffness = BlockStiffness::new(model);
    let structured = match options.solver {
        StaticsSolver::Dense => false,
        StaticsSolver::Structured => {
            if !stiffness.is_definite() {
                return Err(DynamicsError::NotPositiveDefinite {
                    what: "generalized stiffness K, the structured statics' preconditioner (a joint without a spring?)",
                });
            }
            true
        }
        StaticsSolver::Auto => options.solver.is_structured(model),
    };
    if !structured {
        return statics_inner(model, data, q0, options, stiffness, false);
    }
    let first = statics_inner(model, data, q0, options, stiffness, true);
    match first {
        Err(DynamicsError::StaticsFailed { .. })
            if options.solver == StaticsSolver::Auto
                && model.n_dof() <= StaticsSolver::DENSE_FALLBACK_MAX_DOF =>
        {
            let again = statics_inner(model, data, q0, options, BlockStiffness::new(model), false);
            // The first failure is the one to report if both fail.
            again.or(first)
        }
        r => r,
    }
}

/// The static force `τ_s(q) = b(q, 0)` at time `t` (the bias of
/// [`crate::bias_force`] at rest): elasticity with its stress-free offset,
/// gravity, loads, cables at their tensions at `t`, joint springs, with
/// prescribed joints (D59) held at rest at their values at `t`. What
/// [`statics`] drives to zero (with loop closures, less their forces
/// `Jᵀλ`): `q` is an equilibrium of the open model exactly when it
/// vanishes. Result in `data.tau`.
pub fn static_force<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    check_vec(model, "q", q)?;
    let zero = vec![0.0; model.n_dof()];
    crate::algorithms::bias_force_with(
        model,
        data,
        Forces::ALL.with_drives(Drives::AtRest),
        t,
        q,
        &zero,
    )
}

struct Newton<'a> {
    model: &'a Model,
    k: BlockStiffness,
    zero: Vec<f64>,
    time: f64,
    iterations: usize,
    /// The analytic `∂τ/∂q` (D37–D47, D76–D80) at `q̇ = q̈ = 0` (dense
    /// path; `None` on the structured path, which never forms `n × n`).
    derivatives: Option<IdDerivatives>,
}

impl Newton<'_> {
    /// `τ(q) = ID(q, 0, 0)` under `forces`.
    fn residual(
        &self,
        data: &mut Data,
        forces: Forces,
        q: &DVector<f64>,
    ) -> Result<DVector<f64>, DynamicsError> {
        Ok(inverse_dynamics_with(
            self.model,
            data,
            forces,
            self.time,
            q.as_slice(),
            &self.zero,
            &self.zero,
        )?
        .clone())
    }

    /// `∂τ/∂q` of the residual, analytic (the derivatives of the inverse
    /// dynamics at rest under `forces`, the tensions `data` has).
    fn jacobian(
        &mut self,
        data: &Data,
        forces: Forces,
        q: &DVector<f64>,
    ) -> Result<DMatrix<f64>, DynamicsError> {
        let w = self
            .derivatives
            .get_or_insert_with(|| IdDerivatives::new(self.model));
        if let (Some(from), Some(to)) = (&data.contact, &mut w.contact) {
            // The contact stiffness of this solve (CT15), not a fresh one.
            if let Some(cw) = &mut to.contact {
                cw.copy_friction_state(from);
            }
        }
        w.copy_inputs(data);
        inverse_dynamics_derivatives_with(
            self.model,
            w,
            forces,
            self.time,
            q.as_slice(),
            &self.zero,
            &self.zero,
        )?;
        Ok(w.dtau_dq.clone())
    }

    /// Central differences of the residual, steps `10⁻⁶ (1 + |q_j|)`: the
    /// fallback of a singular analytic tangent (see [`Newton::solve`]).
    fn secant(
        &self,
        data: &mut Data,
        forces: Forces,
        q: &DVector<f64>,
    ) -> Result<DMatrix<f64>, DynamicsError> {
        let n = q.len();
        let mut jac = DMatrix::zeros(n, n);
        let mut trial = q.clone();
        for j in 0..n {
            let h = 1e-6 * (1.0 + q[j].abs());
            trial[j] = q[j] + h;
            let plus = self.residual(data, forces, &trial)?;
            trial[j] = q[j] - h;
            let minus = self.residual(data, forces, &trial)?;
            trial[j] = q[j];
            jac.set_column(j, &((plus - minus) / (2.0 * h)));
        }
        Ok(jac)
    }

    /// Newton from `q` under `forces` (one load scale of the continuation):
    /// `Ok(Ok(residual))` when converged (q updated), `Ok(Err(residual))`
    /// with the last residual when it failed (q unspecified).
    fn solve(
        &mut self,
        data: &mut Data,
        forces: Forces,
        q: &mut DVector<f64>,
        tol_ref: f64,
        options: &StaticsOptions,
        structured: bool,
    ) -> Result<Result<f64, f64>, DynamicsError> {
        let mut r = self.residual(data, forces, q)?;
        for _ in 0..options.max_iterations {
            let rn = r.amax();
            let kq = self.k.mul_amax(q.as_slice());
            let tol = options.tolerance * tol_ref.max(kq);
            if rn <= tol {
                return Ok(Ok(rn));
            }
            self.iterations += 1;
            let step = if structured {
                self.krylov_step(data, forces, q, &r, tol)?
            } else {
                let jac = self.jacobian(data, forces, q)?;
                match jac.lu().solve(&(-&r)) {
                    Some(dq) if dq.iter().all(|v| v.is_finite()) => Some(dq),
                    // A singular tangent at a kink of the forces: a contact
                    // at zero gap has zero stiffness (the penalty starts
                    // C¹, CT2), and a coordinate nothing else holds (a free
                    // joint resting on it) has none at all. The secant
                    // over ±h sees both sides of the kink.
                    _ => self.secant(data, forces, q)?.lu().solve(&(-&r)),
                }
            };
            let Some(dq) = step else {
                return Ok(Err(rn));
            };
            if dq.iter().any(|v| !v.is_finite()) {
                return Ok(Err(rn));
            }
            let mut alpha = 1.0;
            loop {
                let trial = &*q + &dq * alpha;
                let rt = match self.residual(data, forces, &trial) {
                    Ok(v) => v,
                    Err(
                        DynamicsError::NotFinite { .. } | DynamicsError::NonFiniteResult { .. },
                    ) => DVector::from_element(r.len(), f64::INFINITY),
                    Err(e) => return Err(e),
                };
                if rt.amax() < (1.0 - 1e-4 * alpha) * rn || rt.amax() <= tol {
                    *q = trial;
                    r = rt;
                    break;
                }
                alpha *= 0.5;
                if alpha < 1e-6 {
                    // Stagnation at round-off counts as converged if the
                    // residual is already tiny.
                    return Ok(if rn <= 1e3 * tol { Ok(rn) } else { Err(rn) });
                }
            }
        }
        let rn = r.amax();
        let tol = options.tolerance * tol_ref.max(self.k.mul_amax(q.as_slice()));
        Ok(if rn <= tol { Ok(rn) } else { Err(rn) })
    }

    /// The inexact Newton step of the structured path (E10): GMRES on
    /// `K_t Δq = −r`, preconditioned by `K`, to the relative residual
    /// `η = clamp(0.1·tol/‖r‖∞, 10⁻¹⁰, 10⁻³)` — loose while far from the
    /// solution, as tight as the differenced products allow near it (an
    /// inexact Newton iteration converges at the rate `η`). `None` if
    /// GMRES does not at least halve the residual.
    fn krylov_step(
        &mut self,
        data: &mut Data,
        forces: Forces,
        q: &DVector<f64>,
        r: &DVector<f64>,
        tol: f64,
    ) -> Result<Option<DVector<f64>>, DynamicsError> {
        let n = q.len();
        let eta = (0.1 * tol / r.amax()).clamp(1e-10, 1e-3);
        let mut tangent = Tangent::new(self.model, forces, self.time, q.as_slice(), &self.zero);
        let rhs: Vec<f64> = r.iter().map(|v| -v).collect();
        let mut dq = vec![0.0; n];
        let k = &self.k;
        let outcome = gmres(
            |v, out| tangent.apply(data, v, out),
            |x| k.solve(x),
            &rhs,
            &mut dq,
            eta,
            KRYLOV_RESTART,
            KRYLOV_MAX_PRODUCTS,
        )?;
        Ok((outcome.relative_residual <= 0.5).then(|| DVector::from_vec(dq)))
    }
}

/// GMRES restart length of the structured statics: long enough that the
/// restart rarely happens on a `K`-preconditioned tangent (E10).
const KRYLOV_RESTART: usize = 80;
/// Products with `K_t` per structured Newton step before it gives up.
const KRYLOV_MAX_PRODUCTS: usize = 400;

fn statics_inner(
    model: &Model,
    data: &mut Data,
    q0: &[f64],
    options: &StaticsOptions,
    k: BlockStiffness,
    structured: bool,
) -> Result<StaticsResult, DynamicsError> {
    let n = model.n_dof();
    let mut newton = Newton {
        model,
        k,
        zero: vec![0.0; n],
        time: options.time,
        iterations: 0,
        derivatives: None,
    };
    let start = DVector::from_column_slice(q0);
    let r_full = newton.residual(data, Forces::at_rest(1.0), &start)?.amax();
    // Reference force: the full-load imbalance at the start.
    let tol_ref = r_full.max(f64::MIN_POSITIVE);
    let mut q = start.clone();
    if let Ok(res) = newton.solve(
        data,
        Forces::at_rest(1.0),
        &mut q,
        tol_ref,
        options,
        structured,
    )? {
        return Ok(StaticsResult {
            q,
            iterations: newton.iterations,
            residual: res,
            load_steps: 1,
        });
    }
    // Continuation from the unloaded state.
    let mut lam = 0.0;
    let mut q_prev = start.clone();
    let unloaded = Forces::at_rest(0.0);
    if newton
        .solve(data, unloaded, &mut q_prev, tol_ref, options, structured)?
        .is_err()
    {
        return Err(DynamicsError::StaticsFailed {
            reason: "no equilibrium even without loads (check the stress-free strain)".into(),
            load_fraction: 0.0,
            iterations: newton.iterations,
            residual: newton.residual(data, unloaded, &q_prev)?.amax(),
        });
    }
    let mut step = 0.25;
    let mut steps = 0;
    let mut last_res = 0.0;
    // Residual of the last failed attempt, for the error message.
    let mut failed_res = f64::NAN;
    while lam < 1.0 {
        if steps >= options.max_load_steps || step < 1e-5 {
            return Err(DynamicsError::StaticsFailed {
                reason: if step < 1e-5 {
                    "load step fell below 1e-5 (a limit point or instability?)".into()
                } else {
                    format!("more than {} load steps", options.max_load_steps)
                },
                load_fraction: lam,
                iterations: newton.iterations,
                residual: if failed_res.is_nan() {
                    last_res
                } else {
                    failed_res
                },
            });
        }
        steps += 1;
        let target = (lam + step).min(1.0);
        let mut trial = q_prev.clone();
        match newton.solve(
            data,
            Forces::at_rest(target),
            &mut trial,
            tol_ref,
            options,
            structured,
        )? {
            Ok(res) => {
                lam = target;
                q_prev = trial;
                last_res = res;
                failed_res = f64::NAN;
                step *= 1.5;
            }
            Err(res) => {
                failed_res = res;
                step *= 0.5;
            }
        }
    }
    Ok(StaticsResult {
        q: q_prev,
        iterations: newton.iterations,
        residual: last_res,
        load_steps: steps,
    })
}
