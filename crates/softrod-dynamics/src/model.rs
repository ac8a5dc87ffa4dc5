//! The immutable description of what is simulated.

use crate::builder::{ModelBuilder, RodSpecBuilder};
use crate::error::{DynamicsError, RodId};
use crate::joint::{Attachment, BodySpec};
use crate::tree::Tree;
use nalgebra::DMatrix;
use softrod_kinematics::{GaussLegendre, Rod, Strain};
use softrod_lie::{Mat6, Vec3, Vec6};
use softrod_mechanics::{
    Cable, DistributedLoad, Drag, LoadFrame, PointLoad, RodBody, piece_matrices,
};

/// Everything about one rod: its geometry and strain bases, its body
/// (section + material), and the force terms acting on it. Only the terms
/// present are evaluated (an empty `cables` list costs nothing).
///
/// Build one with [`RodSpec::builder`] (the length given once), or from its
/// parts with [`RodSpec::new`]. The fields are public; [`Model::new`]
/// checks them ([`RodSpec::validate`]) when the rod enters a model.
///
/// ```
/// use softrod_dynamics::RodSpec;
/// use softrod_kinematics::Strain;
/// use softrod_mechanics::Material;
///
/// let silicone = Material::builder()
///     .density(1000.0)
///     .young(1.0e6)
///     .poisson(0.5)
///     .build()
///     .unwrap();
/// let arm = RodSpec::builder(0.5)
///     .name("arm")
///     .pieces(8)
///     .strains([Strain::Ky, Strain::Qx, Strain::Qz])
///     .circle(0.01)
///     .material(silicone)
///     .build()
///     .unwrap();
/// assert_eq!(arm.rod.n_dof(), 24);
/// assert!(RodSpec::builder(-0.5).circle(0.01).material(silicone).build().is_err());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct RodSpec {
    /// A name for messages and outputs.
    pub name: String,
    /// Pieces, bases, rest strain, base pose.
    pub rod: Rod,
    /// Section and material.
    pub body: RodBody,
    /// Stress-free strain `ξ*_n` per piece when it differs from the rest
    /// strain `ξ̄_n` (the strain at `q = 0`); `None`: `ξ* = ξ̄`.
    pub stress_free: Option<Vec<Vec6>>,
    /// Point loads (dead or follower), any `s`, including the tip.
    pub point_loads: Vec<PointLoad>,
    /// Uniformly distributed loads.
    pub distributed_loads: Vec<DistributedLoad>,
    /// Linear viscous drag of a surrounding fluid.
    pub drag: Option<Drag>,
    /// Cables (tendons) routed along this rod.
    pub cables: Vec<Cable>,
}

impl RodSpec {
    /// A builder for a rod of undeformed length `length` \[m\] (see
    /// [`RodSpecBuilder`]).
    pub fn builder(length: f64) -> RodSpecBuilder {
        RodSpecBuilder::new(length)
    }

    /// A rod with no loads, cables or drag, from its kinematic rod and body
    /// (which must have the same length).
    pub fn new(name: impl Into<String>, rod: Rod, body: RodBody) -> Self {
        Self {
            name: name.into(),
            rod,
            body,
            stress_free: None,
            point_loads: Vec::new(),
            distributed_loads: Vec::new(),
            drag: None,
            cables: Vec::new(),
        }
    }

    /// Checks what the public fields may have put together inconsistently:
    /// body and rod lengths, one finite stress-free strain per piece, the
    /// drag, every cable, point and distributed load on this rod. (The rod
    /// and the body are valid by construction.)
    pub fn validate(&self) -> Result<(), DynamicsError> {
        self.check(None)
    }

    pub(crate) fn id(&self, index: Option<usize>) -> RodId {
        RodId {
            index,
            name: self.name.clone(),
        }
    }

