//! Shared helpers for the mechanics tests (included with `mod common;`).
#![allow(dead_code)]

use nalgebra::{DVector, Matrix6xX};
use softrod_kinematics::{Basis, GaussLegendre, PieceSpec, RodGeometry, Strain, straight};
use softrod_lie::{Mat3, Pose, Vec3, Vec6};
use softrod_mechanics::{Material, PieceMatrices, RodProperties, Section};

/// Small deterministic xorshift generator (no dependency needed).
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    /// Uniform in [-1, 1).
    pub fn sym(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
    pub fn vec(&mut self, n: usize, scale: f64) -> Vec<f64> {
        (0..n).map(|_| scale * self.sym()).collect()
    }
    pub fn vec3(&mut self, scale: f64) -> Vec3 {
        Vec3::new(self.sym(), self.sym(), self.sym()) * scale
    }
}

/// A rotated, translated base pose (not the identity, to exercise `R(s)`).
pub fn oblique_base() -> Pose {
    let r = nalgebra::Rotation3::from_scaled_axis(Vec3::new(0.3, -0.7, 0.4)).into_inner();
    Pose::new(r, Vec3::new(0.1, -0.2, 0.3))
}

pub fn identity_base() -> Pose {
    Pose::new(Mat3::identity(), Vec3::zeros())
}

/// A non-selection (dense) basis of 4 columns.
pub fn dense_basis() -> Basis {
    let mut m = Matrix6xX::zeros(4);
    let cols = [
        [0.2, 1.0, 0.0, 0.0, 0.0, 0.1],
        [0.0, 0.3, 1.0, 0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.1, 0.0, 0.0],
        [0.0, 0.0, 0.2, 1.0, 0.3, 0.0],
    ];
    for (c, col) in cols.iter().enumerate() {
        for r in 0..6 {
            m[(r, c)] = col[r];
        }
    }
    Basis::from_matrix(m).unwrap()
}

/// A three-piece rod of unequal pieces with mixed bases and non-straight rest strains.
pub fn mixed_rod(length: f64, base: Pose) -> RodGeometry {
    let specs = vec![
        PieceSpec {
            length: 0.3 * length,
            basis: Basis::all(),
            rest_strain: straight(),
        },
        PieceSpec {
            length: 0.45 * length,
            basis: Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap(),
            rest_strain: Vec6::new(0.2, -0.5, 0.8, 1.0, 0.0, 0.02),
        },
        PieceSpec {
            length: 0.25 * length,
            basis: dense_basis(),
            rest_strain: Vec6::new(0.0, 1.0, 0.0, 0.98, 0.01, 0.0),
        },
    ];
    RodGeometry::from_pieces(specs, base).unwrap()
}

pub fn soft_material() -> Material {
    Material::builder()
        .density(1000.0)
        .young(1e6)
        .poisson(0.45)
        .viscosity(300.0)
        .build()
        .unwrap()
}

pub fn taper_body(length: f64) -> RodProperties {
    RodProperties::new(
        Section::TaperedCircle {
            radius_base: 0.02,
            radius_tip: 0.008,
        },
        soft_material(),
        length,
    )
    .unwrap()
}

/// Central finite-difference gradient of `f` at `q`.
pub fn fd_gradient(q: &[f64], h: f64, mut f: impl FnMut(&[f64]) -> f64) -> DVector<f64> {
    let mut g = DVector::zeros(q.len());
    let mut x = q.to_vec();
    for i in 0..q.len() {
        let x0 = x[i];
        x[i] = x0 + h;
        let fp = f(&x);
        x[i] = x0 - h;
        let fm = f(&x);
        x[i] = x0;
        g[i] = (fp - fm) / (2.0 * h);
    }
    g
}

/// max|a − b| / max|b|.
pub fn rel_err(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / b.amax()
}

pub fn gauss(n: usize) -> GaussLegendre {
    GaussLegendre::new(n)
}

/// Adds the elastic force `τ_e,n = K_n q_n + e_n` (D13) of every piece into
/// `out` (length n_dof).
pub fn add_elastic_force(
    rod: &RodGeometry,
    matrices: &[PieceMatrices],
    q: &[f64],
    out: &mut [f64],
) {
    for (p, m) in rod.pieces().iter().zip(matrices) {
        let r = p.dofs();
        let qn = &q[r.clone()];
        for (i, o) in out[r].iter_mut().enumerate() {
            let mut acc = m.elastic_offset[i];
            for (j, qj) in qn.iter().enumerate() {
                acc += m.stiffness[(i, j)] * qj;
            }
            *o += acc;
        }
    }
}

/// Adds the viscous force `τ_d,n = D_n q̇_n` (D13) of every piece into `out`.
pub fn add_damping_force(
    rod: &RodGeometry,
    matrices: &[PieceMatrices],
    qd: &[f64],
    out: &mut [f64],
) {
    for (p, m) in rod.pieces().iter().zip(matrices) {
        let r = p.dofs();
        let qn = &qd[r.clone()];
        for (i, o) in out[r].iter_mut().enumerate() {
            let mut acc = 0.0;
            for (j, qj) in qn.iter().enumerate() {
                acc += m.damping[(i, j)] * qj;
            }
            *o += acc;
        }
    }
}
