//! Floor 1, the model: the immutable description of what is simulated
//! ([`Model`]: rods, bodies, joints, prescribed motions, closures, gravity,
//! quadrature; built by [`ModelBuilder`] from [`Rod`]s) and [`Data`],
//! every buffer an evaluation needs. A new joint type goes in [`joint`]
//! (its motion subspace as virtual pieces, D50); a new element or a new
//! description of a load on a rod goes here too, its force in
//! `crate::forces`.

pub(crate) mod builder;
pub(crate) mod closure;
pub(crate) mod contact;
pub(crate) mod data;
pub(crate) mod element;
pub(crate) mod joint;
pub(crate) mod pairs;
pub(crate) mod planar;
pub(crate) mod prescribed;
pub(crate) mod rod;
pub(crate) mod second;
pub(crate) mod tree;

pub use builder::{IntoRod, ModelBuilder, RodBuilder};
pub use closure::{Closure, ClosureFrame, ClosureKind};
pub use data::Data;
pub use element::{BodyModel, Element, ElementInfo, ElementKind};
pub use joint::{Attachment, BodyLoad, BodySpec, Joint, JointActuator, JointForce, JointKind};
pub use prescribed::{Curve, Prescribed, Spline};
pub use rod::{Rod, RodModel};

use crate::error::DynamicsError;
use rod::build_rod;
use softrod_kinematics::GaussLegendre;
use softrod_lie::Vec3;
use tree::Tree;

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
    pub(crate) closures: Vec<closure::ResolvedClosure>,
    /// Baumgarte rate `α = β` of the constrained dynamics \[1/s\] (D68).
    pub(crate) baumgarte: f64,
    /// Whether the forward dynamics takes the planar path for planar rods
    /// (default on).
    pub(crate) planar_path: bool,
    /// Obstacles, rod–rod settings and contact points
    /// (docs/theory-contact.md); empty: no contact work anywhere.
    pub(crate) contact: contact::ContactModel,
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

    /// Builds a model; checks every rod ([`Rod::validate`], errors name
    /// the rod by index and name) and precomputes `K_n`, `D_n` (D13), the
    /// quadrature points with their inertia, and the placement of point
    /// loads on pieces.
    ///
    /// `gravity` is the world acceleration `g_w` [m/s²] (`None` or zero: no
    /// gravity term); `quadrature` the number of Gauss–Legendre points per
    /// piece (≥ 1; see [`Self::DEFAULT_QUADRATURE`]).
    pub fn new(
        rods: Vec<Rod>,
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
        let mut inputs = 0;
        for element in elements {
            match element {
                Element::Rod(spec, mut attachment) => {
                    attachment.joint.validate(&spec.name)?;
                    let jd = attachment.joint.dof();
                    let pd = attachment.joint.prescribed_dof();
                    let ad = attachment.joint.actuated_dof();
                    let index = rods.len();
                    let rm = build_rod(spec, index, off + jd, cables, &gl)?;
                    infos.push(ElementInfo {
                        name: rm.spec.name.clone(),
                        kind: ElementKind::Rod(index),
                        attachment,
                        joint_dofs: off..off + jd,
                        prescribed_dofs: pres..pres + pd,
                        actuator_inputs: inputs..inputs + ad,
                    });
                    inputs += ad;
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
                    let ad = attachment.joint.actuated_dof();
                    infos.push(ElementInfo {
                        name: spec.name.clone(),
                        kind: ElementKind::Body(bodies.len()),
                        attachment,
                        joint_dofs: off..off + jd,
                        prescribed_dofs: pres..pres + pd,
                        actuator_inputs: inputs..inputs + ad,
                    });
                    inputs += ad;
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
            contact: contact::ContactModel::default(),
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
    pub fn with_closures(mut self, closures: Vec<Closure>) -> Result<Self, DynamicsError> {
        self.closures = Vec::new();
        if closures.is_empty() {
            return Ok(self);
        }
        if self.tree.is_none() {
            self.tree = Some(Tree::build(&self)?);
        }
        self.closures = closure::resolve(&self, closures)?;
        self.baumgarte = closure::baumgarte_rate(&self);
        Ok(self)
    }

    /// The closures, as given (slider axes normalized).
    pub fn closures(&self) -> impl Iterator<Item = &Closure> {
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
    pub fn set_time(&self, data: &mut Data, t: f64) {
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

    /// The same model with `loads` added to rod `rod`'s point loads (after
    /// its own): the rod's load placement on pieces and its planar path are
    /// computed again, as [`Model::with_quadrature`] does. A load study
    /// (`softrod.Simulation.statics(loads=…)`) without rebuilding the scene.
    ///
    /// Errors: a rod index past the rods, a load off the rod or not finite
    /// ([`Rod::validate`]).
    pub fn with_point_loads(
        mut self,
        rod: usize,
        loads: Vec<softrod_mechanics::PointLoad>,
    ) -> Result<Self, DynamicsError> {
        let count = self.rods.len();
        let r = self
            .rods
            .get(rod)
            .ok_or(DynamicsError::RodIndex { index: rod, count })?;
        let mut spec = r.spec.clone();
        spec.point_loads.extend(loads);
        self.rods[rod] = build_rod(spec, rod, r.dof_offset, r.cable_offset, &self.quadrature)?;
        Ok(self)
    }

    /// The same model with rod `rod` described by `spec` instead: a change
    /// of its properties (material, section), cables' tensions or loads
    /// that keeps its coordinates and its number of cables. Its pieces
    /// (`K_n`, `D_n`, quadrature inertia, placed loads, planar path) are
    /// computed again, as [`Model::with_quadrature`] does. For a parameter
    /// study or the parameter derivatives of a gradient
    /// (docs/theory-control.md G8) without rebuilding the scene.
    ///
    /// Errors: a rod index past the rods; a spec with other coordinates
    /// (strains, pieces) or another number of cables
    /// ([`DynamicsError::Unsupported`]); those of [`Rod::validate`].
    pub fn with_rod_spec(mut self, rod: usize, spec: Rod) -> Result<Self, DynamicsError> {
        let count = self.rods.len();
        let r = self
            .rods
            .get(rod)
            .ok_or(DynamicsError::RodIndex { index: rod, count })?;
        if spec.geometry.n_dof() != r.n_dof() || spec.cables.len() != r.spec.cables.len() {
            return Err(DynamicsError::Unsupported {
                what: "a rod variant with other coordinates or cables",
            });
        }
        self.rods[rod] = build_rod(spec, rod, r.dof_offset, r.cable_offset, &self.quadrature)?;
        Ok(self)
    }

    /// The same model with body `body` (index among [`Model::bodies`])
    /// described by `spec` (mass, inertia, centre of mass, loads; its base
    /// pose and attachment stay): its screw inertia is computed again.
    ///
    /// Errors: an index past the bodies ([`DynamicsError::Unsupported`]),
    /// an invalid body ([`BodySpec::validate`]).
    pub fn with_body_spec(mut self, body: usize, spec: BodySpec) -> Result<Self, DynamicsError> {
        let b = self
            .bodies
            .get_mut(body)
            .ok_or(DynamicsError::Unsupported {
                what: "a body index past the model's bodies",
            })?;
        // The tree placed the body with its base pose: that stays.
        let spec = BodySpec {
            base: b.spec.base,
            ..spec
        };
        spec.validate()?;
        b.inertia = spec.spatial_inertia();
        b.spec = spec;
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
    /// planar benchmarks. Results agree to rounding. The same switch takes
    /// the linearization of the inverse dynamics (its outward sweep,
    /// docs/theory-derivatives.md D95–D98) on se(2) or on six strain
    /// directions.
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
        if self.n_joint_inputs() > 0 {
            t.push("joint actuators".into());
        }
        t
    }

    /// Number of cables over all rods (columns of the actuation matrix).
    pub fn n_cables(&self) -> usize {
        self.rods.iter().map(|r| r.spec.cables.len()).sum()
    }

    /// Number of joint force inputs: the coordinates of every joint with an
    /// actuator (docs/theory-control.md IS14), elements in order, each
    /// joint's coordinates in order ([`ElementInfo::actuator_inputs`]).
    pub fn n_joint_inputs(&self) -> usize {
        self.elements.iter().map(|e| e.actuator_inputs.len()).sum()
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
