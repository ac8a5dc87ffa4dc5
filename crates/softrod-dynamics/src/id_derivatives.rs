//! Analytic derivatives of the recursive inverse dynamics:
//! `∂τ/∂q`, `∂τ/∂q̇` of `τ = ID(q, q̇, q̈)` (docs/theory-derivatives.md §2–§4,
//! (D37)–(D46)), by one outward and one inward sweep plus a pairing of
//! per-piece quantities — the structure of the RNEA derivatives of rigid
//! chains, with each piece's own points differentiated through the strain
//! derivatives of its maps (D30)–(D36).

use crate::algorithms::check_vec;
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::forces::external::gravity_base_acceleration;
use crate::forces::linearized::{cable_terms, dead_load_map, drag_diagonal, has_dead_loads};
use crate::kernels::piece_derivs::{Coefficients, PieceDerivMaps, lambda, tangent_transpose_form};
use crate::model::rod::PieceData;
use crate::model::{Model, RodModel};
use nalgebra::{DMatrix, DVector};
use softrod_kinematics::Basis;
use softrod_lie::{AdOp, Mat6, PieceMaps, Pose, Vec6, ad, ad_vec, coad, coad_vec};
use softrod_mechanics::LoadFrame;

/// Per-piece buffers of the derivative sweeps (all fixed-size; `k_n`-sized
/// quantities in the leading columns / rows of 6×6).
#[derive(Clone, Debug)]
pub(crate) struct PieceWork {
    /// World poses of the piece base `G_{n−1}` and tip `G_n`; local tip pose.
    pub(crate) base_world: Pose,
    pub(crate) tip_world: Pose,
    pub(crate) tip: Pose,
    /// `T₋(ℓ)`, `η(ℓ)` and the tip linearizations `H_η`, `H_η̇`, `H_v̇` (D39–D41).
    pub(crate) tm_tip: Mat6,
    pub(crate) eta_tip: Vec6,
    pub(crate) etad_tip: Vec6,
    pub(crate) h_eta: Mat6,
    pub(crate) h_etad: Mat6,
    pub(crate) h_vd: Mat6,
    pub(crate) co_tip: Coefficients,
    /// Own-point sums (frame `L_{n−1}`): `𝓜ᵗ`, `𝓑ᵗ`, `𝒴ᵗ` (D43) and the
    /// receivers `Σ w T₋ᵀ X A` for `X = 𝓜, 𝓑̄, 𝒴` (D45).
    pub(crate) mt: Mat6,
    pub(crate) bt: Mat6,
    pub(crate) yt: Mat6,
    pub(crate) rm: Mat6,
    pub(crate) rb: Mat6,
    pub(crate) ry: Mat6,
    /// `Σ w T₋ᵀ f`, `Σ w Aᵀ f` (D17–D18 sums).
    pub(crate) tsum: Vec6,
    pub(crate) wsum: Vec6,
    /// Own-point derivative sums, columns = strain perturbation `ζ` (D42).
    pub(crate) dq_diag: Mat6,
    pub(crate) dv_diag: Mat6,
    pub(crate) dq_w: Mat6,
    pub(crate) dv_w: Mat6,
    /// `φ_i`, `χ_i` of (D36).
    pub(crate) phi: [Vec6; 4],
    pub(crate) chi: [Vec6; 4],
    /// `P^i = ad_ξ^i` and `k̄ = (k; 0)` for 𝒬 (D36).
    pub(crate) powers: [Mat6; 4],
    pub(crate) kbar: Vec6,
    /// Pairing quantities in the world frame (D46), `k` columns (or rows).
    pub(crate) s_world: Mat6,
    pub(crate) dwq_world: Mat6,
    pub(crate) dwv_world: Mat6,
    pub(crate) src_wq: Mat6,
    pub(crate) src_uq: Mat6,
    pub(crate) src_wv: Mat6,
    pub(crate) src_uv: Mat6,
    pub(crate) rcv_m: Mat6,
    pub(crate) rcv_b: Mat6,
    pub(crate) rcv_y: Mat6,
}

