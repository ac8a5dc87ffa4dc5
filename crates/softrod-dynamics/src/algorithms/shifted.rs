//! O(N) factorization and solve of the shifted mass matrix
//! `S = M(q) + a·K + b·D`, the Newton matrix of the implicit integrators.
//!
//! `K = diag(K_n)` and `D = diag(D_n)` are block-diagonal per piece (D13),
//! so `S` is the mass matrix of the same chain with a per-piece "armature"
//! `a·K_n + b·D_n` added to each piece's own block. The articulated
//! recursion of the forward dynamics (docs/theory.md §6) eliminates exactly
//! those blocks: adding the armature to `D̂_n` (D24) makes the inward pass
//! (D24–D25) an `LDLᵀ`-like factorization of `S` and the bias-free
//! inward/outward sweeps (D26–D27) a solve, both O(N) — no `n_dof × n_dof`
//! matrix is formed (docs/theory-derivatives.md §6). Models with joints,
//! bodies or parents run the same recursion on their tree (D56): a joint's
//! spring and damper constants are its armature (D53); closed chains are
//! not covered (their Newton matrix carries the constraints).

use super::chain::outward_inl;
use super::shifted_contact::{ContactShift, check_point};
use super::shifted_geometric;
use super::tree::{inverse_k, local, outward};
use super::{Motion, Pass, check_vec};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::kernels::blocks::{Blk6, Sym6, ad_inv_tr_vec, ad_inv_vec};
use crate::kernels::chol::{backward_sub, cholesky_k, forward_sub, right_solve_lt};
use crate::kernels::inertia::project_add_blocks;
use crate::model::Model;
use crate::model::data::Data;
use crate::model::data::SolveNode;
use crate::model::tree::{NodeKind, Tree};
use softrod_lie::{Mat6, Vec6};

/// Factorization of `S = M(q) + a·K + b·D` by the articulated recursion,
/// with every buffer allocated once in [`ShiftedSolver::new`].
///
/// ```
/// # use softrod_dynamics::*;
/// # use softrod_kinematics::{Basis, RodGeometry, straight};
/// # use softrod_lie::{Pose, Vec3};
/// # use softrod_mechanics::{Material, RodProperties, Section};
/// let rod = RodGeometry::uniform(0.5, 4, Basis::all(), straight(), Pose::identity()).unwrap();
/// let material = Material::with_poisson(1000.0, 1e6, 0.5, 1.0).unwrap();
/// let body = RodProperties::new(Section::Circle { radius: 0.01 }, material, 0.5).unwrap();
/// let model = Model::new(vec![Rod::new("arm", rod, body)], Some(Vec3::new(0.0, 0.0, -9.81)), 4).unwrap();
/// let q = vec![0.1; model.n_dof()];
/// let mut solver = ShiftedSolver::new(&model);
/// solver.factor(&model, &q, 1e-4, 1e-2).unwrap(); // S = M + 1e-4 K + 1e-2 D
/// let mut x = vec![1.0; model.n_dof()];
/// solver.solve(&model, &mut x).unwrap(); // x ← S⁻¹ x
/// ```
#[derive(Clone, Debug)]
pub struct ShiftedSolver {
    /// Per-piece tip maps `A_ℓ`, `T₋(ℓ)`, the factor `L_n` of `D̂_n` (in
    /// `dt`) and `W_n = Û_n L_n⁻ᵀ` (in `ut`), as the forward dynamics
    /// leaves them.
    data: Data,
    factored: bool,
    n_dof: usize,
    /// Per-node scratch of the tree solve (empty for chain models).
    tree_scratch: Vec<crate::model::data::SolveNode>,
    /// The contact's stiffness and damping at the last
    /// [`Self::linearize_contact`] (docs/theory-contact.md CT17; empty:
    /// none, `S = M + aK + bD`).
    contact: ContactShift,
    /// Whether the factorizations add the geometric stiffness of the
    /// world-fixed forces (docs/theory-contact.md CT19–CT23).
    geometric: bool,
    geo_factored: bool,
    /// A chain model's own tree, with its buffers: the geometric terms are
    /// not symmetric, so they run on the tree recursion (dense 6×6 per
    /// node) rather than the chain's symmetric one (CT21). Built by
    /// [`Self::set_geometric`].
    chain_tree: Option<Box<ChainTree>>,
    /// Which recursion holds the last factorization.
    path: Path,
}

