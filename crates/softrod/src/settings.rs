//! Run settings: which integrator, its tolerances or step, and the output
//! spacing — with the recommended defaults, which live here (not in a
//! front end) so that every user of the library gets the same ones.

use softrod_integrate::{Integrator, Iteration, Options, Recommended, RodJacobian, StepControl};
use softrod_scene::Run;

use crate::error::Error;

/// High-frequency spectral radius of generalized-α as softrod uses it:
/// [`Options::DEFAULT_RHO_INF`] (0.9, which says why).
pub const GENERALIZED_ALPHA_RHO_INF: f64 = Options::DEFAULT_RHO_INF;

/// How [`Simulation::simulate`](crate::Simulation::simulate) integrates.
///
/// [`Settings::default`] is the recommended setting (the one a scene without
/// `[run]` keys gets), chosen by `softrod report` on the shipped examples
/// (docs/defaults.md).
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// The integrator (any of [`Integrator::ALL`]).
    pub integrator: Integrator,
    /// Relative tolerance of the adaptive methods.
    pub rtol: f64,
    /// Absolute tolerance of the adaptive methods (units of `q`, `q̇`).
    pub atol: f64,
    /// Step of the fixed-step methods, first step of the adaptive ones \[s\].
    pub dt: f64,
    /// Time between output samples \[s\]; `None`: a thousandth of the duration.
    pub output_every: Option<f64>,
    /// Generalized-α only: control the local error and adapt the step.
    pub error_control: bool,
    /// Generalized-α only: one Newton iteration per step with the elastic
    /// Jacobian (the linearly implicit, IMEX scheme).
    pub linearly_implicit: bool,
    /// Adaptive methods: end the steps on the output times, so every sample
    /// is a step's solution, not the dense output between step ends
    /// (`softrod_integrate::Options::steps_to_outputs`,
    /// docs/theory-derivatives.md CD10). Costs at least one step per output
    /// interval; pays on quasi-static settles whose steps grow far beyond
    /// the decay of the damped modes. Fixed steps ignore it.
    pub steps_to_outputs: bool,
    /// ESDIRK methods on models with loop closures: project the state onto
    /// the closures after each accepted step
    /// (`softrod_integrate::Options::project_state`, docs/theory.md D121).
    /// For loose, long runs whose loops the stabilization alone lets drift
    /// apart; the other methods ignore it.
    pub project_closures: bool,
    /// The run length a scene asks for (`[run] duration`) \[s\]: what a
    /// front end simulates when the user names no duration.
    pub duration: f64,
    /// Bound on the energy-balance error of a run relative to its energy
    /// scale (see [`EnergyBalance`](crate::EnergyBalance)): beyond it
    /// [`Simulation::simulate_with`](crate::Simulation::simulate_with) fails
    /// with [`Error::EnergyBalance`]; beyond a tenth of it the summary warns.
    /// Default [`Run::DEFAULT_ENERGY_TOLERANCE`] (0.1); `f64::INFINITY`
    /// turns the check off.
    pub energy_tolerance: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self::from_run(&Run::default())
    }
}

impl Settings {
    /// The settings of a scene's `[run]` table (every default filled in by
    /// the scene).
    pub fn from_run(run: &Run) -> Self {
        Self {
            integrator: run.integrator,
            rtol: run.rtol,
            atol: run.atol,
            dt: run.dt,
            output_every: Some(run.output_every),
            error_control: run.error_control,
            linearly_implicit: run.linearly_implicit,
            steps_to_outputs: run.steps_to_outputs,
            project_closures: run.project_closures,
            duration: run.duration,
            energy_tolerance: run.energy_tolerance,
        }
    }

    /// The recommended integrator with tolerances `rtol`, `atol`.
    pub fn tolerances(rtol: f64, atol: f64) -> Self {
        Self {
            rtol,
            atol,
            ..Self::default()
        }
    }

    /// These settings with the relative tolerance `rtol` and an absolute
    /// tolerance no looser than it (`atol ← min(atol, rtol)`, the rule of
    /// [`Run::default_atol`]): what a user who sets only `rtol` means.
    pub fn with_rtol(mut self, rtol: f64) -> Self {
        self.rtol = rtol;
        self.atol = self.atol.min(rtol);
        self
    }

    /// These settings with another integrator.
    pub fn with_integrator(mut self, integrator: Integrator) -> Self {
        self.integrator = integrator;
        self
    }