impl PieceWork {
    pub(crate) fn new() -> Self {
        let z = Mat6::zeros();
        Self {
            base_world: Pose::identity(),
            tip_world: Pose::identity(),
            tip: Pose::identity(),
            tm_tip: z,
            eta_tip: Vec6::zeros(),
            etad_tip: Vec6::zeros(),
            h_eta: z,
            h_etad: z,
            h_vd: z,
            co_tip: Coefficients {
                c: [0.0; 4],
                d: [0.0; 4],
                h: [0.0; 4],
            },
            mt: z,
            bt: z,
            yt: z,
            rm: z,
            rb: z,
            ry: z,
            tsum: Vec6::zeros(),
            wsum: Vec6::zeros(),
            dq_diag: z,
            dv_diag: z,
            dq_w: z,
            dv_w: z,
            phi: [Vec6::zeros(); 4],
            chi: [Vec6::zeros(); 4],
            powers: [z; 4],
            kbar: Vec6::zeros(),
            s_world: z,
            dwq_world: z,
            dwv_world: z,
            src_wq: z,
            src_uq: z,
            src_wv: z,
            src_uv: z,
            rcv_m: z,
            rcv_b: z,
            rcv_y: z,
        }
    }

    /// The tip of the piece (or joint) from its linearization at `x = ℓ`
    /// (`base_world` already set).
    pub(crate) fn set_tip(&mut self, g: Pose, p: &PointLin, dm: &PieceDerivMaps) {
        self.tip = g;
        self.tm_tip = p.t.to_mat6();
        self.eta_tip = p.eta;
        self.etad_tip = p.etad;
        self.h_eta = p.h_eta;
        self.h_etad = p.h_etad;
        self.h_vd = p.h_vd;
        self.co_tip = p.co;
        self.powers = dm.p;
        self.kbar = dm.kbar();
        self.tip_world = self.base_world.compose(&g);
    }

    pub(crate) fn reset_sums(&mut self) {
        let z = Mat6::zeros();
        self.mt = z;
        self.bt = z;
        self.yt = z;
        self.rm = z;
        self.rb = z;
        self.ry = z;
        self.tsum = Vec6::zeros();
        self.wsum = Vec6::zeros();
        self.dq_diag = z;
        self.dv_diag = z;
        self.dq_w = z;
        self.dv_w = z;
        self.phi = [Vec6::zeros(); 4];
        self.chi = [Vec6::zeros(); 4];
    }
}

/// Workspace and results of [`inverse_dynamics_derivatives`]
/// (Pinocchio-style: allocated once for a model by [`IdDerivatives::new`],
/// every evaluation writes into it and allocates nothing).
#[derive(Clone, Debug)]
pub struct IdDerivatives {
    pieces: Vec<Vec<PieceWork>>,
    /// `∂τ/∂q` (n_dof × n_dof): row `i`, column `j` is `∂τ_i/∂q_j` at fixed
    /// `q̇, q̈` [N·m or N per coordinate unit].
    pub dtau_dq: DMatrix<f64>,
    /// `∂τ/∂q̇` (n_dof × n_dof) at fixed `q, q̈`.
    pub dtau_dqd: DMatrix<f64>,
    /// `τ = ID(q, q̇, q̈)` itself (n_dof), as [`crate::inverse_dynamics`]
    /// returns it (to round-off).
    pub tau: DVector<f64>,
    /// Cable tensions replacing the schedules, as
    /// [`crate::Data::set_cable_tensions`] (copied from the `Data` by
    /// [`crate::forward_dynamics_derivatives`]).
    pub tensions: Option<DVector<f64>>,
    n_dof: usize,
    /// The per-node buffers of an articulated model (D76–D80).
    tree: Option<Box<crate::tree_derivatives::TreeWork>>,
}

