//! `[[obstacle]]`, `[contact]` and a rod's `contact_radius` (scene-format.md,
//! "Contact: obstacles, rods touching rods, friction"): into the library's
//! `softrod_mechanics::contact` descriptions, which check the values; this
//! module says which keys each shape takes, normalizes the directions the
//! file may give unnormalized, resolves `parent` and names the key path of
//! every error.

use nalgebra::Matrix3;
use serde::Deserialize;
use softrod_dynamics::Rod;
use softrod_kinematics::RodGeometry;
use softrod_lie::{Mat3, Vec3};
use softrod_mechanics::contact::{ContactSettings, Obstacle, ObstacleError, Shape, unit};

use super::{Ctx, Result};
use crate::robot::Robot;

/// `[[obstacle]]`: every key of every shape; which apply is checked per
/// shape.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawObstacle {
    pub name: String,
    pub shape: String,
    pub position: Option<[f64; 3]>,
    pub normal: Option<[f64; 3]>,
    pub axis: Option<[f64; 3]>,
    pub radius: Option<f64>,
    pub length: Option<f64>,
    pub rotation: Option<[[f64; 3]; 3]>,
    pub half_extents: Option<[f64; 3]>,
    pub parent: Option<String>,
    pub friction: Option<f64>,
    pub restitution: Option<f64>,
}

/// `[contact]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawContact {
    pub rods: Option<bool>,
    #[serde(rename = "self")]
    pub self_contact: Option<bool>,
    pub friction: Option<f64>,
    pub restitution: Option<f64>,
}

/// The shapes and the keys each takes (besides `position`, which every
/// shape takes and which defaults to the parent frame's origin).
const SHAPES: [(&str, &[&str], &str); 5] = [
    ("plane", &["normal"], "position, normal"),
    ("sphere", &["radius"], "position, radius"),
    ("cylinder", &["axis", "radius"], "position, axis, radius"),
    (
        "capsule",
        &["axis", "length", "radius"],
        "position, axis, length, radius",
    ),
    (
        "box",
        &["rotation", "half_extents"],
        "position, rotation, half_extents",
    ),
];

