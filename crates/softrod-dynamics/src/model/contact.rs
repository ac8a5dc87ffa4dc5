//! Contact as the model holds it: the obstacles (resolved to their parent
//! bodies), the rod–rod settings, and per rod the material points where
//! contact is looked for, each with its surface radius, the mass it stands
//! for and the penalty constants of docs/theory-contact.md (CT2–CT4).
//! The forces themselves are in `crate::forces::contact`.

use crate::error::{DynamicsError, RodId};
use crate::model::Model;
use crate::model::pairs::PairWork;
use crate::model::second::SecondWork;
use nalgebra::{DMatrix, DVector, Matrix6xX};
use softrod_kinematics::RodKinematics;
use softrod_lie::{Mat3, PieceMaps, Pose, Vec3, Vec6};
use softrod_mechanics::contact::{ContactSettings, Obstacle, contact_radius};

/// Reference impact speed of the default stiffness (CT3) \[m/s\].
pub(crate) const IMPACT_SPEED: f64 = 1.0;
/// Penetration at rest under the rod's own weight, as a fraction of the
/// smaller radius (CT3).
pub(crate) const REST_PENETRATION: f64 = 0.01;
/// Penetration of a 1 m/s impact, as a fraction of the smaller radius
/// (CT3).
pub(crate) const IMPACT_PENETRATION: f64 = 0.10;
/// The spring part of the penetration a contact's stiffness is raised to
/// hold (CT15): half the rest bound, the other half is margin for the
/// quadratic start and a load that grows between two raises.
pub(crate) const REST_TARGET: f64 = 0.5 * REST_PENETRATION;
/// A raised stiffness carries the force that triggered it at the target
/// divided by this (CT15): headroom so that a slowly growing load raises
/// it once per 50 % of growth, not at every step.
pub(crate) const RAISE_HEADROOM: f64 = 1.5;
/// The offset of a raise heals with the time constant of this many
/// periods `2π/ω` of the contact's base law (`ω = √(k/m)`, CT15).
pub(crate) const HEAL_PERIODS: f64 = 2.0;
/// A contact deeper than this fraction of the radius stops a run (CT15):
/// one and a half times the stated impact bound.
pub const IMPACT_LIMIT: f64 = 1.5 * IMPACT_PENETRATION;

/// The stiffness state of one touching contact (CT15): a run state like
/// the friction anchors, committed after accepted steps and read, never
/// written, by the evaluations of a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Hold {
    /// Factor on the base stiffness `k` of CT3 (on the damping `c`: its
    /// square root, the damping ratio stays).
    pub scale: f64,
    /// Penetration at which the raised penalty starts \[m\]: set by a
    /// raise so that the force is continuous, then healed to zero.
    pub offset: f64,
    /// Time of the last commit \[s\].
    pub t: f64,
}

impl Hold {
    /// A contact that starts touching at `t`.
    pub(crate) fn new(t: f64) -> Self {
        Self {
            scale: 1.0,
            offset: 0.0,
            t,
        }
    }
}

/// One material point where contact is looked for (CT1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Sample {
    /// Arc length \[m\].
    pub s: f64,
    /// Surface radius there \[m\].
    pub radius: f64,
    /// Mass the point stands for (its share of the rod) \[kg\].
    pub mass: f64,
    /// The piece holding the point and its local abscissa there \[m\]
    /// (`RodGeometry::locate(s)`, fixed with the model): what every
    /// evaluation would otherwise search for again.
    pub piece: usize,
    pub x: f64,
    /// The piece of the segment from this point to the next (`locate` of
    /// the segment's midpoint, CT8's broadphase); the last point's is its
    /// own piece.
    pub segment_piece: usize,
}

/// The contact part of a [`Model`].
#[derive(Clone, Debug, Default)]
pub(crate) struct ContactModel {
    pub obstacles: Vec<Obstacle>,
    /// Index of each obstacle's parent body (`None`: the world).
    pub parents: Vec<Option<usize>>,
    pub settings: ContactSettings,
    /// Per rod, its contact points base to tip.
    pub samples: Vec<Vec<Sample>>,
    /// `(child rod, parent rod, at)` for every rod attached to another
    /// rod: no contact between the two near the attachment (CT9).
    pub joined: Vec<(usize, usize, f64)>,
}

