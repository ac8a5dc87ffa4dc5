//! Obstacles (a scene's `[[obstacle]]`) as the 3-D view and the plots draw
//! them: plain data in SI units, no physics types.
//!
//! An obstacle is given in its **carrier's frame**: the world for a fixed
//! one, a body's frame for one a body carries (`poses` then gives the
//! carrier's pose at every time). Planes and cylinders are infinite; they
//! are drawn over a [`Region`] around the rods: a plane as a square patch
//! centred where the region's centre projects onto it, a cylinder as the
//! piece of it whose axis passes by the region (both as wide as the
//! region's [`Region::half_size`]).

use serde::{Deserialize, Serialize};

use crate::data::Pose;
use crate::error::VizError;

/// The geometry of an obstacle in its carrier's frame (m). Field names are
/// the scene format's keys.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "lowercase")]
pub enum ObstacleShape {
    /// The half-space on the side `normal` points away from is solid.
    Plane {
        /// A point of the plane.
        position: [f64; 3],
        /// Normal pointing out of the solid (need not be unit, ≠ 0).
        normal: [f64; 3],
    },
    /// A ball.
    Sphere {
        /// Centre.
        position: [f64; 3],
        /// Radius, > 0.
        radius: f64,
    },
    /// An infinite round cylinder.
    Cylinder {
        /// A point of the axis.
        position: [f64; 3],
        /// Axis direction (need not be unit, ≠ 0).
        axis: [f64; 3],
        /// Radius, > 0.
        radius: f64,
    },
    /// The points within `radius` of a segment of `length` along `axis`
    /// centred at `position`.
    Capsule {
        /// Centre of the segment.
        position: [f64; 3],
        /// Axis direction (need not be unit, ≠ 0).
        axis: [f64; 3],
        /// Length of the segment, ≥ 0.
        length: f64,
        /// Radius, > 0.
        radius: f64,
    },
    /// A box.
    Box {
        /// Centre.
        position: [f64; 3],
        /// Rotation from the box's axes to the carrier frame, by rows.
        rotation: [[f64; 3]; 3],
        /// Half the edge lengths along the box's axes, each > 0.
        half_extents: [f64; 3],
    },
}

/// One obstacle over a run (or a static picture).
#[derive(Debug, Clone, PartialEq)]
pub struct ObstacleTrack {
    /// The obstacle's name (legend; never parsed).
    pub name: String,
    /// Its geometry, in the carrier's frame.
    pub shape: ObstacleShape,
    /// The carrier's pose at each time (`None`: fixed in the world).
    pub poses: Option<Vec<Pose>>,
}

impl ObstacleTrack {
    /// An obstacle fixed in the world.
    pub fn fixed(name: impl Into<String>, shape: ObstacleShape) -> Self {
        Self {
            name: name.into(),
            shape,
            poses: None,
        }
    }

    /// Checks the numbers and, when carried, that there are `times` poses.
    pub fn validate(&self, what: &str, times: usize) -> Result<(), VizError> {
        let bad = |problem: String| {
            Err(VizError::Invalid {
                what: format!("{what} ('{}').shape", self.name),
                problem,
            })
        };
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let nonzero = |v: &[f64; 3]| finite(v) && v.iter().any(|x| *x != 0.0);
        let positive = |r: f64| r.is_finite() && r > 0.0;
        match &self.shape {
            ObstacleShape::Plane { position, normal } => {
                if !finite(position) || !nonzero(normal) {
                    return bad(format!(
                        "position {position:?} must be finite, normal {normal:?} finite and ≠ 0"
                    ));
                }
            }
            ObstacleShape::Sphere { position, radius } => {
                if !finite(position) || !positive(*radius) {
                    return bad(format!(
                        "position {position:?} must be finite, radius {radius} > 0"
                    ));
                }
            }
            ObstacleShape::Cylinder {
                position,
                axis,
                radius,
            } => {
                if !finite(position) || !nonzero(axis) || !positive(*radius) {
                    return bad(format!(
                        "position {position:?} must be finite, axis {axis:?} ≠ 0, radius {radius} > 0"
                    ));
                }
            }
            ObstacleShape::Capsule {
                position,
                axis,
                length,
                radius,
            } => {
                let ok = finite(position)
                    && nonzero(axis)
                    && length.is_finite()
                    && *length >= 0.0
                    && positive(*radius);
                if !ok {
                    return bad(format!(
                        "position {position:?} must be finite, axis {axis:?} ≠ 0, length \
                         {length} ≥ 0, radius {radius} > 0"
                    ));
                }
            }
            ObstacleShape::Box {
                position,
                rotation,
                half_extents,
            } => {
                if !finite(position)
                    || !rotation.iter().all(|r| finite(r))
                    || !half_extents.iter().all(|h| positive(*h))
                {
                    return bad(format!(
                        "position {position:?} and rotation must be finite, half_extents \
                         {half_extents:?} > 0"
                    ));
                }
            }
        }
        if let Some(poses) = &self.poses {
            if poses.len() != times {
                return Err(VizError::Count {
                    what: format!("{what} ('{}').poses", self.name),
                    got: poses.len(),
                    expected: times,
                });
            }
            for (k, p) in poses.iter().enumerate() {
                let ok = finite(&p.position)
                    && finite(&p.rotation)
                    && p.rotation.iter().map(|v| v * v).sum::<f64>() > 1e-12;
                if !ok {
                    return Err(VizError::Invalid {
                        what: format!("{what} ('{}').poses[{k}]", self.name),
                        problem: "non-finite position or rotation, or a zero quaternion".into(),
                    });
                }
            }
        }
        Ok(())
    }

