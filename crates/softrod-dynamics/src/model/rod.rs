//! A rod as described ([`Rod`]) and as built into a model
//! ([`RodModel`]: its coordinates, cables and per-piece precomputed data).

use crate::error::{DynamicsError, RodId};
use crate::model::builder::RodBuilder;
use nalgebra::DMatrix;
use softrod_kinematics::{GaussLegendre, RodGeometry, Strain};
use softrod_lie::{Mat6, Vec6};
use softrod_mechanics::{
    Cable, DistributedLoad, Drag, LoadFrame, PointLoad, RodProperties, piece_matrices,
};

/// Everything about one rod: its geometry and strain bases, its body
/// (section + material), and the force terms acting on it. Only the terms
/// present are evaluated (an empty `cables` list costs nothing).
///
/// Build one with [`Rod::builder`] (the length given once), or from its
/// parts with [`Rod::new`]. The fields are public; [`crate::Model::new`]
/// checks them ([`Rod::validate`]) when the rod enters a model.
///
/// ```
/// use softrod_dynamics::Rod;
/// use softrod_kinematics::Strain;
/// use softrod_mechanics::Material;
///
/// let silicone = Material::builder()
///     .density(1000.0)
///     .young(1.0e6)
///     .poisson(0.5)
///     .build()
///     .unwrap();
/// let arm = Rod::builder(0.5)
///     .name("arm")
///     .pieces(8)
///     .strains([Strain::Ky, Strain::Qx, Strain::Qz])
///     .circle(0.01)
///     .material(silicone)
///     .build()
///     .unwrap();
/// assert_eq!(arm.geometry.n_dof(), 24);
/// assert!(Rod::builder(-0.5).circle(0.01).material(silicone).build().is_err());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Rod {
    /// A name for messages and outputs.
    pub name: String,
    /// Pieces, bases, rest strain, base pose.
    pub geometry: RodGeometry,
    /// Section and material.
    pub properties: RodProperties,
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
    /// Radius of the rod's contact surface \[m\] (docs/theory-contact.md
    /// CT1); `None`: from the section
    /// ([`softrod_mechanics::contact::contact_radius`]).
    pub contact_radius: Option<f64>,
}

impl Rod {
    /// A builder for a rod of undeformed length `length` \[m\] (see
    /// [`RodBuilder`]).
    pub fn builder(length: f64) -> RodBuilder {
        RodBuilder::new(length)
    }

    /// A rod with no loads, cables or drag, from its kinematic rod and body
    /// (which must have the same length).
    pub fn new(name: impl Into<String>, rod: RodGeometry, body: RodProperties) -> Self {
        Self {
            name: name.into(),
            geometry: rod,
            properties: body,
            stress_free: None,
            point_loads: Vec::new(),
            distributed_loads: Vec::new(),
            drag: None,
            cables: Vec::new(),
            contact_radius: None,
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
        let length = self.geometry.length();
        self.properties
            .check_rod(&self.geometry)
            .map_err(|source| DynamicsError::RodProperties { rod: rod(), source })?;
        if let Some(sf) = &self.stress_free {
            if sf.len() != self.geometry.n_pieces() {
                return Err(DynamicsError::StressFreeCount {
                    rod: rod(),
                    got: sf.len(),
                    expected: self.geometry.n_pieces(),
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
        if let Some(r) = self.contact_radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(DynamicsError::ContactRadius {
                    rod: rod(),
                    value: r,
                });
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

/// A rod inside a [`crate::Model`], with precomputed piece data.
#[derive(Clone, Debug)]
pub struct RodModel {
    /// The description it was built from.
    pub spec: Rod,
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
    pub(crate) planar: Option<crate::model::planar::PlanarRod>,
}

impl RodModel {
    /// Number of coordinates of this rod.
    pub fn n_dof(&self) -> usize {
        self.spec.geometry.n_dof()
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
    /// unless [`crate::Model::with_planar_path`] turned that off.
    pub fn is_planar(&self) -> bool {
        self.planar.is_some()
    }
}

/// Checks one rod and precomputes its pieces (`K_n`, `D_n`, quadrature
/// points, placed point loads).
pub(crate) fn build_rod(
    spec: Rod,
    index: usize,
    dof_offset: usize,
    cable_offset: usize,
    gl: &GaussLegendre,
) -> Result<RodModel, DynamicsError> {
    spec.check(Some(index))?;
    let rod = &spec.geometry;
    let mats = piece_matrices(rod, &spec.properties, spec.stress_free.as_deref(), gl);
    let mut pieces = Vec::with_capacity(rod.n_pieces());
    for (n, (piece, m)) in rod.pieces().iter().zip(mats).enumerate() {
        let points = gl
            .on_interval(piece.length)
            .map(|(x, w)| {
                let s = piece.start + x;
                QuadPoint {
                    x,
                    w,
                    inertia: spec.properties.screw_inertia(s),
                    mass_per_length: spec.properties.mass_per_length(s),
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
    let planar = crate::model::planar::PlanarRod::detect(&spec, &pieces);
    Ok(RodModel {
        spec,
        dof_offset,
        pieces,
        needs_world_pose_at_points: needs_world,
        cable_offset,
        planar,
    })
}
