//! Kinematic state of a rod: one O(N) sweep, then cheap point queries.

use crate::basis::Basis;
use crate::error::KinematicsError;
use crate::rod::{Piece, RodGeometry};
use nalgebra::{DVectorView, Matrix6xX};
use softrod_lie::{
    AdOp, Mat3, Pose, Vec3, Vec6, ad_vec, d_tangent_minus, d_tangent_minus_self,
    exp_and_tangent_minus,
};

/// In which frame a twist or Jacobian is expressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// Body frame of the section at `s` (the model's native frame).
    Body,
    /// Spatial (world) twist `Ad_{g(s)} η`: angular velocity in world axes and
    /// the velocity of the world point that coincides with the origin.
    Spatial,
    /// Mixed: `(R ω, R v)`, world axes at the section centre — the velocity a
    /// position controller wants (`ṗ = R v`).
    Mixed,
}

/// Kinematic quantities of a rod at given `q` (and optionally `q̇`, `q̈`).
///
/// [`RodKinematics::update`] runs the recursion (D7)–(D12)
/// once from base to tip (O(N)) and keeps the piece-tip values; queries at any
/// `s` then cost one local exponential (O(1)) plus, for Jacobians, one
/// backward sweep over the pieces before `s` (O(n_dof)). Buffers are allocated
/// by [`RodKinematics::new`]; `update` and the queries do not allocate.
///
/// Body-frame velocities are `η = (ω, v)`, accelerations `η̇`, both at the
/// section centre in the section frame.
#[derive(Clone, Debug)]
pub struct RodKinematics {
    n_dof: usize,
    /// `g(L_n)` (world) for `n = 0…N` (`g(L_0)` = base).
    tip_pose: Vec<Pose>,
    /// `η(L_n)`, `n = 0…N`.
    tip_vel: Vec<Vec6>,
    /// `η̇(L_n)`, `n = 0…N`.
    tip_acc: Vec<Vec6>,
    /// `g_n(ℓ_n) = exp(ℓ_n ξ̂_n)` per piece, the local transform whose
    /// `Ad⁻¹` is `A_{n,ℓ}` (applied through `Pose::ad_inv_vec` and
    /// `AdOp::mul_ad_inv`, never formed).
    tip_local: Vec<Pose>,
    /// `T₋(ℓ_n)` per piece (`S_n(ℓ_n) = T₋(ℓ_n) B_n`).
    tip_tm: Vec<AdOp>,
    /// `S_n(ℓ_n)` in the columns of piece n (6 × n_dof), for general bases
    /// only: the columns of a selection basis are columns of `tip_tm`, read
    /// from there (see [`Self::tip_s_column`]).
    tip_s: Matrix6xX<f64>,
    /// `Ṡ_n(ℓ_n)` in the columns of piece n (6 × n_dof), when `q̇` was given.
    tip_sdot: Matrix6xX<f64>,
    /// Strain and strain rate per piece.
    strain: Vec<Vec6>,
    strain_rate: Vec<Vec6>,
    /// `q̈_n` applied through `B_n`, per piece (`B_n q̈_n`).
    strain_acc: Vec<Vec6>,
    has_vel: bool,
    has_acc: bool,
}

impl RodKinematics {
    /// Allocates the buffers for `rod` (state: the rest configuration, at rest,
    /// after the first [`update`](Self::update)).
    pub fn new(rod: &RodGeometry) -> Self {
        let n = rod.n_pieces();
        Self {
            n_dof: rod.n_dof(),
            tip_pose: vec![*rod.base(); n + 1],
            tip_vel: vec![Vec6::zeros(); n + 1],
            tip_acc: vec![Vec6::zeros(); n + 1],
            tip_local: vec![Pose::identity(); n],
            tip_tm: vec![AdOp::zeros(); n],
            tip_s: Matrix6xX::zeros(rod.n_dof()),
            tip_sdot: Matrix6xX::zeros(rod.n_dof()),
            strain: vec![Vec6::zeros(); n],
            strain_rate: vec![Vec6::zeros(); n],
            strain_acc: vec![Vec6::zeros(); n],
            has_vel: false,
            has_acc: false,
        }
    }

