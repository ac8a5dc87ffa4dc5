//! Reusable buffers: everything one evaluation needs, allocated once —
//! [`Data`] and the per-piece, per-node and closure work spaces of the
//! algorithms (each field says which algorithm writes it).

use crate::error::DynamicsError;
use crate::kernels::blocks::Sym6;
use crate::kernels::planar::Pose2;
use crate::model::{Model, RodModel};
use nalgebra::{DMatrix, DVector};
use softrod_lie::{AdOp, Mat3, Mat6, Pose, Vec3, Vec6};

/// Per-piece work space of the recursions (all fixed-size; `k_n`-sized
/// quantities live in the top-left of 6×6 / the head of 6-vectors).
#[derive(Clone, Debug)]
pub(crate) struct PieceWork {
    /// Local tip pose `g_n(ℓ_n)`: `A_ℓ = Ad⁻¹_{g_n(ℓ)}` carries twists across
    /// the joint to the next piece.
    pub tip: Pose,
    /// `T₋(ℓ)` and the velocity-product acceleration `a_ℓ` at the tip.
    pub tm_tip: AdOp,
    pub acc_tip: Vec6,
    /// (D20): `𝓜ᵗ`, `𝓤` (6×k), `𝓓` (k×k). The forward dynamics overwrites
    /// `ut` with `W = ÛL⁻ᵀ` and `dt` with the Cholesky factor `L` of `D̂`.
    pub mt: Sym6,
    pub ut: Mat6,
    pub dt: Mat6,
    /// (D23): `𝓟ᵗ` (6) and `𝓹` (k), or the inverse-dynamics sums of (D17–D18).
    pub p_big: Vec6,
    pub p_small: Vec6,
    /// (D26): `ũ = L⁻¹u`, the articulated bias force projected on the piece.
    pub u: Vec6,
    /// Mass matrix only (kept last, out of the forward dynamics' cache
    /// lines): world pose at the piece base and `Ad_{g(ℓ)}S_ℓ` (6×k).
    pub base_pose: Pose,
    pub s_world: Mat6,
}

impl PieceWork {
    fn new() -> Self {
        Self {
            base_pose: Pose::identity(),
            tip: Pose::identity(),
            tm_tip: AdOp::zeros(),
            s_world: Mat6::zeros(),
            acc_tip: Vec6::zeros(),
            mt: Sym6::default(),
            ut: Mat6::zeros(),
            dt: Mat6::zeros(),
            p_big: Vec6::zeros(),
            p_small: Vec6::zeros(),
            u: Vec6::zeros(),
        }
    }
}

/// All buffers of the algorithms for one [`Model`] (Pinocchio-style
/// `Model`/`Data` split). Create once with [`Data::new`]; evaluations
/// write into it and allocate nothing.
#[derive(Clone, Debug)]
pub struct Data {
    pub(crate) pieces: Vec<Vec<PieceWork>>,
    /// Per-piece work of the planar path, for planar rods (empty for the
    /// others).
    pub(crate) planar: Vec<Vec<PlanarWork>>,
    /// Generalized force from the last [`crate::inverse_dynamics`] (n_dof).
    pub tau: DVector<f64>,
    /// Generalized acceleration from the last forward dynamics (n_dof).
    pub qdd: DVector<f64>,
    /// Mass matrix from the last [`crate::mass_matrix`] (n_dof × n_dof;
    /// allocated by the first call, empty before, so simulations that only
    /// use the O(N) recursion never hold an n_dof² matrix).
    pub mass: DMatrix<f64>,
    /// Strain-space forces scratch: `τ_act + τ_c − τ_e − D q̇` (n_dof).
    pub(crate) strain_force: DVector<f64>,
    /// Cable force per unit tension scratch (n_dof).
    pub(crate) cable_scratch: DVector<f64>,
    /// Cable tensions that replace the cables' schedules (the inputs `u`,
    /// one per cable in model order), set by [`Data::set_cable_tensions`].
    pub(crate) tensions: Option<DVector<f64>>,
    /// Joint actuator forces that replace the actuators' schedules (one per
    /// actuated coordinate, [`Model::n_joint_inputs`]), set by
    /// [`Data::set_joint_forces`] (IS14).
    pub(crate) joint_inputs: Option<DVector<f64>>,
    /// Per-node work space of an articulated model (empty otherwise).
    pub(crate) nodes: Vec<NodeWork>,
    /// World pose of every rod's base frame, from the last [`crate::frames`]
    /// (one per rod).
    pub rod_bases: Vec<Pose>,
    /// World pose of every body's frame, from the last [`crate::frames`]
    /// (one per body).
    pub body_poses: Vec<Pose>,
    /// Prescribed joint coordinates at [`Data::prescribed_time`]
    /// ([`Model::n_prescribed`] of them; D59), in rad or m.
    pub prescribed_q: DVector<f64>,
    /// Their rates.
    pub prescribed_qd: DVector<f64>,
    /// Their accelerations.
    pub prescribed_qdd: DVector<f64>,
    /// The time of the prescribed motion in use \[s\] (set by
    /// [`Model::set_time`] and by forward and inverse dynamics).
    pub prescribed_time: f64,
    /// The generalized force each prescribed coordinate needs (N or N·m)
    /// to follow its motion, from the last forward or inverse dynamics
    /// (D59).
    pub prescribed_force: DVector<f64>,
    /// Buffers of the constrained dynamics of a model with closures.
    pub(crate) closure: Option<ClosureWork>,
    /// Contact buffers and friction state (docs/theory-contact.md), only
    /// for models with contact.
    pub(crate) contact: Option<Box<crate::model::contact::ContactWork>>,
}

