//! Exact gradients of whole trajectories
//! ([`Simulation::value_and_gradient`]): a forward run records its accepted
//! steps, the discrete adjoint of the integrator
//! (`softrod_integrate::adjoint_second_order`) runs them backwards
//! (docs/theory-control.md G1–G9).

mod actuator;
mod params;
mod prescribed;
#[cfg(test)]
mod tests;

use nalgebra::DVector;
use softrod_integrate::{
    ADJOINT_INTEGRATORS, AdjointSolver, Control, Hooks, IntegrateError, Iteration, RodSystem,
    StepControl, StepInfo, Tape, adjoint_second_order_with, forward_sensitivity_second_order,
    integrate_second_order,
};
use softrod_kinematics::Frame;

use super::Simulation;
use crate::error::{Error, Result};
use params::{Kind, ParamSystem};

/// A user loss: at `(t, q, q̇)` returns `(ℓ, ∂ℓ/∂q, ∂ℓ/∂q̇)` (both
/// `n_dof` long) or an error message.
pub type LossFn<'a> =
    dyn FnMut(f64, &[f64], &[f64]) -> std::result::Result<(f64, Vec<f64>, Vec<f64>), String> + 'a;

/// One term of a loss `L = Σₜ ℓ(t, q(t), q̇(t))`, evaluated at its `times`
/// (each in `[0, duration]`; `0` is the initial state). The run's steps end
/// on every such time, so the loss is a function of the accepted states and
/// no dense output enters it (G9).
pub enum LossTerm<'a> {
    /// Tracking of a rod section's world position:
    /// `ℓ = ½ w ‖p(t) − p*(t)‖²` \[w·m²\] with `p(t)` the position of rod
    /// `rod` at `s` (the tip when `None`).
    Position {
        /// The rod's name.
        rod: String,
        /// Abscissa \[m\]; `None`: the tip.
        s: Option<f64>,
        /// Sample times \[s\].
        times: Vec<f64>,
        /// Target positions, one per time \[m\], world frame.
        targets: Vec<[f64; 3]>,
        /// Weight `w ≥ 0`.
        weight: f64,
    },
    /// `ℓ = ½ Σᵢ (wqᵢ (qᵢ − q*ᵢ)² + wvᵢ q̇ᵢ²)` (diagonal weights, `n_dof`
    /// each; `q*` 0 when `None`).
    Quadratic {
        /// Sample times \[s\].
        times: Vec<f64>,
        /// Weights of `q − q*`.
        q_weights: Vec<f64>,
        /// Weights of `q̇`.
        qdot_weights: Vec<f64>,
        /// Reference `q*`.
        q_ref: Option<Vec<f64>>,
    },
    /// A user function at each of `times`.
    Custom {
        /// Sample times \[s\].
        times: Vec<f64>,
        /// `(t, q, q̇) ↦ (ℓ, ∂ℓ/∂q, ∂ℓ/∂q̇)`.
        f: Box<LossFn<'a>>,
    },
}

impl LossTerm<'_> {
    fn times(&self) -> &[f64] {
        match self {
            LossTerm::Position { times, .. }
            | LossTerm::Quadratic { times, .. }
            | LossTerm::Custom { times, .. } => times,
        }
    }
}

/// How [`Simulation::value_and_gradient`] runs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GradientOptions {
    /// Fixed steps of this size \[s\] instead of the run settings' adaptive
    /// ones (the last step before a loss time is shortened to land on it):
    /// one step sequence whatever the parameters, for comparisons with
    /// differences of whole runs.
    pub fixed_step: Option<f64>,
    /// The Newton tolerance of the forward run's stage equations (relative
    /// to the error weights, as `Iteration::Newton`'s `tol`); the gradient is
    /// exact for the map whose stages are solved exactly, so a run whose
    /// stages are solved loosely has a gradient off by about this relative
    /// to the tolerance. `None`: the integrator's default.
    pub newton_tol: Option<f64>,
    /// How the derivatives are carried: backwards (the adjoint, the
    /// default: its cost does not grow with the parameters) or forwards
    /// (sensitivities, G21: one column per parameter entry, `n` more each
    /// for `q0` and `qdot0`; for few parameters on small models, and a
    /// second algorithm for the same numbers).
    pub method: GradientMethod,
}

