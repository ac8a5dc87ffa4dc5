//! Run settings (`[run]`): mode, integrator, tolerances, steps, output.

use serde::{Serialize, Serializer};
pub use softrod_integrate::{Integrator, UnknownIntegrator};

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

/// Run settings (`[run]`), all defaults filled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Run {
    /// Dynamics or statics (default dynamics).
    pub mode: Mode,
    /// Simulated time, s, > 0 (default [`Run::DEFAULT_DURATION`]).
    pub duration: f64,
    /// Time integrator (default [`Integrator::DEFAULT`]).
    #[serde(serialize_with = "integrator_name")]
    pub integrator: Integrator,
    /// Relative tolerance of adaptive methods, > 0 (default [`Run::DEFAULT_RTOL`]).
    pub rtol: f64,
    /// Absolute tolerance of adaptive methods, > 0 (default
    /// [`Run::default_atol`] of `rtol`: [`Run::DEFAULT_ATOL`] at the default
    /// `rtol`).
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
    /// Adaptive methods (an extension of the format): end the steps on the
    /// output times, so every sample is a step's solution rather than the
    /// dense output between step ends (docs/theory-derivatives.md CD10;
    /// default `false`: at least one step per `output_every`).
    pub steps_to_outputs: bool,
    /// ESDIRK methods on models with loop closures (an extension of the
    /// format): after each accepted step the state is projected onto the
    /// closures (docs/theory.md D121), so loops held by Baumgarte's
    /// stabilization alone cannot drift apart at a loose tolerance (default
    /// `false`).
    pub project_closures: bool,
    /// Bound on the run's energy-balance error relative to its energy scale
    /// (an extension of the format; default [`Run::DEFAULT_ENERGY_TOLERANCE`]):
    /// beyond it the run fails, beyond a tenth of it the summary warns.
    pub energy_tolerance: f64,
    /// Samples per piece in `shape.csv` and the 3-D view (an extension of the
    /// format): points at the fractions `0, 1/m, …, (m−1)/m` of each piece,
    /// exact on its arc, then the tip; 1 gives the N+1 piece boundaries.
    /// `None` (default): the front end chooses enough to look smooth.
    pub shape_points_per_piece: Option<usize>,
    /// Memory budget a run, statics or modes is checked against before it
    /// allocates, GiB (an extension of the format; `None`: the facade's
    /// default, 4 GiB). A scene that needs more is refused up front.
    pub memory_limit_gib: Option<f64>,
}

impl Run {
    /// Largest `shape_points_per_piece`: beyond it the chords are far below
    /// a pixel and only the files grow.
    pub const MAX_SHAPE_POINTS_PER_PIECE: usize = 1000;

    /// Default `duration`, s (the contract's).
    pub const DEFAULT_DURATION: f64 = 1.0;
    /// Default `rtol`: with the default `esdirk`, measured by `softrod
    /// report` on the cantilever and steel-wire scenes (docs/defaults.md):
    /// tip errors 7e-5 m and 4e-5 m, two orders below the spatial (PCS)
    /// error of those scenes, in tens of milliseconds.
    pub const DEFAULT_RTOL: f64 = 1.0e-3;
    /// Default `atol` at the default `rtol` (from the same report).
    pub const DEFAULT_ATOL: f64 = 1.0e-6;

    /// The `atol` of a scene that sets `rtol` but not `atol`: the smaller of
    /// [`Run::DEFAULT_ATOL`] and `rtol`. Strains and strain rates of a
    /// metre-scale rod are O(1) in their units, so an `atol` above `rtol`
    /// would cap the accuracy a user asked for by `rtol` alone; with this
    /// rule the tip error tracks `rtol` (docs/performance.md, "error tracks
    /// rtol").
    pub fn default_atol(rtol: f64) -> f64 {
        Run::DEFAULT_ATOL.min(rtol)
    }
    /// Default `dt`, s (the contract's example value).
    pub const DEFAULT_DT: f64 = 1.0e-4;
    /// Default Gauss points per piece: the model's
    /// ([`softrod_dynamics::Model::DEFAULT_QUADRATURE`], 4: polynomials of
    /// degree 7 exactly, ample for the smooth integrands of a piece).
    pub const DEFAULT_QUADRATURE: usize = softrod_dynamics::Model::DEFAULT_QUADRATURE;
    /// Default `energy_tolerance`: 10 % of the energy in play. A run within
    /// its integrator's tolerance keeps the balance to about `rtol`
    /// (1e-3 by default); an unstable or badly under-resolved one breaks it
    /// by tens of percent or by orders of magnitude (docs/scene-format-extensions.md).
    pub const DEFAULT_ENERGY_TOLERANCE: f64 = 0.1;
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
            steps_to_outputs: false,
            project_closures: false,
            energy_tolerance: Run::DEFAULT_ENERGY_TOLERANCE,
            shape_points_per_piece: None,
            memory_limit_gib: None,
        }
    }
}

/// Serializes an integrator as its scene name.
fn integrator_name<S: Serializer>(i: &Integrator, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(i.name())
}
