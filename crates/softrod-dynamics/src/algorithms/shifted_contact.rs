//! Contact in the O(N) shifted solve (docs/theory-contact.md CT17): the
//! Newton matrix of the implicit integrators `M + a(K + K_c) + b(D + D_c)`
//! with the contact's stiffness `K_c = −∂τ_c/∂q` and damping
//! `D_c = −∂τ_c/∂q̇` in their point form `J_wᵀ (−∂f/∂p) J_w`,
//! `J_wᵀ (−∂f/∂v) J_w` (CT6).
//!
//! - A rod point against an obstacle fixed in the world moves with one
//!   section only: its term `J_pᵀ W J_p` (`W = a K_p + b C_p`, 3×3) is a
//!   point inertia at that section — a 6×6 block `Gᵀ(RᵀWR)G` in the section
//!   frame, `G = [−[r]×, I]` (`r` = 0: the force acts on the centreline) —
//!   which the articulated recursion takes like a quadrature point's
//!   inertia (D20, D62): `𝓜ᵗ += AᵀM_cA`, `𝓤 += AᵀM_cS(x)`,
//!   `𝓓 += S(x)ᵀM_cS(x)`. O(1) per contact, exact.
//! - A contact with two moving sides (rod pairs, self contact, an obstacle
//!   carried by a body) couples two paths of the tree, `J_w = J_a − J_b`:
//!   not a tree inertia. Its rank-3 term `U Uᵀ`, `U = J_wᵀ L`, `W = L Lᵀ`,
//!   joins by the Woodbury identity on top of the tree's factorization
//!   `S₀`: `S⁻¹ = S₀⁻¹ − Z (I + UᵀZ)⁻¹ Zᵀ`, `Z = S₀⁻¹U` — `3m` O(N) solves
//!   and a `3m × 3m` Cholesky per factorization for `m` such contacts,
//!   `O(n·m)` more per solve. Exact too.
//!
//! On a tree model the one-sided blocks are the law's `−∂f/∂p`, `−∂f/∂v`
//! whole (CT26: the articulated recursion in its non-symmetric form, LU
//! of each `D̂`). Elsewhere (a chain, the tree with the geometric terms,
//! the two-sided Woodbury part)
//! `K_p`, `C_p` are the symmetric parts of `−∂f/∂p`, `−∂f/∂v` with their
//! negative eigenvalues dropped: `S` must stay positive definite for the
//! recursion's Cholesky factors, and what is dropped (the obstacle's
//! curvature under a pressing force, `−f_n H`; the skew parts of sliding
//! friction) is of the size of the geometric and gyroscopic terms the
//! shifted matrix already leaves out. The Newton iterations that use it
//! keep the exact residual, so this changes their convergence, never
//! their fixed point.

use super::contact::tree_point_jacobian;
use super::{contact_force, shifted};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::kernels::blocks::Sym6;
use crate::kernels::inertia::s_columns;
use crate::model::Model;
use crate::model::data::{Data, SolveNode};
use softrod_kinematics::Frame;
use softrod_lie::{Mat3, Mat6, PieceMaps, Vec3, Vec6, skew};

/// Where a one-sided contact block acts.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Site {
    /// Rod `rod`, its piece `piece` at the local abscissa `x` \[m\].
    Section { rod: usize, piece: usize, x: f64 },
}

/// One contact point against an obstacle fixed in the world: `K_p`, `C_p`
/// (world, symmetric positive semi-definite) at `site`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointBlock {
    pub site: Site,
    /// `−∂f/∂p`, `−∂f/∂v` as the law gives them (CT26: the tree's
    /// factorization takes them whole) and their positive semi-definite
    /// symmetric parts (CT17: the chain's, and the tree's with the
    /// geometric terms).
    pub k: Mat3,
    pub c: Mat3,
    pub k_psd: Mat3,
    pub c_psd: Mat3,
    /// The contact force on the rod (world) \[N\], for its geometric
    /// stiffness (CT21, `shifted_geometric`).
    pub f: Vec3,
}

/// The contact part of the shifted matrix at a linearization point, and
/// the buffers of its low-rank (two-sided) part. Every buffer grows to the
/// largest contact count seen and is reused.
#[derive(Clone, Debug, Default)]
pub(crate) struct ContactShift {
    pub blocks: Vec<PointBlock>,
    /// Whether some block is not symmetric (CT26): the tree's
    /// factorization then runs its non-symmetric form.
    pub nonsym: bool,
    /// Whether a tree model's one-sided blocks are taken whole (CT26;
    /// `ShiftedSolver::set_contact_whole`, default off).
    pub whole: bool,
    /// Two-sided contacts: `(K, C)` each, and `J_w` (3 rows of `n` each,
    /// contact after contact).
    pub pair_kc: Vec<(Mat3, Mat3)>,
    pub jw: Vec<f64>,
    /// `U` and `Z = S₀⁻¹U` (`n × 3m`, column after column), the factored
    /// capacitance `I + UᵀZ` (`3m × 3m`, row-major lower Cholesky factor),
    /// and a `3m` scratch.
    u: Vec<f64>,
    z: Vec<f64>,
    cap: Vec<f64>,
    t: Vec<f64>,
}

