//! Shared pieces: errors with exit codes, scene loading, tip and shape poses.

use std::path::{Path, PathBuf};

use softrod_dynamics::Model;
use softrod_kinematics::RodKinematics;
use softrod_lie::Pose;
use softrod_scene::{Built, Scene, Warning};

/// A failure with its exit code.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Bad input (scene file, arguments): exit 2.
    #[error("{0}")]
    Input(String),
    /// The simulation or an output failed: exit 1.
    #[error("{0}")]
    Failed(String),
}

impl CliError {
    pub fn code(&self) -> u8 {
        match self {
            CliError::Input(_) => 2,
            CliError::Failed(_) => 1,
        }
    }
}

pub fn failed(e: impl std::fmt::Display) -> CliError {
    CliError::Failed(e.to_string())
}

/// A scene read, validated and built.
pub struct Loaded {
    pub scene: Scene,
    pub warnings: Vec<Warning>,
    pub built: Built,
}

pub fn load(path: &Path) -> Result<Loaded, CliError> {
    let (scene, warnings) = Scene::from_path(path).map_err(|e| CliError::Input(e.to_string()))?;
    let built = scene.build().map_err(|e| CliError::Input(e.to_string()))?;
    Ok(Loaded {
        scene,
        warnings,
        built,
    })
}

/// `./out/<file stem>` unless given.
pub fn out_dir(scene: &Path, out: Option<PathBuf>) -> PathBuf {
    out.unwrap_or_else(|| {
        let stem = scene
            .file_stem()
            .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("out").join(stem)
    })
}

/// Poses of the rods for given coordinates: one kinematics sweep per rod.
pub struct Poser {
    kin: Vec<RodKinematics>,
}

impl Poser {
    pub fn new(model: &Model) -> Self {
        Self {
            kin: model
                .rods()
                .iter()
                .map(|r| RodKinematics::new(&r.spec.rod))
                .collect(),
        }
    }

    /// Updates every rod at `q` (n_dof of the model).
    pub fn update(&mut self, model: &Model, q: &[f64]) -> Result<(), CliError> {
        for (k, r) in self.kin.iter_mut().zip(model.rods()) {
            k.update(&r.spec.rod, &q[r.dofs()], None, None)
                .map_err(|e| failed(format!("kinematics of rod '{}': {e}", r.spec.name)))?;
        }
        Ok(())
    }

    /// Tip pose of rod `i` at the last update.
    pub fn tip(&self, i: usize) -> &Pose {
        self.kin[i].tip_pose()
    }

    /// Piece-boundary poses of rod `i` (N+1, base to tip).
    pub fn boundaries(&self, i: usize) -> &[Pose] {
        self.kin[i].boundary_poses()
    }
}

/// `(w, x, y, z)` of the rotation, with `w ≥ 0` (one hemisphere, so that
/// time series do not jump between `q` and `−q`).
pub fn quaternion(p: &Pose) -> [f64; 4] {
    let q = p.quaternion();
    let (w, x, y, z) = (q.w, q.i, q.j, q.k);
    if w < 0.0 {
        [-w, -x, -y, -z]
    } else {
        [w, x, y, z]
    }
}

pub fn rotation_rows(p: &Pose) -> [[f64; 3]; 3] {
    let r = &p.rotation;
    [
        [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
        [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
        [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
    ]
}

pub fn position(p: &Pose) -> [f64; 3] {
    [p.translation[0], p.translation[1], p.translation[2]]
}

/// JSON of a pose: `{ "position": [..], "rotation": [[..],..] }`.
pub fn pose_json(p: &Pose) -> serde_json::Value {
    serde_json::json!({ "position": position(p), "rotation": rotation_rows(p) })
}

/// Whether the scene has static loads (gravity, point loads, cables).
pub fn has_static_loads(scene: &Scene) -> bool {
    scene.has_gravity() || scene.n_point_loads() > 0 || scene.n_cables() > 0
}