/// A chain model as a tree, for the geometric factorization.
#[derive(Clone, Debug)]
struct ChainTree {
    model: Model,
    data: Data,
    scratch: Vec<SolveNode>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Path {
    /// The model's own recursion (chain or tree).
    Own,
    /// A chain model on its [`ChainTree`].
    ChainTree,
}

impl ShiftedSolver {
    /// Allocates the per-piece buffers for `model`.
    pub fn new(model: &Model) -> Self {
        let nodes = model.tree.as_ref().map_or(0, |t| t.nodes.len());
        Self {
            data: Data::new(model),
            factored: false,
            n_dof: model.n_dof(),
            tree_scratch: vec![Default::default(); nodes],
            contact: ContactShift::default(),
            geometric: false,
            geo_factored: false,
            chain_tree: None,
            path: Path::Own,
        }
    }

    /// Turns the geometric stiffness of the world-fixed forces on or off
    /// for the following factorizations: `S = M + a(K + K_c + K_g) + b(D +
    /// D_c)`, `K_g` the Hessian of the potential of gravity (on the rods'
    /// quadrature points and the bodies) and of the contact forces of the
    /// last [`Self::linearize_contact`] held fixed in the world while their
    /// points move (docs/theory-contact.md CT19–CT23: exact between the
    /// coordinates of different pieces, joints and bodies; inside a piece
    /// the second derivative of the piece's map is left out, CT22). What a
    /// tensioned rope's Newton iteration needs: the rope's `T/ℓ` stiffness
    /// is this term. Off by default here; `softrod_integrate::RodSystem`
    /// turns it on. A chain model then factors on its tree (built here
    /// once, an allocation; the tree recursion costs ~1.5× the chain's).
    /// `K_g` is indefinite where the forces destabilize (a compressed or
    /// overhanging rod, the twist of a bent tensioned rod): a node whose
    /// articulated block is then not positive definite is factored with
    /// its eigenvalues' magnitudes (CT23), and if even that fails,
    /// [`Self::factor_at`] factors without the terms.
    pub fn set_geometric(&mut self, model: &Model, on: bool) -> Result<(), DynamicsError> {
        self.check_model(model)?;
        self.factored = false;
        self.geometric = on;
        if on && model.tree.is_none() && self.chain_tree.is_none() {
            let mut m = model.clone();
            m.tree = Some(Tree::build(&m)?);
            let nodes = m.tree.as_ref().map_or(0, |t| t.nodes.len());
            self.chain_tree = Some(Box::new(ChainTree {
                data: Data::new(&m),
                scratch: vec![SolveNode::default(); nodes],
                model: m,
            }));
        }
        Ok(())
    }

    /// Whether the last successful factorization holds the geometric
    /// stiffness ([`Self::set_geometric`]; false after a fallback).
    pub fn geometric_in_factor(&self) -> bool {
        self.geometric && self.factored && self.geo_factored
    }

    /// Makes the following factorizations include the contact at
    /// `(t, q, q̇)`: `S = M(q) + a(K + K_c) + b(D + D_c)` with
    /// `K_c = Σ J_wᵀ K_p J_w`, `D_c = Σ J_wᵀ C_p J_w` over the touching
    /// contacts, `K_p`, `C_p` the positive semi-definite symmetric parts of
    /// `−∂f/∂p`, `−∂f/∂v` of each contact's force law (CT6; on a tree model
    /// without the geometric terms a world obstacle's contact takes them
    /// whole, non-symmetric, CT26) — the stiffness
    /// and damping of the contact in the implicit integrators' Newton
    /// matrix (docs/theory-contact.md CT17). Contact is evaluated with
    /// `data` (the run's friction anchors and raised stiffnesses; its
    /// contact buffers are overwritten). A rod point on an obstacle fixed
    /// in the world is a point inertia at its section (O(1) each);
    /// two-sided contacts (rod pairs, self contact, obstacles carried by a
    /// body) join by a rank-3 Woodbury update each (3 O(N) solves per
    /// factorization, O(n) per solve). Returns the number of contacts kept.
    /// A model without contact keeps none. No allocation once the buffers
    /// have grown to the largest contact count.
    pub fn linearize_contact(
        &mut self,
        model: &Model,
        data: &mut Data,
        t: f64,
        q: &[f64],
        qd: &[f64],
    ) -> Result<usize, DynamicsError> {
        self.check_model(model)?;
        self.factored = false;
        self.contact.clear();
        if !model.has_contact() {
            return Ok(0);
        }
        check_point(model, q, qd)?;
        self.contact.linearize(model, data, t, q, qd);
        Ok(self.contact.blocks.len() + self.contact.pair_kc.len())
    }

