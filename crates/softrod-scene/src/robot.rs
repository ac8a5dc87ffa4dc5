//! What a scene says about bodies, joints and parents (scene-format.md,
//! "Bodies, joints, bases and closures"): the raw tables and the validated
//! [`Robot`] the model is built from.

use serde::Deserialize;
use softrod_dynamics::{Attachment, BodySpec, Closure, Element, ElementKind, Rod};

use crate::raw::RawBase;

/// `joint = { type = …, axis = …, axes = …, stiffness, damping, rest, prescribed }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawJoint {
    #[serde(rename = "type")]
    pub kind: String,
    pub axis: Option<[f64; 3]>,
    pub axes: Option<[[f64; 3]; 2]>,
    pub stiffness: Option<toml::Value>,
    pub damping: Option<toml::Value>,
    pub rest: Option<toml::Value>,
    pub prescribed: Option<toml::Value>,
    pub actuator: Option<toml::Value>,
}

/// `[[body]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBody {
    pub name: String,
    pub parent: String,
    pub at: Option<f64>,
    pub base: Option<RawBase>,
    pub joint: Option<RawJoint>,
    pub mass: f64,
    pub inertia: toml::Value,
    pub center_of_mass: Option<[f64; 3]>,
}

/// The bodies of a scene and where every element hangs. Empty (every rod
/// clamped to the world, no body) for a scene of the section "A scene".
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Robot {
    /// One per rod of [`crate::Scene::rods`]: parent, `at`, joint (default
    /// the world clamp).
    pub rod_attachments: Vec<Attachment>,
    /// The `[[body]]` tables in file order, with their `[[load]]`s.
    pub bodies: Vec<BodySpec>,
    /// One per body.
    pub body_attachments: Vec<Attachment>,
    /// Rods and bodies in the order they appear in the file (the order of
    /// `q`: each element's joint coordinates, then a rod's strains).
    pub order: Vec<ElementKind>,
    /// The `[[closure]]` tables in file order (name defaults to
    /// `closure[i]`).
    pub closures: Vec<Closure>,
}

impl Robot {
    /// Whether the scene has no body, parent, joint or closure.
    pub fn is_trivial(&self) -> bool {
        self.bodies.is_empty()
            && self.closures.is_empty()
            && self.rod_attachments.iter().all(Attachment::is_world_clamp)
    }

    /// The elements in file order, for [`softrod_dynamics::Model::with_elements`].
    pub fn elements(&self, rods: &[Rod]) -> Vec<Element> {
        self.order
            .iter()
            .map(|k| match *k {
                ElementKind::Rod(i) => Element::Rod(rods[i].clone(), self.attachment(*k)),
                ElementKind::Body(j) => Element::Body(self.bodies[j].clone(), self.attachment(*k)),
            })
            .collect()
    }

    fn attachment(&self, k: ElementKind) -> Attachment {
        match k {
            ElementKind::Rod(i) => self
                .rod_attachments
                .get(i)
                .cloned()
                .unwrap_or_else(Attachment::world),
            ElementKind::Body(j) => self.body_attachments[j].clone(),
        }
    }

    /// Number of joint coordinates.
    pub fn joint_dofs(&self) -> usize {
        self.rod_attachments
            .iter()
            .chain(&self.body_attachments)
            .map(|a| a.joint.dof())
            .sum()
    }

    /// Index in `q` of the first strain coordinate of rod `i` (`rods`: the
    /// scene's rods).
    pub fn rod_dof_offset(&self, rods: &[Rod], i: usize) -> usize {
        let mut off = 0;
        for k in &self.order {
            off += self.attachment(*k).joint.dof();
            if *k == ElementKind::Rod(i) {
                return off;
            }
            if let ElementKind::Rod(r) = k {
                off += rods[*r].geometry.n_dof();
            }
        }
        off
    }
}