    pub(crate) fn check(&self, index: Option<usize>) -> Result<(), DynamicsError> {
        let rod = || self.id(index);
        let length = self.rod.length();
        self.body
            .check_rod(&self.rod)
            .map_err(|source| DynamicsError::RodBody { rod: rod(), source })?;
        if let Some(sf) = &self.stress_free {
            if sf.len() != self.rod.n_pieces() {
                return Err(DynamicsError::StressFreeCount {
                    rod: rod(),
                    got: sf.len(),
                    expected: self.rod.n_pieces(),
                });
            }
            for (piece, xi) in sf.iter().enumerate() {
                if let Some((c, &value)) = xi.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                    return Err(DynamicsError::StressFreeNotFinite {
                        rod: rod(),
                        piece,
                        component: Strain::ALL[c],
                        value,
                    });
                }
            }
        }
        if let Some(d) = &self.drag {
            d.validate()
                .map_err(|source| DynamicsError::Drag { rod: rod(), source })?;
        }
        for (cable, c) in self.cables.iter().enumerate() {
            c.validate(length).map_err(|source| DynamicsError::Cable {
                rod: rod(),
                cable,
                source,
            })?;
        }
        for (load, l) in self.point_loads.iter().enumerate() {
            l.validate(length)
                .map_err(|source| DynamicsError::PointLoad {
                    rod: rod(),
                    load,
                    source,
                })?;
        }
        for (load, l) in self.distributed_loads.iter().enumerate() {
            l.validate()
                .map_err(|source| DynamicsError::DistributedLoad {
                    rod: rod(),
                    load,
                    source,
                })?;
        }
        Ok(())
    }
}

/// One evaluation point of a piece: local abscissa, weight and the diagonal
/// of the screw inertia `𝓜` there.
#[derive(Clone, Copy, Debug)]
pub(crate) struct QuadPoint {
    pub x: f64,
    pub w: f64,
    pub inertia: Vec6,
    pub mass_per_length: f64,
}

/// A point load placed on its piece.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PlacedLoad {
    pub x: f64,
    pub index: usize,
}

/// Precomputed per-piece data of a rod.
#[derive(Clone, Debug)]
pub(crate) struct PieceData {
    pub points: Vec<QuadPoint>,
    pub loads: Vec<PlacedLoad>,
    /// `K_n` (k×k), `D_n` (k×k).
    pub stiffness: DMatrix<f64>,
    pub damping: DMatrix<f64>,
    pub has_damping: bool,
    pub has_offset: bool,
    /// `K_n`, `D_n` and the elastic offset `∫Bᵀ Γ (ξ̄ − ξ*)` (k), zero-padded
    /// to fixed size for the per-evaluation strain forces (no heap indexing
    /// in the hot loop).
    pub stiffness6: Mat6,
    pub damping6: Mat6,
    /// The diagonals of `stiffness6`, `damping6` when both are diagonal
    /// (every piece whose basis selects strains of a diagonal `Γ`): the
    /// strain forces then cost 12 multiplications instead of 72.
    pub diagonal: Option<(Vec6, Vec6)>,
    pub offset6: Vec6,
}

/// A rod inside a [`Model`], with precomputed piece data.
#[derive(Clone, Debug)]
pub struct RodModel {
    /// The description it was built from.
    pub spec: RodSpec,
    /// Index of the rod's first coordinate in the model's `q`.
    pub dof_offset: usize,
    pub(crate) pieces: Vec<PieceData>,
    /// Whether world poses at evaluation points are needed (world-frame
    /// distributed loads, gravity potential).
    pub(crate) needs_world_pose_at_points: bool,
    /// Index of the rod's first cable among the model's cables (the order
    /// of the inputs `u`).
    pub cable_offset: usize,
    /// The rod's planar description when it qualifies for the se(2) path
    /// of the forward and inverse dynamics (docs/theory.md §13, D71).
    pub(crate) planar: Option<crate::planar::PlanarRod>,
}

impl RodModel {
    /// Number of coordinates of this rod.
    pub fn n_dof(&self) -> usize {
        self.spec.rod.n_dof()
    }

    /// Range of this rod's coordinates in the model's `q`.
    pub fn dofs(&self) -> std::ops::Range<usize> {
        self.dof_offset..self.dof_offset + self.n_dof()
    }