    /// The carrier's pose at time index `k` (identity when fixed).
    pub fn pose(&self, k: usize) -> Pose {
        match &self.poses {
            Some(p) => p[k.min(p.len().saturating_sub(1))],
            None => Pose::at([0.0; 3]),
        }
    }
}

/// Where infinite shapes are drawn: a centre and a half size (m), in the
/// world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    /// Centre.
    pub center: [f64; 3],
    /// Half the side of a plane's patch, half the length of a cylinder.
    pub half_size: f64,
}

impl Region {
    /// The region around `points`: the centre of their bounding box and
    /// 1.2 times its half diagonal (so a patch reaches past the rods), at
    /// least `min_half` (a single point still gets a patch).
    pub fn around(points: impl IntoIterator<Item = [f64; 3]>, min_half: f64) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in points {
            for j in 0..3 {
                lo[j] = lo[j].min(p[j]);
                hi[j] = hi[j].max(p[j]);
            }
        }
        if !lo[0].is_finite() {
            return Self {
                center: [0.0; 3],
                half_size: min_half,
            };
        }
        let center = [0, 1, 2].map(|j| 0.5 * (lo[j] + hi[j]));
        let half = 0.5 * norm(sub(hi, lo));
        Self {
            center,
            half_size: (1.2 * half).max(min_half),
        }
    }

    /// The region seen from a carrier frame of pose `pose`.
    pub fn in_frame(&self, pose: &Pose) -> Self {
        let r = pose.matrix();
        let d = sub(self.center, pose.position);
        // Rᵀ d.
        let c = [0, 1, 2].map(|j| r[0][j] * d[0] + r[1][j] * d[1] + r[2][j] * d[2]);
        Self {
            center: c,
            half_size: self.half_size,
        }
    }
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(crate) fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

pub(crate) fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = norm(a);
    if n > 0.0 { scale(a, 1.0 / n) } else { a }
}

/// Two unit vectors completing `a` (unit) to a right-handed orthonormal
/// basis `(u, v, a)`.
pub(crate) fn basis(a: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let helper = if a[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let u = unit(cross(a, helper));
    let v = cross(a, u);
    (u, v)
}

/// A triangle mesh in the carrier's frame: `vertices[k] = [x, y, z, nx, ny,
/// nz]` (outward unit normals), `indices` three per triangle.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// Positions and normals.
    pub vertices: Vec<[f64; 6]>,
    /// Triangles.
    pub indices: Vec<u32>,
}

impl Mesh {
    fn vertex(&mut self, p: [f64; 3], n: [f64; 3]) -> u32 {
        self.vertices.push([p[0], p[1], p[2], n[0], n[1], n[2]]);
        (self.vertices.len() - 1) as u32
    }

    /// A grid of `rows + 1` × `cols + 1` vertices from `at(i, j)`, joined
    /// into quads.
    fn grid(
        &mut self,
        rows: usize,
        cols: usize,
        at: impl Fn(usize, usize) -> ([f64; 3], [f64; 3]),
    ) {
        let first = self.vertices.len() as u32;
        for i in 0..=rows {
            for j in 0..=cols {
                let (p, n) = at(i, j);
                self.vertex(p, n);
            }
        }
        let w = (cols + 1) as u32;
        for i in 0..rows as u32 {
            for j in 0..cols as u32 {
                let k = first + i * w + j;
                self.indices
                    .extend([k, k + w, k + 1, k + 1, k + w, k + w + 1]);
            }
        }
    }

