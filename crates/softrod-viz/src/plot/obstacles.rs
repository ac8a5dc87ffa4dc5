//! Obstacles in the geometry figures: the outline of each obstacle in each
//! axis-aligned projection (its silhouette), as 3-D polylines whose two
//! panel coordinates are the outline's (the third is unused).
//!
//! - sphere: the circle of its radius;
//! - capsule: the two end circles joined by their common tangents (exact:
//!   the projection of a swept sphere is the swept disc of the projected
//!   segment);
//! - cylinder (cut to the region around the rods): a strip of half-width
//!   `radius` about the projected axis (exact: every direction in the panel
//!   normal to the projected axis is normal to the axis), or its circle when
//!   the axis points along the view;
//! - box: the convex hull of its eight projected corners;
//! - plane: its trace, a line with short hatches on the solid side, when
//!   the view runs along the plane (its normal has no component along the
//!   view); a plane seen face-on covers the whole panel and is not drawn.

use crate::obstacles::{ObstacleShape, ObstacleTrack, Region, add, cross, dot, scale, sub, unit};

/// A polyline of an obstacle's outline in one panel.
pub(super) struct Outline {
    /// Points; coordinates `a` and `b` of the panel are the outline's.
    pub points: Vec<[f64; 3]>,
    /// Drawn lighter (an earlier position of a carried obstacle).
    pub fade: f64,
}

/// Points on a circle's outline.
const CIRCLE: usize = 72;
/// A component of a unit normal or axis below this counts as zero (the view
/// runs along the plane, the axis lies in the panel).
const ALONG: f64 = 1e-9;

/// The outlines of `obstacles` in the panel of axes `(a, b)`: fixed ones
/// once, carried ones at each of their poses (lighter when earlier).
/// `region`: where infinite shapes are cut (world frame).
pub(super) fn outlines(
    obstacles: &[ObstacleTrack],
    (a, b): (usize, usize),
    region: &Region,
) -> Vec<Outline> {
    let mut out = Vec::new();
    for ob in obstacles {
        match &ob.poses {
            None => {
                for points in outline(&ob.shape, (a, b), region) {
                    out.push(Outline { points, fade: 0.0 });
                }
            }
            Some(poses) => {
                let m = poses.len();
                for (k, pose) in poses.iter().enumerate() {
                    let fade = if m > 1 {
                        0.7 * (1.0 - k as f64 / (m - 1) as f64)
                    } else {
                        0.0
                    };
                    let shape = in_world(&ob.shape, pose);
                    for points in outline(&shape, (a, b), region) {
                        out.push(Outline { points, fade });
                    }
                }
            }
        }
    }
    out
}

/// `shape` (in a carrier frame of pose `pose`) in the world frame.
pub(super) fn in_world(shape: &ObstacleShape, pose: &crate::data::Pose) -> ObstacleShape {
    let r = pose.matrix();
    let rot = |v: [f64; 3]| [0, 1, 2].map(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2]);
    let at = |p: [f64; 3]| pose.apply(p);
    match *shape {
        ObstacleShape::Plane { position, normal } => ObstacleShape::Plane {
            position: at(position),
            normal: rot(normal),
        },
        ObstacleShape::Sphere { position, radius } => ObstacleShape::Sphere {
            position: at(position),
            radius,
        },
        ObstacleShape::Cylinder {
            position,
            axis,
            radius,
        } => ObstacleShape::Cylinder {
            position: at(position),
            axis: rot(axis),
            radius,
        },
        ObstacleShape::Capsule {
            position,
            axis,
            length,
            radius,
        } => ObstacleShape::Capsule {
            position: at(position),
            axis: rot(axis),
            length,
            radius,
        },
        ObstacleShape::Box {
            position,
            rotation,
            half_extents,
        } => {
            // R_world = R_pose · R_box.
            let mut m = [[0.0; 3]; 3];
            for (i, row) in m.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    *v = (0..3).map(|k| r[i][k] * rotation[k][j]).sum();
                }
            }
            ObstacleShape::Box {
                position: at(position),
                rotation: m,
                half_extents,
            }
        }
    }
}