    /// Whether the following [`Self::linearize_contact`] keeps a tree
    /// model's world-obstacle contact blocks whole — the law's
    /// non-symmetric `−∂f/∂p`, `−∂f/∂v` (sliding friction's skew damping),
    /// factored by the recursion's non-symmetric form (docs/theory-contact.md
    /// CT26) — instead of their positive semi-definite symmetric parts
    /// (CT17). Default off. Chain models and the factorization with the
    /// geometric terms keep the symmetric parts either way.
    pub fn set_contact_whole(&mut self, on: bool) {
        self.factored = false;
        self.contact.whole = on;
    }

    /// Forgets the contact of [`Self::linearize_contact`]: the following
    /// factorizations are of `M + aK + bD` again.
    pub fn clear_contact(&mut self) {
        self.factored = false;
        self.contact.clear();
    }

    fn check_model(&self, model: &Model) -> Result<(), DynamicsError> {
        let nodes = model.tree.as_ref().map_or(0, |t| t.nodes.len());
        if model.n_dof() != self.n_dof
            || model.rods().len() != self.data.pieces.len()
            || nodes != self.tree_scratch.len()
        {
            return Err(DynamicsError::WorkspaceMismatch {
                what: "ShiftedSolver",
                built: self.n_dof,
                got: model.n_dof(),
            });
        }
        Ok(())
    }

    /// Factors `S = M(q) + a·K + b·D` (`a, b ≥ 0`, finite) by the
    /// articulated recursion: outward pass for the per-piece inertia
    /// integrals (D20), inward pass (D24–D25) with `D̂_n = 𝓓_n + a·K_n +
    /// b·D_n + S_ℓᵀ𝓜ᴬ_{n+1}S_ℓ`, one `k_n×k_n` Cholesky per piece. O(N), no
    /// allocation. `q`: dim `n_dof`. `K`, `D` are those of
    /// [`crate::stiffness_matrix`], [`crate::damping_matrix`] (units of `a`:
    /// s², of `b`: s, for `S` in kg-like units of `M`).
    ///
    /// Fails on a negative or non-finite shift, a bad `q`, a `D̂_n` that is
    /// not positive definite (then no factorization is kept), and on a model
    /// with closures ([`DynamicsError::UnsupportedClosed`]). Prescribed
    /// joints stand at their values of the last [`Self::factor_at`] (time 0
    /// before any).
    pub fn factor(
        &mut self,
        model: &Model,
        q: &[f64],
        a: f64,
        b: f64,
    ) -> Result<(), DynamicsError> {
        let t = self.data.prescribed_time;
        self.factor_at(model, if t.is_finite() { t } else { 0.0 }, q, a, b)
    }

    /// [`Self::factor`] with the prescribed joints (D59) at time `t` \[s\]
    /// (the mass matrix depends on where they hold the model); the same as
    /// `factor` for models without them.
    pub fn factor_at(
        &mut self,
        model: &Model,
        t: f64,
        q: &[f64],
        a: f64,
        b: f64,
    ) -> Result<(), DynamicsError> {
        self.check_model(model)?;
        self.factored = false;
        check_shift(a, b)?;
        check_vec(model, "q", q)?;
        if model.has_closures() {
            return Err(DynamicsError::UnsupportedClosed {
                what: "ShiftedSolver",
            });
        }
        self.geo_factored = false;
        if self.geometric {
            match self.factor_geometric(model, t, q, a, b) {
                Ok(()) => {
                    self.geo_factored = true;
                    self.factored = true;
                    return Ok(());
                }
                // Not positive definite with K_g: without it below.
                Err(DynamicsError::Singular { .. } | DynamicsError::SingularNode { .. }) => {}
                Err(e) => return Err(e),
            }
        }
        self.path = Path::Own;
        let contact = (!self.contact.is_empty()).then_some(&self.contact);
        if let Some(tree) = &model.tree {
            model.set_time(&mut self.data, t);
            tree_factor(model, tree, &mut self.data, q, a, b, contact, false, &[])?;
        } else {
            shifted_factor(model, &mut self.data, q, a, b, contact)?;
        }
        if contact.is_some() {
            self.contact
                .factor_low_rank(model, &self.data, &mut self.tree_scratch, a, b);
        }
        self.factored = true;
        Ok(())
    }

