//! The facade's error: every failure a user of [`Simulation`](crate::Simulation)
//! can meet, with the lower crates' errors as sources.

use softrod_dynamics::DynamicsError;
use softrod_integrate::IntegrateError;
use softrod_kinematics::KinematicsError;
use softrod_mechanics::MechanicsError;
use softrod_scene::SceneError;

use crate::limits::human_bytes;

/// Why a call failed. Bad input ([`Error::is_input`]) is distinguished from
/// a simulation that failed on valid input.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene file or text is invalid (names file, line, column, key path).
    #[error(transparent)]
    Scene(Box<SceneError>),
    /// The model or a dynamics evaluation rejected its input.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// A material, section, load or cable description is invalid.
    #[error(transparent)]
    Mechanics(#[from] MechanicsError),
    /// A kinematics query rejected its input (abscissa outside the rod, …).
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
    /// The time integration failed (time, step size and the check that
    /// fired are in the source; [`report`] prints them).
    #[error("simulation failed")]
    Integration(#[source] Box<IntegrateError>),
    /// A run setting is invalid.
    #[error("run.{key}: {message}")]
    InvalidSetting {
        /// The setting (as named in a scene's `[run]`).
        key: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The task would need more memory than its budget: refused before
    /// allocating (see [`Limits`](crate::Limits)).
    #[error(
        "{key}: {what} need about {} but the memory budget is {} (run.memory_limit_gib sets it)",
        human_bytes(*estimate),
        human_bytes(*limit)
    )]
    TooLarge {
        /// The scene key that sets the size (`rod[0].pieces`, `run.output_every`).
        key: String,
        /// What needs the memory.
        what: String,
        /// The estimate \[bytes\].
        estimate: u64,
        /// The limit \[bytes\].
        limit: u64,
    },
    /// The run broke the energy balance `dE/dt = P_nc` by more than
    /// `energy_tolerance` of its energy scale (see
    /// [`EnergyBalance`](crate::EnergyBalance)): the integrator is unstable
    /// or far from resolving the motion, or a drive moved abruptly;
    /// `advice` says which.
    #[error(
        "energy balance violated at t = {t:e} s: error {:.3e} J is {relative:.3e} of the energy \
         scale {:.3e} J, beyond energy_tolerance = {tolerance} (energy change {:.3e} J, work of \
         the non-conservative forces {:.3e} J); {advice}",
        balance.error, balance.scale, balance.change, balance.work
    )]
    EnergyBalance {
        /// Time of the violation \[s\].
        t: f64,
        /// The relative error there.
        relative: f64,
        /// The bound.
        tolerance: f64,
        /// The balance up to `t`.
        balance: Box<crate::EnergyBalance>,
        /// What can help: a smaller step or tolerance, or a stiff method;
        /// or, after a drive that starts or stops abruptly, a smoother drive.
        advice: String,
    },
    /// A piece's stretch `ξ_x` reached zero or below: the rod folded onto
    /// itself, which no rod model describes.
    #[error(
        "stretch not positive at t = {t:e} s: rod {rod:?} piece {piece} has stretch {stretch:e} \
         (the rod folded onto itself; the run is unstable or the loads exceed what the rod can carry)"
    )]
    Stretch {
        /// Time \[s\].
        t: f64,
        /// The rod's name.
        rod: String,
        /// The piece.
        piece: usize,
        /// Its stretch.
        stretch: f64,
    },
    /// An argument has the wrong length.
    #[error("{what} has {got} entries, expected {expected}")]
    SizeMismatch {
        /// Which argument.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The length required.
        expected: usize,
    },
    /// An inverse-statics problem is ill-posed or unsupported
    /// ([`crate::control::solve_actuation`]): a target on no rod or outside
    /// it, a bound below zero, NaN, a closed model.
    #[error("{key}: {message}")]
    Actuation {
        /// The key of the offending input (`target[1].s`,
        /// `cable[0].max_tension`), as a scene names it.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A gradient request is ill-posed or unsupported
    /// ([`Simulation::value_and_gradient`](crate::Simulation::value_and_gradient)):
    /// a parameter or loss naming nothing in the model, NaN in a target or
    /// weight, an integrator without an adjoint, a closed model.
    #[error("{key}: {message}")]
    Gradient {
        /// The offending parameter name (`arm.young`) or loss key
        /// (`loss[0].rod`).
        key: String,
        /// What is wrong.
        message: String,
    },
    /// No rod of that name or index.
    #[error("no rod {0}")]
    UnknownRod(String),
    /// A configuration of a work–precision study could not be built or
    /// its reference could not be run (see [`study`](crate::study)).
    #[error("{0}")]
    Study(String),
    /// An observer ended the run with an error at time `t`.
    #[error("output at t = {t:e} s failed: {message}")]
    Output {
        /// The output time.
        t: f64,
        /// What the observer reported.
        message: String,
    },
}

