//! The Newton matrix of a closed model's implicit step without `n×n`
//! matrices (docs/theory-derivatives.md §9, CD5–CD7): the stage equation
//! in the acceleration `x` and the multipliers, the open tree's force
//! residual and the stabilized closure rows, solved in KKT form with the
//! O(N) shifted solve of the open tree and an `m×m` Schur complement.

use super::forward::pivoted_cholesky;
use super::rows::{assemble, closure_rows, prescribed_columns};
use crate::algorithms::frames::frame_state;
use crate::algorithms::shifted::{check_shift, tree_factor, tree_solve};
use crate::algorithms::shifted_geometric::FrameWrench;
use crate::algorithms::tree::outward;
use crate::algorithms::{Motion, Pass, check_vec, inverse_dynamics_open};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::closure::Target;
use crate::model::data::{ConstraintRows, Data, SolveNode};
use crate::model::tree::Tree;
use nalgebra::{DMatrix, DVector};
use softrod_lie::{Vec3, Vec6, join};

/// Solves the KKT system of a closed model's implicit step (CD6),
///
/// `[S, −Jᵀ; s·J, 0] [x; μ] = [b; d]`, `S = M(q) + a·K + b_D·D`,
/// `s = 1 + 2α·b_D + α²·a`,
///
/// at the configuration `q` of the last [`Self::factor_at`] (`J` the
/// closures' velocity rows there, `α` the model's Baumgarte rate), by the
/// Schur complement (CD7): `Y = S⁻¹Jᵀ` (m O(N) solves, at the
/// factorization), `A = J Y` (m×m, pivoted Cholesky), then per solve one
/// O(N) solve `x₀ = S⁻¹b`, `A μ = d/s − J x₀`, `x = x₀ + Y μ`. Rows that
/// `A` finds redundant (pivot below `1e-10` of the largest, as the
/// constrained forward dynamics) get `μ = 0`.
///
/// With `a = h²γ²`, `b_D = hγ` and right-hand side `(−r, −R)` from
/// [`Self::residuals`] this is the simplified Newton step of an implicit
/// stage equation of the constrained dynamics (CD5): `x` the correction of
/// the stage acceleration. The matrix leaves out what the open tree's
/// shifted solve leaves out (geometric, gyroscopic and load terms) and the
/// state dependence of `J`, `J̇q̇` beyond the Baumgarte terms; the fixed
/// point is the constrained `q̈` (D67–D68) either way. O(N·m + m³) per
/// factorization, O(N + n·m) per solve, no allocation after [`Self::new`].
///
/// ```
/// use softrod_dynamics::{Attachment, Closure, ClosureFrame, ClosureKind, ClosedShiftedSolver, Data, Joint, Model, Rod};
/// use softrod_lie::{Pose, Vec3};
/// use softrod_mechanics::Material;
/// let mat = Material::with_poisson(1000.0, 1e6, 0.5, 0.0).unwrap();
/// let rod = Rod::builder(0.3).name("r").pieces(3).circle(0.01).material(mat);
/// let model = Model::builder()
///     .rod_on(rod, Attachment::world_joint(Joint::spherical()))
///     .gravity([0.0, 0.0, -9.81])
///     .closure(Closure::new("pin", ClosureKind::Ball, ClosureFrame::on("r", None, Pose::identity()),
///         ClosureFrame::world(Pose::new(softrod_lie::Mat3::identity(), Vec3::new(0.3, 0.0, 0.0)))))
///     .build()
///     .unwrap();
/// let (n, m) = (model.n_dof(), model.n_constraints());
/// let mut data = Data::new(&model);
/// let mut kkt = ClosedShiftedSolver::new(&model);
/// let q = vec![0.0; n];
/// kkt.factor_at(&model, 0.0, &q, 1e-6, 1e-3).unwrap();
/// // The Newton step from x = 0 of the stage equation at (q, q̇ = 0).
/// let (mut r, mut c) = (vec![0.0; n], vec![0.0; m]);
/// kkt.residuals(&model, &mut data, 0.0, &q, &vec![0.0; n], &vec![0.0; n], None, &mut r, &mut c).unwrap();
/// r.iter_mut().for_each(|v| *v = -*v);
/// c.iter_mut().for_each(|v| *v = -*v);
/// kkt.solve(&model, &mut r, &c).unwrap();
/// ```
#[derive(Clone, Debug)]
pub struct ClosedShiftedSolver {
    /// The open tree's factorization of `S` (the shifted solve's buffers).
    data: Data,
    scratch: Vec<SolveNode>,
    /// `J` at the factorization (velocity rows), and the rows of
    /// [`Self::residuals`] at a trial state.
    rows: ConstraintRows,
    trial: ConstraintRows,
    jac_p: DMatrix<f64>,
    /// `Y = S⁻¹Jᵀ` (n×m), `A = J Y` factored in place (m×m), its pivots
    /// and rank.
    y: DMatrix<f64>,
    a: DMatrix<f64>,
    perm: Vec<usize>,
    rank: usize,
    /// `s = 1 + 2α b_D + α² a`.
    scale: f64,
    mu: DVector<f64>,
    n_dof: usize,
    factored: bool,
    /// Whether the factorizations add the geometric stiffness of gravity
    /// and of the closure forces at `lambda` (CD11), and whether the last
    /// one holds it.
    geometric: bool,
    geo_factored: bool,
    /// The multipliers whose closure forces the geometric terms hold fixed
    /// (m), and their wrenches on the closures' frames (two per closure at
    /// most, capacity reserved in [`Self::new`]).
    lambda: DVector<f64>,
    wrenches: Vec<FrameWrench>,
}