    /// The factorization with the geometric terms, on the model's tree or
    /// a chain model's [`ChainTree`] (arguments checked by the caller).
    fn factor_geometric(
        &mut self,
        model: &Model,
        t: f64,
        q: &[f64],
        a: f64,
        b: f64,
    ) -> Result<(), DynamicsError> {
        let contact = (!self.contact.is_empty()).then_some(&self.contact);
        let (m, data, scratch, path) = match (&model.tree, self.chain_tree.as_deref_mut()) {
            (Some(_), _) => (model, &mut self.data, &mut self.tree_scratch, Path::Own),
            (None, Some(ct)) => (&ct.model, &mut ct.data, &mut ct.scratch, Path::ChainTree),
            (None, None) => {
                return Err(DynamicsError::NotFactored {
                    what: "ShiftedSolver (set_geometric on another model)",
                });
            }
        };
        let tree = m.tree.as_ref().expect("a tree");
        m.set_time(data, t);
        tree_factor(m, tree, data, q, a, b, contact, true, &[])?;
        if contact.is_some() {
            self.contact.factor_low_rank(m, data, scratch, a, b);
        }
        self.path = path;
        Ok(())
    }

    /// `x ← S⁻¹ x` with the last factorization: the bias-free inward pass
    /// (D26, `ũ_n = L_n⁻¹(x_n − S_ℓᵀ𝓟ᴬ_{n+1})`, `𝓟ᴬ_n = A_ℓᵀ𝓟ᴬ_{n+1} +
    /// W_n ũ_n`) and outward pass (D27, `x_n = L_n⁻ᵀ(ũ_n − W_nᵀ η̇(L_{n−1}))`).
    /// O(N), no allocation. `x`: dim `n_dof`.
    ///
    /// Fails before a successful [`Self::factor`], on a wrong length or
    /// non-finite entries of `x`, and if the result is not finite.
    pub fn solve(&mut self, model: &Model, x: &mut [f64]) -> Result<(), DynamicsError> {
        self.check_model(model)?;
        if !self.factored {
            return Err(DynamicsError::NotFactored {
                what: "ShiftedSolver",
            });
        }
        check_vec(model, "x", x)?;
        match (&model.tree, self.path, self.chain_tree.as_deref_mut()) {
            (None, Path::ChainTree, Some(ct)) => {
                let tree = ct.model.tree.as_ref().expect("a tree");
                tree_solve(tree, &ct.data, &mut ct.scratch, x);
            }
            (Some(tree), ..) => tree_solve(tree, &self.data, &mut self.tree_scratch, x),
            (None, ..) => shifted_solve(model, &self.data, x),
        }
        if !self.contact.is_empty() {
            self.contact.solve_low_rank(self.n_dof, x);
        }
        if let Some((i, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(DynamicsError::NotFinite {
                what: format!("shifted solve x[{i}]"),
                value: *v,
            });
        }
        Ok(())
    }
}

crate::kernels::simd::dispatch! {
    /// The factorization of [`ShiftedSolver::factor`] into `data` (arguments
    /// checked by the caller).
    pub fn shifted_factor<'a>(model: &Model, data: &'a mut Data, q: &[f64], a: f64, b: f64, contact: Option<&ContactShift>) -> Result<&'a Data, DynamicsError>
    => shifted_factor_impl, shifted_factor_avx2
}

#[inline(always)]
pub(crate) fn shifted_factor_impl<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    a: f64,
    b: f64,
    contact: Option<&ContactShift>,
) -> Result<&'a Data, DynamicsError> {
    outward_inl(
        model,
        data,
        Motion::at_rest(q),
        Pass::Composite,
        Forces::ALL,
    );
    if let Some(c) = contact {
        c.add_chain(model, data, q, a, b);
    }
    for (r, rm) in model.rods().iter().enumerate() {
        let pieces = rm.spec.geometry.pieces();
        let mut ma_next = Sym6::default();
        for (n, (piece, pd)) in pieces.iter().zip(&rm.pieces).enumerate().rev() {
            let k = piece.basis.dof();
            let w = &mut data.pieces[r][n];
            let leaf = n + 1 == pieces.len();
            // As in the forward dynamics: C = A_ℓᵀ𝓜ᴬA_ℓ, Û = 𝓤 + C T₊B,
            // D̂ = 𝓓 + BᵀT₊ᵀ C T₊B (D24).
            let carried = if leaf {
                Sym6::default()
            } else {
                ma_next.congruence_ad_inv(&w.tip)
            };
            if !leaf {
                let tplus = w.tm_tip.transpose_blocks();
                let mat = carried.mul_op(&tplus);
                project_add_blocks(
                    &piece.basis,
                    &mat,
                    &Blk6::tr_premul_sym(&tplus, &mat),
                    &mut w.ut,
                    &mut w.dt,
                );
            }
            // The armature: K_n, D_n are zero-padded, so the padding of
            // `dt` (never read past k) stays as it was.
            if a != 0.0 {
                w.dt += pd.stiffness6 * a;
            }
            if b != 0.0 && pd.has_damping {
                w.dt += pd.damping6 * b;
            }
            if !cholesky_k(&mut w.dt, k) {
                return Err(DynamicsError::Singular {
                    rod: r,
                    piece: n,
                    what: "shifted articulated block D̂_n + aK_n + bD_n",
                });
            }
            right_solve_lt(&w.dt, k, &mut w.ut);
            let mut next = if leaf { w.mt } else { w.mt + carried };
            next -= Sym6::gram_rows(&w.ut);
            ma_next = next;
        }
    }
    Ok(data)
}