    /// Whether the rod is planar (D71): every piece selects strains among
    /// `κ_a, q_b, q_c` for one bending axis `a` (`(a, b, c)` cyclic, e.g.
    /// `ky, qz, qx`) and its rest strain has no other component. The
    /// forward dynamics of such a rod, clamped alone (no joints, bodies or
    /// parents), runs on 3-vectors and 3×3 blocks (docs/theory.md §13)
    /// unless [`Model::with_planar_path`] turned that off.
    pub fn is_planar(&self) -> bool {
        self.planar.is_some()
    }
}

/// The immutable model: rods (each an independent chain clamped at its own
/// base), world gravity, quadrature order, and the force terms of each rod.
///
/// Generalized coordinates are the concatenation of the rods' `q`
/// (`n_dof = Σ_rods Σ_n k_n`).
///
/// Nothing of a built model changes: its parts are read through
/// accessors, and a variant is a new model ([`Model::with_gravity`],
/// [`Model::with_quadrature`], [`Model::with_closures`],
/// [`Model::with_planar_path`]) — what was precomputed from them stays
/// consistent.
#[derive(Clone, Debug)]
pub struct Model {
    pub(crate) rods: Vec<RodModel>,
    /// World gravity `g_w` [m/s²], `None` if absent.
    pub(crate) gravity: Option<Vec3>,
    /// Gauss points per piece.
    pub(crate) quadrature: GaussLegendre,
    n_dof: usize,
    n_prescribed: usize,
    pub(crate) bodies: Vec<BodyModel>,
    pub(crate) elements: Vec<ElementInfo>,
    /// The tree of nodes of a model with joints, bodies or parents (`None`:
    /// independent rods clamped to the world, the chain path).
    pub(crate) tree: Option<Tree>,
    /// Loop closures on the tree (D63); empty for open models.
    pub(crate) closures: Vec<crate::closure::ResolvedClosure>,
    /// Baumgarte rate `α = β` of the constrained dynamics \[1/s\] (D68).
    pub(crate) baumgarte: f64,
    /// Whether the forward dynamics takes the planar path for planar rods
    /// (default on).
    pub(crate) planar_path: bool,
}

impl Model {
    /// Gauss points per piece when none are asked for: 4 integrate
    /// polynomials of degree 7 exactly, the inertia of a uniform piece to
    /// ~1e-10 for curvatures up to a few rad per piece length.
    pub const DEFAULT_QUADRATURE: usize = 4;

    /// A builder: rods, gravity, quadrature (see [`ModelBuilder`]).
    pub fn builder() -> ModelBuilder {
        ModelBuilder::default()
    }

    /// Builds a model; checks every rod ([`RodSpec::validate`], errors name
    /// the rod by index and name) and precomputes `K_n`, `D_n` (D13), the
    /// quadrature points with their inertia, and the placement of point
    /// loads on pieces.
    ///
    /// `gravity` is the world acceleration `g_w` [m/s²] (`None` or zero: no
    /// gravity term); `quadrature` the number of Gauss–Legendre points per
    /// piece (≥ 1; see [`Self::DEFAULT_QUADRATURE`]).
    pub fn new(
        rods: Vec<RodSpec>,
        gravity: Option<Vec3>,
        quadrature: usize,
    ) -> Result<Self, DynamicsError> {
        if rods.is_empty() {
            return Err(DynamicsError::NoRods);
        }
        Self::with_elements(
            rods.into_iter()
                .map(|r| Element::Rod(r, Attachment::world()))
                .collect(),
            gravity,
            quadrature,
        )
    }

