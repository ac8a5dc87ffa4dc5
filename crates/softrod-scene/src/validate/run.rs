//! `[run]`: mode, integrator, tolerances, steps, output, quadrature.

use super::{Ctx, Result};
use crate::raw::RawRun;
use crate::run::{Integrator, Mode, Run};

/// The most Gauss points per piece a scene may ask for. Gauss–Legendre with
/// `n` points integrates polynomials of degree `2n − 1` exactly and
/// converges geometrically on a piece's smooth integrands (the default is
/// 4); beyond 64 points nothing changes in double precision, while the
/// node computation and every evaluation grow with `n` (100 000 points made
/// `check` take minutes).
pub const MAX_QUADRATURE: i64 = 64;

impl Ctx<'_> {
    pub(super) fn run(&mut self, raw: Option<RawRun>) -> Result<Run> {
        let Some(r) = raw else {
            return Ok(Run::default());
        };
        let d = Run::default();
        let mode = match r.mode.as_deref() {
            None => d.mode,
            Some("dynamics") => Mode::Dynamics,
            Some("statics") => Mode::Statics,
            Some(other) => {
                return Err(self
                    .r
                    .unknown_name("run.mode", other, &["dynamics", "statics"]));
            }
        };
        let duration = self.positive("run.duration", r.duration.unwrap_or(d.duration))?;
        let integrator = match r.integrator.as_deref() {
            None => d.integrator,
            Some(name) => name.parse::<Integrator>().map_err(|_| {
                let valid: Vec<&str> = Integrator::ALL.iter().map(|i| i.name()).collect();
                self.r.unknown_name("run.integrator", name, &valid)
            })?,
        };
        let rtol = self.positive("run.rtol", r.rtol.unwrap_or(d.rtol))?;
        let atol = self.positive("run.atol", r.atol.unwrap_or(Run::default_atol(rtol)))?;
        let dt = self.positive("run.dt", r.dt.unwrap_or(d.dt))?;
        let output_every = self.positive(
            "run.output_every",
            r.output_every.unwrap_or(duration / 1000.0),
        )?;
        let quadrature = match r.quadrature {
            None => d.quadrature,
            Some(n) if (1..=MAX_QUADRATURE).contains(&n) => n as usize,
            Some(n) if n < 1 => return Err(self.r.out_of_range("run.quadrature", n, ">= 1")),
            Some(n) => {
                return Err(self.r.out_of_range(
                    "run.quadrature",
                    n,
                    format!("<= {MAX_QUADRATURE}"),
                ));
            }
        };
        let shape_points_per_piece = match r.shape_points_per_piece {
            None => None,
            Some(n) if n >= 1 && n as u64 <= Run::MAX_SHAPE_POINTS_PER_PIECE as u64 => {
                Some(n as usize)
            }
            Some(n) => {
                return Err(self.r.out_of_range(
                    "run.shape_points_per_piece",
                    n,
                    format!("an integer in [1, {}]", Run::MAX_SHAPE_POINTS_PER_PIECE),
                ));
            }
        };
        let error_control = r.error_control.unwrap_or(d.error_control);
        if error_control && integrator != Integrator::GeneralizedAlpha {
            self.warn(
                "run.error_control",
                format!(
                    "error_control only applies to generalized-alpha ({integrator} is {}): ignored",
                    if integrator.is_adaptive() {
                        "adaptive already"
                    } else {
                        "fixed-step"
                    }
                ),
            );
        }
        let linearly_implicit = r.linearly_implicit.unwrap_or(d.linearly_implicit);
        if linearly_implicit && integrator != Integrator::GeneralizedAlpha {
            self.warn(
                "run.linearly_implicit",
                format!(
                    "linearly_implicit only applies to generalized-alpha ({integrator}): ignored"
                ),
            );
        }
        let steps_to_outputs = r.steps_to_outputs.unwrap_or(d.steps_to_outputs);
        let adaptive = integrator.is_adaptive()
            || (integrator == Integrator::GeneralizedAlpha && error_control);
        if steps_to_outputs && !adaptive {
            self.warn(
                "run.steps_to_outputs",
                format!("steps_to_outputs only applies to adaptive steps ({integrator} here has fixed steps): ignored"),
            );
        }
        let project_closures = r.project_closures.unwrap_or(d.project_closures);
        if project_closures && !integrator.projects_state() {
            self.warn(
                "run.project_closures",
                format!("project_closures only applies to esdirk and esdirk5 ({integrator} here): ignored"),
            );
        }
        if r.dt.is_some() && dt > duration {
            self.warn(
                "run.dt",
                format!("dt = {dt} s is longer than the whole run (duration = {duration} s)"),
            );
        }
        if output_every > duration {
            self.warn(
                "run.output_every",
                format!(
                    "output_every = {output_every} s is longer than duration = {duration} s: \
                     only the initial and final states will be written"
                ),
            );
        }
        let energy_tolerance = self.positive(
            "run.energy_tolerance",
            r.energy_tolerance.unwrap_or(d.energy_tolerance),
        )?;
        let memory_limit_gib = match r.memory_limit_gib {
            None => None,
            Some(g) => Some(self.positive("run.memory_limit_gib", g)?),
        };
        Ok(Run {
            mode,
            duration,
            integrator,
            rtol,
            atol,
            dt,
            output_every,
            quadrature,
            error_control,
            linearly_implicit,
            steps_to_outputs,
            project_closures,
            energy_tolerance,
            shape_points_per_piece,
            memory_limit_gib,
        })
    }
}