    /// Largest distance of a vertex from the origin of the frame.
    pub fn reach(&self) -> f64 {
        self.vertices
            .iter()
            .map(|v| norm([v[0], v[1], v[2]]))
            .fold(0.0, f64::max)
    }
}

/// Segments around a circle of the drawn surfaces of revolution.
const AROUND: usize = 32;
/// Segments from pole to pole of a sphere.
const POLE_TO_POLE: usize = 16;

/// The surface of `shape` as triangles in its carrier's frame; planes and
/// cylinders over `region` (in the same frame).
pub fn mesh(shape: &ObstacleShape, region: &Region) -> Mesh {
    let mut m = Mesh::default();
    match *shape {
        ObstacleShape::Plane { position, normal } => {
            let n = unit(normal);
            let (u, v) = basis(n);
            // The patch centre: the region's centre projected onto the plane.
            let c = sub(
                region.center,
                scale(n, dot(sub(region.center, position), n)),
            );
            let h = region.half_size;
            m.grid(1, 1, |i, j| {
                let a = if i == 0 { -h } else { h };
                let b = if j == 0 { -h } else { h };
                (add(c, add(scale(u, a), scale(v, b))), n)
            });
        }
        ObstacleShape::Sphere { position, radius } => {
            swept_sphere(&mut m, position, [0.0, 0.0, 1.0], 0.0, radius);
        }
        ObstacleShape::Capsule {
            position,
            axis,
            length,
            radius,
        } => swept_sphere(&mut m, position, unit(axis), length, radius),
        ObstacleShape::Cylinder {
            position,
            axis,
            radius,
        } => {
            let a = unit(axis);
            let (u, v) = basis(a);
            let mid = add(position, scale(a, dot(sub(region.center, position), a)));
            let h = region.half_size;
            m.grid(1, AROUND, |i, j| {
                let th = 2.0 * std::f64::consts::PI * j as f64 / AROUND as f64;
                let n = add(scale(u, th.cos()), scale(v, th.sin()));
                let along = if i == 0 { -h } else { h };
                (add(add(mid, scale(a, along)), scale(n, radius)), n)
            });
        }
        ObstacleShape::Box {
            position,
            rotation,
            half_extents,
        } => {
            let col = |k: usize| [rotation[0][k], rotation[1][k], rotation[2][k]];
            for k in 0..3 {
                for sign in [-1.0, 1.0] {
                    let (b, c) = ((k + 1) % 3, (k + 2) % 3);
                    let n = scale(col(k), sign);
                    let centre = add(position, scale(n, half_extents[k]));
                    m.grid(1, 1, |i, j| {
                        let s1 = if i == 0 { -1.0 } else { 1.0 };
                        let s2 = if j == 0 { -1.0 } else { 1.0 } * sign;
                        let p = add(
                            centre,
                            add(
                                scale(col(b), s1 * half_extents[b]),
                                scale(col(c), s2 * half_extents[c]),
                            ),
                        );
                        (p, n)
                    });
                }
            }
        }
    }
    m
}

/// A sphere of `radius` swept along `length` of `axis` about `center`
/// (a capsule; a sphere for length 0): latitude rings from pole to pole,
/// the upper half shifted by `+length/2` along the axis, the lower by
/// `−length/2` (the equator ring twice, so the shift does not tear it).
fn swept_sphere(m: &mut Mesh, center: [f64; 3], axis: [f64; 3], length: f64, radius: f64) {
    let (u, v) = basis(axis);
    let half = POLE_TO_POLE / 2;
    let ring = |lat: usize, shift: f64, j: usize| {
        let th = std::f64::consts::PI * lat as f64 / POLE_TO_POLE as f64;
        let ph = 2.0 * std::f64::consts::PI * j as f64 / AROUND as f64;
        let n = add(
            scale(axis, th.cos()),
            scale(add(scale(u, ph.cos()), scale(v, ph.sin())), th.sin()),
        );
        (add(add(center, scale(axis, shift)), scale(n, radius)), n)
    };
    m.grid(half, AROUND, |i, j| ring(i, 0.5 * length, j));
    m.grid(half, AROUND, |i, j| ring(i + half, -0.5 * length, j));
    if length > 0.0 {
        // The side between the two equators.
        m.grid(1, AROUND, |i, j| {
            ring(half, if i == 0 { 0.5 } else { -0.5 } * length, j)
        });
    }
}