    /// Sweeps base → tip at `q` (and `q̇`, `q̈` when given; missing ones are
    /// taken as zero for velocity/acceleration queries). Each slice has
    /// `n_dof` entries.
    ///
    /// Per piece (D7)–(D10) at `x = ℓ_n`: `g(L_n) = g(L_{n−1}) exp(ℓ_n ξ̂_n)`,
    /// `η(L_n) = A_ℓ η(L_{n−1}) + S_ℓ q̇_n`,
    /// `η̇(L_n) = A_ℓ η̇(L_{n−1}) + S_ℓ q̈_n + ad_{A_ℓ η(L_{n−1})} S_ℓ q̇_n + Ṡ_ℓ q̇_n`.
    pub fn update(
        &mut self,
        rod: &RodGeometry,
        q: &[f64],
        qd: Option<&[f64]>,
        qdd: Option<&[f64]>,
    ) -> Result<(), KinematicsError> {
        rod.check_coordinates("q", q)?;
        if let Some(v) = qd {
            rod.check_coordinates("qdot", v)?;
        }
        if let Some(v) = qdd {
            rod.check_coordinates("qddot", v)?;
        }
        debug_assert_eq!(self.n_dof, rod.n_dof());
        let had_vel = self.has_vel;
        self.has_vel = qd.is_some();
        self.has_acc = qdd.is_some();
        if had_vel && !self.has_vel {
            // Ṡ_ℓ is only refreshed when q̇ is given; without it q̇ = 0 and so
            // Ṡ = 0 — do not leave a previous update's values behind.
            self.tip_sdot.as_mut_slice().fill(0.0);
        }
        let np = rod.n_pieces();
        self.tip_pose[0] = *rod.base();
        self.tip_vel[0] = Vec6::zeros();
        self.tip_acc[0] = Vec6::zeros();
        // Slices of the piece count up front so the loop indexes without
        // bounds checks.
        let strain = &mut self.strain[..np];
        let strain_rate = &mut self.strain_rate[..np];
        let strain_acc = &mut self.strain_acc[..np];
        let tip_local = &mut self.tip_local[..np];
        let tip_tm = &mut self.tip_tm[..np];
        let tip_pose = &mut self.tip_pose[..np + 1];
        let tip_vel = &mut self.tip_vel[..np + 1];
        let tip_acc = &mut self.tip_acc[..np + 1];
        let tip_s = self.tip_s.as_mut_slice();
        for (n, piece) in rod.pieces().iter().enumerate() {
            let xi = piece.strain(q);
            strain[n] = xi;
            let (g, tm) = exp_and_tangent_minus(piece.length, &xi);
            // Stored at once and used from the buffers below: keeping local
            // copies alive made the compiler move them with memcpy calls.
            tip_tm[n] = tm;
            tip_local[n] = g;
            let (tm, g) = (&tip_tm[n], &tip_local[n]);
            let cols = 6 * piece.dof_offset..6 * (piece.dof_offset + piece.basis.dof());
            if piece.basis.selection().is_none() {
                write_op_columns(tm, &piece.basis, &mut tip_s[cols]);
            }
            tip_pose[n + 1] = tip_pose[n].compose(g);
            if let Some(qd) = qd {
                let dxi = piece.strain_rate(qd);
                let ddxi = qdd.map_or(Vec6::zeros(), |v| piece.strain_rate(v));
                strain_rate[n] = dxi;
                strain_acc[n] = ddxi;
                let dt = d_tangent_minus(piece.length, &xi, &dxi);
                op_times_basis(&dt, &piece.basis, &mut self.tip_sdot, piece.dof_offset);
                let carried = g.ad_inv_vec(&tip_vel[n]);
                let local_v = tm.mul_vec(&dxi);
                tip_vel[n + 1] = carried + local_v;
                tip_acc[n + 1] = g.ad_inv_vec(&tip_acc[n])
                    + tm.mul_vec(&ddxi)
                    + ad_vec(&carried, &local_v)
                    + d_tangent_minus_self(piece.length, &xi, &dxi);
            } else {
                // q̇ = 0: η ≡ 0 and the velocity terms of (D10) vanish.
                strain_rate[n] = Vec6::zeros();
                tip_vel[n + 1] = Vec6::zeros();
                if let Some(qdd) = qdd {
                    let ddxi = piece.strain_rate(qdd);
                    strain_acc[n] = ddxi;
                    tip_acc[n + 1] = g.ad_inv_vec(&tip_acc[n]) + tm.mul_vec(&ddxi);
                } else {
                    strain_acc[n] = Vec6::zeros();
                    tip_acc[n + 1] = Vec6::zeros();
                }
            }
        }
        Ok(())
    }