    /// These settings with samples every `every` seconds.
    pub fn with_output_every(mut self, every: f64) -> Self {
        self.output_every = Some(every);
        self
    }

    /// The Jacobian the implicit methods get:
    /// [`RodJacobian::recommended`] for the integrator (which says why).
    pub fn stiff_jacobian(&self) -> RodJacobian {
        RodJacobian::recommended(self.integrator)
    }

    /// Checks the values (positive and finite).
    pub fn validate(&self) -> Result<(), Error> {
        for (what, v) in [
            ("rtol", self.rtol),
            ("atol", self.atol),
            ("dt", self.dt),
            ("duration", self.duration),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidSetting {
                    key: what,
                    message: format!("must be positive and finite, got {v}"),
                });
            }
        }
        if self.energy_tolerance.is_nan() || self.energy_tolerance <= 0.0 {
            return Err(Error::InvalidSetting {
                key: "energy_tolerance",
                message: format!("must be positive, got {}", self.energy_tolerance),
            });
        }
        if let Some(e) = self.output_every {
            if !(e.is_finite() && e > 0.0) {
                return Err(Error::InvalidSetting {
                    key: "output_every",
                    message: format!("must be positive and finite, got {e}"),
                });
            }
        }
        Ok(())
    }

    /// The integrator and its options for a run of `duration` seconds (the
    /// step budget depends on it).
    pub fn method_and_options(&self, duration: f64) -> Result<(Integrator, Options), Error> {
        self.validate()?;
        let fixed_steps = (duration / self.dt).ceil();
        // Generalized-α steps with the fixed dt unless error control is on;
        // rk4 always does; the other methods are adaptive with dt as their
        // first step.
        let adaptive = self.integrator.is_adaptive()
            || (self.integrator == Integrator::GeneralizedAlpha && self.error_control);
        let mut opts = Options {
            rtol: self.rtol,
            atol: self.atol,
            step: if adaptive {
                StepControl::Adaptive {
                    h0: Some(self.dt.min(duration)),
                }
            } else {
                StepControl::Fixed(self.dt)
            },
            ..Options::default()
        };
        if self.integrator == Integrator::GeneralizedAlpha && self.linearly_implicit {
            // One iteration with W = M⁻¹K, always accepted: the IMEX scheme
            // (ρ∞ < 1, which its explicit remainder needs).
            opts.iteration = Iteration::LinearlyImplicit;
        }
        opts.steps_to_outputs = adaptive && self.steps_to_outputs;
        opts.project_state = self.project_closures && self.integrator.projects_state();
        if adaptive {
            opts.max_steps = Recommended::MAX_STEPS;
        } else {
            if fixed_steps.is_nan() || fixed_steps >= 1e12 {
                return Err(Error::InvalidSetting {
                    key: "dt",
                    message: format!(
                        "{duration} s in steps of {} s is more than 1e12 steps",
                        self.dt
                    ),
                });
            }
            opts.max_steps = 2 * fixed_steps as usize + 100;
        }
        Ok((self.integrator, opts))
    }

    /// The output spacing for a run of `duration` seconds.
    pub fn output_spacing(&self, duration: f64) -> f64 {
        self.output_every.unwrap_or(duration / 1000.0)
    }
}

