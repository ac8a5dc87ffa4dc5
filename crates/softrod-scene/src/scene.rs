//! The validated scene and its run settings.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use serde::Serialize;

use crate::actuation::{Cable, Load};
use crate::error::{SceneError, Warning};
use crate::rod::Rod;

/// The world: uniform gravity.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct World {
    /// Gravitational acceleration in the world frame, m/s² (default zero: no gravity).
    pub gravity: [f64; 3],
}

/// Initial state; `None` means the rest configuration / at rest.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Initial {
    /// Generalized coordinates q (strain deviations from the rest strain),
    /// length [`Scene::n_dof`], rods in order, pieces base to tip, selected
    /// strains in canonical order.
    pub q: Option<Vec<f64>>,
    /// Generalized velocities q̇, same layout as `q`.
    pub qdot: Option<Vec<f64>>,
}

/// What `run.mode` asks for. Commands ignore it when they imply a mode
/// (`softrod statics` always computes the equilibrium).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Time integration (default).
    #[default]
    Dynamics,
    /// Static equilibrium.
    Statics,
}

impl Mode {
    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Dynamics => "dynamics",
            Mode::Statics => "statics",
        }
    }
}

/// Time integrator named by `run.integrator`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum Integrator {
    /// Classical 4th-order Runge–Kutta, fixed step `dt` (`"rk4"`).
    #[serde(rename = "rk4")]
    Rk4,
    /// Dormand–Prince 5(4), adaptive explicit (`"dopri5"`).
    #[serde(rename = "dopri5")]
    Dopri5,
    /// Linearly-implicit Rosenbrock method, adaptive, for stiff problems (`"rosenbrock"`).
    #[serde(rename = "rosenbrock")]
    Rosenbrock,
    /// Radau IIA order 5, adaptive implicit, for stiff problems (`"radau5"`).
    #[serde(rename = "radau5")]
    Radau5,
    /// Generalized-α (Chung–Hulbert), implicit second-order method with
    /// controllable numerical damping (`"generalized-alpha"`).
    #[serde(rename = "generalized-alpha")]
    GeneralizedAlpha,
}

impl Integrator {
    /// Every integrator, in the order error messages list them.
    pub const ALL: [Integrator; 5] = [
        Integrator::Rk4,
        Integrator::Dopri5,
        Integrator::Rosenbrock,
        Integrator::Radau5,
        Integrator::GeneralizedAlpha,
    ];

    /// Default when the scene names none: the stiff, error-controlled method.
    /// `softrod report` (docs/defaults.md) found generalized-α cheaper per
    /// accuracy but without error control (and gaining energy on a fast
    /// whirl), and dopri5 stability-limited or failing on stiff rods.
    pub const DEFAULT: Integrator = Integrator::Rosenbrock;

    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Rk4 => "rk4",
            Integrator::Dopri5 => "dopri5",
            Integrator::Rosenbrock => "rosenbrock",
            Integrator::Radau5 => "radau5",
            Integrator::GeneralizedAlpha => "generalized-alpha",
        }
    }

    /// Whether the method adapts its step to `rtol`/`atol` (otherwise it steps with `dt`).
    pub fn is_adaptive(self) -> bool {
        !matches!(self, Integrator::Rk4 | Integrator::GeneralizedAlpha)
    }

    /// Whether the method is implicit or linearly implicit (suited to stiff problems).
    pub fn is_implicit(self) -> bool {
        !matches!(self, Integrator::Rk4 | Integrator::Dopri5)
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Error of [`Integrator::from_str`]: the name is not one of [`Integrator::ALL`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown integrator {name:?} (valid: rk4, dopri5, rosenbrock, radau5, generalized-alpha)")]
pub struct UnknownIntegrator {
    /// The name given.
    pub name: String,
}

impl FromStr for Integrator {
    type Err = UnknownIntegrator;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Integrator::ALL
            .into_iter()
            .find(|i| i.name() == s)
            .ok_or_else(|| UnknownIntegrator { name: s.to_owned() })
    }
}

/// Run settings (`[run]`), all defaults filled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Run {
    /// Dynamics or statics (default dynamics).
    pub mode: Mode,
    /// Simulated time, s, > 0 (default [`Run::DEFAULT_DURATION`]).
    pub duration: f64,
    /// Time integrator (default [`Integrator::DEFAULT`]).
    pub integrator: Integrator,
    /// Relative tolerance of adaptive methods, > 0 (default [`Run::DEFAULT_RTOL`]).
    pub rtol: f64,
    /// Absolute tolerance of adaptive methods, > 0 (default [`Run::DEFAULT_ATOL`]).
    pub atol: f64,
    /// Step of fixed-step methods, initial step of adaptive ones, s, > 0
    /// (default [`Run::DEFAULT_DT`]).
    pub dt: f64,
    /// Time between output rows, s, > 0 (default `duration / 1000`).
    pub output_every: f64,
    /// Gauss points per piece, ≥ 1 (default [`Run::DEFAULT_QUADRATURE`]).
    pub quadrature: usize,
    /// `generalized-alpha` only (an extension of the format): control the
    /// local error to `rtol`/`atol` and adapt the step, `dt` being the first
    /// step (default `false`: fixed step `dt`).
    pub error_control: bool,
    /// `generalized-alpha` only (an extension of the format): one Newton
    /// iteration per step with the elastic Jacobian, i.e. the linearly
    /// implicit (IMEX) scheme — elastic and viscous forces implicit,
    /// gravity, Coriolis, loads and cables explicit (default `false`: Newton
    /// to convergence).
    pub linearly_implicit: bool,
}

