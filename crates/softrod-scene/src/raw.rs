//! Raw serde structs mirroring the TOML text, before validation.
//!
//! Every struct denies unknown fields so that a typo (`lenght`) is an error,
//! not a silently ignored key. Optional keys are `Option`s; defaults are filled
//! in by [`crate::validate`]. Keys whose value can take several shapes
//! (`strains`, `tension`) are kept as [`toml::Value`] and decoded by hand so that
//! their errors can name the exact key.

use serde::Deserialize;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScene {
    pub world: Option<RawWorld>,
    #[serde(default)]
    pub rod: Vec<RawRod>,
    #[serde(default)]
    pub body: Vec<crate::robot::RawBody>,
    #[serde(default)]
    pub closure: Vec<crate::validate::closures::RawClosure>,
    #[serde(default)]
    pub cable: Vec<RawCable>,
    #[serde(default)]
    pub load: Vec<RawLoad>,
    pub initial: Option<RawInitial>,
    pub run: Option<RawRun>,
    pub reference: Option<RawReference>,
    #[serde(default)]
    pub obstacle: Vec<crate::validate::contact::RawObstacle>,
    pub contact: Option<crate::validate::contact::RawContact>,
    #[serde(default)]
    pub target: Vec<crate::validate::targets::RawTarget>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawWorld {
    pub gravity: Option<[f64; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRod {
    pub name: String,
    pub length: f64,
    pub pieces: Option<i64>,
    pub piece_lengths: Option<Vec<f64>>,
    pub strains: Option<toml::Value>,
    pub rest_strain: Option<[f64; 6]>,
    pub base: Option<RawBase>,
    pub section: RawSection,
    pub material: RawMaterial,
    pub drag: Option<RawDrag>,
    pub parent: Option<String>,
    pub at: Option<f64>,
    pub joint: Option<crate::robot::RawJoint>,
    /// Radius of the rod's contact surface, overriding the section's.
    pub contact_radius: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBase {
    pub position: Option<[f64; 3]>,
    pub rotation: Option<[[f64; 3]; 3]>,
}

/// All section keys of all shapes; which apply is checked per shape.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSection {
    pub shape: String,
    pub radius: Option<f64>,
    pub radius_base: Option<f64>,
    pub radius_tip: Option<f64>,
    pub inner_radius: Option<f64>,
    pub width: Option<f64>,
    pub height: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMaterial {
    pub density: f64,
    pub young: f64,
    pub poisson: Option<f64>,
    pub shear_modulus: Option<f64>,
    pub viscosity: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDrag {
    pub translational: Option<f64>,
    pub rotational: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCable {
    pub rod: String,
    pub offset: Option<[f64; 2]>,
    pub path: Option<Vec<[f64; 3]>>,
    pub tension: toml::Value,
    pub from: Option<f64>,
    pub to: Option<f64>,
    pub friction: Option<f64>,
    /// Bound of the tension for `softrod inverse` \[N\].
    pub max_tension: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLoad {
    pub rod: Option<String>,
    pub s: Option<f64>,
    /// A load on a rigid body instead of a rod (at the body frame's origin).
    pub body: Option<String>,
    pub force: Option<[f64; 3]>,
    pub moment: Option<[f64; 3]>,
    pub frame: Option<String>,
    /// An unknown of `softrod inverse` (IS13) instead of a given load.
    pub unknown: Option<bool>,
    /// Bound of an unknown load's world components: a number or three.
    pub max_force: Option<toml::Value>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawInitial {
    pub q: Option<Vec<f64>>,
    pub qdot: Option<Vec<f64>>,
    pub trajectory: Option<String>,
    pub row: Option<i64>,
    pub shape: Option<Vec<RawShape>>,
}

/// `[initial] shape = [{ rod, centerline }]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawShape {
    pub rod: String,
    pub centerline: Vec<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRun {
    pub mode: Option<String>,
    pub duration: Option<f64>,
    pub integrator: Option<String>,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    pub dt: Option<f64>,
    pub output_every: Option<f64>,
    pub quadrature: Option<i64>,
    pub error_control: Option<bool>,
    pub linearly_implicit: Option<bool>,
    pub steps_to_outputs: Option<bool>,
    pub project_closures: Option<bool>,
    pub energy_tolerance: Option<f64>,
    pub shape_points_per_piece: Option<i64>,
    pub memory_limit_gib: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawReference {
    pub rod: Option<String>,
    pub tip: Option<[f64; 3]>,
    pub tolerance: Option<f64>,
    pub time: Option<f64>,
    pub frequencies_hz: Option<Vec<f64>>,
    pub note: Option<String>,
}
