//! Builders of [`Rod`] and [`Model`]: named arguments, the rod length
//! given once, every value checked once where it enters (the lower layers'
//! constructors, then [`Rod::validate`]).

use crate::error::{DynamicsError, RodId};
use crate::model::closure::Closure;
use crate::model::joint::{Attachment, BodySpec};
use crate::model::{Element, Model, Rod};
use softrod_kinematics::{Basis, RodGeometry, Strain, straight};
use softrod_lie::{Pose, Vec3, Vec6};
use softrod_mechanics::contact::{ContactSettings, Obstacle};
use softrod_mechanics::{
    Cable, DistributedLoad, Drag, Material, MechanicsError, PointLoad, RodProperties, Section,
};

/// How the rod is cut into pieces.
#[derive(Clone, Debug, PartialEq)]
enum Pieces {
    /// `n` equal pieces.
    Equal(usize),
    /// Pieces of these lengths [m], base to tip.
    Lengths(Vec<f64>),
}

/// Which strains are coordinates.
#[derive(Clone, Debug, PartialEq)]
enum Strains {
    /// A selection, in coordinate order.
    Select(Vec<Strain>),
    /// A general basis.
    Basis(Basis),
}

/// The stress-free strain `ξ*`.
#[derive(Clone, Debug, PartialEq)]
enum StressFree {
    /// The same on every piece.
    Uniform(Vec6),
    /// One per piece.
    PerPiece(Vec<Vec6>),
}

/// Builder of a [`Rod`] ([`Rod::builder`]): a rod of undeformed
/// length `L` given once, clamped at its base.
///
/// Defaults: one piece, all six strains, the straight unstretched rest
/// strain `(0, 0, 0, 1, 0, 0)` (stress-free), base at the world origin with
/// the local axes along the world's, no drag, cables or loads. A section
/// and a material are required.
#[derive(Clone, Debug)]
#[must_use]
pub struct RodBuilder {
    length: f64,
    name: String,
    pieces: Pieces,
    strains: Strains,
    rest_strain: Vec6,
    base: Pose,
    section: Option<Section>,
    material: Option<Material>,
    stress_free: Option<StressFree>,
    drag: Option<Drag>,
    cables: Vec<Cable>,
    point_loads: Vec<PointLoad>,
    distributed_loads: Vec<DistributedLoad>,
    contact_radius: Option<f64>,
}

impl RodBuilder {
    /// A rod of undeformed length `length` \[m\] (> 0).
    pub fn new(length: f64) -> Self {
        Self {
            length,
            name: String::new(),
            pieces: Pieces::Equal(1),
            strains: Strains::Select(Strain::ALL.to_vec()),
            rest_strain: straight(),
            base: Pose::identity(),
            section: None,
            material: None,
            stress_free: None,
            drag: None,
            cables: Vec::new(),
            contact_radius: None,
            point_loads: Vec::new(),
            distributed_loads: Vec::new(),
        }
    }

