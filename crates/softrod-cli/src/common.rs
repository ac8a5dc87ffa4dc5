//! Shared pieces: errors with exit codes, scene loading, poses as JSON.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use softrod::dynamics::Model;
use softrod::lie::Pose;
use softrod::record::{RodSampling, WorldPoses};
use softrod::{Error, Simulation};
use softrod_scene::{Override, Scene, Warning};

pub use softrod::record::position;

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

/// The message is the error with each of its causes once
/// ([`softrod::report`]).
impl From<Error> for CliError {
    fn from(e: Error) -> Self {
        if e.is_input() {
            CliError::Input(e.report())
        } else {
            CliError::Failed(e.report())
        }
    }
}

/// A scene read, validated and built into a simulation: what every command
/// starts from, so that `check` rejects exactly what `run` would.
pub struct Loaded {
    pub scene: Scene,
    pub warnings: Vec<Warning>,
    pub sim: Simulation,
}

/// Loads a scene and prints its warnings on stderr (every command but
/// `check`, which lists them in its summary: [`load_silent`]).
pub fn load(path: &Path) -> Result<Loaded, CliError> {
    let l = load_silent(path)?;
    for w in &l.warnings {
        eprintln!("softrod: warning: {}", warning_text(&l.scene.source, w));
    }
    Ok(l)
}

/// The `--set KEY=VALUE` settings of this invocation, applied to every
/// scene it loads (set once by `main`, before any command runs; a process
/// runs one command, so they are the command's arguments).
static OVERRIDES: OnceLock<Vec<Override>> = OnceLock::new();

/// Records the `--set` settings of the command line (once).
pub fn set_overrides(overrides: Vec<Override>) {
    let _ = OVERRIDES.set(overrides);
}

/// Loads a scene without printing its warnings.
pub fn load_silent(path: &Path) -> Result<Loaded, CliError> {
    let overrides = OVERRIDES.get().map_or(&[][..], Vec::as_slice);
    let (scene, warnings) = Scene::from_path_with(path, overrides).map_err(Error::from)?;
    let sim = Simulation::from_scene(&scene)?;
    Ok(Loaded {
        scene,
        warnings,
        sim,
    })
}

/// `FILE:LINE:COL: KEY: message`, the layout of errors (`FILE: KEY:
/// message` when the location is unknown).
pub fn warning_text(source: &str, w: &Warning) -> String {
    if w.at.is_some() {
        format!("{source}:{w}")
    } else {
        format!("{source}: {w}")
    }
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

/// The world poses of `model` at `q` (prescribed joints at `t`), each rod
/// sampled as `softrod run` samples it by default.
pub fn sampled_poses(model: &Model, t: f64, q: &[f64]) -> Result<WorldPoses, CliError> {
    let mut poses = WorldPoses::with_sampling(model, RodSampling::of_model(model, None));
    poses.update(model, t, q)?;
    Ok(poses)
}

/// The sampled centrelines of every rod (world frame, m).
pub fn centrelines(poses: &WorldPoses) -> Vec<Vec<[f64; 3]>> {
    (0..poses.n_rods())
        .map(|r| poses.samples(r).iter().map(position).collect())
        .collect()
}

pub fn rotation_rows(p: &Pose) -> [[f64; 3]; 3] {
    let r = &p.rotation;
    [
        [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
        [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
        [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
    ]
}

/// JSON of a pose: `{ "position": [..], "rotation": [[..],..] }`.
pub fn pose_json(p: &Pose) -> serde_json::Value {
    serde_json::json!({ "position": position(p), "rotation": rotation_rows(p) })
}