/// The symmetric part of `m` with its negative eigenvalues set to zero.
fn psd_part(m: &Mat3) -> Mat3 {
    let s = (m + m.transpose()) * 0.5;
    if s.iter().all(|v| *v == 0.0) {
        return s;
    }
    let e = s.symmetric_eigen();
    let mut out = Mat3::zeros();
    for i in 0..3 {
        let l = e.eigenvalues[i];
        if l > 0.0 {
            let v = e.eigenvectors.column(i);
            out += v * v.transpose() * l;
        }
    }
    out
}

/// `L` with `L Lᵀ = w` for a symmetric positive semi-definite `w`.
fn psd_root(w: &Mat3) -> Mat3 {
    let e = w.symmetric_eigen();
    let mut l = Mat3::zeros();
    for i in 0..3 {
        let s = e.eigenvalues[i].max(0.0).sqrt();
        l.set_column(i, &(e.eigenvectors.column(i) * s));
    }
    l
}

/// The 6×6 inertia-like block, in a frame of rotation `rot` (world) whose
/// point `r` (frame coordinates) carries the world 3×3 `w`:
/// `Gᵀ (RᵀwR) G`, `G = [−[r]×, I]`.
fn point_block(rot: &Mat3, r: &Vec3, w: &Mat3) -> Mat6 {
    let wl = rot.transpose() * w * rot;
    let rx = skew(r);
    let mut out = Mat6::zeros();
    // G = [−[r]×, I]: Gᵀ W G = [[rx W (−rx)… ]] written out by blocks.
    let wg = -(wl * rx);
    out.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(rx.transpose() * (wl * rx)));
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&wg.transpose());
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&wg);
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&wl);
    out
}

impl ContactShift {
    pub(crate) fn clear(&mut self) {
        self.nonsym = false;
        self.blocks.clear();
        self.pair_kc.clear();
        self.jw.clear();
    }

    /// Whether there is anything to add.
    pub(crate) fn is_empty(&self) -> bool {
        self.blocks.is_empty() && self.pair_kc.is_empty()
    }

    /// Number of two-sided contacts.
    fn m(&self) -> usize {
        self.pair_kc.len()
    }

    /// Evaluates contact with `data` (its friction anchors and stiffness
    /// state) at `(t, q, q̇)` and keeps its linearization (arguments checked
    /// by the caller).
    pub(crate) fn linearize(
        &mut self,
        model: &Model,
        data: &mut Data,
        t: f64,
        q: &[f64],
        qd: &[f64],
    ) {
        self.clear();
        if !contact_force(model, data, Forces::ALL, t, q, Some(qd)) {
            return;
        }
        let n = model.n_dof();
        let mut work = data.contact.take().expect("contact work");
        let mut jrel = std::mem::take(&mut work.jrel);
        let active = std::mem::take(&mut work.active);
        for a in &active {
            let k = psd_part(&-a.dp);
            let c = psd_part(&-a.dv);
            let smp = &model.contact.samples[a.rod][a.sample];
            match model.contact.parents[a.obstacle] {
                None => {
                    let (piece, x) = model.rods[a.rod]
                        .spec
                        .geometry
                        .locate(smp.s)
                        .expect("a sample lies on its rod");
                    // The tree's factorization takes the law's blocks
                    // whole (CT26); a chain's keeps their PSD parts.
                    let (kw, cw) = match (&model.tree, self.whole) {
                        (Some(_), true) => (-a.dp, -a.dv),
                        _ => (k, c),
                    };
                    self.nonsym |= kw != kw.transpose() || cw != cw.transpose();
                    self.blocks.push(PointBlock {
                        site: Site::Section {
                            rod: a.rod,
                            piece,
                            x,
                        },
                        k: kw,
                        c: cw,
                        k_psd: k,
                        c_psd: c,
                        f: a.force,
                    });
                }
                Some(body) => {
                    tree_point_jacobian(model, data, q, a.rod, smp.s, Some(body), &mut jrel);
                    self.push_pair(n, k, c, |r, j| jrel[(r, j)]);
                }
            }
        }
        work.active = active;
        if let Some(pairs) = work.pairs.take() {
            for p in &pairs.active {
                let k = psd_part(&-(p.dw + p.de));
                let c = psd_part(&-p.dv);
                match &model.tree {
                    Some(_) => {
                        tree_point_jacobian(model, data, q, p.a, p.sa, None, &mut jrel);
                        let start = self.jw.len();
                        self.push_pair(n, k, c, |r, j| jrel[(r, j)]);
                        tree_point_jacobian(model, data, q, p.b, p.sb, None, &mut jrel);
                        for r in 0..3 {
                            for j in 0..n {
                                self.jw[start + r * n + j] -= jrel[(r, j)];
                            }
                        }
                    }
                    None => {
                        let start = self.jw.len();
                        self.push_pair(n, k, c, |_, _| 0.0);
                        for (rod, s, sign) in [(p.a, p.sa, 1.0), (p.b, p.sb, -1.0)] {
                            let rm = &model.rods[rod];
                            let jac = &mut work.jac[rod];
                            work.kin[rod]
                                .jacobian_at(&rm.spec.geometry, s, Frame::Mixed, jac)
                                .expect("on the rod");
                            for r in 0..3 {
                                for c in 0..rm.n_dof() {
                                    self.jw[start + r * n + rm.dof_offset + c] +=
                                        sign * jac[(3 + r, c)];
                                }
                            }
                        }
                    }
                }
            }
            work.pairs = Some(pairs);
        }
        work.jrel = jrel;
        data.contact = Some(work);
    }

