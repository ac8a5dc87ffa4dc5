//! The rod scenes of the integrator studies (issue 13) and what measuring a
//! run on them needs: tip trajectories, converged references (cached on
//! disk), errors, work and wall time.

use std::path::PathBuf;
use std::time::Instant;

use nalgebra::DVector;
use softrod_dynamics::{Model, RodSpec};
use softrod_integrate::{
    Control, Hooks, Method, Options, RodSystem, Stats, Status, integrate_second_order,
};
use softrod_kinematics::{Basis, Rod, RodKinematics, Strain, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{Material, RodBody, Section};

#[allow(clippy::too_many_arguments)]
fn cantilever(
    length: f64,
    radius: f64,
    density: f64,
    young: f64,
    poisson: f64,
    pieces: usize,
    basis: Basis,
    gauss: usize,
) -> Model {
    let rod = Rod::uniform(length, pieces, basis, straight(), Pose::identity()).unwrap();
    let mat = Material::with_poisson(density, young, poisson, 0.0).unwrap();
    let body = RodBody::new(Section::Circle { radius }, mat, length).unwrap();
    Model::new(
        vec![RodSpec::new("rod", rod, body)],
        Some(Vec3::new(0.0, 0.0, -9.81)),
        gauss,
    )
    .unwrap()
}

/// The planar release of derivations §8(h): L = 0.5 m, r = 0.01 m,
/// ρ = 1000, E = 1e7, ν = 0.5, 8 pieces with strains (ky, qx, qz), 5 Gauss
/// points, undamped, from straight horizontal rest.
pub fn planar_release() -> Model {
    let basis = Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap();
    cantilever(0.5, 0.01, 1000.0, 1e7, 0.5, 8, basis, 5)
}

/// The 3-D release of issue 13: the same rod with all six strains on
/// `pieces` pieces, 4 Gauss points, undamped.
pub fn release_3d(pieces: usize) -> Model {
    cantilever(0.5, 0.01, 1000.0, 1e7, 0.5, pieces, Basis::all(), 4)
}

/// The steel wire of issue 13: E = 200 GPa, ρ = 7800, ν = 0.3, r = 1 mm,
/// L = 1 m, all six strains on `pieces` pieces, 4 Gauss points, undamped.
pub fn steel_wire(pieces: usize) -> Model {
    cantilever(1.0, 1e-3, 7800.0, 2e11, 0.3, pieces, Basis::all(), 4)
}

/// Tip positions (first rod) of first-order states `(q, q̇)`.
pub struct TipProbe {
    kin: RodKinematics,
    rod: Rod,
    n: usize,
}

impl TipProbe {
    /// For the first rod of `model`.
    pub fn new(model: &Model) -> Self {
        let rod = model.rods()[0].spec.rod.clone();
        Self {
            kin: RodKinematics::new(&rod),
            rod,
            n: model.n_dof(),
        }
    }

    /// The tip position at the state `y`.
    pub fn tip(&mut self, y: &DVector<f64>) -> [f64; 3] {
        self.kin
            .update(&self.rod, &y.as_slice()[..self.n], None, None)
            .unwrap();
        let p = self.kin.tip_pose().translation;
        [p.x, p.y, p.z]
    }
}

/// A measured run.
#[derive(Clone, Debug)]
pub struct Measured {
    /// Tip positions at the output times.
    pub tips: Vec<[f64; 3]>,
    /// Work counters.
    pub stats: Stats,
    /// Wall seconds of the integration (outputs included, tip evaluation
    /// not).
    pub wall: f64,
}

/// Output times `k·t1/n`, `k = 0 … n`.
pub fn times(t1: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|k| t1 * k as f64 / n as f64).collect()
}

/// Integrates `model` from rest with `method`, `opts` to the last of
/// `times` (the outputs), stopping as a failure beyond `budget` wall
/// seconds. `setup` may configure the system (e.g. its Jacobian choice).
pub fn measure(
    model: &Model,
    setup: impl FnOnce(&mut RodSystem),
    method: Method,
    opts: &Options,
    times: &[f64],
    budget: f64,
) -> Result<Measured, String> {
    let mut sys = RodSystem::new(model.clone());
    setup(&mut sys);
    let n = model.n_dof();
    let z = DVector::zeros(n);
    let t1 = *times.last().unwrap();
    let opts = Options {
        t_eval: Some(times.to_vec()),
        max_steps: usize::MAX,
        ..opts.clone()
    };
    let start = Instant::now();
    let hooks = Hooks::new().on_step(move |_, _: &mut RodSystem| {
        if start.elapsed().as_secs_f64() > budget {
            Control::Stop
        } else {
            Control::Continue
        }
    });
    let sol = integrate_second_order(&mut sys, method, 0.0, t1, &z, &z, &opts, hooks)
        .map_err(|e| e.to_string())?;
    let wall = start.elapsed().as_secs_f64();
    if sol.status == Status::Stopped {
        return Err(format!(
            "over the budget of {budget} s at t = {:.4} ({} steps)",
            sol.t_final, sol.stats.steps
        ));
    }
    let mut probe = TipProbe::new(model);
    Ok(Measured {
        tips: sol.y.iter().map(|y| probe.tip(y)).collect(),
        stats: sol.stats,
        wall,
    })
}

/// Largest Euclidean distance between matching tips.
pub fn max_error(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

/// Where references are cached: `$SOFTROD_STUDY_DIR`, else
/// `target/integrate-study` of the workspace.
pub fn cache_dir() -> PathBuf {
    std::env::var_os("SOFTROD_STUDY_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/integrate-study")
        })
}

/// The tip trajectory of a converged run at `times`, computed once with
/// `method`, `opts` and cached under `name` (a JSON array of `[x, y, z]`;
/// delete the file to recompute). Returns the tips and, when it was
/// computed now, its work and wall time.
pub fn reference(
    name: &str,
    model: &Model,
    method: Method,
    opts: &Options,
    times: &[f64],
) -> (Vec<[f64; 3]>, Option<Measured>) {
    let dir = cache_dir();
    let path = dir.join(format!("{name}.json"));
    if let Ok(text) = std::fs::read_to_string(&path)
        && let Ok(tips) = serde_json::from_str::<Vec<[f64; 3]>>(&text)
        && tips.len() == times.len()
    {
        return (tips, None);
    }
    let m = measure(model, |_| {}, method, opts, times, f64::INFINITY)
        .unwrap_or_else(|e| panic!("reference {name} failed: {e}"));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(&path, serde_json::to_string(&m.tips).unwrap()).unwrap();
    (m.tips.clone(), Some(m))
}