    /// Builds a model of rods and rigid bodies, each hanging from a parent
    /// (the world, a rod, a body) through a joint (docs/theory.md §11,
    /// D50–D55). Coordinates follow the elements' order: for each, its
    /// joint's coordinates, then (rods) its strains piece by piece.
    ///
    /// A child of a rod attaches anywhere on it (`at` in `[0, L]`, default
    /// the tip; inside a piece as D62 describes): its frame is the rod's
    /// frame there, then the element's base pose, then the joint.
    /// Without any body, parent or non-fixed joint this is [`Model::new`]
    /// and the algorithms take the chain path unchanged.
    ///
    /// Errors: those of [`Model::new`], invalid joints and bodies, unknown
    /// or ambiguous parents, parent cycles, `at` off the parent rod.
    pub fn with_elements(
        elements: Vec<Element>,
        gravity: Option<Vec3>,
        quadrature: usize,
    ) -> Result<Self, DynamicsError> {
        // Every output names the first rod's tip: a model needs one.
        if !elements.iter().any(|e| matches!(e, Element::Rod(..))) {
            return Err(DynamicsError::NoRods);
        }
        if quadrature == 0 {
            return Err(DynamicsError::NoQuadraturePoints);
        }
        let gravity = checked_gravity(gravity)?;
        let gl = GaussLegendre::new(quadrature);
        let mut rods = Vec::new();
        let mut bodies = Vec::new();
        let mut infos = Vec::with_capacity(elements.len());
        let mut off = 0;
        let mut pres = 0;
        let mut cables = 0;
        for element in elements {
            match element {
                Element::Rod(spec, mut attachment) => {
                    attachment.joint.validate(&spec.name)?;
                    let jd = attachment.joint.dof();
                    let pd = attachment.joint.prescribed_dof();
                    let index = rods.len();
                    let rm = build_rod(spec, index, off + jd, cables, &gl)?;
                    infos.push(ElementInfo {
                        name: rm.spec.name.clone(),
                        kind: ElementKind::Rod(index),
                        attachment,
                        joint_dofs: off..off + jd,
                        prescribed_dofs: pres..pres + pd,
                    });
                    pres += pd;
                    off += jd + rm.n_dof();
                    cables += rm.spec.cables.len();
                    rods.push(rm);
                }
                Element::Body(spec, mut attachment) => {
                    spec.validate()?;
                    attachment.joint.validate(&spec.name)?;
                    let jd = attachment.joint.dof();
                    let pd = attachment.joint.prescribed_dof();
                    infos.push(ElementInfo {
                        name: spec.name.clone(),
                        kind: ElementKind::Body(bodies.len()),
                        attachment,
                        joint_dofs: off..off + jd,
                        prescribed_dofs: pres..pres + pd,
                    });
                    pres += pd;
                    off += jd;
                    bodies.push(BodyModel {
                        inertia: spec.spatial_inertia(),
                        spec,
                    });
                }
            }
        }
        let articulated =
            !bodies.is_empty() || infos.iter().any(|e| !e.attachment.is_world_clamp());
        let mut model = Self {
            rods,
            gravity,
            quadrature: gl,
            n_dof: off,
            n_prescribed: pres,
            bodies,
            elements: infos,
            tree: None,
            closures: Vec::new(),
            baumgarte: 0.0,
            planar_path: true,
        };
        if articulated {
            model.tree = Some(Tree::build(&model)?);
        }
        Ok(model)
    }

    /// Closure residual tolerance relative to the model's length scale
    /// (its longest rod): a closure whose residual norm `max(‖d‖, ℓ‖r‖)`
    /// exceeds `1e-9 ℓ` at the initial state does not hold (D66).
    pub const CLOSURE_TOLERANCE: f64 = 1e-9;

    /// This model with loop closures (docs/theory.md §11, D63–D69): each
    /// frame names a rod (at any `s`, default its tip), a body or the
    /// world. The model takes the tree path from then on (built here if
    /// every rod was clamped to the world). Replaces any closures given
    /// before.
    ///
    /// Errors: an unknown or ambiguous element, `at` outside `[0, L]`, a
    /// base pose that is not a rigid motion, a zero or non-finite slider
    /// axis, both ends on the world — each naming the closure.
    pub fn with_closures(mut self, closures: Vec<crate::Closure>) -> Result<Self, DynamicsError> {
        self.closures = Vec::new();
        if closures.is_empty() {
            return Ok(self);
        }
        if self.tree.is_none() {
            self.tree = Some(Tree::build(&self)?);
        }
        self.closures = crate::closure::resolve(&self, closures)?;
        self.baumgarte = crate::constrained::baumgarte_rate(&self);
        Ok(self)
    }