/// The solve of [`ShiftedSolver::solve`] (arguments checked by the caller).
pub(crate) fn shifted_solve(model: &Model, data: &Data, x: &mut [f64]) {
    for (r, rm) in model.rods().iter().enumerate() {
        let pieces = rm.spec.geometry.pieces();
        let mut pa = Vec6::zeros();
        for (n, piece) in pieces.iter().enumerate().rev() {
            let k = piece.basis.dof();
            let o = rm.dof_offset + piece.dof_offset;
            let w = &data.pieces[r][n];
            let mut sty = Vec6::zeros();
            piece
                .basis
                .tr_apply(&w.tm_tip.tr_mul_vec(&pa), &mut sty.as_mut_slice()[..k]);
            let mut u = Vec6::zeros();
            for i in 0..k {
                u[i] = x[o + i] - sty[i];
            }
            forward_sub(&w.dt, k, &mut u);
            // ũ_n waits in x_n for the outward pass.
            x[o..o + k].copy_from_slice(&u.as_slice()[..k]);
            pa = ad_inv_tr_vec(&w.tip, &pa) + w.ut * u;
        }
        let mut etadot = Vec6::zeros();
        for (n, piece) in pieces.iter().enumerate() {
            let k = piece.basis.dof();
            let o = rm.dof_offset + piece.dof_offset;
            let w = &data.pieces[r][n];
            let mut u = Vec6::zeros();
            u.as_mut_slice()[..k].copy_from_slice(&x[o..o + k]);
            let mut qn = u - w.ut.tr_mul(&etadot);
            backward_sub(&w.dt, k, &mut qn);
            x[o..o + k].copy_from_slice(&qn.as_slice()[..k]);
            let sq = w.tm_tip.mul_vec(&piece.basis.apply(&qn.as_slice()[..k]));
            etadot = ad_inv_vec(&w.tip, &etadot) + sq;
        }
    }
}