    fn push_pair(&mut self, n: usize, k: Mat3, c: Mat3, jw: impl Fn(usize, usize) -> f64) {
        self.pair_kc.push((k, c));
        for r in 0..3 {
            for j in 0..n {
                self.jw.push(jw(r, j));
            }
        }
    }

    /// Adds the one-sided blocks `a K_p + b C_p` to the chain's per-piece
    /// sums of `data` (after its composite outward sweep at `q`).
    pub(crate) fn add_chain(&self, model: &Model, data: &mut Data, q: &[f64], a: f64, b: f64) {
        let mut scols = [Vec6::zeros(); 6];
        for blk in &self.blocks {
            let Site::Section { rod, piece, x } = blk.site;
            let rm = &model.rods[rod];
            let pc = &rm.spec.geometry.pieces()[piece];
            let xi = pc.strain(&q[rm.dofs()]);
            let (gl, tm) = PieceMaps::new(&xi, None).exp_and_tangent_minus(x);
            let w = &mut data.pieces[rod][piece];
            let rot = w.base_pose.compose(&gl).rotation;
            let mc = point_block(&rot, &Vec3::zeros(), &(blk.k_psd * a + blk.c_psd * b));
            let am = gl.ad_inv().to_mat6();
            let k = s_columns(&tm, &pc.basis, &mut scols);
            let mut s = Mat6::zeros();
            for (c, col) in scols.iter().enumerate().take(k) {
                s.set_column(c, col);
            }
            let mca = mc * am;
            w.mt += Sym6::from_mat6(&(am.transpose() * mca));
            w.ut += mca.transpose() * s;
            w.dt += s.transpose() * (mc * s);
        }
    }

    /// The same on the tree's nodes (after its composite outward sweep),
    /// whole (CT26) when `whole`, else their positive semi-definite
    /// symmetric parts: `𝓜ᵗ += AᵀM_cA`, `𝓤 += AᵀM_cS`, `𝓤_L += AᵀM_cᵀS`,
    /// `𝓓 += SᵀM_cS`.
    pub(crate) fn add_tree(
        &self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        a: f64,
        b: f64,
        whole: bool,
    ) {
        let tree = model.tree.as_ref().expect("a tree model");
        for blk in &self.blocks {
            let Site::Section { rod, piece, x } = blk.site;
            let rm = &model.rods[rod];
            let pc = &rm.spec.geometry.pieces()[piece];
            let xi = pc.strain(&q[rm.dofs()]);
            let (gl, tm) = PieceMaps::new(&xi, None).exp_and_tangent_minus(x);
            let i = tree.rod_nodes[rod][piece];
            let node = &tree.nodes[i];
            let w = &mut data.nodes[i];
            let rot = w.base_world.compose(&gl).rotation;
            let pw = if whole {
                blk.k * a + blk.c * b
            } else {
                blk.k_psd * a + blk.c_psd * b
            };
            let mc = point_block(&rot, &Vec3::zeros(), &pw);
            let am = gl.ad_inv().to_mat6();
            let s = tm.to_mat6() * node.bpad;
            if whole {
                let amt = am.transpose();
                w.mt += amt * (mc * am);
                w.ut += amt * (mc * s);
                w.ul += amt * (mc.transpose() * s);
                w.dt += s.transpose() * (mc * s);
            } else {
                let mca = mc * am;
                w.mt += am.transpose() * mca;
                w.ut += mca.transpose() * s;
                w.dt += s.transpose() * (mc * s);
            }
        }
    }

