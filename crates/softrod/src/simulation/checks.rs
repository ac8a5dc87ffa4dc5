//! What a task is refused for before it allocates: its dense matrices and
//! output samples against the memory limit ([`Error::TooLarge`], naming
//! the scene key that sets the size), and the run settings.

use super::Simulation;
use crate::error::{Error, Result};
use crate::limits::{
    STATICS_DENSE_MATRICES, check_memory, dense_bytes, dense_matrices_of, output_sample_count,
};
use softrod_dynamics::StaticsSolver;

impl Simulation {
    /// Refuses `task` if its `count` dense `n_dof × n_dof` matrices exceed
    /// the memory limit, naming the `pieces` of the rod with the most DoFs.
    pub(super) fn check_dense(&self, task: &str, count: u64) -> Result<()> {
        let n = self.n_dof();
        let estimate = dense_bytes(count, n);
        if estimate <= self.limits.memory {
            return Ok(());
        }
        let (i, r) = self
            .model()
            .rods()
            .iter()
            .enumerate()
            .max_by_key(|(_, r)| r.n_dof())
            .expect("a model with DoFs has rods");
        check_memory(
            format!("rod[{i}].pieces"),
            format!(
                "{task}: {count} dense {n}×{n} matrices (n_dof = {n}; rod {:?} has {} pieces, {} DoF)",
                r.spec.name,
                r.spec.geometry.n_pieces(),
                r.n_dof()
            ),
            estimate,
            &self.limits,
        )
    }

    /// Refuses a run whose output samples (`bytes_per_sample` each) exceed
    /// the memory limit, naming `run.output_every`.
    pub(super) fn check_samples(&self, duration: f64, bytes_per_sample: u64) -> Result<()> {
        let every = self.settings.output_spacing(duration);
        let estimate = output_sample_count(duration, every)
            .map_or(u64::MAX, |n| n.saturating_mul(bytes_per_sample));
        check_memory(
            "run.output_every".into(),
            format!(
                "{duration} s sampled every {every} s: {:.3e} samples of {bytes_per_sample} bytes",
                duration / every
            ),
            estimate,
            &self.limits,
        )
    }

    /// The checks a run of `duration` seconds passes before it starts: the
    /// settings, the output samples and the integrator's dense matrices
    /// against the machine's memory ([`Error::TooLarge`], naming the key).
    /// `softrod check` calls it, so that it rejects what `softrod run`
    /// would.
    pub fn check_run(&self, duration: f64) -> Result<()> {
        if !(duration.is_finite() && duration > 0.0) {
            return Err(Error::InvalidSetting {
                key: "duration",
                message: format!("must be positive and finite, got {duration}"),
            });
        }
        self.settings.validate()?;
        // The output times are kept (8 bytes each).
        self.check_samples(duration, 8)?;
        let (method, _) = self.settings.method_and_options(duration)?;
        self.check_dense(
            &format!("the {} integrator", self.settings.integrator.name()),
            dense_matrices_of(method),
        )
    }

    /// The check [`Simulation::statics`] passes before it starts: its dense
    /// matrices against the machine's memory ([`Error::TooLarge`]).
    pub fn check_statics(&self) -> Result<()> {
        // Large open models take the matrix-free statics: no n × n matrix
        // (its dense retry stops at `DENSE_FALLBACK_MAX_DOF`, 128 MB).
        if StaticsSolver::Auto.is_structured(self.model()) {
            return Ok(());
        }
        self.check_dense("statics", STATICS_DENSE_MATRICES)
    }
}