/// The factorization of `S = M(q) + a·K + b·D` on the tree
/// (docs/theory-derivatives.md §6 on the recursion of D56): the
/// articulated inward pass of [`super::tree::forward_dynamics`] without biases, with the
/// armature `a·K_n + b·D_n` of each node added to its `D̂` — a piece's
/// `K_n`, `D_n` (D13), a joint's spring and damper constants (D53), nothing
/// for bodies and prescribed joints. Leaves `Û`, `D̂⁻¹` per node in `data`;
/// prescribed joints at `data.prescribed_q` (their last [`Model::set_time`]).
/// With `contact`, its one-sided blocks join the nodes' sums (CT17); with
/// `geometric`, the geometric stiffness of gravity and of the contact
/// forces (CT19–CT22) and of the frame wrenches `extra` (a closed model's
/// closure forces, docs/theory-derivatives.md CD11): non-symmetric `𝓜ᵗ`, `𝓤`, `𝓓`, read with the inboard
/// coordinate on the left (`Û = 𝓤 + AᵀM_tip S`, `M_base = 𝓜ᵗ + AᵀM_tipA −
/// ÛD̂⁻¹Ûᵀ`), `D̂`'s symmetric part factored.
#[allow(clippy::too_many_arguments)]
pub(crate) fn tree_factor(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    q: &[f64],
    a: f64,
    b: f64,
    contact: Option<&ContactShift>,
    geometric: bool,
    extra: &[shifted_geometric::FrameWrench],
) -> Result<(), DynamicsError> {
    outward(
        model,
        tree,
        data,
        Motion::at_rest(q),
        Pass::Composite,
        Forces::ALL,
    );
    // Non-symmetric contact blocks (CT26) are taken whole only without the
    // geometric terms, whose blocks are read "inboard on the left" (CT21).
    let nonsym = !geometric && contact.is_some_and(|c| c.nonsym);
    if nonsym {
        for w in &mut data.nodes {
            w.ul = w.ut;
        }
    }
    if let Some(c) = contact {
        c.add_tree(model, data, q, a, b, nonsym);
    }
    if geometric {
        shifted_geometric::add(model, tree, data, q, a, contact, extra);
    }
    for w in &mut data.nodes {
        w.m_tip = Mat6::zeros();
    }
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        let k = node.k;
        let w = &mut data.nodes[i];
        let am = w.tip.ad_inv().to_mat6();
        let ma = w.m_tip;
        let mas = ma * w.s_tip;
        let uhat = w.ut + am.transpose() * mas;
        let mut dhat = w.dt + w.s_tip.transpose() * mas;
        match node.kind {
            NodeKind::Piece { rod, piece } => {
                let pd = &model.rods[rod].pieces[piece];
                if a != 0.0 {
                    dhat += pd.stiffness6 * a;
                }
                if b != 0.0 && pd.has_damping {
                    dhat += pd.damping6 * b;
                }
            }
            NodeKind::Joint { element } => {
                let joint = &model.elements[element].attachment.joint;
                for c in 0..k {
                    let (kc, dc, _) = joint.coefficients(c);
                    dhat[(c, c)] += a * kc + b * dc;
                }
            }
            NodeKind::Body { .. } => {}
        }
        let dinv = if nonsym {
            // CT26: `D̂` is not symmetric; its LU.
            if k > 0 {
                general_inverse_k(&dhat, k).ok_or_else(|| DynamicsError::SingularNode {
                    node: tree.describe(model, i),
                    what: "shifted articulated block D̂ + aK + bD",
                })?
            } else {
                Mat6::zeros()
            }
        } else if k > 0 {
            // With the geometric terms a node's D̂ may be indefinite where
            // the forces destabilize (CT23): its eigenvalues' magnitudes.
            inverse_k(&dhat, k)
                .or_else(|| {
                    geometric
                        .then(|| shifted_geometric::abs_inverse_k(&dhat, k))
                        .flatten()
                })
                .ok_or_else(|| DynamicsError::SingularNode {
                    node: tree.describe(model, i),
                    what: "shifted articulated block D̂ + aK + bD",
                })?
        } else {
            Mat6::zeros()
        };
        // `Û_L`: the node's rows against the parent's columns (CT26); `Û`
        // itself when the matrix is symmetric.
        let uhat_l = if nonsym {
            w.ul + am.transpose() * (ma.transpose() * w.s_tip)
        } else {
            uhat
        };
        let ud = uhat * dinv;
        let mb = w.mt + am.transpose() * ma * am - ud * uhat_l.transpose();
        w.uhat = uhat;
        w.uhat_l = uhat_l;
        w.dinv = dinv;
        if let Some(p) = node.parent {
            let x = node.offset.ad_inv().to_mat6();
            let mx = x.transpose() * mb * x;
            if node.attach.is_some() {
                let (ax, sx) = (w.attach_a, w.attach_s);
                let pw = &mut data.nodes[p];
                pw.mt += ax.transpose() * mx * ax;
                pw.ut += ax.transpose() * mx * sx;
                if nonsym {
                    pw.ul += ax.transpose() * (mx.transpose() * sx);
                }
                pw.dt += sx.transpose() * mx * sx;
            } else {
                data.nodes[p].m_tip += mx;
            }
        }
    }
    Ok(())
}

