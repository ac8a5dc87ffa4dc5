//! The validated scene: the library's rods, and what only a scene has
//! (world, initial state, run settings, reference, source file).

use std::path::Path;

use crate::overrides::Override;

use serde::Serialize;
use softrod_dynamics::Rod;
use softrod_mechanics::contact::{ContactSettings, Obstacle};

use crate::error::{SceneError, Warning};
use crate::robot::Robot;
use crate::run::Run;

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
    /// Rods that start from a given centreline (`[initial] shape`): their
    /// strains are fitted to it when the model is built
    /// ([`crate::Built::shape_fits`]).
    pub shape: Vec<InitialShape>,
}

/// A centreline a rod starts from: points `(s, [x, y, z])` in the world
/// frame \[m\], base to tip.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct InitialShape {
    /// Index of the rod in [`Scene::rods`].
    pub rod: usize,
    /// `(s, position)` pairs, `s` strictly increasing in `[0, L]`.
    pub points: Vec<(f64, [f64; 3])>,
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

/// Where the file put each cable and point load of a rod (`cable[j]`,
/// `load[j]`), so that an error the model reports about "cable 1 of rod 0"
/// names the key path of the file.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Origins {
    /// `cables[rod][k]`: file index of the rod's cable `k`.
    pub cables: Vec<Vec<usize>>,
    /// `loads[rod][k]`: file index of the rod's point load `k`.
    pub loads: Vec<Vec<usize>>,
}

/// A validated scene: SI units, every default filled in, the rods as the
/// library's own [`Rod`]s (section, material, strains, cables, point
/// loads and drag inside them).
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Name of the source used in messages (the path for [`Scene::from_path`]).
    pub source: String,
    /// World settings (gravity).
    pub world: World,
    /// Rods, at least one, with unique names, in file order; each holds the
    /// `[[cable]]` and `[[load]]` entries that name it, in file order.
    pub rods: Vec<Rod>,
    /// Bodies, parents and joints (empty for a scene without them).
    pub robot: Robot,
    /// Initial state (lengths checked against [`Scene::n_dof`]).
    pub initial: Initial,
    /// Run settings.
    pub run: Run,
    /// Known answer, when the scene states one.
    pub reference: Option<Reference>,
    /// The `[[obstacle]]` tables in file order, directions normalized
    /// (empty: none).
    pub obstacles: Vec<Obstacle>,
    /// `[contact]` (default: rods touch neither each other nor themselves).
    pub contact: ContactSettings,
    /// The `[[target]]` tables in file order (for `softrod inverse`; empty:
    /// none).
    pub targets: Vec<Target>,
    /// Each `[[cable]]`'s `max_tension` \[N\] in file order (`None`: no
    /// upper bound); [`Scene::max_tensions`] in the model's order.
    pub max_tension: Vec<Option<f64>>,
    /// The `[[load]]` tables with `unknown = true`, in file order: point
    /// forces `softrod inverse` solves for (docs/theory-control.md IS13);
    /// the other commands ignore them.
    pub unknown_loads: Vec<UnknownLoad>,
    pub(crate) origins: Origins,
}

/// A `[[load]]` with `unknown = true`: a world force at a rod section whose
/// value inverse statics finds, each component within `|f_k| ≤ max_force[k]`.
#[derive(Debug, Clone, PartialEq)]
pub struct UnknownLoad {
    /// Index of the `[[load]]` table in the file (`load[j]` in messages).
    pub load: usize,
    /// The rod's index in [`Scene::rods`].
    pub rod: usize,
    /// Arc length of the point of application \[m\], in `[0, L]`.
    pub s: f64,
    /// Bound of each world component \[N\] (`+∞`: none).
    pub max_force: [f64; 3],
}

/// A `[[target]]`: where `softrod inverse` should bring a rod section or
/// a body's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Target {
    /// The rod's or body's name, as written.
    pub element: String,
    /// The rod's index in [`Scene::rods`] (= in the model); 0 and not
    /// read for a body.
    pub rod: usize,
    /// Arc length of the section \[m\] (default the tip); 0 and not read
    /// for a body.
    pub s: f64,
    /// The body's index in the `[[body]]` tables (= in the model's
    /// bodies), when `element` names a body: the target is then its frame.
    pub body: Option<usize>,
    /// Wanted world position \[m\].
    pub position: Option<softrod_lie::Vec3>,
    /// Wanted orientation, section (body frame) to world (made exactly
    /// orthonormal).
    pub rotation: Option<softrod_lie::Mat3>,
    /// Weight of the squared error (default 1).
    pub weight: f64,
}