impl ContactModel {
    /// Whether anything touches anything.
    pub(crate) fn active(&self) -> bool {
        !self.obstacles.is_empty() || self.settings.any()
    }
}

/// The contact points of a rod (CT1): every piece boundary and interior
/// points no farther apart than the local surface radius, so that a sphere
/// of the swept surface sits on every stretch of the centreline.
pub(crate) fn samples(spec: &crate::model::Rod) -> Vec<Sample> {
    let g = &spec.geometry;
    let length = g.length();
    let section = spec.properties.section();
    let radius_at = |s: f64| {
        spec.contact_radius
            .unwrap_or_else(|| contact_radius(section, s, length))
    };
    let mut s_list = vec![0.0];
    let mut start = 0.0;
    for l in g.piece_lengths() {
        let r = radius_at(start).min(radius_at(start + l)).max(1e-12);
        let m = (l / r).ceil().clamp(1.0, 1.0e4) as usize;
        for j in 1..=m {
            s_list.push(start + l * j as f64 / m as f64);
        }
        start += l;
    }
    let last = s_list.len() - 1;
    s_list[last] = length;
    let on_rod = |s: f64| g.locate(s).expect("a contact point lies on its rod");
    (0..s_list.len())
        .map(|i| {
            let lo = if i == 0 {
                s_list[0]
            } else {
                0.5 * (s_list[i - 1] + s_list[i])
            };
            let hi = if i == last {
                s_list[last]
            } else {
                0.5 * (s_list[i] + s_list[i + 1])
            };
            let mid = 0.5 * (lo + hi);
            let (piece, x) = on_rod(s_list[i]);
            let segment_piece = if i == last {
                piece
            } else {
                on_rod(0.5 * (s_list[i] + s_list[i + 1])).0
            };
            Sample {
                s: s_list[i],
                radius: radius_at(s_list[i]),
                mass: spec.properties.mass_per_length(mid) * (hi - lo),
                piece,
                x,
                segment_piece,
            }
        })
        .collect()
}

impl Model {
    /// This model with obstacles and rod–rod contact settings
    /// (docs/theory-contact.md). Replaces any given before.
    ///
    /// Errors: an invalid obstacle ([`DynamicsError::Obstacle`], naming
    /// its index and name, the [`softrod_mechanics::ObstacleError`] as
    /// source), a parent that is no body of the model
    /// ([`DynamicsError::ObstacleParent`], listing the bodies), invalid
    /// contact settings ([`DynamicsError::ContactSettings`]).
    pub fn with_contact(
        mut self,
        obstacles: Vec<Obstacle>,
        settings: ContactSettings,
    ) -> Result<Self, DynamicsError> {
        let mut parents = Vec::with_capacity(obstacles.len());
        for (index, o) in obstacles.iter().enumerate() {
            o.validate().map_err(|source| DynamicsError::Obstacle {
                index,
                name: o.name.clone(),
                source,
            })?;
            parents.push(match &o.parent {
                None => None,
                Some(p) if p == "world" => None,
                Some(p) => Some(
                    self.bodies
                        .iter()
                        .position(|b| &b.spec.name == p)
                        .ok_or_else(|| DynamicsError::ObstacleParent {
                            index,
                            name: o.name.clone(),
                            parent: p.clone(),
                            bodies: self.bodies.iter().map(|b| b.spec.name.clone()).collect(),
                        })?,
                ),
            });
        }
        settings
            .validate()
            .map_err(|source| DynamicsError::ContactSettings { source })?;
        let active = !obstacles.is_empty() || settings.any();
        let joined = self
            .elements
            .iter()
            .filter_map(|e| {
                let crate::model::ElementKind::Rod(child) = e.kind else {
                    return None;
                };
                let parent = e.attachment.parent.as_ref()?;
                let p = self.rods.iter().position(|r| &r.spec.name == parent)?;
                let at = e
                    .attachment
                    .at
                    .unwrap_or_else(|| self.rods[p].spec.geometry.length());
                Some((child, p, at))
            })
            .collect();
        self.contact = ContactModel {
            joined,
            samples: if active {
                self.rods.iter().map(|r| samples(&r.spec)).collect()
            } else {
                Vec::new()
            },
            obstacles,
            parents,
            settings,
        };
        Ok(self)
    }