impl Data {
    /// Allocates the buffers for `model`.
    pub fn new(model: &Model) -> Self {
        let n = model.n_dof();
        let mut data = Self {
            pieces: model
                .rods()
                .iter()
                .map(|r| {
                    (0..r.spec.geometry.n_pieces())
                        .map(|_| PieceWork::new())
                        .collect()
                })
                .collect(),
            planar: model
                .rods()
                .iter()
                .map(|r| {
                    let n = if r.is_planar() {
                        r.spec.geometry.n_pieces()
                    } else {
                        0
                    };
                    (0..n).map(|_| PlanarWork::new()).collect()
                })
                .collect(),
            tau: DVector::zeros(n),
            qdd: DVector::zeros(n),
            mass: DMatrix::zeros(0, 0),
            strain_force: DVector::zeros(n),
            cable_scratch: DVector::zeros(n),
            tensions: None,
            joint_inputs: None,
            nodes: model.tree.as_ref().map_or(Vec::new(), |t| {
                (0..t.nodes.len()).map(|_| NodeWork::new()).collect()
            }),
            rod_bases: model
                .rods()
                .iter()
                .map(|r| *r.spec.geometry.base())
                .collect(),
            body_poses: vec![Pose::identity(); model.bodies().len()],
            prescribed_q: DVector::zeros(model.n_prescribed()),
            prescribed_qd: DVector::zeros(model.n_prescribed()),
            prescribed_qdd: DVector::zeros(model.n_prescribed()),
            prescribed_time: f64::NAN,
            prescribed_force: DVector::zeros(model.n_prescribed()),
            closure: model.has_closures().then(|| {
                ClosureWork::new(
                    n,
                    model.n_constraints(),
                    model.n_prescribed(),
                    model.tree.as_ref().map_or(0, |t| t.nodes.len()),
                )
            }),
            contact: model
                .has_contact()
                .then(|| Box::new(crate::model::contact::ContactWork::new(model))),
        };
        model.set_time(&mut data, 0.0);
        data
    }