impl IdDerivatives {
    /// Allocates the buffers and the two `n_dof × n_dof` results for `model`.
    pub fn new(model: &Model) -> Self {
        let n = model.n_dof();
        Self {
            pieces: model
                .rods()
                .iter()
                .map(|r| {
                    (0..r.spec.rod.n_pieces())
                        .map(|_| PieceWork::new())
                        .collect()
                })
                .collect(),
            dtau_dq: DMatrix::zeros(n, n),
            dtau_dqd: DMatrix::zeros(n, n),
            tau: DVector::zeros(n),
            tensions: None,
            n_dof: n,
            tree: model
                .tree
                .as_ref()
                .map(|t| Box::new(crate::tree_derivatives::TreeWork::new(model, t))),
        }
    }
}

/// `B` as a zero-padded 6×6 (columns past `k` are zero).
#[inline(always)]
pub(crate) fn basis6(basis: &Basis) -> Mat6 {
    let mut b = Mat6::zeros();
    for c in 0..basis.dof() {
        b.set_column(c, &basis.column(c));
    }
    b
}

/// `diag(d) X`.
#[inline(always)]
pub(crate) fn diag_mul(d: &Vec6, x: &Mat6) -> Mat6 {
    Mat6::from_fn(|i, j| d[i] * x[(i, j)])
}

/// `X diag(d)`.
#[inline(always)]
fn scale_columns(x: &Mat6, d: &Vec6) -> Mat6 {
    Mat6::from_fn(|i, j| x[(i, j)] * d[j])
}

/// `X · Op` for a block operator (dense: nalgebra's unrolled 6×6 product
/// measured cheaper than six 3×3 block products with their copies).
#[inline(always)]
fn mul_op(x: &Mat6, op: &AdOp) -> Mat6 {
    x * op.to_mat6()
}

/// `Op · X`.
#[inline(always)]
fn op_mul(op: &AdOp, x: &Mat6) -> Mat6 {
    op.to_mat6() * x
}

/// `Opᵀ · X`.
#[inline(always)]
fn op_tr_mul(op: &AdOp, x: &Mat6) -> Mat6 {
    op.to_mat6().tr_mul(x)
}

/// One evaluation point of a piece, linearized (D39–D41).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointLin {
    pub a: AdOp,
    pub t: AdOp,
    pub eta: Vec6,
    pub etad: Vec6,
    pub h_eta: Mat6,
    pub h_etad: Mat6,
    pub h_vd: Mat6,
    pub co: Coefficients,
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn linearize_point(
    maps: &PieceMaps,
    dm: &PieceDerivMaps,
    x: f64,
    eta0: &Vec6,
    etad0: &Vec6,
    xid: &Vec6,
    xidd: &Vec6,
) -> (Pose, PointLin) {
    let (g, tm, beta) = maps.eval(x);
    let a = g.ad_inv();
    let t = tm;
    let c = a.mul_vec(eta0);
    let sv = t.mul_vec(xid);
    let eta = c + sv;
    let a0 = a.mul_vec(etad0);
    let etad = a0 + t.mul_vec(xidd) + ad_vec(&c, &sv) + beta;
    let co = Coefficients::at(x, dm.theta);
    let d1 = dm.d_tangent_applied(&co, false);
    let d2 = dm.d_tangent_applied(&co, true);
    let dd = dm.bias_strain_derivative(&co);
    let td = dm.tangent_rate(&co);
    // Products of block operators [[A, 0], [B, A]] in that form (3 instead
    // of 8 3×3 products).
    let adc_op = AdOp::ad(&c);
    let adc_t_op = adc_op * tm;
    let adc_t = adc_t_op.to_mat6();
    // (D39): δη = ad_c Δ + 𝒟_ξ̇ ζ with Δ = T₋ζ.
    let h_eta = adc_t + d1;
    // (D40): δη̇′ = ad_{a₀}Δ − ad_{Tξ̇} ad_c Δ + 𝒟_ξ̈ ζ + ad_c 𝒟_ξ̇ ζ + 𝒟² ζ.
    let h_etad =
        (AdOp::ad(&a0) * tm - AdOp::ad(&sv) * adc_t_op).to_mat6() + d2 + op_mul(&adc_op, &d1) + dd;
    // (D41): ∂η̇′/∂ξ̇ = ad_c T₋ + 𝒟_ξ̇ + Ṫ.
    let h_vd = h_eta + td;
    (
        g,
        PointLin {
            a,
            t,
            eta,
            etad,
            h_eta,
            h_etad,
            h_vd,
            co,
        },
    )
}

