//! The rod scenes of the integrator studies (issue 13) and what measuring a
//! run on them needs: tip positions, output times, tip errors, the cache
//! directory of converged references.

use std::path::PathBuf;

use nalgebra::DVector;
use softrod_dynamics::{Model, Rod};
use softrod_kinematics::{Basis, RodGeometry, RodKinematics, Strain, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{Material, RodProperties, Section};

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
    let rod = RodGeometry::uniform(length, pieces, basis, straight(), Pose::identity()).unwrap();
    let mat = Material::with_poisson(density, young, poisson, 0.0).unwrap();
    let body = RodProperties::new(Section::Circle { radius }, mat, length).unwrap();
    Model::new(
        vec![Rod::new("rod", rod, body)],
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
    rod: RodGeometry,
    n: usize,
}

impl TipProbe {
    /// For the first rod of `model`.
    pub fn new(model: &Model) -> Self {
        let rod = model.rods()[0].spec.geometry.clone();
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

/// Output times `k·t1/n`, `k = 0 … n`.
pub fn times(t1: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|k| t1 * k as f64 / n as f64).collect()
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