    /// The closures, as given (slider axes normalized).
    pub fn closures(&self) -> impl Iterator<Item = &crate::Closure> {
        self.closures.iter().map(|c| &c.spec)
    }

    /// Number of scalar closure constraints `m` (6 per weld, 3 per ball, 2
    /// per slider).
    pub fn n_constraints(&self) -> usize {
        self.closures
            .iter()
            .map(|c| c.spec.kind.n_constraints())
            .sum()
    }

    /// Whether the model has loop closures.
    pub fn has_closures(&self) -> bool {
        !self.closures.is_empty()
    }

    /// The Baumgarte rate `α = β` \[1/s\] of the constrained dynamics
    /// (D68; 0 without closures).
    pub fn baumgarte_rate(&self) -> f64 {
        self.baumgarte
    }

    /// Total number of generalized coordinates.
    pub fn n_dof(&self) -> usize {
        self.n_dof
    }

    /// Number of prescribed joint coordinates (D59): given functions of
    /// time, not in `q`; their forces are an output
    /// ([`crate::Data::prescribed_force`]).
    pub fn n_prescribed(&self) -> usize {
        self.n_prescribed
    }

    /// Evaluates every prescribed coordinate at `t` \[s\] into `data`
    /// (values, rates, accelerations), so that the algorithms that take no
    /// time ([`crate::mass_matrix`], [`crate::energies`], [`crate::frames`])
    /// see the configuration at `t`. Forward and inverse dynamics do this
    /// themselves. A no-op without prescribed joints.
    pub fn set_time(&self, data: &mut crate::Data, t: f64) {
        if self.n_prescribed == 0 {
            return;
        }
        self.prescribed_values(
            t,
            data.prescribed_q.as_mut_slice(),
            data.prescribed_qd.as_mut_slice(),
            data.prescribed_qdd.as_mut_slice(),
        );
        data.prescribed_time = t;
    }

    /// The prescribed joints' values, rates and accelerations at `t` (D59;
    /// each of length [`Model::n_prescribed`]).
    pub(crate) fn prescribed_values(&self, t: f64, q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) {
        for e in &self.elements {
            if let Some(p) = &e.attachment.joint.prescribed {
                let r = e.prescribed_dofs.clone();
                p.eval_into(t, &mut q[r.clone()], &mut qd[r.clone()], &mut qdd[r]);
            }
        }
    }

    /// The rods.
    pub fn rods(&self) -> &[RodModel] {
        &self.rods
    }

    /// World gravity `g_w` \[m/s²\], `None` if absent (or given as zero).
    pub fn gravity(&self) -> Option<Vec3> {
        self.gravity
    }

    /// The Gauss–Legendre rule on each piece ([`GaussLegendre::len`] points).
    pub fn quadrature(&self) -> &GaussLegendre {
        &self.quadrature
    }

    /// The same model under another world gravity `g_w` \[m/s²\] (`None`
    /// or zero: none). Errors: a component that is not finite.
    pub fn with_gravity(mut self, gravity: Option<Vec3>) -> Result<Self, DynamicsError> {
        self.gravity = checked_gravity(gravity)?;
        Ok(self)
    }

    /// The same model with `points` Gauss–Legendre points per piece (≥ 1):
    /// every rod's quadrature points, their inertia, the placement of its
    /// point loads and its `K_n`, `D_n` are computed again.
    pub fn with_quadrature(mut self, points: usize) -> Result<Self, DynamicsError> {
        if points == 0 {
            return Err(DynamicsError::NoQuadraturePoints);
        }
        let gl = GaussLegendre::new(points);
        self.rods = std::mem::take(&mut self.rods)
            .into_iter()
            .enumerate()
            .map(|(i, r)| build_rod(r.spec, i, r.dof_offset, r.cable_offset, &gl))
            .collect::<Result<_, _>>()?;
        self.quadrature = gl;
        Ok(self)
    }

    /// The rigid bodies, in the order given.
    pub fn bodies(&self) -> &[BodyModel] {
        &self.bodies
    }