impl Ctx<'_> {
    /// `rod[i].contact_radius`, when given: > 0 (finiteness is checked with
    /// every number of the file).
    pub(super) fn contact_radius(&self, i: usize, r: Option<f64>) -> Result<Option<f64>> {
        r.map(|r| self.positive(&format!("rod[{i}].contact_radius"), r))
            .transpose()
    }

    /// Every `[[obstacle]]`, names unique and distinct from the rods' (a
    /// contact's `b` names either).
    pub(super) fn obstacles(
        &mut self,
        raw: Vec<RawObstacle>,
        rods: &[Rod],
        robot: &Robot,
    ) -> Result<Vec<Obstacle>> {
        let mut out: Vec<Obstacle> = Vec::with_capacity(raw.len());
        for (i, o) in raw.into_iter().enumerate() {
            let p = format!("obstacle[{i}]");
            let name_path = format!("{p}.name");
            if o.name.trim().is_empty() {
                return Err(self
                    .r
                    .invalid(&name_path, "obstacle name must not be empty"));
            }
            if let Some(k) = out.iter().position(|x| x.name == o.name) {
                return Err(self.r.invalid(
                    &name_path,
                    format!("duplicate obstacle name {:?} (also obstacle[{k}])", o.name),
                ));
            }
            if let Some(k) = rods.iter().position(|r| r.name == o.name) {
                return Err(self.r.invalid(
                    &name_path,
                    format!(
                        "obstacle name {:?} is also the name of rod[{k}]: a contact's `b` names \
                         an obstacle or a rod, so they must differ",
                        o.name
                    ),
                ));
            }
            let obstacle = self.obstacle(&p, o, rods, robot)?;
            out.push(obstacle);
        }
        Ok(out)
    }

    fn obstacle(&self, p: &str, o: RawObstacle, rods: &[Rod], robot: &Robot) -> Result<Obstacle> {
        let path = |k: &str| format!("{p}.{k}");
        let Some((_, takes, listed)) = SHAPES.iter().find(|(n, _, _)| *n == o.shape) else {
            let valid: Vec<&str> = SHAPES.iter().map(|(n, _, _)| *n).collect();
            return Err(self.r.unknown_name(&path("shape"), &o.shape, &valid));
        };
        let given = [
            ("normal", o.normal.is_some()),
            ("axis", o.axis.is_some()),
            ("radius", o.radius.is_some()),
            ("length", o.length.is_some()),
            ("rotation", o.rotation.is_some()),
            ("half_extents", o.half_extents.is_some()),
        ];
        for (k, present) in given {
            if present && !takes.contains(&k) {
                return Err(self.r.invalid(
                    &path(k),
                    format!(
                        "key {k:?} does not apply to shape {:?} (it takes {listed})",
                        o.shape
                    ),
                ));
            }
        }
        let required = |k: &str, v: Option<f64>| v.ok_or_else(|| self.r.missing(&path(k), ""));
        let direction = |k: &'static str, v: Option<[f64; 3]>| {
            let v = v.ok_or_else(|| self.r.missing(&path(k), ""))?;
            unit(k, Vec3::from(v)).map_err(|e| self.obstacle_error(p, e, None))
        };
        let position = Vec3::from(o.position.unwrap_or([0.0; 3]));
        let shape = match o.shape.as_str() {
            "plane" => Shape::Plane {
                point: position,
                normal: direction("normal", o.normal)?,
            },
            "sphere" => Shape::Sphere {
                center: position,
                radius: required("radius", o.radius)?,
            },
            "cylinder" => Shape::Cylinder {
                point: position,
                axis: direction("axis", o.axis)?,
                radius: required("radius", o.radius)?,
            },
            "capsule" => Shape::Capsule {
                center: position,
                axis: direction("axis", o.axis)?,
                length: required("length", o.length)?,
                radius: required("radius", o.radius)?,
            },
            _ => Shape::Box {
                center: position,
                rotation: self.box_rotation(&path("rotation"), o.rotation)?,
                half_extents: Vec3::from(
                    o.half_extents
                        .ok_or_else(|| self.r.missing(&path("half_extents"), ""))?,
                ),
            },
        };
        let parent = match o.parent.as_deref() {
            None | Some("world") => None,
            Some(name) if robot.bodies.iter().any(|b| b.name == name) => Some(name.to_owned()),
            Some(name) => {
                let mut valid: Vec<&str> = robot.bodies.iter().map(|b| b.name.as_str()).collect();
                valid.push("world");
                let err = self.r.unknown_name(&path("parent"), name, &valid);
                if rods.iter().any(|r| r.name == name) {
                    return Err(self.r.invalid(
                        &path("parent"),
                        format!(
                            "{name:?} is a rod: obstacles ride on the world or on a [[body]] \
                             ({})",
                            choices(&valid)
                        ),
                    ));
                }
                return Err(err);
            }
        };
        let half_extents = o.half_extents;
        let obstacle = Obstacle {
            name: o.name,
            shape,
            parent,
            friction: o.friction.unwrap_or(0.0),
            restitution: o.restitution.unwrap_or(0.0),
        };
        obstacle
            .validate()
            .map_err(|e| self.obstacle_error(p, e, half_extents))?;
        Ok(obstacle)
    }

    /// A box's rotation, row-major like a rod's `base.rotation` and accepted
    /// to the same tolerance ([`RodGeometry::ROTATION_TOL`], so that a
    /// matrix written with six decimals passes), then made exactly
    /// orthonormal (the nearest rotation, `U Vᵀ` of its SVD) for the
    /// library, which asks for 1e-9.
    pub(super) fn box_rotation(&self, path: &str, r: Option<[[f64; 3]; 3]>) -> Result<Mat3> {
        let Some(r) = r else {
            return Ok(Mat3::identity());
        };
        let m: Mat3 = Matrix3::from_fn(|i, j| r[i][j]);
        let deviation = (m * m.transpose() - Mat3::identity()).abs().max();
        let determinant = m.determinant();
        let tol = RodGeometry::ROTATION_TOL;
        if deviation > tol || (determinant - 1.0).abs() > tol {
            return Err(self.r.invalid(
                path,
                format!(
                    "not a rotation matrix: must be orthonormal with determinant +1 within \
                     {tol:e} (max |R Rᵀ − I| = {deviation:.3e}, det R = {determinant})"
                ),
            ));
        }
        let svd = m.svd(true, true);
        match (svd.u, svd.v_t) {
            (Some(u), Some(v_t)) => Ok(u * v_t),
            _ => Ok(m),
        }
    }

    /// An [`ObstacleError`] of `obstacle[i]` (`p`) or `contact` at the key
    /// it names (`half_extents`: the box's, to name the component), the
    /// library's error as source.
    fn obstacle_error(
        &self,
        p: &str,
        e: ObstacleError,
        half_extents: Option<[f64; 3]>,
    ) -> crate::SceneError {
        let path = |k: &str| format!("{p}.{k}");
        let err = match &e {
            ObstacleError::NotPositive { what, value } => {
                self.r.out_of_range(&path(what), value, "> 0")
            }
            ObstacleError::Negative { what, value } => {
                self.r.out_of_range(&path(what), value, ">= 0")
            }
            ObstacleError::NotFinite { what } => self.r.not_finite(&path(what), "NaN or infinite"),
            ObstacleError::ZeroVector { what } => self.r.invalid(
                &path(what),
                format!("{what} is the zero vector: it has no direction"),
            ),
            ObstacleError::NotUnit { what, norm } => self.r.invalid(
                &path(what),
                format!("{what} must be a unit vector, its length is {norm}"),
            ),
            ObstacleError::NotRotation { .. } => self.r.invalid(&path("rotation"), &e),
            ObstacleError::Restitution { value } => {
                self.r
                    .out_of_range(&path("restitution"), value, "in [0, 1]")
            }
            other => self.r.invalid(p, other),
        };
        let err = match (&e, half_extents) {
            // The library names the key; the file's values name the component.
            (
                ObstacleError::NotPositive {
                    what: "half_extents",
                    value,
                },
                Some(h),
            ) => {
                let k = h.iter().position(|x| x.is_nan() || *x <= 0.0).unwrap_or(0);
                self.r
                    .out_of_range(&format!("{p}.half_extents[{k}]"), value, "> 0")
            }
            _ => err,
        };
        err.caused_by(Box::new(e))
    }

    /// `[contact]`, default none. Settings that cannot act (friction or
    /// restitution with neither `rods` nor `self`) are warned about.
    pub(super) fn contact(&mut self, raw: Option<RawContact>) -> Result<ContactSettings> {
        let Some(c) = raw else {
            return Ok(ContactSettings::default());
        };
        let settings = ContactSettings {
            rods: c.rods.unwrap_or(false),
            self_contact: c.self_contact.unwrap_or(false),
            friction: c.friction.unwrap_or(0.0),
            restitution: c.restitution.unwrap_or(0.0),
        };
        settings
            .validate()
            .map_err(|e| self.obstacle_error("contact", e, None))?;
        if !settings.any() && (c.friction.is_some() || c.restitution.is_some()) {
            self.warn(
                "contact",
                "friction and restitution act between rods only: with neither rods = true nor \
                 self = true they have no effect (obstacles take their own)"
                    .to_owned(),
            );
        }
        Ok(settings)
    }
}

fn choices(valid: &[&str]) -> String {
    format!("valid: {}", valid.join(", "))
}