    /// Sets the cable tensions `u` \[N\] (one per cable, in model order:
    /// rods in order, each rod's cables in order) that every evaluation
    /// with this `Data` uses instead of the cables' tension schedules — the
    /// inputs of a controller (D15: `τ_c = Σ_c u_c ∂ℓ_c/∂q`, still scaled by
    /// [`crate::Forces::load_scale`]). `None` goes back to the schedules.
    ///
    /// Errors: a length other than [`Model::n_cables`], or a tension that
    /// is negative or not finite (a cable can only pull).
    pub fn set_cable_tensions(
        &mut self,
        model: &Model,
        u: Option<&[f64]>,
    ) -> Result<(), DynamicsError> {
        let Some(u) = u else {
            self.tensions = None;
            return Ok(());
        };
        if u.len() != model.n_cables() {
            return Err(DynamicsError::TensionCount {
                got: u.len(),
                expected: model.n_cables(),
            });
        }
        if let Some((i, v)) = u
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(DynamicsError::InvalidTension {
                index: i,
                value: *v,
            });
        }
        match &mut self.tensions {
            Some(t) => t.as_mut_slice().copy_from_slice(u),
            None => self.tensions = Some(DVector::from_column_slice(u)),
        }
        Ok(())
    }

    /// Sets the joint actuators' forces \[N or N·m\] (one per actuated
    /// coordinate, in the order of [`Model::n_joint_inputs`]) that every
    /// evaluation with this `Data` uses instead of the actuators' schedules
    /// (docs/theory-control.md IS14; still scaled by
    /// [`crate::Forces::load_scale`]). `None` goes back to the schedules.
    ///
    /// Errors: a length other than [`Model::n_joint_inputs`], or a value
    /// that is not finite.
    pub fn set_joint_forces(
        &mut self,
        model: &Model,
        f: Option<&[f64]>,
    ) -> Result<(), DynamicsError> {
        let Some(f) = f else {
            self.joint_inputs = None;
            return Ok(());
        };
        if f.len() != model.n_joint_inputs() {
            return Err(DynamicsError::JointForceCount {
                got: f.len(),
                expected: model.n_joint_inputs(),
            });
        }
        if let Some((i, v)) = f.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(DynamicsError::NotFinite {
                what: format!("joint force f[{i}]"),
                value: *v,
            });
        }
        match &mut self.joint_inputs {
            Some(t) => t.as_mut_slice().copy_from_slice(f),
            None => self.joint_inputs = Some(DVector::from_column_slice(f)),
        }
        Ok(())
    }

    /// The joint forces set by [`Data::set_joint_forces`], if any.
    pub fn joint_forces(&self) -> Option<&[f64]> {
        self.joint_inputs.as_ref().map(|t| t.as_slice())
    }

    /// The map from the poses `softrod_kinematics` computes for rod `r`
    /// (which start at `Rod::base()`) to world poses, at the `q` of the last
    /// [`crate::frames`]: `rod_bases[r] · Rod::base()⁻¹` (D51); the identity
    /// for a rod clamped to the world.
    pub fn rod_to_world(&self, model: &Model, r: usize) -> Pose {
        self.rod_bases[r].compose(&model.rods()[r].spec.geometry.base().inverse())
    }

    /// The tensions set by [`Data::set_cable_tensions`], if any.
    pub fn cable_tensions(&self) -> Option<&[f64]> {
        self.tensions.as_ref().map(|t| t.as_slice())
    }

    /// Takes `other`'s friction state (the anchors of sticking contacts,
    /// CT5, committed after accepted steps) so that forces evaluated with
    /// this workspace are the forces of `other`'s run: e.g. a monitor that
    /// keeps its own `Data` for the same model. Nothing without contact;
    /// `other` must be a workspace of the same model.
    pub fn copy_friction_state_from(&mut self, other: &Data) {
        if let (Some(a), Some(b)) = (&mut self.contact, &other.contact) {
            a.copy_friction_state(b);
        }
    }

    /// Forgets the contact state that runs and statics commit to this
    /// workspace — the friction anchors (docs/theory-contact.md CT5) and
    /// the raised stiffness scales and offsets (CT15) of obstacle and
    /// rod–rod contacts — so that the next evaluation sees the contact
    /// state of a fresh workspace: the base stiffness of CT3, no friction
    /// history. A run or a statics solve that starts from a scene's
    /// initial state calls it first (CT15); a continuation (the next step
    /// of a run) must not. Nothing without contact; no allocation.
    pub fn reset_contact(&mut self) {
        if let Some(c) = &mut self.contact {
            c.reset_friction_state();
        }
    }

    /// Tension of cable `c` of rod `rm` at time `t` \[N\]: the override
    /// when set, else the cable's schedule (without the load factor).
    #[inline]
    pub(crate) fn tension(&self, rm: &RodModel, c: usize, t: f64) -> f64 {
        cable_tension(self.tensions.as_ref(), rm, c, t)
    }
}

/// Tension of cable `c` of rod `rm` at time `t` \[N\]: `u[cable_offset + c]`
/// when inputs are given, else the cable's schedule.
#[inline]
pub(crate) fn cable_tension(u: Option<&DVector<f64>>, rm: &RodModel, c: usize, t: f64) -> f64 {
    match u {
        Some(u) => u[rm.cable_offset + c],
        None => rm.spec.cables[c].tension_at(t),
    }
}