    /// After `S₀` is factored in `data`: the Woodbury terms of the
    /// two-sided contacts at the shifts `a`, `b` (`U`, `Z = S₀⁻¹U`, the
    /// Cholesky factor of `I + UᵀZ`).
    pub(crate) fn factor_low_rank(
        &mut self,
        model: &Model,
        data: &Data,
        scratch: &mut [SolveNode],
        a: f64,
        b: f64,
    ) {
        let (n, m3) = (model.n_dof(), 3 * self.m());
        if m3 == 0 {
            return;
        }
        self.u.clear();
        self.u.resize(n * m3, 0.0);
        for (c, (k, cc)) in self.pair_kc.iter().enumerate() {
            let l = psd_root(&(k * a + cc * b));
            let jw = &self.jw[3 * c * n..3 * (c + 1) * n];
            for col in 0..3 {
                let u = &mut self.u[(3 * c + col) * n..(3 * c + col + 1) * n];
                for r in 0..3 {
                    let lr = l[(r, col)];
                    if lr != 0.0 {
                        for (uj, jj) in u.iter_mut().zip(&jw[r * n..(r + 1) * n]) {
                            *uj += jj * lr;
                        }
                    }
                }
            }
        }
        self.z.clear();
        self.z.extend_from_slice(&self.u);
        for col in self.z.chunks_mut(n) {
            solve_s0(model, data, scratch, col);
        }
        self.cap.clear();
        self.cap.resize(m3 * m3, 0.0);
        for i in 0..m3 {
            let ui = &self.u[i * n..(i + 1) * n];
            for j in 0..=i {
                let zj = &self.z[j * n..(j + 1) * n];
                let v: f64 = ui.iter().zip(zj).map(|(x, y)| x * y).sum();
                self.cap[i * m3 + j] = v + if i == j { 1.0 } else { 0.0 };
            }
        }
        // Cholesky of the SPD capacitance (eigenvalues ≥ 1), lower, in place.
        for j in 0..m3 {
            let mut d = self.cap[j * m3 + j];
            for p in 0..j {
                d -= self.cap[j * m3 + p] * self.cap[j * m3 + p];
            }
            let d = d.max(1.0e-300).sqrt();
            self.cap[j * m3 + j] = d;
            for i in j + 1..m3 {
                let mut v = self.cap[i * m3 + j];
                for p in 0..j {
                    v -= self.cap[i * m3 + p] * self.cap[j * m3 + p];
                }
                self.cap[i * m3 + j] = v / d;
            }
        }
        self.t.clear();
        self.t.resize(m3, 0.0);
    }

    /// `x ← x − Z (I + UᵀZ)⁻¹ Uᵀ x` for `x = S₀⁻¹ b` already solved: the
    /// Woodbury correction of the two-sided contacts.
    pub(crate) fn solve_low_rank(&mut self, n: usize, x: &mut [f64]) {
        let m3 = 3 * self.m();
        if m3 == 0 {
            return;
        }
        for i in 0..m3 {
            let ui = &self.u[i * n..(i + 1) * n];
            self.t[i] = ui.iter().zip(x.iter()).map(|(a, b)| a * b).sum();
        }
        for i in 0..m3 {
            let mut v = self.t[i];
            for p in 0..i {
                v -= self.cap[i * m3 + p] * self.t[p];
            }
            self.t[i] = v / self.cap[i * m3 + i];
        }
        for i in (0..m3).rev() {
            let mut v = self.t[i];
            for p in i + 1..m3 {
                v -= self.cap[p * m3 + i] * self.t[p];
            }
            self.t[i] = v / self.cap[i * m3 + i];
        }
        for (i, ti) in self.t.iter().enumerate() {
            let zi = &self.z[i * n..(i + 1) * n];
            for (xj, zj) in x.iter_mut().zip(zi) {
                *xj -= zj * ti;
            }
        }
    }
}

/// `x ← S₀⁻¹x` with the tree's or the chain's factorization in `data`.
pub(crate) fn solve_s0(model: &Model, data: &Data, scratch: &mut [SolveNode], x: &mut [f64]) {
    match &model.tree {
        Some(tree) => shifted::tree_solve(tree, data, scratch, x),
        None => shifted::shifted_solve(model, data, x),
    }
}

/// Checks the linearization point.
pub(crate) fn check_point(model: &Model, q: &[f64], qd: &[f64]) -> Result<(), DynamicsError> {
    super::check_vec(model, "q", q)?;
    super::check_vec(model, "qd", qd)
}
