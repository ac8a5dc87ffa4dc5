//! Shared helpers of the integration tests: a small deterministic RNG and an
//! *independent* reference for the rod pose, built only from nalgebra's
//! matrix exponential (Padé scaling-and-squaring) of the 4×4 `x·ξ̂`. Nothing
//! here calls `softrod-lie` or the code under test.
#![allow(dead_code)]

use nalgebra::{DMatrix, Matrix3, Matrix4, Matrix6, Matrix6xX, Vector3, Vector6};
use softrod_kinematics::{Basis, Frame, PieceSpec, RodGeometry, RodKinematics};
use softrod_lie::Pose;

/// SplitMix64: deterministic, dependency-free.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    pub fn vec(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.range(lo, hi)).collect()
    }
    pub fn unit_vec3(&mut self) -> Vector3<f64> {
        loop {
            let v = Vector3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let n = v.norm();
            if n > 0.1 && n <= 1.0 {
                return v / n;
            }
        }
    }
}

pub fn skew3(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// Rotation by `angle` about the unit `axis` (Rodrigues, written out).
pub fn axis_angle(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let k = skew3(axis);
    Matrix3::identity() + k * angle.sin() + k * k * (1.0 - angle.cos())
}

/// A random rigid pose (axis–angle rotation, translation in [-1, 1]³).
pub fn random_pose(rng: &mut Rng) -> Pose {
    let axis = rng.unit_vec3();
    let angle = rng.range(-3.0, 3.0);
    Pose::new(
        axis_angle(&axis, angle),
        Vector3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ),
    )
}

pub fn hat4(xi: &Vector6<f64>) -> Matrix4<f64> {
    let mut m = Matrix4::zeros();
    m.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&skew3(&Vector3::new(xi[0], xi[1], xi[2])));
    m[(0, 3)] = xi[3];
    m[(1, 3)] = xi[4];
    m[(2, 3)] = xi[5];
    m
}

/// vee of a 4×4 matrix assumed close to se(3): skew part of the rotation
/// block, translation column.
pub fn vee4(m: &Matrix4<f64>) -> Vector6<f64> {
    Vector6::new(
        0.5 * (m[(2, 1)] - m[(1, 2)]),
        0.5 * (m[(0, 2)] - m[(2, 0)]),
        0.5 * (m[(1, 0)] - m[(0, 1)]),
        m[(0, 3)],
        m[(1, 3)],
        m[(2, 3)],
    )
}

pub fn homog(p: &Pose) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&p.rotation);
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(&p.translation);
    m
}

/// Inverse of a homogeneous rigid transform (written out).
pub fn homog_inv(m: &Matrix4<f64>) -> Matrix4<f64> {
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let p: Vector3<f64> = m.fixed_view::<3, 1>(0, 3).into_owned();
    let mut out = Matrix4::identity();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&r.transpose());
    out.fixed_view_mut::<3, 1>(0, 3)
        .copy_from(&(-(r.transpose() * p)));
    out
}

/// Dense `Ad_g = [[R, 0], [p̃R, R]]` from a homogeneous matrix.
pub fn ad_mat(m: &Matrix4<f64>) -> Matrix6<f64> {
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let p: Vector3<f64> = m.fixed_view::<3, 1>(0, 3).into_owned();
    let mut a = Matrix6::zeros();
    a.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    a.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    a.fixed_view_mut::<3, 3>(3, 0).copy_from(&(skew3(&p) * r));
    a
}

/// Dense `diag(R, R)`.
pub fn rr_mat(m: &Matrix4<f64>) -> Matrix6<f64> {
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let mut a = Matrix6::zeros();
    a.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    a.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    a
}

/// Independent description of a rod for the reference evaluation.
#[derive(Clone)]
pub struct RefRod {
    pub base: Matrix4<f64>,
    pub lengths: Vec<f64>,
    pub bases: Vec<Matrix6xX<f64>>,
    pub rest: Vec<Vector6<f64>>,
}

impl RefRod {
    pub fn n_dof(&self) -> usize {
        self.bases.iter().map(|b| b.ncols()).sum()
    }

    pub fn length(&self) -> f64 {
        self.lengths.iter().sum()
    }

    /// Piece boundaries L_0 = 0, …, L_N, summed the same way as a rod would.
    pub fn boundaries(&self) -> Vec<f64> {
        let mut out = vec![0.0];
        let mut acc = 0.0;
        for l in &self.lengths {
            acc += l;
            out.push(acc);
        }
        out
    }

    pub fn strains(&self, q: &[f64]) -> Vec<Vector6<f64>> {
        let mut off = 0;
        let mut out = Vec::new();
        for (b, r) in self.bases.iter().zip(&self.rest) {
            let k = b.ncols();
            let qn = nalgebra::DVector::from_column_slice(&q[off..off + k]);
            out.push(b * qn + r);
            off += k;
        }
        out
    }

    /// Reference poses at `(piece, local x)` pairs, by products of `expm`.
    pub fn poses_local(&self, q: &[f64], at: &[(usize, f64)]) -> Vec<Matrix4<f64>> {
        let xi = self.strains(q);
        let mut tips = vec![self.base];
        for (n, l) in self.lengths.iter().enumerate() {
            let next = tips[n] * (hat4(&xi[n]) * *l).exp();
            tips.push(next);
        }
        at.iter()
            .map(|&(n, x)| tips[n] * (hat4(&xi[n]) * x).exp())
            .collect()
    }