/// The outline polylines of a world-frame `shape` in the panel `(a, b)`.
pub(super) fn outline(
    shape: &ObstacleShape,
    (a, b): (usize, usize),
    region: &Region,
) -> Vec<Vec<[f64; 3]>> {
    let view = 3 - a - b;
    let lift = |p: [f64; 2]| {
        let mut q = region.center;
        q[a] = p[0];
        q[b] = p[1];
        q
    };
    let flat = |p: [f64; 3]| [p[a], p[b]];
    let circle = |c: [f64; 2], r: f64| -> Vec<[f64; 3]> {
        (0..=CIRCLE)
            .map(|k| {
                let t = 2.0 * std::f64::consts::PI * k as f64 / CIRCLE as f64;
                lift([c[0] + r * t.cos(), c[1] + r * t.sin()])
            })
            .collect()
    };
    match *shape {
        ObstacleShape::Sphere { position, radius } => vec![circle(flat(position), radius)],
        ObstacleShape::Capsule {
            position,
            axis,
            length,
            radius,
        } => {
            let d = scale(unit(axis), 0.5 * length);
            vec![stadium(
                flat(sub(position, d)),
                flat(add(position, d)),
                radius,
                &lift,
            )]
        }
        ObstacleShape::Cylinder {
            position,
            axis,
            radius,
        } => {
            let u = unit(axis);
            let mid = add(position, scale(u, dot(sub(region.center, position), u)));
            let d = scale(u, region.half_size);
            let (p0, p1) = (flat(sub(mid, d)), flat(add(mid, d)));
            let along = [p1[0] - p0[0], p1[1] - p0[1]];
            let len = along[0].hypot(along[1]);
            if len <= ALONG * region.half_size {
                return vec![circle(p0, radius)];
            }
            let w = [-along[1] / len * radius, along[0] / len * radius];
            vec![
                [
                    [p0[0] + w[0], p0[1] + w[1]],
                    [p1[0] + w[0], p1[1] + w[1]],
                    [p1[0] - w[0], p1[1] - w[1]],
                    [p0[0] - w[0], p0[1] - w[1]],
                    [p0[0] + w[0], p0[1] + w[1]],
                ]
                .map(lift)
                .to_vec(),
            ]
        }
        ObstacleShape::Box {
            position,
            rotation,
            half_extents,
        } => {
            let col = |k: usize| [rotation[0][k], rotation[1][k], rotation[2][k]];
            let corners: Vec<[f64; 2]> = (0..8)
                .map(|c| {
                    let mut p = position;
                    for (k, h) in half_extents.iter().enumerate() {
                        let s = if c & (1 << k) != 0 { 1.0 } else { -1.0 };
                        p = add(p, scale(col(k), s * h));
                    }
                    flat(p)
                })
                .collect();
            let mut hull = convex_hull(corners);
            if let Some(&first) = hull.first() {
                hull.push(first);
            }
            vec![hull.into_iter().map(lift).collect()]
        }
        ObstacleShape::Plane { position, normal } => {
            let n = unit(normal);
            if n[view].abs() > ALONG {
                return Vec::new();
            }
            // The trace: through the region's centre projected onto the plane.
            let c = sub(
                region.center,
                scale(n, dot(sub(region.center, position), n)),
            );
            let t = cross(n, {
                let mut e = [0.0; 3];
                e[view] = 1.0;
                e
            });
            let t = unit(t);
            let h = region.half_size;
            let mut lines = vec![vec![sub(c, scale(t, h)), add(c, scale(t, h))]];
            // Hatches on the solid side (against the normal), at 45°.
            let step = h / 10.0;
            let hatch = scale(unit(sub(t, n)), 0.5 * step);
            for k in -10..10 {
                let p = add(c, scale(t, (k as f64 + 0.5) * step));
                lines.push(vec![p, add(p, hatch)]);
            }
            lines
        }
    }
    .into_iter()
    .map(|l| l.into_iter().map(|p| keep(p, a, b, region)).collect())
    .collect()
}

/// A point with its panel coordinates and the region centre's third one.
fn keep(p: [f64; 3], a: usize, b: usize, region: &Region) -> [f64; 3] {
    let mut q = region.center;
    q[a] = p[a];
    q[b] = p[b];
    q
}