/// The algorithm of [`Simulation::value_and_gradient`]
/// ([`GradientOptions::method`]); both give the exact gradient of the
/// computed trajectory, equal to round-off.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GradientMethod {
    /// The discrete adjoint (docs/theory-control.md G1–G13).
    #[default]
    Adjoint,
    /// Forward sensitivities (G21).
    Forward,
}

/// The result of [`Simulation::value_and_gradient`].
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    /// The loss `L`.
    pub value: f64,
    /// `∂L/∂p` for each parameter named, in the order named: one entry
    /// for a material constant or a mass, one per table value (or one for
    /// a constant) for a cable's tension, samples × coordinates for a
    /// prescribed joint (entry `i·dof + c` for sample `i`, coordinate `c`),
    /// `n_dof` for `q0` and `qdot0`.
    pub gradients: Vec<(String, Vec<f64>)>,
    /// Accepted steps of the forward run (the backward pass has as many).
    pub steps: usize,
    /// Dense Jacobian evaluations of the backward pass (of the force
    /// residual, docs/theory-control.md G11).
    pub jacobian_evaluations: usize,
    /// Dense LU factorizations of the backward pass (one per step for the
    /// recomputed stages; more where a transposed stage solve fell back).
    pub dense_factorizations: usize,
    /// GMRES iterations of the backward pass's transposed stage solves.
    pub krylov_iterations: usize,
}

impl Gradient {
    /// The gradient of parameter `name`, if it was asked for.
    pub fn get(&self, name: &str) -> Option<&[f64]> {
        self.gradients
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, g)| g.as_slice())
    }
}

/// Records the tape: every accepted step.
struct TapeHooks {
    n: usize,
    tape: Tape,
}

impl Hooks<RodSystem> for TapeHooks {
    fn keep_outputs(&self) -> bool {
        false
    }
    fn step(&mut self, info: &StepInfo<'_>, _sys: &mut RodSystem) -> Control {
        let (q, qd) = info.y.as_slice().split_at(self.n);
        self.tape.push(info.t, info.h, q, qd);
        self.tape.push_stages(info.stages);
        Control::Continue
    }
}

/// Two loss times closer than this are one node of the run \[s\].
fn node_tolerance(duration: f64) -> f64 {
    1e-12 * duration.max(1.0)
}

fn bad(key: impl Into<String>, message: impl Into<String>) -> Error {
    Error::Gradient {
        key: key.into(),
        message: message.into(),
    }
}