crate::kernels::simd::dispatch! {
    /// Analytic `∂τ/∂q` and `∂τ/∂q̇` of the inverse dynamics
    /// `τ = ID(q, q̇, q̈)` at time `t` (docs/theory-derivatives.md, (D37)–(D47)),
    /// with every term of the model: inertia, Coriolis and centrifugal forces,
    /// gravity, elasticity and Kelvin–Voigt damping, cables, dead and follower
    /// point loads, distributed loads, drag. `∂τ/∂q̈ = M(q)`
    /// ([`crate::mass_matrix`]).
    ///
    /// One outward sweep linearizes every evaluation point in its own piece's
    /// strain (D39–D42); one inward sweep carries the composite inertia,
    /// velocity-product and dead-load operators (D43) and forms each piece's
    /// diagonal block and the change of its transmitted wrench (D44); the
    /// off-diagonal blocks are pairings of per-piece world-frame quantities
    /// (D45–D46). Cost O(N·n_dof) (the result is dense), no allocation.
    ///
    /// `q`, `q̇`, `q̈`: dim `n_dof`. Results in `work.dtau_dq`, `work.dtau_dqd`
    /// (n_dof × n_dof, row = component of `τ`, column = coordinate) and
    /// `work.tau`, of the inverse dynamics under `forces` (loads and cable
    /// tensions scaled by [`Forces::load_scale`]; prescribed joints moving or
    /// at rest).
    pub fn inverse_dynamics_derivatives_with<'a>(model: &Model, work: &'a mut IdDerivatives, forces: Forces, t: f64, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<&'a IdDerivatives, DynamicsError>
    => id_derivatives_impl, id_derivatives_avx2
}

/// [`inverse_dynamics_derivatives_with`] of every force of the model
/// ([`Forces::ALL`]).
pub fn inverse_dynamics_derivatives<'a>(
    model: &Model,
    work: &'a mut IdDerivatives,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a IdDerivatives, DynamicsError> {
    inverse_dynamics_derivatives_with(model, work, Forces::ALL, t, q, qd, qdd)
}

#[inline(always)]
pub(crate) fn id_derivatives_impl<'a>(
    model: &Model,
    work: &'a mut IdDerivatives,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a IdDerivatives, DynamicsError> {
    let nodes = model.tree.as_ref().map(|t| t.nodes.len());
    if work.n_dof != model.n_dof()
        || work.pieces.len() != model.rods().len()
        || work.tree.as_ref().map(|t| t.n_nodes()) != nodes
    {
        return Err(DynamicsError::WorkspaceMismatch {
            what: "IdDerivatives",
            built: work.n_dof,
            got: model.n_dof(),
        });
    }
    forces.check()?;
    // Gravity alone is no public pass; its derivatives are not taken.
    debug_assert!(!forces.gravity_only, "derivatives of gravity alone");
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    check_vec(model, "qddot", qdd)?;
    if model.has_closures() {
        return Err(DynamicsError::UnsupportedClosed {
            what: "inverse_dynamics_derivatives",
        });
    }
    if let (Some(tree), Some(mut tw)) = (&model.tree, work.tree.take()) {
        crate::tree_derivatives::tree_id_derivatives(
            model, tree, work, &mut tw, forces, t, q, qd, qdd,
        );
        work.tree = Some(tw);
    } else {
        let scale = forces.load_scale;
        if model.rods().len() > 1 {
            work.dtau_dq.fill(0.0);
            work.dtau_dqd.fill(0.0);
        }
        for (r, rm) in model.rods().iter().enumerate() {
            outward(model, rm, &mut work.pieces[r], q, qd, qdd, scale);
            inward(model, rm, work, r, t, q, qd, scale);
            pairs(rm, work, r);
        }
    }
    for (what, m) in [("dtau/dq", &work.dtau_dq), ("dtau/dqdot", &work.dtau_dqd)] {
        // One vectorizable pass (x·0 is NaN exactly for non-finite x), the
        // index search only on failure.
        let probe: f64 = m.as_slice().iter().map(|v| v * 0.0).sum();
        if probe.is_nan() {
            if let Some((i, v)) = m.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(DynamicsError::NotFinite {
                    what: format!(
                        "{what} entry ({}, {}) at t = {t}",
                        i % m.nrows(),
                        i / m.nrows()
                    ),
                    value: *v,
                });
            }
        }
    }
    Ok(work)
}