    /// Every element (rods and bodies in the order given) with its
    /// attachment and the range of its joint's coordinates in `q`.
    pub fn elements(&self) -> &[ElementInfo] {
        &self.elements
    }

    /// The same model with the planar path of the forward dynamics on
    /// (the default) or off: off, planar rods take the general se(3) path
    /// — the cross-check of docs/validation.md and the baseline of the
    /// planar benchmarks. Results agree to rounding.
    pub fn with_planar_path(mut self, on: bool) -> Self {
        self.planar_path = on;
        self
    }

    /// Whether [`crate::forward_dynamics`] runs rod `rod` on the planar
    /// path (D71–D75): a planar rod ([`RodModel::is_planar`]) of a model
    /// without joints, bodies or parents, the path on.
    pub fn uses_planar_path(&self, rod: usize) -> bool {
        self.planar_path && self.tree.is_none() && self.rods.get(rod).is_some_and(|r| r.is_planar())
    }

    /// Whether the model has joints, bodies or parents (the tree path of
    /// the algorithms) rather than independent rods clamped to the world.
    pub fn is_articulated(&self) -> bool {
        self.tree.is_some()
    }

    /// [`DynamicsError::Unsupported`] for an algorithm that covers only
    /// independent clamped rods, called on an articulated model.
    pub(crate) fn require_chain(&self, what: &'static str) -> Result<(), DynamicsError> {
        if self.tree.is_some() {
            return Err(DynamicsError::Unsupported { what });
        }
        Ok(())
    }

    /// Names of the force terms present, for summaries (`softrod check`).
    pub fn terms(&self) -> Vec<String> {
        let mut t = vec!["inertia".to_string(), "elasticity".to_string()];
        let any = |f: &dyn Fn(&RodModel) -> bool| self.rods.iter().any(f);
        if any(&|r| r.pieces.iter().any(|p| p.has_damping)) {
            t.push("damping".into());
        }
        if self.gravity.is_some() {
            t.push("gravity".into());
        }
        if any(&|r| !r.spec.cables.is_empty()) {
            t.push("cables".into());
        }
        if any(&|r| !r.spec.point_loads.is_empty()) {
            t.push("point loads".into());
        }
        if any(&|r| !r.spec.distributed_loads.is_empty()) {
            t.push("distributed loads".into());
        }
        if any(&|r| r.spec.drag.is_some()) {
            t.push("drag".into());
        }
        if !self.bodies.is_empty() {
            t.push("rigid bodies".into());
        }
        if self.bodies.iter().any(|b| !b.spec.loads.is_empty()) {
            t.push("body loads".into());
        }
        if self.n_prescribed > 0 {
            t.push("prescribed joints".into());
        }
        if !self.closures.is_empty() {
            t.push("closures".into());
        }
        if self.elements.iter().any(|e| e.attachment.joint.dof() > 0) {
            t.push("joints".into());
        }
        if self.elements.iter().any(|e| {
            let j = &e.attachment.joint;
            j.stiffness.iter().chain(&j.damping).any(|v| *v != 0.0)
        }) {
            t.push("joint springs".into());
        }
        t
    }

    /// Number of cables over all rods (columns of the actuation matrix).
    pub fn n_cables(&self) -> usize {
        self.rods.iter().map(|r| r.spec.cables.len()).sum()
    }
}

/// Gravity as the model keeps it: every component finite, zero as `None`.
fn checked_gravity(gravity: Option<Vec3>) -> Result<Option<Vec3>, DynamicsError> {
    if let Some(g) = gravity {
        if let Some((component, &value)) = g.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(DynamicsError::GravityNotFinite { component, value });
        }
    }
    Ok(gravity.filter(|g| g.norm() > 0.0))
}