    /// A name for messages and outputs.
    pub fn name(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// `n` equal pieces (1 to `RodGeometry::MAX_PIECES`).
    pub fn pieces(mut self, n: usize) -> Self {
        self.pieces = Pieces::Equal(n);
        self
    }

    /// Pieces of these lengths \[m\], base to tip; they must sum to the rod
    /// length (to `RodProperties::LENGTH_RTOL`).
    pub fn piece_lengths(mut self, lengths: &[f64]) -> Self {
        self.pieces = Pieces::Lengths(lengths.to_vec());
        self
    }

    /// The strains that are coordinates, in the order of each piece's
    /// coordinates (e.g. planar bending and shear `[Ky, Qx, Qz]`); default
    /// all six.
    pub fn strains(mut self, strains: impl IntoIterator<Item = Strain>) -> Self {
        self.strains = Strains::Select(strains.into_iter().collect());
        self
    }

    /// A general strain basis `B` (6×k) for every piece instead of a selection.
    pub fn basis(mut self, basis: Basis) -> Self {
        self.strains = Strains::Basis(basis);
        self
    }

    /// Rest strain `ξ̄` (the strain at `q = 0`) of every piece; default
    /// straight, `(0, 0, 0, 1, 0, 0)`.
    pub fn rest_strain(mut self, rest_strain: Vec6) -> Self {
        self.rest_strain = rest_strain;
        self
    }

    /// Pose of the clamped base in the world; default identity.
    pub fn base(mut self, base: Pose) -> Self {
        self.base = base;
        self
    }

    /// The cross-section.
    pub fn section(mut self, section: Section) -> Self {
        self.section = Some(section);
        self
    }

    /// Shorthand for a solid circular section of radius `radius` \[m\].
    pub fn circle(self, radius: f64) -> Self {
        self.section(Section::Circle { radius })
    }

    /// The material (density, elastic constants, viscosity).
    pub fn material(mut self, material: Material) -> Self {
        self.material = Some(material);
        self
    }

    /// Stress-free strain `ξ*` of every piece when it differs from the rest
    /// strain (a pre-stressed rod); default `ξ* = ξ̄`.
    pub fn stress_free(mut self, strain: Vec6) -> Self {
        self.stress_free = Some(StressFree::Uniform(strain));
        self
    }

    /// Stress-free strain `ξ*_n` of each piece, base to tip.
    pub fn stress_free_per_piece(mut self, strains: Vec<Vec6>) -> Self {
        self.stress_free = Some(StressFree::PerPiece(strains));
        self
    }

    /// Linear drag of a surrounding fluid.
    pub fn drag(mut self, drag: Drag) -> Self {
        self.drag = Some(drag);
        self
    }

    /// Adds a cable (its span defaults to the whole rod, `Cable::new`).
    pub fn cable(mut self, cable: Cable) -> Self {
        self.cables.push(cable);
        self
    }

    /// Adds a point load.
    pub fn point_load(mut self, load: PointLoad) -> Self {
        self.point_loads.push(load);
        self
    }

    /// Adds a uniformly distributed load.
    pub fn distributed_load(mut self, load: DistributedLoad) -> Self {
        self.distributed_loads.push(load);
        self
    }

    /// The radius of the rod's contact surface \[m\] (default: from the
    /// section, [`softrod_mechanics::contact::contact_radius`]).
    pub fn contact_radius(mut self, radius: f64) -> Self {
        self.contact_radius = Some(radius);
        self
    }

    /// The rod, or the first thing wrong with it: the section and material
    /// present, the length and the section (mechanics), the pieces,
    /// strains, rest strain and base (kinematics), the piece lengths against
    /// the length, then [`Rod::validate`].
    /// Errors name the rod by its name (the index is set when it enters a
    /// model).
    pub fn build(self) -> Result<Rod, DynamicsError> {
        let id = || RodId {
            index: None,
            name: self.name.clone(),
        };
        let section = self
            .section
            .ok_or_else(|| DynamicsError::MissingSection { rod: id() })?;
        let material = self
            .material
            .ok_or_else(|| DynamicsError::MissingMaterial { rod: id() })?;
        // The body first: it owns the check of the length, whichever way
        // the pieces are given.
        let body = RodProperties::new(section, material, self.length)
            .map_err(|source| DynamicsError::RodProperties { rod: id(), source })?;
        let geometry = |source| DynamicsError::RodGeometry { rod: id(), source };
        let basis = match self.strains {
            Strains::Select(list) => Basis::select(&list).map_err(geometry)?,
            Strains::Basis(b) => b,
        };
        let rod = match &self.pieces {
            Pieces::Equal(n) => {
                RodGeometry::uniform(self.length, *n, basis, self.rest_strain, self.base)
            }
            Pieces::Lengths(l) => RodGeometry::with_lengths(l, basis, self.rest_strain, self.base),
        }
        .map_err(geometry)?;
        if let Err(MechanicsError::LengthMismatch { body, rod }) = body.check_rod(&rod) {
            return Err(DynamicsError::PieceLengthSum {
                rod: id(),
                sum: rod,
                length: body,
            });
        }
        let stress_free = self.stress_free.map(|sf| match sf {
            StressFree::Uniform(xi) => vec![xi; rod.n_pieces()],
            StressFree::PerPiece(v) => v,
        });
        let spec = Rod {
            name: self.name,
            geometry: rod,
            properties: body,
            stress_free,
            point_loads: self.point_loads,
            distributed_loads: self.distributed_loads,
            drag: self.drag,
            cables: self.cables,
            contact_radius: self.contact_radius,
        };
        spec.validate()?;
        Ok(spec)
    }
}

/// What [`ModelBuilder::rod`] takes: a finished [`Rod`] or its builder
/// (built with the model, errors then carry the rod's index).
pub trait IntoRod {
    /// The rod description.
    fn into_rod_spec(self) -> Result<Rod, DynamicsError>;
}

impl IntoRod for Rod {
    fn into_rod_spec(self) -> Result<Rod, DynamicsError> {
        Ok(self)
    }
}

impl IntoRod for RodBuilder {
    fn into_rod_spec(self) -> Result<Rod, DynamicsError> {
        self.build()
    }
}

/// An element of a [`ModelBuilder`] in order.
#[derive(Debug)]
enum Item {
    RodGeometry(usize, Attachment),
    Body(Box<BodySpec>, Attachment),
}

/// Builder of a [`Model`] ([`Model::builder`]): rods in order (their
/// coordinates are concatenated in this order), optional gravity, Gauss
/// points per piece (default [`Model::DEFAULT_QUADRATURE`]).
///
/// ```
/// use softrod_dynamics::{Model, Rod};
/// use softrod_mechanics::Material;
///
/// let steel = Material::builder()
///     .density(7850.0)
///     .young(2.0e11)
///     .poisson(0.3)
///     .build()
///     .unwrap();
/// let model = Model::builder()
///     .rod(Rod::builder(1.0).name("wire").pieces(10).circle(1e-3).material(steel))
///     .gravity([0.0, 0.0, -9.81])
///     .build()
///     .unwrap();
/// assert_eq!(model.n_dof(), 60);
/// ```
#[derive(Debug, Default)]
#[must_use]
pub struct ModelBuilder {
    rods: Vec<Result<Rod, DynamicsError>>,
    /// Elements in order: rods by index into `rods` with their attachment,
    /// bodies with theirs.
    order: Vec<Item>,
    gravity: Option<Vec3>,
    quadrature: Option<usize>,
    closures: Vec<Closure>,
    obstacles: Vec<Obstacle>,
    contact: ContactSettings,
}

impl ModelBuilder {
    /// Adds a rod (a [`Rod`] or a [`RodBuilder`]).
    pub fn rod(self, rod: impl IntoRod) -> Self {
        self.rod_on(rod, Attachment::world())
    }