    /// The obstacles, as given.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.contact.obstacles
    }

    /// The rod–rod and self contact settings (default: none).
    pub fn contact_settings(&self) -> ContactSettings {
        self.contact.settings
    }

    /// Whether the model has any contact (an obstacle, rod–rod or self
    /// contact). Without it no evaluation does any contact work.
    pub fn has_contact(&self) -> bool {
        self.contact.active()
    }

    /// The penetration \[m\] a rod may start with at `s` before
    /// [`Model::check_initial_contact`] refuses it: 1 % of its surface
    /// radius there (CT3).
    pub fn allowed_penetration(&self, rod: usize, s: f64) -> f64 {
        let rm = &self.rods[rod];
        let length = rm.spec.geometry.length();
        let r = rm.spec.contact_radius.unwrap_or_else(|| {
            contact_radius(rm.spec.properties.section(), s.clamp(0.0, length), length)
        });
        REST_PENETRATION * r
    }

    pub(crate) fn rod_id(&self, rod: usize) -> RodId {
        self.rods[rod].spec.id(Some(rod))
    }
}

/// One contact found by an evaluation (world frame): what the derivatives
/// and the outputs read back.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Active {
    pub rod: usize,
    pub sample: usize,
    pub obstacle: usize,
    /// Rod point (centreline) and the unit normal from the obstacle.
    pub point: Vec3,
    pub normal: Vec3,
    pub gap: f64,
    /// Force on the rod and its derivatives in the point's position and
    /// velocity relative to the obstacle.
    pub force: Vec3,
    pub dp: Mat3,
    pub dv: Mat3,
    pub sticking: bool,
    /// The point's velocity relative to the obstacle, and (friction with
    /// an anchor) the tangential stretch `P(p − a)` from its anchor and the
    /// tangential spring's stiffness `k`: what the stop location of CT29
    /// reads.
    pub velocity: Vec3,
    pub stretch: Vec3,
    pub k: f64,
}

/// The buffers and the friction state of contact, in [`crate::Data`]
/// (only for models with contact).
#[derive(Clone, Debug)]
pub(crate) struct ContactWork {
    /// Per rod, its kinematics (chain models).
    pub kin: Vec<RodKinematics>,
    /// Per rod, `J(s)` and `J̇(s)` in the mixed frame (6 × rod dofs).
    pub jac: Vec<Matrix6xX<f64>>,
    pub jdot: Vec<Matrix6xX<f64>>,
    /// The relative point Jacobian (3 × n_dof) of tree models.
    pub jrel: DMatrix<f64>,
    /// Per node of a tree model, the world wrenches of the contact forces
    /// gathered for one inward sweep (CT28); zero between evaluations.
    pub wrenches: Vec<Vec6>,
    /// The contacts of the last evaluation.
    pub active: Vec<Active>,
    /// The generalized contact force of the last evaluation (n_dof), and
    /// `τ_act + τ_contact` for the forward dynamics.
    pub tau: DVector<f64>,
    pub tau_total: DVector<f64>,
    /// The contact forces' generalized force on the prescribed coordinates
    /// (n_prescribed, `Σ J_pᵀ f`, CT18): what the drives need less.
    pub tau_p: DVector<f64>,
    /// Friction anchors (CT5), committed after accepted steps: per rod,
    /// `sample · n_obstacles + obstacle`, in the obstacle's parent frame.
    pub anchors: Vec<Vec<Option<Vec3>>>,
    /// Stiffness states (CT15), indexed like `anchors`.
    pub holds: Vec<Vec<Option<Hold>>>,
    /// Per rod of a tree model, the world pose of each contact point at
    /// the state of the last evaluation (`frame_pose`'s bits, CT7), and
    /// per piece the stretch `|ν|` of its strain: filled once per
    /// evaluation, read by the obstacle test and the broadphase. Empty on
    /// chain models (their kinematics hold the poses).
    pub poses: Vec<Vec<Pose>>,
    pub stretch: Vec<Vec<f64>>,
    /// Per rod and piece of a tree model, the strain `ξ` at that state and
    /// its rate-free `PieceMaps` (D4): what the closest-point iterations
    /// of the pairs (CT8) evaluate the piece's exponential with.
    pub strains: Vec<Vec<Vec6>>,
    pub maps: Vec<Vec<PieceMaps>>,
    /// Rod–rod and self contact (CT8–CT11); `None` without them: no
    /// broadphase is built.
    pub pairs: Option<Box<PairWork>>,
    /// The buffers of the analytic linearization (CT12–CT14).
    pub second: Box<SecondWork>,
    /// The step-start slide rates of [`crate::friction_stop`] (CT29): per
    /// contact sliding back toward its anchor, `(rod, index, v_t·ê, μ f_n/k)`.
    pub slides: Vec<(usize, usize, f64, f64)>,
}