impl From<SceneError> for Error {
    fn from(e: SceneError) -> Self {
        Error::Scene(Box::new(e))
    }
}

impl From<IntegrateError> for Error {
    fn from(e: IntegrateError) -> Self {
        Error::Integration(Box::new(e))
    }
}

impl Error {
    /// Whether this is bad input (a scene, setting or argument the caller
    /// can fix) rather than a failed simulation.
    pub fn is_input(&self) -> bool {
        match self {
            Error::Scene(_)
            | Error::InvalidSetting { .. }
            | Error::TooLarge { .. }
            | Error::SizeMismatch { .. }
            | Error::UnknownRod(_)
            | Error::Actuation { .. }
            | Error::Gradient { .. }
            | Error::Mechanics(_)
            | Error::Kinematics(_) => true,
            Error::Dynamics(e) => {
                e.rod().is_some()
                    || matches!(
                        e,
                        DynamicsError::NoRods
                            | DynamicsError::NoQuadraturePoints
                            | DynamicsError::GravityNotFinite { .. }
                            | DynamicsError::SizeMismatch { .. }
                            | DynamicsError::NotFinite { .. }
                            | DynamicsError::InvalidShift { .. }
                    )
            }
            Error::Integration(_)
            | Error::Output { .. }
            | Error::Study(_)
            | Error::EnergyBalance { .. }
            | Error::Stretch { .. } => false,
        }
    }
}

impl Error {
    /// The error and its causes, each once: see [`report`].
    pub fn report(&self) -> String {
        report(self)
    }
}

/// An error and its causes, each stated once, as one line for a person:
/// `what failed: why: why that happened`.
///
/// softrod's errors follow one rule so that this walk repeats nothing: a
/// variant either states its cause in its own message or returns it as
/// [`std::error::Error::source`], never both (`#[error(transparent)]`
/// wrappers hand both to the inner error). A scene error
/// ([`SceneError`]) states its cause in the scene's terms (key path,
/// value, allowed range) and keeps the library's error as its source for
/// programs to inspect, so the walk ends there.
pub fn report(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut cur = e;
    while !states_its_cause(cur) {
        let Some(next) = cur.source() else { break };
        text.push_str(": ");
        text.push_str(&next.to_string());
        cur = next;
    }
    text
}

/// Whether `e`'s message already states its causes (see [`report`]): a
/// scene error other than an unreadable file.
fn states_its_cause(e: &(dyn std::error::Error + 'static)) -> bool {
    let scene = match e.downcast_ref::<Error>() {
        Some(Error::Scene(s)) => Some(&**s),
        _ => e.downcast_ref::<SceneError>(),
    };
    scene.is_some_and(|s| !matches!(s, SceneError::Io { .. }))
}

/// `Result` with the facade's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    /// The chain printed once each: a dynamics error names the rod and
    /// what is invalid, its source says why; an error that already prints
    /// its cause does not get it twice.
    #[test]
    fn report_shows_each_cause_once() {
        let e = Error::Dynamics(DynamicsError::RodProperties {
            rod: softrod_dynamics::RodId {
                index: Some(0),
                name: "arm".into(),
            },
            source: MechanicsError::NotPositive {
                quantity: softrod_mechanics::Quantity::RodLength,
                value: -0.5,
            },
        });
        assert_eq!(
            e.report(),
            "rod 0 ('arm'): invalid body: rod length [m] must be positive and finite, got -0.5"
        );
        let e = Error::Integration(Box::new(IntegrateError::System {
            t: 0.5,
            h: 1e-3,
            what: "rhs",
            source: Box::new(DynamicsError::NotFinite {
                what: "qddot[3]".into(),
                value: f64::NAN,
            }),
        }));
        let text = e.report();
        assert_eq!(text.matches("qddot[3] is not finite").count(), 1, "{text}");
    }
}