/// The region a view draws infinite obstacles over: around every rod
/// sample and body origin at every time.
pub fn view_region(d: &crate::data::ViewData) -> Region {
    let rods = d
        .rods
        .iter()
        .flat_map(|r| r.frames.iter().flatten().map(|p| p.position));
    let bodies = d
        .bodies
        .iter()
        .flat_map(|b| b.poses.iter().map(|p| p.position));
    let max_radius = d
        .rods
        .iter()
        .flat_map(|r| r.radius.iter().copied())
        .fold(0.0, f64::max);
    Region::around(rods.chain(bodies), (10.0 * max_radius).max(1e-3))
}

/// Writes the view's `obstacles` array (layout: [`crate::html`]). A fixed
/// obstacle's mesh is in the world frame less `origin` (what the view's GPU
/// coordinates are relative to); a carried one's in its carrier's frame
/// (the region taken at the first kept pose), with the carrier's pose per
/// kept frame written by `push_pose`.
pub(crate) fn push_view_json(
    o: &mut String,
    d: &crate::data::ViewData,
    frames: &[usize],
    origin: [f64; 3],
    push_pose: &dyn Fn(&mut String, &Pose),
) {
    use std::fmt::Write as _;
    o.push('[');
    if d.obstacles.is_empty() {
        // The region (a pass over every pose) is for the meshes only.
        o.push(']');
        return;
    }
    let region = view_region(d);
    for (k, ob) in d.obstacles.iter().enumerate() {
        if k > 0 {
            o.push(',');
        }
        let first = frames.first().copied().unwrap_or(0);
        let (m, shift) = match &ob.poses {
            None => (mesh(&ob.shape, &region), origin),
            Some(_) => (mesh(&ob.shape, &region.in_frame(&ob.pose(first))), [0.0; 3]),
        };
        let _ = write!(
            o,
            "{{\"name\":{},\"shape\":\"{}\",\"mesh\":[",
            crate::html::json_str(&ob.name),
            kind(&ob.shape)
        );
        for (i, v) in m.vertices.iter().enumerate() {
            if i > 0 {
                o.push(',');
            }
            // Six significant digits: far below a pixel, a third of the bytes.
            let _ = write!(
                o,
                "{},{},{},{},{},{}",
                short(v[0] - shift[0]),
                short(v[1] - shift[1]),
                short(v[2] - shift[2]),
                short(v[3]),
                short(v[4]),
                short(v[5])
            );
        }
        o.push_str("],\"triangles\":[");
        for (i, t) in m.indices.iter().enumerate() {
            if i > 0 {
                o.push(',');
            }
            let _ = write!(o, "{t}");
        }
        o.push_str("],\"frames\":");
        match &ob.poses {
            None => o.push_str("null"),
            Some(poses) => {
                o.push('[');
                for (i, &f) in frames.iter().enumerate() {
                    if i > 0 {
                        o.push(',');
                    }
                    o.push('[');
                    push_pose(o, &poses[f]);
                    if o.ends_with(',') {
                        o.pop();
                    }
                    o.push(']');
                }
                o.push(']');
            }
        }
        o.push('}');
    }
    o.push(']');
}

/// The contract's name of a shape (`"plane"`, `"sphere"`, …).
pub fn kind(shape: &ObstacleShape) -> &'static str {
    match shape {
        ObstacleShape::Plane { .. } => "plane",
        ObstacleShape::Sphere { .. } => "sphere",
        ObstacleShape::Cylinder { .. } => "cylinder",
        ObstacleShape::Capsule { .. } => "capsule",
        ObstacleShape::Box { .. } => "box",
    }
}