impl Simulation {
    /// The loss `L = Σ` over `loss`'s terms and times of `ℓ(t, q, q̇)`
    /// along a run of `duration` seconds from the initial state, and its
    /// exact gradient with respect to `params` (docs/theory-control.md
    /// G1–G9): `"q0"`, `"qdot0"`, `"ROD.young"`, `"ROD.shear_modulus"`
    /// (a material given by its shear modulus), `"ROD.density"`,
    /// `"ROD.viscosity"`, `"BODY.mass"`, `"cableN.tension"` (one entry per
    /// value of a tension table, the scene's `[[cable]]` order),
    /// `"ELEMENT.prescribed"` (the samples of the spline that prescribes
    /// the joint of rod or body `ELEMENT` \[rad or m\]: one entry per
    /// sample and coordinate, sample-major — the order of the scene's
    /// `values` rows; G17–G20, closed models G28), `"ELEMENT.actuator"` (the
    /// force values of the actuator on the joint of `ELEMENT` \[N or N·m\]:
    /// one entry per table row and coordinate, row-major, or per
    /// coordinate for a constant; G29).
    ///
    /// The gradient is the discrete adjoint of the run's integrator: exact
    /// for the computed trajectory (its accepted step sequence held fixed)
    /// to round-off and the Newton tolerance of the forward run
    /// ([`GradientOptions::newton_tol`]). Its cost does not grow with the
    /// number of parameters beyond two O(N) inverse dynamics per parameter
    /// and stage (docs/performance.md, "Trajectory gradients"). With no
    /// `params` it is the loss of the recorded run alone (no backward pass).
    ///
    /// Errors ([`Error::Gradient`], naming the key): an integrator without
    /// an adjoint (supported: esdirk, esdirk5, radau5), a model with contact,
    /// `ELEMENT.prescribed` on a joint that is not prescribed, or prescribed
    /// by a sinusoid,
    /// a parameter or loss naming nothing in the model, a time outside the
    /// run, non-finite or negative weights, non-finite targets, a custom
    /// loss that fails or returns the wrong lengths or NaN.
    pub fn value_and_gradient(
        &mut self,
        loss: &mut [LossTerm<'_>],
        params: &[&str],
        duration: f64,
        options: &GradientOptions,
    ) -> Result<Gradient> {
        self.gradient_with(loss, params, duration, options, AdjointSolver::Structured)
    }

    /// [`Simulation::value_and_gradient`] with the backward pass's linear
    /// algebra chosen (the dense one is the reference of the tests).
    pub(crate) fn gradient_with(
        &mut self,
        loss: &mut [LossTerm<'_>],
        params: &[&str],
        duration: f64,
        options: &GradientOptions,
        solver: AdjointSolver,
    ) -> Result<Gradient> {
        self.check_run(duration)?;
        let integrator = self.settings.integrator;
        if !ADJOINT_INTEGRATORS.contains(&integrator) {
            let names: Vec<&str> = ADJOINT_INTEGRATORS.iter().map(|i| i.name()).collect();
            return Err(bad(
                "run.integrator",
                format!(
                    "gradients need the discrete adjoint of the integrator; {} has none \
                     (supported: {})",
                    integrator.name(),
                    names.join(", ")
                ),
            ));
        }
        if self.model().has_contact() {
            return Err(bad(
                "contact",
                "gradients of models with contact are not supported yet",
            ));
        }
        let parsed = params
            .iter()
            .map(|p| params::parse(self.model(), p))
            .collect::<Result<Vec<_>>>()?;
        let stops = self.check_loss(loss, duration)?;
        let tape = self.record(duration, &stops, options)?;
        // The loss at the nodes, and its derivatives as the seeds of the
        // backward pass.
        let n = self.n_dof();
        let mut seeds: Vec<Option<(DVector<f64>, DVector<f64>)>> = vec![None; tape.nodes()];
        let mut value = 0.0;
        let saved_time = self.time;
        let evaluated = self.evaluate_loss(loss, &tape, duration, &mut seeds, &mut value);
        self.time = saved_time;
        evaluated?;
        if !value.is_finite() {
            return Err(bad("loss", format!("the loss is {value}")));
        }
        if parsed.is_empty() {
            // Nothing to differentiate: the loss alone, no backward pass.
            return Ok(Gradient {
                value,
                gradients: Vec::new(),
                steps: tape.steps(),
                jacobian_evaluations: 0,
                dense_factorizations: 0,
                krylov_iterations: 0,
            });
        }
        // The position terms' rods and abscissae, for their direct
        // dependence on prescribed samples (G19).
        let mut sections = Vec::new();
        for term in loss.iter() {
            if let LossTerm::Position { rod, s, .. } = term {
                let r = self.rod_index(rod.as_str())?;
                sections.push((
                    r,
                    s.unwrap_or(self.model().rods()[r].spec.properties.length()),
                ));
            }
        }
        let mut sys = ParamSystem::new(&mut self.system, &parsed)?;
        let mut seed = |k: usize, lq: &mut DVector<f64>, lv: &mut DVector<f64>| {
            if let Some((dq, dv)) = &seeds[k] {
                *lq += dq;
                *lv += dv;
            }
        };
        let mut g = match options.method {
            GradientMethod::Adjoint => {
                adjoint_second_order_with(&mut sys, integrator, &tape, &mut seed, solver)
            }
            GradientMethod::Forward => {
                let initial = parsed
                    .iter()
                    .any(|p| matches!(p.kind, Kind::Q0 | Kind::Qdot0));
                forward_sensitivity_second_order(&mut sys, integrator, &tape, &mut seed, initial)
            }
        }
        .map_err(|e| Error::Integration(Box::new(e)))?;
        if sys.has_prescribed() {
            // A section's world position depends on the prescribed
            // coordinates directly, besides through q (G19).
            let eps = node_tolerance(duration);
            let mut positions = sections.iter();
            for term in loss.iter() {
                let LossTerm::Position {
                    times,
                    targets,
                    weight,
                    ..
                } = term
                else {
                    continue;
                };
                let &(rod, s) = positions.next().expect("one per position term");
                for (&t, target) in times.iter().zip(targets) {
                    let k = (0..tape.nodes())
                        .find(|&k| (tape.time(k) - t).abs() <= eps)
                        .expect("evaluate_loss found every node");
                    sys.prescribed_position_term(
                        tape.time(k),
                        tape.q(k),
                        rod,
                        s,
                        *target,
                        *weight,
                        &mut g.dp,
                    )?;
                }
            }
        }
        let mut gradients = Vec::with_capacity(parsed.len());
        let mut slot = 0;
        for p in &parsed {
            let v = match p.kind {
                Kind::Q0 => g.dq0.as_slice().to_vec(),
                Kind::Qdot0 => g.dqd0.as_slice().to_vec(),
                _ => {
                    slot += p.len;
                    g.dp[slot - p.len..slot].to_vec()
                }
            };
            debug_assert_eq!(v.len(), if p.kind == Kind::Q0 { n } else { v.len() });
            gradients.push((p.name.clone(), v));
        }
        Ok(Gradient {
            value,
            gradients,
            steps: tape.steps(),
            jacobian_evaluations: g.jacobian_evaluations,
            dense_factorizations: g.dense_factorizations,
            krylov_iterations: g.krylov_iterations,
        })
    }

    /// Checks the loss terms; returns the sorted distinct times where steps
    /// must end (without 0).
    fn check_loss(&self, loss: &[LossTerm<'_>], duration: f64) -> Result<Vec<f64>> {
        let n = self.n_dof();
        let mut stops = Vec::new();
        for (i, term) in loss.iter().enumerate() {
            let key = |k: &str| format!("loss[{i}].{k}");
            for &t in term.times() {
                if !(t.is_finite() && (0.0..=duration).contains(&t)) {
                    return Err(bad(key("times"), format!("{t} is outside [0, {duration}]")));
                }
                if t > 0.0 {
                    stops.push(t);
                }
            }
            match term {
                LossTerm::Position {
                    rod,
                    s,
                    times,
                    targets,
                    weight,
                } => {
                    let r = self
                        .rod_index(rod.as_str())
                        .map_err(|_| bad(key("rod"), format!("no rod named '{rod}'")))?;
                    let length = self.model().rods()[r].spec.properties.length();
                    if let Some(s) = s {
                        if !(s.is_finite() && (0.0..=length).contains(s)) {
                            return Err(bad(
                                key("s"),
                                format!("{s} is outside rod '{rod}' [0, {length}]"),
                            ));
                        }
                    }
                    if targets.len() != times.len() {
                        return Err(bad(
                            key("targets"),
                            format!("{} targets for {} times", targets.len(), times.len()),
                        ));
                    }
                    if let Some(p) = targets.iter().flatten().find(|v| !v.is_finite()) {
                        return Err(bad(key("targets"), format!("a target is {p}")));
                    }
                    if !(weight.is_finite() && *weight >= 0.0) {
                        return Err(bad(
                            key("weight"),
                            format!("{weight} must be finite and ≥ 0"),
                        ));
                    }
                }
                LossTerm::Quadratic {
                    q_weights,
                    qdot_weights,
                    q_ref,
                    ..
                } => {
                    for (k, v) in [
                        ("q_weights", Some(q_weights)),
                        ("qdot_weights", Some(qdot_weights)),
                        ("q_ref", q_ref.as_ref()),
                    ] {
                        let Some(v) = v else { continue };
                        if v.len() != n {
                            return Err(bad(key(k), format!("{} entries, n_dof is {n}", v.len())));
                        }
                        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                            return Err(bad(key(k), format!("an entry is {x}")));
                        }
                    }
                }
                LossTerm::Custom { .. } => {}
            }
        }
        // Times equal up to rounding (`0.05 * 6` and `0.3`) are one node
        // (`evaluate_loss` finds it within the same tolerance): a fixed-step
        // segment between them would be a step of a few ulps.
        let eps = node_tolerance(duration);
        stops.retain(|&t| t > eps);
        stops.sort_by(f64::total_cmp);
        stops.dedup_by(|b, a| *b - *a <= eps);
        Ok(stops)
    }

    /// The forward run, recorded: steps end on every loss time.
    fn record(&mut self, duration: f64, stops: &[f64], options: &GradientOptions) -> Result<Tape> {
        let (method, mut opts) = self.settings.method_and_options(duration)?;
        opts.t_eval = Some(Vec::new());
        if let Some(tol) = options.newton_tol {
            if !(tol.is_finite() && tol > 0.0) {
                return Err(bad("newton_tol", format!("{tol} must be positive")));
            }
            opts.iteration = Iteration::Newton { tol, max_iter: 40 };
        }
        if let Some(dt) = options.fixed_step {
            if !(dt.is_finite() && dt > 0.0) {
                return Err(bad("fixed_step", format!("{dt} must be positive")));
            }
            opts.step = StepControl::Fixed(dt);
            opts.max_steps = 2 * (duration / dt).ceil().min(1e12) as usize + 2 * stops.len() + 100;
        }
        let mut breakpoints = self.system.model.breakpoints();
        breakpoints.extend_from_slice(stops);
        breakpoints.sort_by(f64::total_cmp);
        breakpoints.dedup();
        opts.breakpoints = breakpoints;
        self.system.jacobian = self.settings.stiff_jacobian();
        let n = self.n_dof();
        let mut hooks = TapeHooks {
            n,
            tape: Tape::new(0.0, self.q0.as_slice(), self.qd0.as_slice()),
        };
        // Fixed steps do not stop at breakpoints: one run per interval
        // between loss times. Adaptive ones end their steps there.
        let segments: Vec<(f64, f64)> = if options.fixed_step.is_some() {
            let mut ends = stops.to_vec();
            // A last loss time within rounding of the end is the end.
            if ends
                .last()
                .is_some_and(|&t| duration - t <= node_tolerance(duration))
            {
                ends.pop();
            }
            ends.push(duration);
            let mut t0 = 0.0;
            ends.iter()
                .map(|&t1| {
                    let s = (t0, t1);
                    t0 = t1;
                    s
                })
                .collect()
        } else {
            vec![(0.0, duration)]
        };
        let (mut q, mut qd) = (self.q0.clone(), self.qd0.clone());
        for span in segments {
            integrate_second_order(&mut self.system, method, span, &q, &qd, &opts, &mut hooks)
                .map_err(|e| match (e, options.fixed_step) {
                    // A fixed step whose Newton fails is subdivided; running out
                    // of steps then means the stage equations cannot be solved to
                    // `newton_tol` at all (a tolerance below their round-off), which
                    // the bare step count would hide.
                    (IntegrateError::MaxStepsExceeded { t, h, .. }, Some(dt)) => bad(
                        "newton_tol",
                        format!(
                            "the fixed steps of {dt:e} s had to be cut to {h:e} s at t = {t:e} s: \
                             Newton could not solve the stage equations to newton_tol = {} \
                             (below their round-off?); use a looser newton_tol or a smaller fixed_step",
                            options
                                .newton_tol
                                .map_or("the integrator's default".into(), |v| format!("{v:e}"))
                        ),
                    ),
                    (e, _) => Error::Integration(Box::new(e)),
                })?;
            let last = hooks.tape.nodes() - 1;
            q.copy_from_slice(hooks.tape.q(last));
            qd.copy_from_slice(hooks.tape.qd(last));
        }
        Ok(hooks.tape)
    }

    /// Evaluates every loss term at its nodes: adds to `value` and to the
    /// nodes' seeds `(∂ℓ/∂q, ∂ℓ/∂q̇)`. Moves the clock (the caller restores it).
    fn evaluate_loss(
        &mut self,
        loss: &mut [LossTerm<'_>],
        tape: &Tape,
        duration: f64,
        seeds: &mut [Option<(DVector<f64>, DVector<f64>)>],
        value: &mut f64,
    ) -> Result<()> {
        let n = self.n_dof();
        // The node where the steps ended on `t` (they end there exactly;
        // the tolerance only absorbs a representation of `t` off by an ulp).
        let eps = node_tolerance(duration);
        let node = |t: f64| -> Result<usize> {
            (0..tape.nodes())
                .find(|&k| (tape.time(k) - t).abs() <= eps)
                .ok_or_else(|| bad("loss", format!("no step ended at t = {t}")))
        };
        for (i, term) in loss.iter_mut().enumerate() {
            let key = |k: &str| format!("loss[{i}].{k}");
            for (j, &t) in term.times().to_vec().iter().enumerate() {
                let k = node(t)?;
                let (q, qd) = (tape.q(k), tape.qd(k));
                let (dq, dv) =
                    seeds[k].get_or_insert_with(|| (DVector::zeros(n), DVector::zeros(n)));
                match term {
                    LossTerm::Position {
                        rod,
                        s,
                        targets,
                        weight,
                        ..
                    } => {
                        self.time = tape.time(k);
                        let r = self.rod_index(rod.as_str())?;
                        let s = s.unwrap_or(self.model().rods()[r].spec.properties.length());
                        let p = self.pose(r, s, q)?.translation;
                        let jac = self.jacobian(r, s, q, Frame::Mixed)?;
                        let target = targets[j];
                        let e = [p.x - target[0], p.y - target[1], p.z - target[2]];
                        *value += 0.5 * *weight * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
                        // ∂p/∂q: the linear rows of the mixed-frame Jacobian.
                        for c in 0..n {
                            dq[c] += *weight
                                * (e[0] * jac[(3, c)] + e[1] * jac[(4, c)] + e[2] * jac[(5, c)]);
                        }
                    }
                    LossTerm::Quadratic {
                        q_weights,
                        qdot_weights,
                        q_ref,
                        ..
                    } => {
                        for c in 0..n {
                            let d = q[c] - q_ref.as_ref().map_or(0.0, |r| r[c]);
                            *value +=
                                0.5 * (q_weights[c] * d * d + qdot_weights[c] * qd[c] * qd[c]);
                            dq[c] += q_weights[c] * d;
                            dv[c] += qdot_weights[c] * qd[c];
                        }
                    }
                    LossTerm::Custom { f, .. } => {
                        let (l, gq, gv) = f(tape.time(k), q, qd)
                            .map_err(|m| bad(key("f"), format!("at t = {t}: {m}")))?;
                        if gq.len() != n || gv.len() != n {
                            return Err(bad(
                                key("f"),
                                format!(
                                    "returned gradients of {} and {} entries, n_dof is {n}",
                                    gq.len(),
                                    gv.len()
                                ),
                            ));
                        }
                        if !l.is_finite() || gq.iter().chain(&gv).any(|v| !v.is_finite()) {
                            return Err(bad(
                                key("f"),
                                format!("returned a non-finite value at t = {t}"),
                            ));
                        }
                        *value += l;
                        for c in 0..n {
                            dq[c] += gq[c];
                            dv[c] += gv[c];
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