    /// World pose `g(L_n)` of the piece boundaries, `n = 0…N` (base to tip).
    pub fn boundary_poses(&self) -> &[Pose] {
        &self.tip_pose
    }

    /// Strain `ξ_n` of each piece at the last update.
    pub fn strains(&self) -> &[Vec6] {
        &self.strain
    }

    /// World pose of the tip `g(L)`.
    pub fn tip_pose(&self) -> &Pose {
        self.tip_pose.last().expect("at least one piece")
    }

    /// World pose `g(s)` at any abscissa (D7).
    pub fn pose_at(&self, rod: &RodGeometry, s: f64) -> Result<Pose, KinematicsError> {
        let (n, x) = rod.locate(s)?;
        Ok(self.local(n, x).0)
    }

    /// World poses at several abscissae (any order); `out.len() == s.len()`.
    pub fn poses_at(
        &self,
        rod: &RodGeometry,
        s: &[f64],
        out: &mut [Pose],
    ) -> Result<(), KinematicsError> {
        if out.len() != s.len() {
            return Err(KinematicsError::SizeMismatch {
                what: "output poses",
                got: out.len(),
                expected: s.len(),
            });
        }
        for (o, &si) in out.iter_mut().zip(s) {
            *o = self.pose_at(rod, si)?;
        }
        Ok(())
    }