impl ContactWork {
    /// Takes `from`'s friction anchors and stiffness states (obstacles' and
    /// pairs', CT5, CT15): the contact state of a run, for a second
    /// evaluation of its forces. Allocates only while the pairs' lists grow
    /// to the pairs that touch.
    pub(crate) fn copy_friction_state(&mut self, from: &ContactWork) {
        for (a, b) in self.anchors.iter_mut().zip(&from.anchors) {
            a.copy_from_slice(b);
        }
        for (a, b) in self.holds.iter_mut().zip(&from.holds) {
            a.copy_from_slice(b);
        }
        if let (Some(a), Some(b)) = (&mut self.pairs, &from.pairs) {
            a.anchors.clear();
            a.anchors.extend_from_slice(&b.anchors);
            a.holds.clear();
            a.holds.extend_from_slice(&b.holds);
        }
    }

    /// Forgets the friction anchors and stiffness states (obstacles' and
    /// pairs', CT5, CT15): the contact state of a model no run has
    /// touched (base stiffness, no anchors). Keeps the buffers' capacity.
    pub(crate) fn reset_friction_state(&mut self) {
        for a in &mut self.anchors {
            a.fill(None);
        }
        for h in &mut self.holds {
            h.fill(None);
        }
        if let Some(p) = &mut self.pairs {
            p.anchors.clear();
            p.holds.clear();
        }
    }

    /// The stiffness scale and offset of obstacle contact `idx` of `rod`
    /// (CT15).
    pub(crate) fn held(&self, rod: usize, idx: usize) -> (f64, f64) {
        self.holds[rod][idx].map_or((1.0, 0.0), |h| (h.scale, h.offset))
    }

    pub(crate) fn new(model: &Model) -> Self {
        let n_obs = model.contact.obstacles.len();
        Self {
            kin: model
                .rods
                .iter()
                .map(|r| RodKinematics::new(&r.spec.geometry))
                .collect(),
            jac: model
                .rods
                .iter()
                .map(|r| Matrix6xX::zeros(r.n_dof()))
                .collect(),
            jdot: model
                .rods
                .iter()
                .map(|r| Matrix6xX::zeros(r.n_dof()))
                .collect(),
            jrel: DMatrix::zeros(3, model.n_dof()),
            wrenches: vec![Vec6::zeros(); model.tree.as_ref().map_or(0, |t| t.nodes.len())],
            active: Vec::with_capacity(64),
            tau: DVector::zeros(model.n_dof()),
            tau_total: DVector::zeros(model.n_dof()),
            tau_p: DVector::zeros(model.n_prescribed()),
            anchors: model
                .contact
                .samples
                .iter()
                .map(|s| vec![None; s.len() * n_obs])
                .collect(),
            holds: model
                .contact
                .samples
                .iter()
                .map(|s| vec![None; s.len() * n_obs])
                .collect(),
            poses: match model.tree {
                Some(_) => model
                    .contact
                    .samples
                    .iter()
                    .map(|s| vec![Pose::identity(); s.len()])
                    .collect(),
                None => Vec::new(),
            },
            stretch: match model.tree {
                Some(_) => model
                    .rods
                    .iter()
                    .map(|r| vec![0.0; r.spec.geometry.pieces().len()])
                    .collect(),
                None => Vec::new(),
            },
            strains: match model.tree {
                Some(_) => model
                    .rods
                    .iter()
                    .map(|r| vec![Vec6::zeros(); r.spec.geometry.pieces().len()])
                    .collect(),
                None => Vec::new(),
            },
            maps: match model.tree {
                Some(_) => model
                    .rods
                    .iter()
                    .map(|r| {
                        vec![PieceMaps::new(&Vec6::zeros(), None); r.spec.geometry.pieces().len()]
                    })
                    .collect(),
                None => Vec::new(),
            },
            pairs: PairWork::new(model).map(Box::new),
            second: Box::new(SecondWork::new(model.n_dof())),
            slides: Vec::new(),
        }
    }
}