    /// The softrod rod with the same description.
    pub fn rod(&self) -> RodGeometry {
        let specs = self
            .lengths
            .iter()
            .zip(&self.bases)
            .zip(&self.rest)
            .map(|((&length, b), r)| PieceSpec {
                length,
                basis: Basis::from_matrix(b.clone()).expect("valid basis"),
                rest_strain: *r,
            })
            .collect();
        let base = Pose::new(
            self.base.fixed_view::<3, 3>(0, 0).into_owned(),
            self.base.fixed_view::<3, 1>(0, 3).into_owned(),
        );
        RodGeometry::from_pieces(specs, base).expect("valid rod")
    }
}

/// Evaluation points `(piece, local x, s)`: for every piece its base `x = 0`
/// (s = L_{n−1}, which the rod attributes to the previous piece except at 0),
/// the three Gauss points of a 3-point rule, and its tip.
pub fn eval_points(r: &RefRod) -> Vec<(usize, f64, f64)> {
    let gauss3 = [
        0.5 - 0.5 * (0.6f64).sqrt(),
        0.5,
        0.5 + 0.5 * (0.6f64).sqrt(),
    ];
    let b = r.boundaries();
    let mut out = vec![(0, 0.0, 0.0)];
    for (n, &l) in r.lengths.iter().enumerate() {
        for g in gauss3 {
            out.push((n, g * l, b[n] + g * l));
        }
        out.push((n, l, b[n + 1]));
    }
    out
}

/// A column-selection basis matrix.
pub fn selection(idx: &[usize]) -> Matrix6xX<f64> {
    let mut m = Matrix6xX::zeros(idx.len());
    for (c, &i) in idx.iter().enumerate() {
        m[(i, c)] = 1.0;
    }
    m
}

pub fn straight() -> Vector6<f64> {
    Vector6::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
}

/// Max abs entry of a dynamic matrix.
pub fn amax(m: &DMatrix<f64>) -> f64 {
    m.iter().fold(0.0f64, |a, v| a.max(v.abs()))
}

pub fn jac(kin: &RodKinematics, rod: &RodGeometry, s: f64, frame: Frame) -> Matrix6xX<f64> {
    let mut j = Matrix6xX::zeros(rod.n_dof());
    kin.jacobian_at(rod, s, frame, &mut j).expect("jacobian");
    j
}

pub fn jac_dot(kin: &RodKinematics, rod: &RodGeometry, s: f64, frame: Frame) -> Matrix6xX<f64> {
    let mut j = Matrix6xX::zeros(rod.n_dof());
    kin.jacobian_dot_at(rod, s, frame, &mut j)
        .expect("jacobian_dot");
    j
}

/// A random configuration of the kind `kind` for `r`: coordinates are drawn
/// so that the *strain* of every piece is of the requested size.
///  - "moderate": curvatures O(1)/L, extension/shear perturbed by ±0.3;
///  - "straight": curvatures ~1e-9 (θ ~ 1e-9), small shear/extension changes;
///  - "curled": |k| such that θ·L ≈ 20.
///
/// The strain is drawn in R⁶ and projected on the basis by least squares, so
/// a reduced basis gets the part of it that it can represent.
pub fn random_q(rng: &mut Rng, r: &RefRod, kind: &str) -> Vec<f64> {
    let l = r.length();
    let mut q = Vec::new();
    for (b, rest) in r.bases.iter().zip(&r.rest) {
        let (kscale, qscale) = match kind {
            "moderate" => (2.0 / l, 0.3),
            "straight" => (1e-9 / l, 1e-3),
            "curled" => (20.0 / l, 0.3),
            _ => panic!("unknown kind"),
        };
        let dir = rng.unit_vec3();
        let k = dir * kscale * rng.range(0.8, 1.2);
        let lin = Vector3::new(
            rng.range(-qscale, qscale),
            rng.range(-qscale, qscale),
            rng.range(-qscale, qscale),
        );
        let target = Vector6::new(k[0], k[1], k[2], 1.0 + lin[0], lin[1], lin[2]) - rest;
        // Least squares B q ≈ target.
        let bd = DMatrix::from_column_slice(6, b.ncols(), b.as_slice());
        let svd = bd.svd(true, true);
        let sol = svd
            .solve(
                &nalgebra::DVector::from_column_slice(target.as_slice()),
                1e-14,
            )
            .expect("solve");
        let mut qn: Vec<f64> = sol.iter().copied().collect();
        // For a pure bending basis the projection may lose curvature; make
        // sure curvature coordinates are of the requested size anyway.
        for (c, v) in qn.iter_mut().enumerate() {
            let col = b.column(c);
            let is_k = col.rows(0, 3).norm() > 0.0 && col.rows(3, 3).norm() == 0.0;
            if is_k && v.abs() < 0.5 * kscale {
                *v = kscale * if rng.unit() < 0.5 { -1.0 } else { 1.0 };
            }
        }
        q.extend(qn);
    }
    q
}
