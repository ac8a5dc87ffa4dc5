//! The elements of a robot as given to [`Model::with_elements`] and as a
//! built [`Model`] lists them.

#[cfg(doc)]
use crate::model::Model;
use crate::model::joint::{Attachment, BodySpec};
use crate::model::rod::Rod;
use softrod_lie::Mat6;

/// An element of a model given to [`Model::with_elements`]: a rod or a
/// rigid body, with where it hangs.
#[derive(Clone, Debug, PartialEq)]
pub enum Element {
    /// A rod; its base pose ([`softrod_kinematics::RodGeometry::base`]) is relative
    /// to the attachment frame.
    Rod(Rod, Attachment),
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
    /// Range of an actuated joint's forces among the model's joint force
    /// inputs ([`Model::n_joint_inputs`], IS14; empty otherwise).
    pub actuator_inputs: std::ops::Range<usize>,
}

/// A rigid body inside a [`Model`].
#[derive(Clone, Debug, PartialEq)]
pub struct BodyModel {
    /// The description it was built from.
    pub spec: BodySpec,
    /// Its screw inertia at the body frame (D52).
    pub inertia: Mat6,
}