/// The own evaluation points and point loads of one piece (D38–D43): every
/// Gauss point linearized in the piece's strain and rate (D39–D41), its
/// force density and linearization summed into the diagonal and
/// transmitted-wrench sums (D42), the composites' own parts and the
/// receivers (D43, D45); point loads likewise, with weight 1. `pose` is the
/// world pose of the piece's base frame, `(η₀, η̇′₀)` its motion (gravity
/// in `η̇′₀`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn own_points(
    rm: &RodModel,
    pd: &PieceData,
    maps: &PieceMaps,
    dm: &PieceDerivMaps,
    pose: &Pose,
    motion: (&Vec6, &Vec6),
    rates: (&Vec6, &Vec6),
    drag: Option<&Vec6>,
    scale: f64,
    w: &mut PieceWork,
) {
    let (eta0, etad0) = motion;
    let (xid, xidd) = rates;
    for qp in &pd.points {
        let (g, p) = linearize_point(maps, dm, qp.x, eta0, etad0, xid, xidd);
        let m = &qp.inertia;
        let me = m.component_mul(&p.eta);
        let mut f = m.component_mul(&p.etad) + coad_vec(&p.eta, &me);
        // (D38): b = Λ(𝓜η) + ad*_η 𝓜 + C, the velocity part of δf.
        let mut b = lambda(&me) + scale_columns(&coad(&p.eta), m);
        if let Some(c) = drag {
            f += c.component_mul(&p.eta);
            b += Mat6::from_diagonal(c);
        }
        let mut y = Mat6::zeros();
        let mut has_y = false;
        if !rm.spec.distributed_loads.is_empty() {
            let world = pose.compose(&g);
            for dl in &rm.spec.distributed_loads {
                let load = dl.wrench_density(&world) * scale;
                f -= load;
                if dl.frame == LoadFrame::World {
                    y += dead_load_map(&load);
                    has_y = true;
                }
            }
        }
        let wt = qp.w;
        let df_q = (diag_mul(m, &p.h_etad)
            + b * p.h_eta
            + if has_y {
                mul_op(&y, &p.t)
            } else {
                Mat6::zeros()
            })
            * wt;
        let df_v = (diag_mul(m, &p.h_vd) + mul_op(&b, &p.t)) * wt;
        let fw = f * wt;
        w.dq_diag += op_tr_mul(&p.t, &df_q);
        w.dv_diag += op_tr_mul(&p.t, &df_v);
        w.dq_w += op_tr_mul(&p.a, &(mul_op(&lambda(&fw), &p.t) + df_q));
        w.dv_w += op_tr_mul(&p.a, &df_v);
        w.tsum += p.t.tr_mul_vec(&fw);
        w.wsum += p.a.tr_mul_vec(&fw);
        for i in 0..4 {
            w.phi[i] += f * (wt * p.co.d[i]);
            w.chi[i] += f * (wt * p.co.c[i]);
        }
        // (D43): B̄ = b − 𝓜 ad_η.
        let bbar = b - diag_mul(m, &ad(&p.eta));
        let pa = p.a.to_mat6();
        let ma = diag_mul(&(m * wt), &pa);
        let ba = mul_op(&(bbar * wt), &p.a);
        w.mt += op_tr_mul(&p.a, &ma);
        w.bt += op_tr_mul(&p.a, &ba);
        w.rm += op_tr_mul(&p.t, &ma);
        w.rb += op_tr_mul(&p.t, &ba);
        if has_y {
            let ya = mul_op(&(y * wt), &p.a);
            w.yt += op_tr_mul(&p.a, &ya);
            w.ry += op_tr_mul(&p.t, &ya);
        }
    }
    for pl in &pd.loads {
        let load = &rm.spec.point_loads[pl.index];
        let (g, tm) = maps.exp_and_tangent_minus(pl.x);
        let a = g.ad_inv().to_mat6();
        let t = tm.to_mat6();
        let co = Coefficients::at(pl.x, dm.theta);
        let fp = -(load.wrench(&pose.compose(&g)) * scale);
        let (at, tt) = (a.transpose(), t.transpose());
        let mut dq = lambda(&fp) * t;
        if load.frame == LoadFrame::World {
            let y = dead_load_map(&-fp);
            let yt_ = y * t;
            w.dq_diag += tt * yt_;
            dq += yt_;
            let ya = y * a;
            w.yt += at * ya;
            w.ry += tt * ya;
        }
        w.dq_w += at * dq;
        w.tsum += tt * fp;
        w.wsum += at * fp;
        for i in 0..4 {
            w.phi[i] += fp * co.d[i];
            w.chi[i] += fp * co.c[i];
        }
    }
}

