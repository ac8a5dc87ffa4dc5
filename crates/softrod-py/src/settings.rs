//! `softrod.Settings`: the facade's run settings from Python keywords.

use std::str::FromStr;

use pyo3::prelude::*;
use softrod::Settings as RustSettings;
use softrod::scene::Integrator;

use crate::errors::{input, to_py};

/// Run settings: integrator, tolerances, steps and output spacing.
///
/// `integrator`: "esdirk" (the default: stiff, adaptive, error controlled,
/// Newton on the exact Jacobian), "esdirk5" (order 5, the same Newton: less
/// work at equal error on most rods, more accurate and dearer at equal
/// `rtol`), "radau5" (Radau IIA order 5, faster on
/// small models at tight tolerances), "rosenbrock" (linearly implicit,
/// adaptive), "dopri5" (explicit adaptive), "rk4" (explicit, fixed `dt`)
/// or "generalized-alpha" (implicit, fixed `dt`; with `error_control` the
/// step adapts to `rtol`/`atol`; with `linearly_implicit` one Newton
/// iteration per step, the fast IMEX scheme). `rtol`, `atol`: tolerances
/// of the adaptive methods; setting `rtol` alone also lowers `atol` to it
/// if `atol` was larger, so that the error tracks `rtol`. `dt` [s]: step of the fixed-step methods, first
/// step of the adaptive ones. `output_every` [s]: spacing of the samples
/// (None: a thousandth of the duration). `steps_to_outputs`: the adaptive
/// methods' steps end on the sample times, so every sample is a step's
/// solution rather than the dense output between steps (at least one step
/// per sample; for quasi-static settles, docs/theory-derivatives.md CD10).
/// `project_closures`: ESDIRK methods on models with loop closures project
/// the state onto the closures after each step (docs/theory.md D121), so a
/// loose run's loops cannot drift apart.
/// Defaults: `softrod.Settings()`,
/// the recommended setting of docs/defaults.md.
#[pyclass(module = "softrod", from_py_object)]
#[derive(Clone)]
pub struct Settings {
    pub(crate) inner: RustSettings,
}

fn integrator(name: &str) -> PyResult<Integrator> {
    Integrator::from_str(name).map_err(|e| input(format!("integrator: {e}")))
}

/// Applies the keyword overrides of `Settings(...)` and `simulate(...)`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn overrides(
    s: &mut RustSettings,
    integrator_name: Option<&str>,
    rtol: Option<f64>,
    atol: Option<f64>,
    dt: Option<f64>,
    output_every: Option<f64>,
    error_control: Option<bool>,
    linearly_implicit: Option<bool>,
    steps_to_outputs: Option<bool>,
    project_closures: Option<bool>,
) -> PyResult<()> {
    if let Some(i) = integrator_name {
        s.integrator = integrator(i)?;
    }
    if let Some(v) = rtol {
        *s = s.clone().with_rtol(v);
    }
    if let Some(v) = atol {
        s.atol = v;
    }
    if let Some(v) = dt {
        s.dt = v;
    }
    if let Some(v) = output_every {
        s.output_every = Some(v);
    }
    if let Some(v) = error_control {
        s.error_control = v;
    }
    if let Some(v) = linearly_implicit {
        s.linearly_implicit = v;
    }
    if let Some(v) = steps_to_outputs {
        s.steps_to_outputs = v;
    }
    if let Some(v) = project_closures {
        s.project_closures = v;
    }
    s.validate().map_err(to_py)
}