/// Checks one rod and precomputes its pieces (`K_n`, `D_n`, quadrature
/// points, placed point loads).
fn build_rod(
    spec: RodSpec,
    index: usize,
    dof_offset: usize,
    cable_offset: usize,
    gl: &GaussLegendre,
) -> Result<RodModel, DynamicsError> {
    spec.check(Some(index))?;
    let rod = &spec.rod;
    let mats = piece_matrices(rod, &spec.body, spec.stress_free.as_deref(), gl);
    let mut pieces = Vec::with_capacity(rod.n_pieces());
    for (n, (piece, m)) in rod.pieces().iter().zip(mats).enumerate() {
        let points = gl
            .on_interval(piece.length)
            .map(|(x, w)| {
                let s = piece.start + x;
                QuadPoint {
                    x,
                    w,
                    inertia: spec.body.screw_inertia(s),
                    mass_per_length: spec.body.mass_per_length(s),
                }
            })
            .collect();
        let mut loads = Vec::new();
        for (i, l) in spec.point_loads.iter().enumerate() {
            let (pn, x) = rod.locate(l.s).expect("PointLoad::validate checked s");
            if pn == n {
                loads.push(PlacedLoad { x, index: i });
            }
        }
        let k = m.stiffness.nrows();
        let pad =
            |d: &DMatrix<f64>| Mat6::from_fn(|i, j| if i < k && j < k { d[(i, j)] } else { 0.0 });
        let (stiffness6, damping6) = (pad(&m.stiffness), pad(&m.damping));
        let off_diagonal_zero =
            |a: &Mat6| (0..6).all(|i| (0..6).all(|j| i == j || a[(i, j)] == 0.0));
        let diagonal = (off_diagonal_zero(&stiffness6) && off_diagonal_zero(&damping6))
            .then(|| (stiffness6.diagonal(), damping6.diagonal()));
        pieces.push(PieceData {
            points,
            loads,
            stiffness6,
            damping6,
            diagonal,
            offset6: Vec6::from_fn(|i, _| if i < k { m.elastic_offset[i] } else { 0.0 }),
            has_damping: m.damping.iter().any(|v| *v != 0.0),
            has_offset: m.elastic_offset.iter().any(|v| *v != 0.0),
            stiffness: m.stiffness,
            damping: m.damping,
        });
    }
    let needs_world = spec
        .distributed_loads
        .iter()
        .any(|d| d.frame == LoadFrame::World);
    let planar = crate::planar::PlanarRod::detect(&spec, &pieces);
    Ok(RodModel {
        spec,
        dof_offset,
        pieces,
        needs_world_pose_at_points: needs_world,
        cable_offset,
        planar,
    })
}

/// An element of a model given to [`Model::with_elements`]: a rod or a
/// rigid body, with where it hangs.
#[derive(Clone, Debug, PartialEq)]
pub enum Element {
    /// A rod; its base pose ([`softrod_kinematics::Rod::base`]) is relative
    /// to the attachment frame.
    Rod(RodSpec, Attachment),
    /// A rigid body.
    Body(BodySpec, Attachment),
}

/// What an element of a [`Model`] is: the index among the model's rods or
/// bodies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementKind {
    /// Index in [`Model::rods`].
    Rod(usize),
    /// Index in [`Model::bodies`].
    Body(usize),
}

/// An element of a [`Model`] as built: name, kind, attachment (the joint's
/// axes normalized) and its joint's coordinates in `q`.
#[derive(Clone, Debug, PartialEq)]
pub struct ElementInfo {
    /// The element's name.
    pub name: String,
    /// Rod or body, and its index.
    pub kind: ElementKind,
    /// Parent, `at`, joint.
    pub attachment: Attachment,
    /// Range of the joint's coordinates in `q` (empty for a fixed or a
    /// prescribed joint).
    pub joint_dofs: std::ops::Range<usize>,
    /// Range of a prescribed joint's coordinates among the model's
    /// prescribed coordinates ([`Model::n_prescribed`]; empty otherwise).
    pub prescribed_dofs: std::ops::Range<usize>,
}

/// A rigid body inside a [`Model`].
#[derive(Clone, Debug, PartialEq)]
pub struct BodyModel {
    /// The description it was built from.
    pub spec: BodySpec,
    /// Its screw inertia at the body frame (D52).
    pub inertia: Mat6,
}