/// `v` with six significant digits, as short JSON text (`0.05`, `-1.2e-7`).
fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return "0".into();
    }
    let r: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    serde_json::Value::from(r).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn on_surface(shape: &ObstacleShape, p: [f64; 3]) -> f64 {
        // Signed distance of p to the (finite) shapes, for the mesh check.
        match *shape {
            ObstacleShape::Sphere { position, radius } => norm(sub(p, position)) - radius,
            ObstacleShape::Capsule {
                position,
                axis,
                length,
                radius,
            } => {
                let a = unit(axis);
                let t = dot(sub(p, position), a).clamp(-0.5 * length, 0.5 * length);
                norm(sub(p, add(position, scale(a, t)))) - radius
            }
            ObstacleShape::Box {
                position,
                rotation,
                half_extents,
            } => {
                let d = sub(p, position);
                let local = [0, 1, 2]
                    .map(|k| rotation[0][k] * d[0] + rotation[1][k] * d[1] + rotation[2][k] * d[2]);
                (0..3)
                    .map(|k| local[k].abs() - half_extents[k])
                    .fold(f64::NEG_INFINITY, f64::max)
            }
            _ => unreachable!(),
        }
    }

    /// Every vertex of a finite shape's mesh lies on its surface, and each
    /// normal is the unit outward normal there (the direction in which the
    /// distance grows: checked by central differences of the distance).
    #[test]
    fn finite_meshes_lie_on_their_surfaces() {
        let c = std::f64::consts::FRAC_1_SQRT_2;
        let shapes = [
            ObstacleShape::Sphere {
                position: [0.1, -0.2, 0.3],
                radius: 0.05,
            },
            ObstacleShape::Capsule {
                position: [0.0, 0.0, 1.0],
                axis: [0.0, 3.0, 4.0],
                length: 0.2,
                radius: 0.03,
            },
            ObstacleShape::Box {
                position: [1.0, 2.0, 3.0],
                rotation: [[c, -c, 0.0], [c, c, 0.0], [0.0, 0.0, 1.0]],
                half_extents: [0.1, 0.2, 0.3],
            },
        ];
        let region = Region::around([[0.0; 3]], 1.0);
        for s in &shapes {
            let m = mesh(s, &region);
            assert!(!m.indices.is_empty() && m.indices.len() % 3 == 0);
            assert!(m.indices.iter().all(|&i| (i as usize) < m.vertices.len()));
            for v in &m.vertices {
                let p = [v[0], v[1], v[2]];
                let n = [v[3], v[4], v[5]];
                assert!(on_surface(s, p).abs() < 1e-12, "{s:?}: {p:?}");
                assert!((norm(n) - 1.0).abs() < 1e-12);
                // The distance grows at rate 1 going out along the normal
                // (a forward difference: at a box's corner the distance is
                // not differentiable, but outward it is the face's).
                let h = 1e-7;
                let grow = (on_surface(s, add(p, scale(n, h))) - on_surface(s, p)) / h;
                assert!(
                    (grow - 1.0).abs() < 1e-6,
                    "{s:?}: normal {n:?} at {p:?} grows {grow}"
                );
            }
        }
    }

    /// A plane's patch lies in the plane, centred on the region's centre
    /// projected onto it, as wide as the region; a cylinder's vertices are
    /// at its radius from the axis, centred along it on the region.
    #[test]
    fn infinite_shapes_are_cut_to_the_region() {
        let region = Region {
            center: [0.3, 0.2, 0.5],
            half_size: 0.4,
        };
        let plane = ObstacleShape::Plane {
            position: [0.0, 0.0, -0.1],
            normal: [0.0, 0.0, 2.0],
        };
        let m = mesh(&plane, &region);
        assert_eq!(m.vertices.len(), 4);
        let mut centre = [0.0; 3];
        for v in &m.vertices {
            assert!((v[2] + 0.1).abs() < 1e-15);
            assert_eq!([v[3], v[4], v[5]], [0.0, 0.0, 1.0]);
            assert!(((v[0] - 0.3).abs() - 0.4).abs() < 1e-12);
            centre = add(centre, scale([v[0], v[1], v[2]], 0.25));
        }
        assert!(norm(sub(centre, [0.3, 0.2, -0.1])) < 1e-12);
        let cyl = ObstacleShape::Cylinder {
            position: [0.0, 0.0, 0.0],
            axis: [0.0, 1.0, 0.0],
            radius: 0.05,
        };
        let m = mesh(&cyl, &region);
        for v in &m.vertices {
            assert!(((v[0] * v[0] + v[2] * v[2]).sqrt() - 0.05).abs() < 1e-12);
            assert!(((v[1] - 0.2).abs() - 0.4).abs() < 1e-12);
        }
    }

    #[test]
    fn regions_and_validation() {
        let r = Region::around([[0.0, 0.0, 0.0], [0.6, 0.0, 0.8]], 1e-3);
        assert_eq!(r.center, [0.3, 0.0, 0.4]);
        assert!((r.half_size - 0.6).abs() < 1e-15);
        let bad = ObstacleTrack::fixed(
            "s",
            ObstacleShape::Sphere {
                position: [0.0; 3],
                radius: 0.0,
            },
        );
        assert!(bad.validate("obstacles[0]", 1).is_err());
        let mut carried = ObstacleTrack::fixed(
            "s",
            ObstacleShape::Sphere {
                position: [0.0; 3],
                radius: 1.0,
            },
        );
        carried.poses = Some(vec![Pose::at([0.0; 3])]);
        assert!(carried.validate("obstacles[0]", 1).is_ok());
        assert!(carried.validate("obstacles[0]", 2).is_err());
    }
}