/// The outline of the disc of `radius` swept from `p0` to `p1`.
fn stadium(
    p0: [f64; 2],
    p1: [f64; 2],
    radius: f64,
    lift: &dyn Fn([f64; 2]) -> [f64; 3],
) -> Vec<[f64; 3]> {
    let d = [p1[0] - p0[0], p1[1] - p0[1]];
    let phi = d[1].atan2(d[0]);
    let half = CIRCLE / 2;
    let arc = |c: [f64; 2], from: f64| {
        (0..=half).map(move |k| {
            let t = from + std::f64::consts::PI * k as f64 / half as f64;
            [c[0] + radius * t.cos(), c[1] + radius * t.sin()]
        })
    };
    let half_pi = std::f64::consts::FRAC_PI_2;
    let mut pts: Vec<[f64; 2]> = arc(p1, phi - half_pi).collect();
    pts.extend(arc(p0, phi + half_pi));
    pts.push(pts[0]);
    pts.into_iter().map(lift).collect()
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain).
fn convex_hull(mut points: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    points.sort_by(|p, q| p[0].total_cmp(&q[0]).then(p[1].total_cmp(&q[1])));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let turn = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// The world-frame region a figure cuts infinite obstacles to: around the
/// drawn points, reaching just past them (0.6 of their box's half
/// diagonal: a table's trace spans the rods without widening the panels
/// much).
pub(super) fn region_of(points: impl IntoIterator<Item = [f64; 3]>) -> Region {
    let r = Region::around(points, 1e-3);
    Region {
        center: r.center,
        half_size: (0.5 * r.half_size).max(1e-3),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn region() -> Region {
        Region {
            center: [0.0, 0.0, 0.0],
            half_size: 1.0,
        }
    }

    /// Every point of each outline is at the shape's silhouette: for a
    /// sphere at its radius from the centre; for a box on the boundary of
    /// the projected box's extent along x and z (an axis-aligned box
    /// projects to its rectangle).
    #[test]
    fn silhouettes_of_spheres_boxes_and_capsules() {
        let s = ObstacleShape::Sphere {
            position: [0.2, 5.0, -0.3],
            radius: 0.1,
        };
        for p in &outline(&s, (0, 2), &region())[0] {
            assert!(((p[0] - 0.2).hypot(p[2] + 0.3) - 0.1).abs() < 1e-12);
        }
        let b = ObstacleShape::Box {
            position: [1.0, 2.0, 3.0],
            rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            half_extents: [0.1, 0.2, 0.3],
        };
        let o = &outline(&b, (0, 2), &region())[0];
        assert_eq!(o.len(), 5);
        for p in o {
            assert!(((p[0] - 1.0).abs() - 0.1).abs() < 1e-12);
            assert!(((p[2] - 3.0).abs() - 0.3).abs() < 1e-12);
        }
        // A capsule along y seen along y is its circle; seen along z a
        // stadium reaching length/2 + radius along y.
        let c = ObstacleShape::Capsule {
            position: [0.0; 3],
            axis: [0.0, 2.0, 0.0],
            length: 0.4,
            radius: 0.05,
        };
        let top = outline(&c, (0, 1), &region())[0]
            .iter()
            .map(|p| p[1])
            .fold(f64::NEG_INFINITY, f64::max);
        assert!((top - 0.25).abs() < 1e-12);
        for p in &outline(&c, (0, 2), &region())[0] {
            assert!((p[0].hypot(p[2]) - 0.05).abs() < 1e-12);
        }
    }

    /// A table seen from the side is the line z = its height, hatched
    /// below; seen from above it is not drawn.
    #[test]
    fn planes_are_drawn_edge_on_only() {
        let table = ObstacleShape::Plane {
            position: [0.0, 0.0, -0.2],
            normal: [0.0, 0.0, 3.0],
        };
        let side = outline(&table, (0, 2), &region());
        assert!(side[0].iter().all(|p| (p[2] + 0.2).abs() < 1e-12));
        assert!(side[1..].iter().all(|h| h[1][2] < -0.2));
        assert!(outline(&table, (0, 1), &region()).is_empty());
    }
}