impl ClosedShiftedSolver {
    /// Allocates every buffer for `model` (with or without closures: with
    /// none it is the open tree's shifted solve).
    pub fn new(model: &Model) -> Self {
        let (n, m) = (model.n_dof(), model.n_constraints());
        Self {
            data: Data::new(model),
            scratch: vec![SolveNode::default(); model.tree.as_ref().map_or(0, |t| t.nodes.len())],
            rows: ConstraintRows::new(m, n),
            trial: ConstraintRows::new(m, n),
            jac_p: DMatrix::zeros(m, model.n_prescribed()),
            y: DMatrix::zeros(n, m),
            a: DMatrix::zeros(m, m),
            perm: vec![0; m],
            rank: 0,
            scale: 1.0,
            mu: DVector::zeros(m),
            n_dof: n,
            factored: false,
            geometric: false,
            geo_factored: false,
            lambda: DVector::zeros(m),
            wrenches: Vec::with_capacity(2 * model.closures.len()),
        }
    }

    /// Turns the geometric stiffness on or off for the following
    /// factorizations (docs/theory-derivatives.md CD11): `S` then also
    /// holds the Hessian of the potential of gravity (on the rods'
    /// quadrature points and the bodies, docs/theory-contact.md CT19–CT22)
    /// and of the closure forces `Jᵀλ` at the multipliers of
    /// [`Self::set_multipliers`], held fixed in the world while the frames
    /// they act on move — the tension of a rope pinned at both ends, which
    /// the elastic `K` lacks. Where a node's block is then indefinite it is
    /// factored with its eigenvalues' magnitudes (CT23); if the
    /// factorization fails even so, [`Self::factor_at`] factors without the
    /// terms ([`Self::geometric_in_factor`] tells). The fixed point of the
    /// Newton iteration does not change, only how fast it contracts.
    pub fn set_geometric(&mut self, on: bool) {
        self.geometric = on;
        self.factored = false;
    }