    /// World poses at the same relative positions `fractions` (each in
    /// `[0, 1]`, e.g. the Gauss nodes) of every piece, piece by piece:
    /// `out[n·m + j] = g(L_{n−1} + fractions[j]·ℓ_n)`, `m = fractions.len()`.
    /// No Jacobian work, no bounds search: the fast path for drawing a rod or
    /// evaluating it at quadrature points.
    pub fn poses_along(
        &self,
        rod: &RodGeometry,
        fractions: &[f64],
        out: &mut [Pose],
    ) -> Result<(), KinematicsError> {
        let m = fractions.len();
        if out.len() != m * rod.n_pieces() {
            return Err(KinematicsError::SizeMismatch {
                what: "output poses",
                got: out.len(),
                expected: m * rod.n_pieces(),
            });
        }
        if let Some(&f) = fractions.iter().find(|f| !(0.0..=1.0).contains(*f)) {
            return Err(KinematicsError::OutOfRod { s: f, length: 1.0 });
        }
        if m == 0 {
            return Ok(());
        }
        for ((piece, (xi, base)), out) in rod
            .pieces()
            .iter()
            .zip(self.strain.iter().zip(&self.tip_pose))
            .zip(out.chunks_exact_mut(m))
        {
            // g(L_{n−1})·exp(xξ̂) with exp from (D4): R₀R(x) = R₀ + x a R₀k̃ +
            // x² b R₀k̃², p = p₀ + x R₀q + x² b R₀(k×q) + x³ c R₀(k×(k×q)).
            // The products with R₀ are formed once per piece, so a point costs
            // three series and a few scaled additions. Column j of M k̃ is
            // M (k × e_j), a difference of two scaled columns of M; applied
            // to R₀ and then to R₀k̃ it gives R₀k̃ and R₀k̃² without products
            // with skew matrices.
            let k = softrod_lie::angular(xi);
            let q = softrod_lie::linear(xi);
            let times_k = |m: [Vec3; 3]| {
                [
                    m[1] * k[2] - m[2] * k[1],
                    m[2] * k[0] - m[0] * k[2],
                    m[0] * k[1] - m[1] * k[0],
                ]
            };
            let r0c = [0, 1, 2].map(|j| base.rotation.column(j).into_owned());
            let rk = times_k(r0c);
            let rkk = times_k(rk);
            // Column-major 3×3 blocks as plain arrays: the per-point update is
            // then 12 independent scaled sums the compiler packs into SIMD.
            let r0: [f64; 9] = base.rotation.as_slice().try_into().expect("3×3");
            let r0k: [f64; 9] = std::array::from_fn(|e| rk[e / 3][e % 3]);
            let r0k2: [f64; 9] = std::array::from_fn(|e| rkk[e / 3][e % 3]);
            // R₀q, R₀(k×q) = (R₀k̃)q, R₀(k×(k×q)) = (R₀k̃²)q from the columns.
            let times_q = |m: &[Vec3; 3]| m[0] * q[0] + m[1] * q[1] + m[2] * q[2];
            let (r0q, r0kq, r0kkq) = (times_q(&r0c), times_q(&rk), times_q(&rkk));
            let p0 = base.translation;
            let theta = k.norm();
            for (o, f) in out.iter_mut().zip(fractions) {
                let x = f * piece.length;
                let [a, b, c] = softrod_lie::series::abc(x * theta);
                let xa = x * a;
                let x2b = x * x * b;
                let x3c = x * x * x * c;
                let r: [f64; 9] = std::array::from_fn(|e| r0[e] + r0k[e] * xa + r0k2[e] * x2b);
                o.rotation = Mat3::from_column_slice(&r);
                o.translation =
                    Vec3::from_fn(|i, _| p0[i] + r0q[i] * x + r0kq[i] * x2b + r0kkq[i] * x3c);
            }
        }
        Ok(())
    }

    /// Pose at local abscissa `x` of piece `n` (no bounds check beyond debug).
    #[inline]
    pub fn pose_in_piece(&self, n: usize, x: f64) -> Pose {
        let g = softrod_lie::exp_twist(x, &self.strain[n]);
        self.tip_pose[n].compose(&g)
    }

    /// `(g(s), A_n(x), T₋(x))` for piece `n`, local abscissa `x`.
    #[inline]
    fn local(&self, n: usize, x: f64) -> (Pose, AdOp, AdOp) {
        let (g, tm) = exp_and_tangent_minus(x, &self.strain[n]);
        (self.tip_pose[n].compose(&g), g.ad_inv(), tm)
    }

    /// Velocity `η(s)` (D8) in the requested frame.
    pub fn velocity_at(
        &self,
        rod: &RodGeometry,
        s: f64,
        frame: Frame,
    ) -> Result<Vec6, KinematicsError> {
        let (n, x) = rod.locate(s)?;
        let (g, a, tm) = self.local(n, x);
        let eta = a.mul_vec(&self.tip_vel[n]) + tm.mul_vec(&self.strain_rate[n]);
        Ok(to_frame(&g, &eta, frame))
    }

    /// Acceleration `η̇(s)` (D10), the time derivative of the body velocity,
    /// in the requested frame. For `Spatial`/`Mixed` this is the rotated body
    /// acceleration `Ad_g η̇` / `(Rω̇, Rv̇)` (not the derivative of the rotated
    /// velocity, which also contains `ω × ·` terms; use [`Self::jacobian_dot_at`]
    /// for those).
    pub fn acceleration_at(
        &self,
        rod: &RodGeometry,
        s: f64,
        frame: Frame,
    ) -> Result<Vec6, KinematicsError> {
        let (n, x) = rod.locate(s)?;
        let (g, a, tm) = self.local(n, x);
        let carried = a.mul_vec(&self.tip_vel[n]);
        let dxi = self.strain_rate[n];
        let local_v = tm.mul_vec(&dxi);
        let acc = a.mul_vec(&self.tip_acc[n])
            + tm.mul_vec(&self.strain_acc[n])
            + ad_vec(&carried, &local_v)
            + d_tangent_minus_self(x, &self.strain[n], &dxi);
        Ok(to_frame(&g, &acc, frame))
    }