/// `x ← S⁻¹x` with the factorization of [`tree_factor`] in `data`: the
/// bias-free inward (D26) and outward (D27) sweeps of the tree, the
/// children's wrenches summed at each tip or at their point inside the
/// parent piece (D62). O(N).
pub(crate) fn tree_solve(tree: &Tree, data: &Data, scratch: &mut [SolveNode], x: &mut [f64]) {
    scratch.fill(SolveNode::default());
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        let k = node.k;
        let w = &data.nodes[i];
        let sc = scratch[i];
        let y = sc.f_tip;
        let xs = local(x, node.dof, k);
        let u = xs - sc.p_small - w.s_tip.tr_mul(&y);
        let u = Vec6::from_fn(|r, _| if r < k { u[r] } else { 0.0 });
        let pb = sc.p_big + w.tip.ad_inv().tr_mul_vec(&y) + w.uhat * (w.dinv * u);
        scratch[i].u = u;
        if let Some(p) = node.parent {
            let px = node.offset.ad_inv().tr_mul_vec(&pb);
            if node.attach.is_some() {
                let sp = &mut scratch[p];
                sp.p_big += w.attach_a.transpose() * px;
                sp.p_small += w.attach_s.transpose() * px;
            } else {
                scratch[p].f_tip += px;
            }
        }
    }
    for (i, node) in tree.nodes.iter().enumerate() {
        let w = &data.nodes[i];
        let etadot_p = match node.parent {
            Some(p) if node.attach.is_some() => {
                w.attach_a * scratch[p].etadot_base + w.attach_s * scratch[p].qn
            }
            Some(p) => scratch[p].etadot_tip,
            None => Vec6::zeros(),
        };
        let etadot_b = node.offset.ad_inv().mul_vec(&etadot_p);
        let qn = w.dinv * (scratch[i].u - w.uhat_l.tr_mul(&etadot_b));
        for c in 0..node.k {
            x[node.dof + c] = qn[c];
        }
        let sc = &mut scratch[i];
        sc.etadot_base = etadot_b;
        sc.qn = qn;
        sc.etadot_tip = w.tip.ad_inv().mul_vec(&etadot_b) + w.s_tip * qn;
    }
}

/// The inverse of the leading `k×k` block of a general `d` (LU), padded
/// with zeros; `None` if singular.
fn general_inverse_k(d: &Mat6, k: usize) -> Option<Mat6> {
    let padded = Mat6::from_fn(|i, j| {
        if i < k && j < k {
            d[(i, j)]
        } else if i == j {
            1.0
        } else {
            0.0
        }
    });
    let inv = padded.try_inverse()?;
    inv.iter()
        .all(|v| v.is_finite())
        .then(|| Mat6::from_fn(|i, j| if i < k && j < k { inv[(i, j)] } else { 0.0 }))
}

/// The shifts `a`, `b` of `M + a·K + b·D`: finite and non-negative (the
/// matrix is then positive definite with `M`), else `InvalidShift` naming
/// the one that is not. Shared by the open and the closed (KKT) solvers.
pub(crate) fn check_shift(a: f64, b: f64) -> Result<(), DynamicsError> {
    for (what, value) in [("a", a), ("b", b)] {
        if !(value.is_finite() && value >= 0.0) {
            return Err(DynamicsError::InvalidShift { what, value });
        }
    }
    Ok(())
}