    /// Adds a rod hanging from a parent through a joint (docs/theory.md
    /// §11): its base pose ([`RodBuilder::base`]) is then relative to
    /// the attachment frame.
    pub fn rod_on(mut self, rod: impl IntoRod, attachment: Attachment) -> Self {
        self.order
            .push(Item::RodGeometry(self.rods.len(), attachment));
        self.rods.push(rod.into_rod_spec());
        self
    }

    /// Adds a rigid body hanging from a parent through a joint.
    pub fn body(mut self, body: BodySpec, attachment: Attachment) -> Self {
        self.order.push(Item::Body(Box::new(body), attachment));
        self
    }

    /// Adds several rods.
    pub fn rods<R: IntoRod>(mut self, rods: impl IntoIterator<Item = R>) -> Self {
        for r in rods {
            self = self.rod(r);
        }
        self
    }

    /// Uniform gravity, world acceleration `g_w` [m/s²] (e.g. `[0, 0, -9.81]`).
    pub fn gravity(mut self, gravity: impl Into<Vec3>) -> Self {
        self.gravity = Some(gravity.into());
        self
    }

    /// Adds a loop closure (docs/theory.md D63; see [`Model::with_closures`]).
    pub fn closure(mut self, closure: Closure) -> Self {
        self.closures.push(closure);
        self
    }

    /// Adds an obstacle (docs/theory-contact.md; see [`Model::with_contact`]).
    pub fn obstacle(mut self, obstacle: Obstacle) -> Self {
        self.obstacles.push(obstacle);
        self
    }

    /// Rod–rod and self contact settings (see [`Model::with_contact`]).
    pub fn contact(mut self, settings: ContactSettings) -> Self {
        self.contact = settings;
        self
    }

    /// Gauss–Legendre points per piece (≥ 1).
    pub fn quadrature(mut self, points: usize) -> Self {
        self.quadrature = Some(points);
        self
    }

    /// The model ([`Model::new`]), or the first error, naming the rod by
    /// index and name.
    pub fn build(self) -> Result<Model, DynamicsError> {
        let mut rods = self
            .rods
            .into_iter()
            .enumerate()
            .map(|(i, r)| r.map(Some).map_err(|e| e.at_rod_index(i)))
            .collect::<Result<Vec<_>, _>>()?;
        let elements = self
            .order
            .into_iter()
            .map(|item| match item {
                Item::RodGeometry(i, a) => Element::Rod(rods[i].take().expect("each rod once"), a),
                Item::Body(b, a) => Element::Body(*b, a),
            })
            .collect();
        Model::with_elements(
            elements,
            self.gravity,
            self.quadrature.unwrap_or(Model::DEFAULT_QUADRATURE),
        )?
        .with_closures(self.closures)?
        .with_contact(self.obstacles, self.contact)
    }
}