    /// Geometric Jacobian `J(s)` (6 × n_dof), `η(s) = J(s) q̇` (D11):
    /// `J = [ A_n(x) A_{n−1,ℓ}⋯A_{i+1,ℓ} S_i(ℓ_i) (i < n) | S_n(x) | 0 ]`,
    /// computed tip-side first so each earlier block costs one `AdOp` product.
    pub fn jacobian_at(
        &self,
        rod: &RodGeometry,
        s: f64,
        frame: Frame,
        out: &mut Matrix6xX<f64>,
    ) -> Result<(), KinematicsError> {
        self.check_out(out)?;
        let (n, x) = rod.locate(s)?;
        let pieces = rod.pieces();
        let p = &pieces[n];
        // Raw column-major storage: column c is entries 6c…6c+5. Every column
        // up to piece n is written below, so only the later ones are zeroed.
        let os = out.as_mut_slice();
        let cols = 6 * p.dof_offset..6 * (p.dof_offset + p.basis.dof());
        os[cols.end..].fill(0.0);
        let (g, a) = if x == p.length {
            // At a piece tip everything is in the sweep's cache (same values
            // `local` would recompute): g(L_n), A_ℓ and the columns S_ℓ.
            self.write_tip_s(p, n, &mut os[cols]);
            (self.tip_pose[n + 1], self.tip_local[n].ad_inv())
        } else {
            let (g, a, tm) = self.local(n, x);
            write_op_columns(&tm, &p.basis, &mut os[cols]);
            (g, a)
        };
        // Earlier pieces, tip-side first.
        let ts = self.tip_s.as_slice();
        let mut carry = a;
        for i in (0..n).rev() {
            let pi = &pieces[i];
            let cols = 6 * pi.dof_offset..6 * (pi.dof_offset + pi.basis.dof());
            if pi.basis.is_identity() {
                // C·S_i = C·T₋ as one block product (3 instead of 6 3×3
                // products for the six columns).
                write_op_columns(&(carry * self.tip_tm[i]), &pi.basis, &mut os[cols]);
            } else if let Some(sel) = pi.basis.selection() {
                carry_times_selected(&carry, &self.tip_tm[i], sel, &mut os[cols]);
            } else {
                for (o, t) in os[cols.clone()]
                    .chunks_exact_mut(6)
                    .zip(ts[cols].chunks_exact(6))
                {
                    o.copy_from_slice(carry.mul_vec(&Vec6::from_column_slice(t)).as_slice());
                }
            }
            carry = carry.mul_ad_inv(&self.tip_local[i]);
        }
        apply_frame(&g, frame, out);
        Ok(())
    }

