//! Shared pieces: errors with exit codes, scene loading, tip and shape poses.

use std::path::{Path, PathBuf};

use softrod::{Error, Simulation};
use softrod_dynamics::Model;
use softrod_kinematics::RodKinematics;
use softrod_lie::Pose;
use softrod_scene::{Scene, Warning};

use crate::outputs::RodSampling;

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

impl From<Error> for CliError {
    fn from(e: Error) -> Self {
        if e.is_input() {
            CliError::Input(e.with_causes())
        } else {
            CliError::Failed(e.with_causes())
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

/// Loads a scene without printing its warnings.
pub fn load_silent(path: &Path) -> Result<Loaded, CliError> {
    let (sim, scene, warnings) = Simulation::from_scene_file(path)?;
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

/// Poses of the rods for given coordinates: one kinematics sweep per rod;
/// for a model with joints or parents, carried into the world by each
/// rod's base frame (`softrod_dynamics::frames`), and the bodies' poses.
pub struct Poser {
    kin: Vec<RodKinematics>,
    /// Articulated models: the dynamics buffers and the world poses of each
    /// rod's piece boundaries.
    robot: Option<(softrod_dynamics::Data, Vec<Vec<Pose>>)>,
}

impl Poser {
    pub fn new(model: &Model) -> Self {
        Self {
            kin: model
                .rods()
                .iter()
                .map(|r| RodKinematics::new(&r.spec.rod))
                .collect(),
            robot: model.is_articulated().then(|| {
                let world = model
                    .rods()
                    .iter()
                    .map(|r| vec![Pose::identity(); r.spec.rod.n_pieces() + 1])
                    .collect();
                (softrod_dynamics::Data::new(model), world)
            }),
        }
    }

    /// Updates every rod at `q` (n_dof of the model), prescribed joints at
    /// time `t` \[s\].
    pub fn update(&mut self, model: &Model, t: f64, q: &[f64]) -> Result<(), CliError> {
        for (k, r) in self.kin.iter_mut().zip(model.rods()) {
            k.update(&r.spec.rod, &q[r.dofs()], None, None)
                .map_err(|e| failed(format!("kinematics of rod '{}': {e}", r.spec.name)))?;
        }
        if let Some((data, world)) = &mut self.robot {
            model.set_time(data, t);
            softrod_dynamics::frames(model, data, q)
                .map_err(|e| failed(format!("frames of the model: {e}")))?;
            for (r, (k, out)) in self.kin.iter().zip(world.iter_mut()).enumerate() {
                let to_world = data.rod_to_world(model, r);
                for (o, p) in out.iter_mut().zip(k.boundary_poses()) {
                    *o = to_world.compose(p);
                }
            }
        }
        Ok(())
    }

    /// Tip pose of rod `i` at the last update.
    pub fn tip(&self, i: usize) -> &Pose {
        match &self.robot {
            Some((_, world)) => world[i].last().expect("N+1 boundaries"),
            None => self.kin[i].tip_pose(),
        }
    }

    /// Strain `ξ_n` of each piece of rod `i` at the last update.
    pub fn strains(&self, i: usize) -> &[softrod_lie::Vec6] {
        self.kin[i].strains()
    }

    /// Exact poses of rod `i` at `sampling` (points of the PCS arcs within
    /// each piece, then the tip) into `out` (`sampling.s.len()` poses).
    pub fn sample(
        &self,
        model: &Model,
        i: usize,
        sampling: &RodSampling,
        out: &mut [Pose],
    ) -> Result<(), CliError> {
        let rod = &model.rods()[i].spec.rod;
        let n = out.len() - 1;
        self.kin[i]
            .poses_along(rod, &sampling.fractions, &mut out[..n])
            .map_err(|e| failed(format!("sampling rod '{}': {e}", model.rods()[i].spec.name)))?;
        if let Some((data, _)) = &self.robot {
            // Articulated models: the rod's own frame carried into the world.
            let to_world = data.rod_to_world(model, i);
            for p in &mut out[..n] {
                *p = to_world.compose(p);
            }
        }
        out[n] = *self.tip(i);
        Ok(())
    }

    /// Sampled centrelines of every rod (world frame, m).
    pub fn centrelines(
        &self,
        model: &Model,
        sampling: &[RodSampling],
    ) -> Result<Vec<Vec<[f64; 3]>>, CliError> {
        let mut out = Vec::with_capacity(sampling.len());
        for (i, sm) in sampling.iter().enumerate() {
            let mut poses = vec![Pose::identity(); sm.s.len()];
            self.sample(model, i, sm, &mut poses)?;
            out.push(poses.iter().map(position).collect());
        }
        Ok(out)
    }

    /// World poses of the model's bodies at the last update (empty without).
    pub fn bodies(&self) -> &[Pose] {
        self.robot.as_ref().map_or(&[], |(d, _)| &d.body_poses)
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