/// Per-node work space (all fixed-size).
#[derive(Clone, Debug)]
pub(crate) struct NodeWork {
    /// World pose of the node's base frame.
    pub base_world: Pose,
    /// Local tip pose `g(ℓ)`, `S(ℓ) = T₋(ℓ)B` (6×k padded), the tip's
    /// velocity-product acceleration.
    pub tip: Pose,
    pub s_tip: Mat6,
    pub acc_tip: Vec6,
    /// Velocity and acceleration of the tip frame (tip axes).
    pub eta_tip: Vec6,
    pub etadot_tip: Vec6,
    /// (D20) `𝓜ᵗ = Σ wAᵀ𝓜A`, `𝓤 = Σ wAᵀ𝓜S`, `𝓓 = Σ wSᵀ𝓜S` of the node's
    /// own mass; (D23/D17) bias sums `𝓟ᵗ` (6) and `𝓹 = Bᵀ Σ T₋ᵀ f` (k).
    pub mt: Mat6,
    pub ut: Mat6,
    pub dt: Mat6,
    /// The shifted factorization with non-symmetric contact blocks (CT26):
    /// `𝓤` of the transposed blocks (the node's rows against the parent's
    /// columns), and `Û_L`, its articulated counterpart used by the
    /// solve's outward pass (equal to `Û` when the matrix is symmetric).
    pub ul: Mat6,
    pub uhat_l: Mat6,
    pub p_big: Vec6,
    pub p_small: Vec6,
    /// What the children hand to the tip (tip axes): articulated or
    /// composite inertia, and bias or transmitted wrench.
    pub m_tip: Mat6,
    pub f_tip: Vec6,
    /// Forward dynamics: `Û`, `D̂⁻¹` (k×k padded), `u` (k).
    pub uhat: Mat6,
    pub dinv: Mat6,
    pub u: Vec6,
    /// Mass matrix: `Ad_{g_world(ℓ)} S(ℓ)` (world twists per unit rate).
    pub s_world: Mat6,
    /// A node hanging inside its parent piece at `x` (D62): the parent's
    /// `g(x)`, `Ad⁻¹_{g(x)}`, `S(x) = T₋(x)B` (6×k padded), the
    /// velocity-product acceleration there and the motion of that frame
    /// (its axes), all written by the parent's outward step.
    pub attach_pose: Pose,
    pub attach_a: Mat6,
    pub attach_s: Mat6,
    pub attach_acc: Vec6,
    pub attach_eta: Vec6,
    pub attach_etadot: Vec6,
    /// Forward dynamics pass 3: the base acceleration and `q̈_n` (padded).
    pub etadot_base: Vec6,
    pub qn: Vec6,
}

impl NodeWork {
    pub(crate) fn new() -> Self {
        Self {
            base_world: Pose::identity(),
            tip: Pose::identity(),
            s_tip: Mat6::zeros(),
            acc_tip: Vec6::zeros(),
            eta_tip: Vec6::zeros(),
            etadot_tip: Vec6::zeros(),
            mt: Mat6::zeros(),
            ut: Mat6::zeros(),
            dt: Mat6::zeros(),
            ul: Mat6::zeros(),
            uhat_l: Mat6::zeros(),
            p_big: Vec6::zeros(),
            p_small: Vec6::zeros(),
            m_tip: Mat6::zeros(),
            f_tip: Vec6::zeros(),
            uhat: Mat6::zeros(),
            dinv: Mat6::zeros(),
            u: Vec6::zeros(),
            s_world: Mat6::zeros(),
            attach_pose: Pose::identity(),
            attach_a: Mat6::identity(),
            attach_s: Mat6::zeros(),
            attach_acc: Vec6::zeros(),
            attach_eta: Vec6::zeros(),
            attach_etadot: Vec6::zeros(),
            etadot_base: Vec6::zeros(),
            qn: Vec6::zeros(),
        }
    }
}