    /// Time derivative `J̇(s)` (6 × n_dof) of the Jacobian in the requested
    /// frame, so that `η̇ = J q̈ + J̇ q̇` (body frame, D12). Needs `q̇` in the
    /// last update. Blocks `i < n` use
    /// `J̇_i(s) = C_i Ṡ_i(ℓ_i) − ad_{η(s) − C_i η(L_i)} C_i S_i(ℓ_i)` with
    /// `C_i = Ad⁻¹` of the transform from `L_i` to `s`, which equals the
    /// recursion (D12); block `n` is `Ṡ_n(x) = D_ξT₋(x)[B_n q̇_n] B_n` (D9).
    pub fn jacobian_dot_at(
        &self,
        rod: &RodGeometry,
        s: f64,
        frame: Frame,
        out: &mut Matrix6xX<f64>,
    ) -> Result<(), KinematicsError> {
        self.check_out(out)?;
        let (n, x) = rod.locate(s)?;
        let (g, a, tm) = self.local(n, x);
        let xi = self.strain[n];
        let dxi = self.strain_rate[n];
        let eta = a.mul_vec(&self.tip_vel[n]) + tm.mul_vec(&dxi);
        // Frame change: d/dt (X J) = X (J̇ + Y J), X = Ad_g and Y = ad_η
        // (spatial) or X = diag(R, R) and Y = diag(ω̃, ω̃) (mixed).
        let w = softrod_lie::angular(&eta);
        let extra = |jc: &Vec6| match frame {
            Frame::Body => Vec6::zeros(),
            Frame::Spatial => ad_vec(&eta, jc),
            Frame::Mixed => softrod_lie::join(
                &w.cross(&softrod_lie::angular(jc)),
                &w.cross(&softrod_lie::linear(jc)),
            ),
        };
        out.as_mut_slice().fill(0.0);
        let pieces = rod.pieces();
        let p = &pieces[n];
        let dt = d_tangent_minus(x, &xi, &dxi);
        for c in 0..p.basis.dof() {
            let bc = p.basis.column(c);
            let jc = tm.mul_vec(&bc);
            let col = dt.mul_vec(&bc) + extra(&jc);
            out.fixed_view_mut::<6, 1>(0, p.dof_offset + c)
                .copy_from(&to_frame(&g, &col, frame));
        }
        let mut carry = a;
        for i in (0..n).rev() {
            let rel = eta - carry.mul_vec(&self.tip_vel[i + 1]);
            for c in pieces[i].dofs() {
                let sc = self.tip_s_column(&pieces[i], i, c);
                let sdc = self.tip_sdot.fixed_view::<6, 1>(0, c).into_owned();
                let jc = carry.mul_vec(&sc);
                let col = carry.mul_vec(&sdc) - ad_vec(&rel, &jc) + extra(&jc);
                out.fixed_view_mut::<6, 1>(0, c)
                    .copy_from(&to_frame(&g, &col, frame));
            }
            carry = carry.mul_ad_inv(&self.tip_local[i]);
        }
        Ok(())
    }

    /// Column `c` (global index) of `S_i(ℓ_i)`, piece `i`.
    #[inline]
    fn tip_s_column(&self, piece: &Piece, i: usize, c: usize) -> Vec6 {
        match piece.basis.selection() {
            Some(sel) => {
                let t = &self.tip_tm[i];
                let j = sel[c - piece.dof_offset];
                if j < 3 {
                    softrod_lie::join(&t.a.column(j).into_owned(), &t.b.column(j).into_owned())
                } else {
                    softrod_lie::join(&Vec3::zeros(), &t.a.column(j - 3).into_owned())
                }
            }
            None => self.tip_s.fixed_view::<6, 1>(0, c).into_owned(),
        }
    }

    /// Writes `S_n(ℓ_n)` (the columns of piece `n`) column-major into `out`.
    #[inline]
    fn write_tip_s(&self, piece: &Piece, n: usize, out: &mut [f64]) {
        if piece.basis.selection().is_some() {
            write_op_columns(&self.tip_tm[n], &piece.basis, out);
        } else {
            let cols = 6 * piece.dof_offset..6 * (piece.dof_offset + piece.basis.dof());
            out.copy_from_slice(&self.tip_s.as_slice()[cols]);
        }
    }

    fn check_out(&self, out: &Matrix6xX<f64>) -> Result<(), KinematicsError> {
        if out.ncols() != self.n_dof {
            return Err(KinematicsError::SizeMismatch {
                what: "Jacobian columns",
                got: out.ncols(),
                expected: self.n_dof,
            });
        }
        Ok(())
    }