#[pymethods]
impl Settings {
    #[new]
    #[pyo3(signature = (integrator = None, rtol = None, atol = None, dt = None, output_every = None,
                        error_control = None, linearly_implicit = None, steps_to_outputs = None,
                        project_closures = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        integrator: Option<&str>,
        rtol: Option<f64>,
        atol: Option<f64>,
        dt: Option<f64>,
        output_every: Option<f64>,
        error_control: Option<bool>,
        linearly_implicit: Option<bool>,
        steps_to_outputs: Option<bool>,
        project_closures: Option<bool>,
    ) -> PyResult<Self> {
        let mut inner = RustSettings {
            output_every: None,
            ..RustSettings::default()
        };
        overrides(
            &mut inner,
            integrator,
            rtol,
            atol,
            dt,
            output_every,
            error_control,
            linearly_implicit,
            steps_to_outputs,
            project_closures,
        )?;
        Ok(Self { inner })
    }

    /// A copy with the given keywords changed, by the rules of
    /// `Settings(...)` (`rtol` alone also lowers a larger `atol`); what
    /// is not named — including the scene's `[run] duration` and energy
    /// tolerance, which `Settings(...)` cannot state and would reset to
    /// their defaults — is kept. Raises `InputError` as `Settings(...)`.
    #[pyo3(signature = (*, integrator = None, rtol = None, atol = None, dt = None,
                        output_every = None, error_control = None, linearly_implicit = None, steps_to_outputs = None,
                        project_closures = None))]
    #[allow(clippy::too_many_arguments)]
    fn replace(
        &self,
        integrator: Option<&str>,
        rtol: Option<f64>,
        atol: Option<f64>,
        dt: Option<f64>,
        output_every: Option<f64>,
        error_control: Option<bool>,
        linearly_implicit: Option<bool>,
        steps_to_outputs: Option<bool>,
        project_closures: Option<bool>,
    ) -> PyResult<Self> {
        let mut inner = self.inner.clone();
        overrides(
            &mut inner,
            integrator,
            rtol,
            atol,
            dt,
            output_every,
            error_control,
            linearly_implicit,
            steps_to_outputs,
            project_closures,
        )?;
        Ok(Self { inner })
    }

    /// The integrator's name.
    #[getter]
    fn integrator(&self) -> &'static str {
        self.inner.integrator.name()
    }

    /// Relative tolerance (adaptive methods).
    #[getter]
    fn rtol(&self) -> f64 {
        self.inner.rtol
    }

    /// Absolute tolerance (adaptive methods; units of q, q̇).
    #[getter]
    fn atol(&self) -> f64 {
        self.inner.atol
    }

    /// Fixed step / first adaptive step [s].
    #[getter]
    fn dt(&self) -> f64 {
        self.inner.dt
    }

    /// Sample spacing [s], or None (a thousandth of the duration).
    #[getter]
    fn output_every(&self) -> Option<f64> {
        self.inner.output_every
    }

    /// Generalized-α only: adapt the step to rtol/atol.
    #[getter]
    fn error_control(&self) -> bool {
        self.inner.error_control
    }

    /// Generalized-α only: one Newton iteration per step (IMEX).
    #[getter]
    fn linearly_implicit(&self) -> bool {
        self.inner.linearly_implicit
    }

    /// Adaptive methods: steps end on the output times, so every sample is
    /// a step's solution (docs/theory-derivatives.md CD10).
    #[getter]
    fn steps_to_outputs(&self) -> bool {
        self.inner.steps_to_outputs
    }

    /// ESDIRK methods on models with loop closures: the state is projected
    /// onto the closures after each step (docs/theory.md D121).
    #[getter]
    fn project_closures(&self) -> bool {
        self.inner.project_closures
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "Settings(integrator={:?}, rtol={:?}, atol={:?}, dt={:?}, output_every={}, \
             error_control={}, linearly_implicit={}, steps_to_outputs={}, project_closures={})",
            s.integrator.name(),
            s.rtol,
            s.atol,
            s.dt,
            s.output_every.map_or("None".into(), |v| format!("{v:?}")),
            if s.error_control { "True" } else { "False" },
            if s.linearly_implicit { "True" } else { "False" },
            if s.steps_to_outputs { "True" } else { "False" },
            if s.project_closures { "True" } else { "False" },
        )
    }
}