/// Per-piece work of the planar path (the 3×3 counterparts of
/// `PieceWork`'s forward-dynamics fields).
#[derive(Clone, Debug)]
pub(crate) struct PlanarWork {
    pub(crate) tip: Pose2,
    pub(crate) tm_tip: Mat3,
    pub(crate) acc_tip: Vec3,
    pub(crate) p_big: Vec3,
    pub(crate) p_small: Vec3,
    /// `𝓤ᶠ = ∫Aᵀ𝓜T₋` (3×3), then `W = ÛL⁻ᵀ` in its first `k` columns.
    pub(crate) ut: Mat3,
    /// `𝓓ᶠ = ∫T₋ᵀ𝓜T₋` (3×3), then the factor `L` of `D̂` (k×k).
    pub(crate) dt: Mat3,
    pub(crate) mt: Mat3,
    pub(crate) u: Vec3,
}

impl PlanarWork {
    pub(crate) fn new() -> Self {
        Self {
            tip: Pose2::IDENTITY,
            tm_tip: Mat3::zeros(),
            acc_tip: Vec3::zeros(),
            p_big: Vec3::zeros(),
            p_small: Vec3::zeros(),
            ut: Mat3::zeros(),
            dt: Mat3::zeros(),
            mt: Mat3::zeros(),
            u: Vec3::zeros(),
        }
    }
}

/// Per-node scratch of the tree's shifted solve: what the children hand
/// to the node (at its tip, or inside it at `x`, D62) and the outward
/// motion.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SolveNode {
    pub(crate) f_tip: Vec6,
    pub(crate) p_big: Vec6,
    pub(crate) p_small: Vec6,
    pub(crate) u: Vec6,
    pub(crate) etadot_base: Vec6,
    pub(crate) etadot_tip: Vec6,
    pub(crate) qn: Vec6,
}

/// The stacked rows of a model's closures at one state (D63–D65): the
/// residual `φ` (m), the Jacobian `J` (m×n; exact `∂φ/∂q` or the velocity
/// rows) and the velocity product `J̇q̇` (m).
#[derive(Clone, Debug)]
pub(crate) struct ConstraintRows {
    pub phi: DVector<f64>,
    pub jac: DMatrix<f64>,
    pub jdot_qd: DVector<f64>,
}

impl ConstraintRows {
    /// Zero rows for `m` constraints on `n` coordinates.
    pub(crate) fn new(m: usize, n: usize) -> Self {
        Self {
            phi: DVector::zeros(m),
            jac: DMatrix::zeros(m, n),
            jdot_qd: DVector::zeros(m),
        }
    }
}

/// Buffers of the constrained forward dynamics (allocated once, in
/// [`Data::new`], for a model with closures).
#[derive(Clone, Debug)]
pub(crate) struct ClosureWork {
    /// `φ`, the velocity rows `J` and `J̇q̇` of the last evaluation.
    pub rows: ConstraintRows,
    /// Per-node scratch of the O(N) solves with `M`, `Y = M⁻¹Jᵀ` (n×m),
    /// `A = J M⁻¹ Jᵀ` (m×m, factored in place), right side and multipliers.
    pub solve: Vec<SolveNode>,
    pub y: DMatrix<f64>,
    pub a: DMatrix<f64>,
    pub rhs: DVector<f64>,
    pub lambda: DVector<f64>,
    pub scratch: DVector<f64>,
    pub perm: Vec<usize>,
    /// Numerical rank of `A` at the last evaluation.
    pub rank: usize,
    /// With prescribed joints (D59): the constraint rows' columns of the
    /// prescribed coordinates `J_p` (m×n_p), and a copy of `q̈` (n).
    pub jac_p: DMatrix<f64>,
    pub qdd: DVector<f64>,
    /// The last correction of a projection onto the closures (n, D121).
    pub step: DVector<f64>,
}

impl ClosureWork {
    pub(crate) fn new(n: usize, m: usize, n_p: usize, nodes: usize) -> Self {
        Self {
            solve: vec![SolveNode::default(); nodes],
            jac_p: DMatrix::zeros(m, n_p),
            qdd: DVector::zeros(if n_p > 0 { n } else { 0 }),
            step: DVector::zeros(n),
            rows: ConstraintRows::new(m, n),
            y: DMatrix::zeros(n, m),
            a: DMatrix::zeros(m, m),
            rhs: DVector::zeros(m),
            lambda: DVector::zeros(m),
            scratch: DVector::zeros(m.max(n)),
            perm: (0..m).collect(),
            rank: m,
        }
    }
}