/// Output times `0, Δ, 2Δ, …` up to `duration`, which is always included.
pub fn output_times(duration: f64, every: f64) -> Vec<f64> {
    let n = (duration / every + 1e-9).floor() as usize;
    let mut t: Vec<f64> = (0..=n).map(|k| (k as f64 * every).min(duration)).collect();
    if duration - t[t.len() - 1] > 1e-9 * duration {
        t.push(duration);
    } else {
        let last = t.len() - 1;
        t[last] = duration;
    }
    t.dedup();
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_times_include_both_ends() {
        assert_eq!(output_times(1.0, 0.25), vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        let t = output_times(1.0, 0.3);
        assert_eq!(t.len(), 5);
        assert_eq!(*t.last().unwrap(), 1.0);
        let t = output_times(1.0, 1e-3);
        assert_eq!(t.len(), 1001);
        assert_eq!(*t.last().unwrap(), 1.0);
    }

    /// Generalized-α: error control gets the adaptive budget and `dt` as
    /// its first step; without it the fixed step keeps a budget of twice
    /// the step count; `linearly_implicit` is `Options::linearly_implicit`.
    #[test]
    fn generalized_alpha_flags_reach_the_options() {
        let base = Settings {
            integrator: Integrator::GeneralizedAlpha,
            dt: 1e-3,
            rtol: 1e-4,
            ..Settings::default()
        };
        let (_, o) = Settings {
            error_control: true,
            ..base.clone()
        }
        .method_and_options(1.0)
        .unwrap();
        assert_eq!(o.step, StepControl::Adaptive { h0: Some(1e-3) });
        assert_eq!(o.rtol, 1e-4);
        assert!(o.max_steps > 1_000_000);
        let (_, o) = base.method_and_options(1.0).unwrap();
        assert_eq!(o.step, StepControl::Fixed(1e-3));
        assert_eq!(o.max_steps, 2 * 1000 + 100);
        assert!(matches!(o.iteration, Iteration::Newton { max_iter, .. } if max_iter > 1));
        let (_, o) = Settings {
            linearly_implicit: true,
            ..base
        }
        .method_and_options(1.0)
        .unwrap();
        assert_eq!(o.iteration, Iteration::LinearlyImplicit);
        assert_eq!(o.step, StepControl::Fixed(1e-3));
    }

    /// `steps_to_outputs` reaches the adaptive methods' options, never the
    /// fixed-step ones'; off by default.
    #[test]
    fn steps_to_outputs_reaches_adaptive_options_only() {
        let (_, o) = Settings::default().method_and_options(1.0).unwrap();
        assert!(!o.steps_to_outputs);
        let on = Settings {
            steps_to_outputs: true,
            ..Settings::default()
        };
        let (_, o) = on.clone().method_and_options(1.0).unwrap();
        assert!(o.steps_to_outputs);
        let (_, o) = on
            .with_integrator(Integrator::Rk4)
            .method_and_options(1.0)
            .unwrap();
        assert!(!o.steps_to_outputs);
    }

    /// `project_closures` reaches ESDIRK's and ESDIRK5's options only
    /// (docs/theory.md D121); off by default.
    #[test]
    fn project_closures_reaches_the_esdirk_methods_only() {
        let (_, o) = Settings::default().method_and_options(1.0).unwrap();
        assert!(!o.project_state);
        let on = Settings {
            project_closures: true,
            ..Settings::default()
        };
        for (integrator, projects) in [
            (Integrator::Esdirk, true),
            (Integrator::Esdirk5, true),
            (Integrator::Radau5, false),
            (Integrator::Dopri5, false),
            (Integrator::Rk4, false),
        ] {
            let (_, o) = on
                .clone()
                .with_integrator(integrator)
                .method_and_options(1.0)
                .unwrap();
            assert_eq!(o.project_state, projects, "{integrator}");
        }
    }

    /// `with_rtol` tightens `atol` to `rtol`, never loosens it.
    #[test]
    fn with_rtol_lowers_a_larger_atol_only() {
        let s = Settings::default().with_rtol(1e-8);
        assert_eq!((s.rtol, s.atol), (1e-8, 1e-8));
        let s = Settings::default().with_rtol(1e-2);
        assert_eq!((s.rtol, s.atol), (1e-2, Run::DEFAULT_ATOL));
        let s = Settings::tolerances(1e-6, 1e-12).with_rtol(1e-4);
        assert_eq!((s.rtol, s.atol), (1e-4, 1e-12));
    }

    /// The scene's rule for an omitted `atol` and the integrate layer's
    /// recommended one are the same rule (two crates that cannot see each
    /// other hold it).
    #[test]
    fn scene_and_recommended_atol_agree() {
        for rtol in [1e-1, 1e-3, 3e-5, 1e-6, 1e-7, 1e-10] {
            assert_eq!(
                Run::default_atol(rtol),
                softrod_integrate::Recommended::atol(rtol),
                "rtol {rtol}"
            );
        }
        assert_eq!(Run::default_atol(Run::DEFAULT_RTOL), Run::DEFAULT_ATOL);
    }

    /// A duration that would need more steps than a machine can count is
    /// refused, not wrapped.
    #[test]
    fn absurd_fixed_step_budgets_are_refused() {
        let s = Settings {
            integrator: Integrator::Rk4,
            dt: 1e-4,
            ..Settings::default()
        };
        let err = s.method_and_options(1e300).unwrap_err();
        assert!(
            matches!(err, Error::InvalidSetting { key: "dt", .. }),
            "{err}"
        );
    }
}