    /// `J(s) q̇` for a velocity vector, checked against [`Self::velocity_at`]
    /// in tests; convenience for callers holding a Jacobian.
    pub fn apply_jacobian(j: &Matrix6xX<f64>, qd: DVectorView<'_, f64>) -> Vec6 {
        (j * qd).fixed_rows::<6>(0).into_owned()
    }
}

/// Writes `op · B` (6 × k) into the columns `offset…offset + k` of `out`.
#[inline]
fn op_times_basis(op: &AdOp, basis: &Basis, out: &mut Matrix6xX<f64>, offset: usize) {
    let cols = 6 * offset..6 * (offset + basis.dof());
    write_op_columns(op, basis, &mut out.as_mut_slice()[cols]);
}

/// Writes `op · B` (6 × k) column-major into `out` (`6k` entries). For a
/// selection basis the columns of `op = [[A, 0], [B, A]]` are copied
/// (`op · e_i` exactly); otherwise one product per basis column.
#[inline]
fn write_op_columns(op: &AdOp, basis: &Basis, out: &mut [f64]) {
    let (a, b) = (op.a.as_slice(), op.b.as_slice());
    if basis.is_identity() {
        // Fixed-size views: constant indices, no bounds checks.
        let out: &mut [f64; 36] = out.try_into().expect("six columns");
        let a: &[f64; 9] = a.try_into().expect("3×3");
        let b: &[f64; 9] = b.try_into().expect("3×3");
        for j in 0..3 {
            for r in 0..3 {
                out[6 * j + r] = a[3 * j + r];
                out[6 * j + 3 + r] = b[3 * j + r];
                out[18 + 6 * j + r] = 0.0;
                out[18 + 6 * j + 3 + r] = a[3 * j + r];
            }
        }
        return;
    }
    match basis.selection() {
        Some(sel) => {
            for (col, &i) in out.chunks_exact_mut(6).zip(sel) {
                if i < 3 {
                    col[..3].copy_from_slice(&a[3 * i..3 * i + 3]);
                    col[3..].copy_from_slice(&b[3 * i..3 * i + 3]);
                } else {
                    col[..3].fill(0.0);
                    col[3..].copy_from_slice(&a[3 * (i - 3)..3 * (i - 2)]);
                }
            }
        }
        None => {
            for (c, col) in out.chunks_exact_mut(6).enumerate() {
                col.copy_from_slice(op.mul_vec(&basis.column(c)).as_slice());
            }
        }
    }
}

/// Writes `C · T · e_i` for the selected components `i` (column-major, 6 per
/// column), using the zero block of `T e_i = (0, A_T e_{i−3})` for `i ≥ 3`:
/// `(A_C t, B_C t + A_C u)` for `T e_i = (t, u)`.
#[inline]
fn carry_times_selected(c: &AdOp, t: &AdOp, sel: &[usize], out: &mut [f64]) {
    for (col, &i) in out.chunks_exact_mut(6).zip(sel) {
        let (w, v) = if i < 3 {
            c.mul_parts(&t.a.column(i).into_owned(), &t.b.column(i).into_owned())
        } else {
            (Vec3::zeros(), c.a * t.a.column(i - 3))
        };
        col[..3].copy_from_slice(w.as_slice());
        col[3..].copy_from_slice(v.as_slice());
    }
}

fn to_frame(g: &Pose, v: &Vec6, frame: Frame) -> Vec6 {
    match frame {
        Frame::Body => *v,
        Frame::Spatial => g.ad().mul_vec(v),
        Frame::Mixed => softrod_lie::join(
            &(g.rotation * softrod_lie::angular(v)),
            &(g.rotation * softrod_lie::linear(v)),
        ),
    }
}

fn apply_frame(g: &Pose, frame: Frame, out: &mut Matrix6xX<f64>) {
    if frame == Frame::Body {
        return;
    }
    for c in 0..out.ncols() {
        let col = out.fixed_view::<6, 1>(0, c).into_owned();
        out.fixed_view_mut::<6, 1>(0, c)
            .copy_from(&to_frame(g, &col, frame));
    }
}