/// The outward sweep (D39–D43): velocities, accelerations, force
/// densities and their linearizations at every point; own-point sums.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn outward(
    model: &Model,
    rm: &RodModel,
    works: &mut [PieceWork],
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    scale: f64,
) {
    let rod = &rm.spec.rod;
    let range = rm.dofs();
    let (qr, qdr, qddr) = (&q[range.clone()], &qd[range.clone()], &qdd[range]);
    let mut pose = *rod.base();
    let mut eta0 = Vec6::zeros();
    let mut etad0 = gravity_base_acceleration(model, rm, scale);
    let drag = drag_diagonal(rm);
    for ((piece, pd), w) in rod.pieces().iter().zip(&rm.pieces).zip(works.iter_mut()) {
        let xi = piece.strain(qr);
        let xid = piece.strain_rate(qdr);
        let xidd = piece.strain_rate(qddr);
        let maps = PieceMaps::new(&xi, Some(&xid));
        let dm = PieceDerivMaps::new(&xi, &xid, &xidd);
        w.reset_sums();
        w.base_world = pose;
        own_points(
            rm,
            pd,
            &maps,
            &dm,
            &pose,
            (&eta0, &etad0),
            (&xid, &xidd),
            drag.as_ref(),
            scale,
            w,
        );
        let (g, p) = linearize_point(&maps, &dm, piece.length, &eta0, &etad0, &xid, &xidd);
        w.set_tip(g, &p, &dm);
        eta0 = p.eta;
        etad0 = p.etad;
        pose = w.tip_world;
    }
}

/// What a subtree hands to the frame it hangs from (D43): the composite
/// inertia, velocity-product and dead-load operators `𝓜ᶜ`, `𝓑ᶜ`, `𝒴ᶜ` and
/// the transmitted wrench `W`, all in that frame's axes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Subtree {
    pub m: Mat6,
    pub b: Mat6,
    pub y: Mat6,
    pub w: Vec6,
}

impl Subtree {
    pub(crate) fn zero() -> Self {
        Self {
            m: Mat6::zeros(),
            b: Mat6::zeros(),
            y: Mat6::zeros(),
            w: Vec6::zeros(),
        }
    }

    /// The same subtree in the axes of a frame from which twists reach
    /// this one's by `η = a η′` (a rigid map): `aᵀ X a`, `aᵀ W`.
    pub(crate) fn through(&self, a: &Mat6, dead: bool) -> Self {
        let at = a.transpose();
        Self {
            m: at * self.m * a,
            b: at * self.b * a,
            y: if dead { at * self.y * a } else { Mat6::zeros() },
            w: at * self.w,
        }
    }

    pub(crate) fn add(&mut self, o: &Self) {
        self.m += o.m;
        self.b += o.b;
        self.y += o.y;
        self.w += o.w;
    }
}