impl Scene {
    /// The cables' `max_tension` \[N\] in the model's order (rod by rod,
    /// each rod's cables in file order; `+∞` where none is given), with the
    /// file index of each (for `cable[j]` in messages).
    pub fn max_tensions(&self) -> Vec<(usize, f64)> {
        self.origins
            .cables
            .iter()
            .flatten()
            .map(|&j| (j, self.max_tension[j].unwrap_or(f64::INFINITY)))
            .collect()
    }

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
        crate::validate::parse(text, name, &[])
    }

    /// As [`Scene::from_str`] with `overrides` (`KEY=VALUE` settings such as
    /// `run.integrator=esdirk`) applied in order to the parsed document
    /// before validation: each is validated as if written in the file, under
    /// the same key path, and errors and warnings about it name the
    /// `--set` it came from instead of a line.
    pub fn from_str_with(
        text: &str,
        name: &str,
        overrides: &[Override],
    ) -> Result<(Scene, Vec<Warning>), SceneError> {
        crate::validate::parse(text, name, overrides)
    }

    /// As [`Scene::from_path`] with `overrides` ([`Scene::from_str_with`]).
    pub fn from_path_with(
        path: &Path,
        overrides: &[Override],
    ) -> Result<(Scene, Vec<Warning>), SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            file: file.clone(),
            source,
        })?;
        Scene::from_str_with(&text, &file, overrides)
    }

    /// Total number of generalized coordinates: Σ over rods of pieces ×
    /// selected strains, plus the joints' coordinates.
    pub fn n_dof(&self) -> usize {
        self.rods.iter().map(|r| r.geometry.n_dof()).sum::<usize>() + self.robot.joint_dofs()
    }

    /// Index in `q` of the first coordinate of rod `i` (`i = rods.len()` gives `n_dof()`).
    ///
    /// # Panics
    /// If `i > rods.len()`.
    pub fn rod_dof_offset(&self, i: usize) -> usize {
        if self.robot.order.is_empty() || i == self.rods.len() {
            let strains: usize = self.rods[..i].iter().map(|r| r.geometry.n_dof()).sum();
            return if i == self.rods.len() {
                strains + self.robot.joint_dofs()
            } else {
                strains
            };
        }
        self.robot.rod_dof_offset(&self.rods, i)
    }

    /// Index of the rod called `name`.
    pub fn rod_index(&self, name: &str) -> Option<usize> {
        self.rods.iter().position(|r| r.name == name)
    }

    /// Number of cables over all rods (`[[cable]]` entries).
    pub fn n_cables(&self) -> usize {
        self.rods.iter().map(|r| r.cables.len()).sum()
    }

    /// Number of point loads over all rods (`[[load]]` entries).
    pub fn n_point_loads(&self) -> usize {
        self.rods.iter().map(|r| r.point_loads.len()).sum()
    }

    /// Whether the scene has any contact: an obstacle, or rod–rod or self
    /// contact switched on. A scene without pays nothing for contact.
    pub fn has_contact(&self) -> bool {
        !self.obstacles.is_empty() || self.contact.any()
    }

    /// The radius of rod `i`'s contact surface at arc length `s` \[m\]: its
    /// `contact_radius`, or the section's outer radius (half the diagonal of
    /// a rectangle, a taper's local radius).
    ///
    /// # Panics
    /// If `i >= rods.len()`.
    pub fn contact_radius(&self, i: usize, s: f64) -> f64 {
        let rod = &self.rods[i];
        rod.contact_radius.unwrap_or_else(|| {
            softrod_mechanics::contact::contact_radius(
                rod.properties.section(),
                s,
                rod.properties.length(),
            )
        })
    }

    /// Whether the world has non-zero gravity.
    pub fn has_gravity(&self) -> bool {
        self.world.gravity.iter().any(|&g| g != 0.0)
    }
}