    /// The closure multipliers `λ` (m = [`Model::n_constraints`], the
    /// velocity rows' multipliers of the constrained forward dynamics,
    /// `crate::closure_multipliers`) whose forces the geometric terms of
    /// the following factorizations hold (CD11). Zero until set. Fails on
    /// a wrong length or non-finite entries (nothing changed then).
    pub fn set_multipliers(&mut self, lambda: &[f64]) -> Result<(), DynamicsError> {
        if lambda.len() != self.lambda.len() {
            return Err(DynamicsError::SizeMismatch {
                what: "lambda",
                expected: self.lambda.len(),
                got: lambda.len(),
            });
        }
        if let Some((i, v)) = lambda.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(DynamicsError::NotFinite {
                what: format!("closure multiplier [{i}]"),
                value: *v,
            });
        }
        self.lambda.copy_from_slice(lambda);
        self.factored = false;
        Ok(())
    }

    /// Whether the last successful factorization holds the geometric
    /// terms ([`Self::set_geometric`]; false after its fallback).
    pub fn geometric_in_factor(&self) -> bool {
        self.geometric && self.factored && self.geo_factored
    }

    /// The closure forces at `lambda` as wrenches on the closures' frames
    /// (CD11), after a kinematic outward pass at `q`: on frame a the
    /// spatial wrench `Cᵀλ` of the velocity rows `φ̇ = C(V_a − V_b)` (about
    /// the world origin), on frame b its opposite, each moved to its
    /// frame's origin and axes. The world carries none.
    fn closure_wrenches(&mut self, model: &Model, tree: &Tree, q: &[f64]) {
        self.wrenches.clear();
        for rc in &model.closures {
            let fa = frame_state(model, tree, &self.data, &rc.a, q, None);
            let fb = frame_state(model, tree, &self.data, &rc.b, q, None);
            let rows = closure_rows(rc, &fa, &fb, false);
            let mut w = Vec6::zeros();
            for i in 0..rc.spec.kind.n_constraints() {
                w += rows.c.row(i).transpose() * self.lambda[rc.row + i];
            }
            let (m0, f) = (Vec3::new(w[0], w[1], w[2]), Vec3::new(w[3], w[4], w[5]));
            for (fs, frame, sign) in [(&fa, &rc.a, 1.0), (&fb, &rc.b, -1.0)] {
                let (node, x) = match frame.target {
                    Target::World => continue,
                    Target::Rod { node, x, .. } => (node, Some(x)),
                    Target::Body { node } => (node, None),
                };
                let (p, r) = (fs.pose.translation, fs.pose.rotation);
                let m = (m0 - p.cross(&f)) * sign;
                let rt = r.transpose();
                self.wrenches.push(FrameWrench {
                    node,
                    x,
                    offset: frame.offset,
                    wrench: join(&(rt * m), &(rt * (f * sign))),
                });
            }
        }
    }

    fn check_model(&self, model: &Model) -> Result<(), DynamicsError> {
        if model.n_dof() != self.n_dof
            || model.n_constraints() != self.mu.len()
            || model.tree.as_ref().map_or(0, |t| t.nodes.len()) != self.scratch.len()
        {
            return Err(DynamicsError::WorkspaceMismatch {
                what: "ClosedShiftedSolver",
                built: self.n_dof,
                got: model.n_dof(),
            });
        }
        if model.tree.is_none() && model.has_closures() {
            unreachable!("closures live on the tree");
        }
        Ok(())
    }

    /// Factors the KKT matrix at `(t, q)` (CD6–CD7): the open tree's
    /// `S = M(q) + a·K + b·D` (`a, b ≥ 0`, finite; prescribed joints where
    /// they stand at `t`), the closures' velocity rows `J(q)`,
    /// `Y = S⁻¹Jᵀ` and the pivoted Cholesky of `J Y`. Fails on a bad shift
    /// or `q`, a model without a tree (a lone chain has no closures: use
    /// [`crate::ShiftedSolver`]) or with contact, and a piece whose shifted
    /// inertia is not positive definite (nothing is kept then).
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
        if model.has_contact() {
            return Err(DynamicsError::UnsupportedClosed {
                what: "ClosedShiftedSolver with contact",
            });
        }
        let Some(tree) = &model.tree else {
            return Err(DynamicsError::Unsupported {
                what: "ClosedShiftedSolver on a model without joints (use ShiftedSolver)",
            });
        };
        model.set_time(&mut self.data, t);
        // The rows first: the factorization's own outward sweep comes after
        // (it reads nothing the kinematic sweep leaves).
        let motion = Motion::at_rest(q);
        outward(
            model,
            tree,
            &mut self.data,
            motion,
            Pass::Kinematic,
            Forces::ALL,
        );
        assemble(model, tree, &self.data, motion, false, &mut self.rows);
        self.geo_factored = false;
        if self.geometric && a != 0.0 {
            self.closure_wrenches(model, tree, q);
            match tree_factor(
                model,
                tree,
                &mut self.data,
                q,
                a,
                b,
                None,
                true,
                &self.wrenches,
            ) {
                Ok(()) => self.geo_factored = true,
                // Not positive definite even with CT23: without the terms.
                Err(DynamicsError::Singular { .. } | DynamicsError::SingularNode { .. }) => {}
                Err(e) => return Err(e),
            }
        }
        if !self.geo_factored {
            tree_factor(model, tree, &mut self.data, q, a, b, None, false, &[])?;
        }
        let m = model.n_constraints();
        for c in 0..m {
            for i in 0..self.n_dof {
                self.y[(i, c)] = self.rows.jac[(c, i)];
            }
            let mut col = self.y.column_mut(c);
            tree_solve(tree, &self.data, &mut self.scratch, col.as_mut_slice());
        }
        self.a.gemm(1.0, &self.rows.jac, &self.y, 0.0);
        self.rank = pivoted_cholesky(&mut self.a, &mut self.perm);
        let rate = model.baumgarte;
        self.scale = 1.0 + 2.0 * rate * b + rate * rate * a;
        self.factored = true;
        Ok(())
    }

    /// `x ← ` the first block of the KKT solution for the right-hand side
    /// `(x, d)` (`x`: n_dof, `d`: m = [`Model::n_constraints`]) with the
    /// last [`Self::factor_at`] (CD7). Fails before a factorization, on
    /// wrong lengths, non-finite input or a non-finite result.
    // Triangular solves read clearest with explicit indices.
    #[allow(clippy::needless_range_loop)]
    pub fn solve(&mut self, model: &Model, x: &mut [f64], d: &[f64]) -> Result<(), DynamicsError> {
        self.check_model(model)?;
        if !self.factored {
            return Err(DynamicsError::NotFactored {
                what: "ClosedShiftedSolver",
            });
        }
        check_vec(model, "x", x)?;
        let m = self.mu.len();
        if d.len() != m {
            return Err(DynamicsError::SizeMismatch {
                what: "d",
                expected: m,
                got: d.len(),
            });
        }
        if let Some((i, v)) = x.iter().chain(d).enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(DynamicsError::NotFinite {
                what: format!("KKT right-hand side [{i}]"),
                value: *v,
            });
        }
        let Some(tree) = &model.tree else {
            unreachable!("factor_at refused a model without a tree")
        };
        tree_solve(tree, &self.data, &mut self.scratch, x);
        // μ: A μ = d/s − J x₀ on the independent rows (permuted).
        let xv = nalgebra::DVectorView::from_slice(x, x.len());
        for i in 0..m {
            let p = self.perm[i];
            self.mu[i] = d[p] / self.scale - self.rows.jac.row(p).dot(&xv.transpose());
        }
        let r = self.rank;
        for i in 0..r {
            let mut s = self.mu[i];
            for k in 0..i {
                s -= self.a[(i, k)] * self.mu[k];
            }
            self.mu[i] = s / self.a[(i, i)];
        }
        for i in (0..r).rev() {
            let mut s = self.mu[i];
            for k in i + 1..r {
                s -= self.a[(k, i)] * self.mu[k];
            }
            self.mu[i] = s / self.a[(i, i)];
        }
        for i in 0..m {
            if i >= r {
                continue;
            }
            let (p, v) = (self.perm[i], self.mu[i]);
            for (xr, yr) in x.iter_mut().zip(self.y.column(p).iter()) {
                *xr += v * yr;
            }
        }
        if let Some((i, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(DynamicsError::NotFinite {
                what: format!("KKT solve x[{i}]"),
                value: *v,
            });
        }
        Ok(())
    }

    /// The two residuals of the constrained dynamics at a trial
    /// acceleration `q̈` (CD5): the open tree's force residual
    /// `r = ID(t, q, q̇, q̈) − τ_act` (`M q̈ + b − τ_act`, without the closure
    /// forces; n_dof) and the stabilized closure rows
    /// `R = J q̈ + J̇q̇ + 2α(J q̇ + J_p q̇_p) + α²φ` (m, D67–D68). They vanish
    /// together (with `r = Jᵀλ` for some `λ`) exactly at the constrained
    /// forward dynamics' `q̈`. `data`: the caller's workspace of `model`
    /// (its cable tensions apply). O(N + n·m), no allocation.
    #[allow(clippy::too_many_arguments)]
    pub fn residuals(
        &mut self,
        model: &Model,
        data: &mut Data,
        t: f64,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        tau_act: Option<&[f64]>,
        r: &mut [f64],
        c: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.check_model(model)?;
        for (what, v) in [("q", q), ("qdot", qd), ("qddot", qdd), ("r", &*r)] {
            check_vec(model, what, v)?;
        }
        if let Some(tau) = tau_act {
            check_vec(model, "tau", tau)?;
        }
        if c.len() != self.mu.len() {
            return Err(DynamicsError::SizeMismatch {
                what: "c",
                expected: self.mu.len(),
                got: c.len(),
            });
        }
        if model.has_contact() {
            return Err(DynamicsError::UnsupportedClosed {
                what: "ClosedShiftedSolver with contact",
            });
        }
        let Some(tree) = &model.tree else {
            return Err(DynamicsError::Unsupported {
                what: "ClosedShiftedSolver on a model without joints (use ShiftedSolver)",
            });
        };
        inverse_dynamics_open(
            model,
            data,
            Forces::ALL,
            t,
            Motion::new(q, Some(qd), Some(qdd)),
        );
        r.copy_from_slice(data.tau.as_slice());
        if let Some(tau) = tau_act {
            for (ri, ti) in r.iter_mut().zip(tau) {
                *ri -= ti;
            }
        }
        if c.is_empty() {
            return Ok(());
        }
        let motion = Motion::new(q, Some(qd), None);
        outward(model, tree, data, motion, Pass::Kinematic, Forces::ALL);
        assemble(model, tree, data, motion, false, &mut self.trial);
        let rate = model.baumgarte;
        let (qddv, qdv) = (
            nalgebra::DVectorView::from_slice(qdd, qdd.len()),
            nalgebra::DVectorView::from_slice(qd, qd.len()),
        );
        let mut out = nalgebra::DVectorViewMut::from_slice(c, self.mu.len());
        out.copy_from(&self.trial.jdot_qd);
        out.axpy(rate * rate, &self.trial.phi, 1.0);
        out.gemv(1.0, &self.trial.jac, &qddv, 1.0);
        out.gemv(2.0 * rate, &self.trial.jac, &qdv, 1.0);
        if model.n_prescribed() > 0 {
            prescribed_columns(model, tree, data, motion, &mut self.jac_p);
            out.gemv(2.0 * rate, &self.jac_p, &data.prescribed_qd, 1.0);
        }
        Ok(())
    }
}