/// One piece of the inward sweep (D43–D46) given what its subtree hands to
/// its tip frame (`tip`): writes the piece's world-frame pairing quantities
/// into `w` and returns its diagonal blocks in strain space (6×6, before
/// `Bᵀ · B` and the strain-space terms of (D47)), the wrench it projects on
/// its coordinates (`τ_n = Bᵀ(·)` before those terms) and what it hands to
/// its base frame.
#[inline(always)]
pub(crate) fn close_piece(
    w: &mut PieceWork,
    tip: &Subtree,
    bm: &Mat6,
    dead: bool,
) -> (Mat6, Mat6, Vec6, Subtree) {
    let (mc, bc, yc, wn) = (&tip.m, &tip.b, &tip.y, &tip.w);
    let al = w.tip.ad_inv().to_mat6();
    let tl = w.tm_tip;
    let adeta = ad(&w.eta_tip);
    // (D43): the subtree's wrench at L_n changes by
    // 𝓜ᶜ w̄ + 𝓑ᶜ u + 𝒴ᶜ Δ, with u = δη(ℓ), w̄ = δη̇′(ℓ) + ad_η(ℓ) δη(ℓ).
    let wq = w.h_etad + adeta * w.h_eta;
    let uq = w.h_eta;
    let mut dwn_q = mc * wq + bc * uq;
    if dead {
        dwn_q += yc * tl;
    }
    let wv = w.h_vd + adeta * tl;
    let dwn_v = mc * wv + bc * tl;
    let (mut phi, mut chi) = (w.phi, w.chi);
    for i in 0..4 {
        phi[i] += wn * w.co_tip.d[i];
        chi[i] += wn * w.co_tip.c[i];
    }
    let qform = tangent_transpose_form(&w.powers, &w.kbar, &phi, &chi);
    let tlt = tl.transpose();
    let diag_q = w.dq_diag + tlt * dwn_q + qform;
    let diag_v = w.dv_diag + tlt * dwn_v;
    let alt = al.transpose();
    let dw_q = w.dq_w + alt * (lambda(wn) * tl + dwn_q);
    let dw_v = w.dv_w + alt * dwn_v;
    // World-frame pairing quantities (D46).
    let to_world_tip = w.tip_world.ad().to_mat6();
    let base_inv = w.base_world.ad_inv().to_mat6();
    w.s_world = to_world_tip * tl * bm;
    w.src_wq = to_world_tip * wq * bm;
    w.src_uq = to_world_tip * uq * bm;
    w.src_wv = to_world_tip * wv * bm;
    w.src_uv = w.s_world;
    w.dwq_world = base_inv.transpose() * dw_q * bm;
    w.dwv_world = base_inv.transpose() * dw_v * bm;
    let bt_ = bm.transpose();
    w.rcv_m = bt_ * (w.rm + tlt * mc * al) * base_inv;
    w.rcv_b = bt_ * (w.rb + tlt * bc * al) * base_inv;
    if dead {
        w.rcv_y = bt_ * (w.ry + tlt * yc * al) * base_inv;
    }
    // Composites carried to L_{n−1} (D43), and τ_n's wrench (D18).
    let base = Subtree {
        m: w.mt + alt * mc * al,
        b: w.bt + alt * bc * al,
        y: if dead {
            w.yt + alt * yc * al
        } else {
            Mat6::zeros()
        },
        w: w.wsum + alt * wn,
    };
    (diag_q, diag_v, w.tsum + tlt * wn, base)
}

