//! What a task will allocate, estimated before anything big is allocated,
//! against a memory budget ([`Limits`], 4 GiB unless set): a scene that
//! cannot fit is refused with an input error naming the key and the
//! estimate ([`Error::TooLarge`]), never aborted by
//! the allocator. The budget is a setting, not a reading of the machine's
//! free memory, so that what is refused does not depend on the machine's
//! load; a program that wants the machine's figure sets
//! [`Limits::of_machine`] itself.
//!
//! The estimates count what grows faster than the rod: dense
//! `n_dof × n_dof` matrices (8 bytes per entry) and the output samples. The
//! per-piece and per-quadrature-point buffers are linear in the rod and are
//! allocated when the model is built.

use softrod_integrate::Integrator;

use crate::error::Error;

/// The budget a task is checked against before it allocates
/// ([`Simulation::set_limits`](crate::Simulation::set_limits)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Memory a task may allocate \[bytes\].
    pub memory: u64,
}

/// The default memory budget: 4 GiB, what a small laptop or CI runner has
/// free.
pub const DEFAULT_MEMORY: u64 = 4 << 30;

impl Default for Limits {
    /// [`DEFAULT_MEMORY`].
    fn default() -> Self {
        Self {
            memory: DEFAULT_MEMORY,
        }
    }
}

impl Limits {
    /// What the machine has free now: `MemAvailable` of `/proc/meminfo`
    /// (Linux), else [`DEFAULT_MEMORY`]. It changes with the machine's
    /// load; no part of softrod uses it unless asked.
    pub fn of_machine() -> Self {
        Self {
            memory: available_memory().unwrap_or(DEFAULT_MEMORY),
        }
    }
}

/// `MemAvailable` from `/proc/meminfo` \[bytes\], if readable.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// How many dense `n × n` matrices of `f64` a time integration of a
/// [`RodSystem`](softrod_integrate::RodSystem) with `integrator` may allocate
/// (lazily, but a run must not abort when it does). The explicit methods
/// and generalized-α (structured O(N) solve of `M + aK + bD` only) allocate
/// none; ESDIRK falls back to the dense exact Jacobian when its structured
/// Newton iteration fails: `∂a/∂q`, `∂a/∂q̇`, their LU, and the exact
/// Jacobian's workspace (counted as two); ROS34PW2 holds `M`, `K`, `D` and
/// its LU besides (8); Radau IIA adds a complex LU (two real matrices, 10).
pub fn dense_matrices_of(integrator: Integrator) -> u64 {
    match integrator {
        Integrator::Rk4 | Integrator::Dopri5 | Integrator::GeneralizedAlpha => 0,
        Integrator::Esdirk | Integrator::Esdirk5 => 5,
        Integrator::Rosenbrock => 8,
        Integrator::Radau5 => 10,
    }
}

/// Dense matrices of [`Simulation::statics`](crate::Simulation::statics)
/// on its dense path (small or closed models, or joints without springs;
/// `softrod_dynamics::StaticsSolver::Auto`): `K`, the Newton Jacobian and
/// its factorization, and a copy for the line search. The structured path
/// of large open models has none.
pub const STATICS_DENSE_MATRICES: u64 = 4;

/// Dense matrices of [`Simulation::modes`](crate::Simulation::modes) beyond
/// statics: `K`, the effective stiffness, `M`, its Cholesky factor, the
/// symmetric eigenproblem's matrix and eigenvectors, and the mode shapes.
pub const MODES_DENSE_MATRICES: u64 = 8;

/// Coordinates from which [`Simulation::lowest_modes`](crate::Simulation::lowest_modes)
/// takes the matrix-free Lanczos instead of the dense eigensolver (on open
/// models with a positive definite generalized stiffness): where the two
/// cost the same for the lowest 10 modes of a clamped rod under gravity,
/// statics included (docs/performance.md, "Scaling": 120 coordinates 9–14
/// ms dense against 15 ms, 240 coordinates 58 ms against 31 ms).
pub const LANCZOS_MIN_DOF: usize = 160;

/// Bytes of `count` dense `n × n` matrices of `f64` (saturating).
pub fn dense_bytes(count: u64, n: usize) -> u64 {
    (n as u64)
        .saturating_mul(n as u64)
        .saturating_mul(8)
        .saturating_mul(count)
}

/// `bytes` as a short human number (`2.9 TB`).
pub(crate) fn human_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    for (unit, scale) in [("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)] {
        if b >= scale {
            return format!("{:.1} {unit}", b / scale);
        }
    }
    format!("{bytes} B")
}

/// Refuses a task whose estimate exceeds the limit: `key` is the scene key
/// to change, `what` says what needs the memory.
pub(crate) fn check_memory(
    key: String,
    what: String,
    estimate: u64,
    limits: &Limits,
) -> Result<(), Error> {
    if estimate > limits.memory {
        return Err(Error::TooLarge {
            key,
            what,
            estimate,
            limit: limits.memory,
        });
    }
    Ok(())
}

/// Number of output samples for `duration` seconds every `every` seconds
/// (what [`output_times`](crate::output_times) returns), computed in floating
/// point so that an absurd ratio does not wrap; `None` when it is not a
/// finite count below 2⁶³.
pub fn output_sample_count(duration: f64, every: f64) -> Option<u64> {
    let n = (duration / every + 1e-9).floor() + 2.0;
    (n.is_finite() && n < 9.2e18).then_some(n as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent count: the bytes of a 300 000² matrix of f64 are
    /// 300 000² · 8 = 7.2e11.
    #[test]
    fn dense_bytes_count_and_saturate() {
        assert_eq!(dense_bytes(1, 300_000), 720_000_000_000);
        assert_eq!(dense_bytes(3, usize::MAX), u64::MAX);
        assert_eq!(human_bytes(720_000_000_000), "720.0 GB");
    }

    #[test]
    fn sample_counts_match_output_times() {
        for (d, e) in [(1.0, 0.25), (1.0, 0.3), (1.0, 1e-3), (0.05, 1e-3)] {
            let n = crate::output_times(d, e).len() as u64;
            let est = output_sample_count(d, e).unwrap();
            assert!(est >= n && est <= n + 1, "{d} {e}: {est} vs {n}");
        }
        assert_eq!(output_sample_count(1e300, 1e-9), None);
    }

    #[test]
    fn meminfo_is_read_on_linux() {
        if std::path::Path::new("/proc/meminfo").exists() {
            assert!(available_memory().unwrap() > 0);
        }
    }
}