impl Run {
    /// Default `duration`, s (the contract's).
    pub const DEFAULT_DURATION: f64 = 1.0;
    /// Default `rtol`: with the default `rosenbrock`, the best measured by
    /// `softrod report` on the cantilever and steel-wire scenes
    /// (docs/defaults.md): tip errors 3e-7 m and 6e-6 m, far below the
    /// spatial (PCS) error, where rtol 1e-6 was 20–200× slower because
    /// error control then resolves the ringing shear/extension modes.
    pub const DEFAULT_RTOL: f64 = 1.0e-3;
    /// Default `atol` (with [`Run::DEFAULT_RTOL`], from the same report).
    pub const DEFAULT_ATOL: f64 = 1.0e-6;
    /// Default `dt`, s (the contract's example value).
    pub const DEFAULT_DT: f64 = 1.0e-4;
    /// Default Gauss points per piece: 4 integrates polynomials of degree 7
    /// exactly, ample for the smooth integrands of a piece.
    pub const DEFAULT_QUADRATURE: usize = 4;
}

impl Default for Run {
    fn default() -> Self {
        Run {
            mode: Mode::Dynamics,
            duration: Run::DEFAULT_DURATION,
            integrator: Integrator::DEFAULT,
            rtol: Run::DEFAULT_RTOL,
            atol: Run::DEFAULT_ATOL,
            dt: Run::DEFAULT_DT,
            output_every: Run::DEFAULT_DURATION / 1000.0,
            quadrature: Run::DEFAULT_QUADRATURE,
            error_control: false,
            linearly_implicit: false,
        }
    }
}

/// Known answer for the scene (`[reference]`, an extension of the format),
/// used by `softrod report` and tests.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Reference {
    /// Name of the rod whose tip is meant (default the first rod).
    pub rod: String,
    /// Index of that rod in [`Scene::rods`].
    pub rod_index: usize,
    /// Expected tip position in the world frame, m.
    pub tip: Option<[f64; 3]>,
    /// How far from `tip` a result may be and still agree, m, > 0 (`None`: not stated).
    pub tolerance: Option<f64>,
    /// Time at which `tip` holds in a dynamics run, s, in `[0, duration]`
    /// (`None`: the end of the run, or the equilibrium for statics).
    pub time: Option<f64>,
    /// Expected natural frequencies, Hz, lowest first, each > 0.
    pub frequencies_hz: Option<Vec<f64>>,
    /// Where the numbers come from (free text).
    pub note: Option<String>,
}

/// A validated scene: SI units, every default filled in.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scene {
    /// Name of the source used in messages (the path for [`Scene::from_path`]).
    pub source: String,
    /// World settings (gravity).
    pub world: World,
    /// Rods, at least one, with unique names.
    pub rods: Vec<Rod>,
    /// Cables, in file order.
    pub cables: Vec<Cable>,
    /// Point loads, in file order.
    pub loads: Vec<Load>,
    /// Initial state (lengths checked against [`Scene::n_dof`]).
    pub initial: Initial,
    /// Run settings.
    pub run: Run,
    /// Known answer, when the scene states one.
    pub reference: Option<Reference>,
}

impl Scene {
    /// Reads and validates the scene file at `path`. Messages name the file as
    /// `path.display()`.
    ///
    /// Returns the scene and the warnings about suspicious but legal input.
    pub fn from_path(path: &Path) -> Result<(Scene, Vec<Warning>), SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            file: file.clone(),
            source,
        })?;
        Scene::from_str(&text, &file)
    }

    /// Parses and validates scene `text`; `name` stands for the file in messages
    /// and becomes [`Scene::source`].
    ///
    /// Returns the scene and the warnings about suspicious but legal input.
    pub fn from_str(text: &str, name: &str) -> Result<(Scene, Vec<Warning>), SceneError> {
        crate::validate::parse(text, name)
    }

    /// Total number of generalized coordinates: Σ over rods of pieces × selected strains.
    pub fn n_dof(&self) -> usize {
        self.rods.iter().map(Rod::n_dof).sum()
    }

    /// Index in `q` of the first coordinate of rod `i` (`i = rods.len()` gives `n_dof()`).
    ///
    /// # Panics
    /// If `i > rods.len()`.
    pub fn rod_dof_offset(&self, i: usize) -> usize {
        self.rods[..i].iter().map(Rod::n_dof).sum()
    }

    /// Index of the rod called `name`.
    pub fn rod_index(&self, name: &str) -> Option<usize> {
        self.rods.iter().position(|r| r.name == name)
    }

    /// Whether the world has non-zero gravity.
    pub fn has_gravity(&self) -> bool {
        self.world.gravity.iter().any(|&g| g != 0.0)
    }
}