/// Writes a piece's `τ_n` and its diagonal blocks, adding the strain-space
/// terms (D13, D15, D47): `K_n q_n + D_n q̇_n`, the elastic offset and the
/// cables' force and strain Hessian. `bm`: the piece's basis
/// ([`basis6`]); `diag_q`, `diag_v`, `wrench` are [`close_piece`]'s.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn write_piece(
    model: &Model,
    rm: &RodModel,
    n: usize,
    work: &mut IdDerivatives,
    t: f64,
    (q, qd): (&[f64], &[f64]),
    scale: f64,
    bm: &Mat6,
    (diag_q, diag_v, wrench): (&Mat6, &Mat6, &Vec6),
) {
    let piece = &rm.spec.rod.pieces()[n];
    let pd = &rm.pieces[n];
    let k = piece.basis.dof();
    let o = rm.dof_offset + piece.dof_offset;
    let xi = piece.strain(&q[rm.dofs()]);
    let (cable_force, cable_hess) =
        cable_terms(model, rm, piece, &xi, t, scale, work.tensions.as_ref());
    let bt_ = bm.transpose();
    let dq6 = bt_ * (diag_q + cable_hess) * bm;
    let dv6 = bt_ * diag_v * bm;
    let inert = wrench + cable_force;
    for i in 0..k {
        let mut tau = piece.basis.column(i).dot(&inert) + pd.offset6[i];
        for j in 0..k {
            tau += pd.stiffness[(i, j)] * q[o + j] + pd.damping[(i, j)] * qd[o + j];
            work.dtau_dq[(o + i, o + j)] = dq6[(i, j)] + pd.stiffness[(i, j)];
            work.dtau_dqd[(o + i, o + j)] = dv6[(i, j)] + pd.damping[(i, j)];
        }
        work.tau[o + i] = tau;
    }
}

/// The inward sweep (D43–D46): composites, each piece's diagonal block,
/// `τ`, and the world-frame pairing quantities.
#[allow(clippy::too_many_arguments)]
fn inward(
    model: &Model,
    rm: &RodModel,
    work: &mut IdDerivatives,
    r: usize,
    t: f64,
    q: &[f64],
    qd: &[f64],
    scale: f64,
) {
    // Dead loads only: the 𝒴 composites and receivers are zero otherwise.
    let dead = has_dead_loads(rm);
    let mut sub = Subtree::zero();
    for (n, piece) in rm.spec.rod.pieces().iter().enumerate().rev() {
        let bm = basis6(&piece.basis);
        let (diag_q, diag_v, wrench, base) = close_piece(&mut work.pieces[r][n], &sub, &bm, dead);
        sub = base;
        write_piece(
            model,
            rm,
            n,
            work,
            t,
            (q, qd),
            scale,
            &bm,
            (&diag_q, &diag_v, &wrench),
        );
    }
}

/// The off-diagonal blocks (D45–D46): `i < j` pairs the world tip column
/// `Ad_{G_i}S_i(ℓ)` with the change of the transmitted wrench of piece `j`;
/// `i > j` pairs the receivers of piece `i` with the tip sources of `j`.
fn pairs(rm: &RodModel, work: &mut IdDerivatives, r: usize) {
    let pieces = rm.spec.rod.pieces();
    let dead = has_dead_loads(rm);
    let ws = &work.pieces[r];
    for (j, pj) in pieces.iter().enumerate() {
        let kj = pj.basis.dof();
        let oj = rm.dof_offset + pj.dof_offset;
        let wj = &ws[j];
        for (i, pi) in pieces.iter().enumerate() {
            if i == j {
                continue;
            }
            let ki = pi.basis.dof();
            let oi = rm.dof_offset + pi.dof_offset;
            let wi = &ws[i];
            let (bq, bv) = if i < j {
                (
                    wi.s_world.transpose() * wj.dwq_world,
                    wi.s_world.transpose() * wj.dwv_world,
                )
            } else {
                (
                    if dead {
                        wi.rcv_m * wj.src_wq + wi.rcv_b * wj.src_uq + wi.rcv_y * wj.s_world
                    } else {
                        wi.rcv_m * wj.src_wq + wi.rcv_b * wj.src_uq
                    },
                    wi.rcv_m * wj.src_wv + wi.rcv_b * wj.src_uv,
                )
            };
            let ld = work.dtau_dq.nrows();
            let (sq, sv) = (work.dtau_dq.as_mut_slice(), work.dtau_dqd.as_mut_slice());
            for c in 0..kj {
                let col = (oj + c) * ld + oi;
                // Element loops, not `copy_from_slice`: a `memcpy` call per
                // column of at most six entries costs more than the copy.
                for (d, v) in sq[col..col + ki].iter_mut().zip(&bq.as_slice()[6 * c..]) {
                    *d = *v;
                }
                for (d, v) in sv[col..col + ki].iter_mut().zip(&bv.as_slice()[6 * c..]) {
                    *d = *v;
                }
            }
        }
    }
}
