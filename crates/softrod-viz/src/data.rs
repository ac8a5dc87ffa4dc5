//! The inputs of the 3-D view: plain data, no physics types.
//!
//! Everything is SI (metres, seconds) in the **world frame**. A rod is given
//! by its centreline frames sampled at fixed material abscissae `s` (the
//! unstretched arc length, m, base to tip) at every output time; the frame
//! at a sample maps the rod's local frame to the world frame. The local x axis
//! is the rod's material tangent (the cross-section normal), local y and z
//! span the cross-section (docs/theory.md §0.1), so the tube is drawn as
//! circles of radius `r(s)` in the local y–z plane: with shear the
//! cross-section is drawn tilted against the centreline, as the Cosserat model
//! has it.

use serde::{Deserialize, Serialize};

use crate::error::VizError;

/// A rigid pose: position (m) and the unit quaternion `[w, x, y, z]` of the
/// rotation that maps the local frame to the world frame (the convention of
/// `shape.csv` and `trajectory.csv`'s `tip_q*`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position in the world frame, m.
    pub position: [f64; 3],
    /// Unit quaternion `[w, x, y, z]`, local → world. Need not be normalized
    /// exactly (the view normalizes); must not be zero.
    pub rotation: [f64; 4],
}

impl Pose {
    /// The identity rotation at `position`.
    pub fn at(position: [f64; 3]) -> Self {
        Self {
            position,
            rotation: [1.0, 0.0, 0.0, 0.0],
        }
    }

    /// A pose from a rotation matrix given by rows (`r[i][j] = R_ij`, local →
    /// world, columns are the local axes in world coordinates). Uses
    /// Shepperd's method (the largest of `w, x, y, z` is computed first, so
    /// no division by a small number). Returns `w ≥ 0`.
    pub fn from_matrix(position: [f64; 3], r: [[f64; 3]; 3]) -> Self {
        let tr = r[0][0] + r[1][1] + r[2][2];
        let q = if tr > r[0][0].max(r[1][1]).max(r[2][2]) {
            let w = 0.5 * (1.0 + tr).max(0.0).sqrt();
            let f = 0.25 / w;
            [
                w,
                (r[2][1] - r[1][2]) * f,
                (r[0][2] - r[2][0]) * f,
                (r[1][0] - r[0][1]) * f,
            ]
        } else if r[0][0] >= r[1][1] && r[0][0] >= r[2][2] {
            let x = 0.5 * (1.0 + r[0][0] - r[1][1] - r[2][2]).max(0.0).sqrt();
            let f = 0.25 / x;
            [
                (r[2][1] - r[1][2]) * f,
                x,
                (r[0][1] + r[1][0]) * f,
                (r[0][2] + r[2][0]) * f,
            ]
        } else if r[1][1] >= r[2][2] {
            let y = 0.5 * (1.0 - r[0][0] + r[1][1] - r[2][2]).max(0.0).sqrt();
            let f = 0.25 / y;
            [
                (r[0][2] - r[2][0]) * f,
                (r[0][1] + r[1][0]) * f,
                y,
                (r[1][2] + r[2][1]) * f,
            ]
        } else {
            let z = 0.5 * (1.0 - r[0][0] - r[1][1] + r[2][2]).max(0.0).sqrt();
            let f = 0.25 / z;
            [
                (r[1][0] - r[0][1]) * f,
                (r[0][2] + r[2][0]) * f,
                (r[1][2] + r[2][1]) * f,
                z,
            ]
        };
        let rotation = if q[0] < 0.0 {
            [-q[0], -q[1], -q[2], -q[3]]
        } else {
            q
        };
        Self { position, rotation }
    }

    /// The rotation matrix (rows) of the normalized quaternion.
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        let [w, x, y, z] = normalized(self.rotation);
        [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ]
    }

    /// `position + R · local`: a point given in the local frame, in world
    /// coordinates.
    pub fn apply(&self, local: [f64; 3]) -> [f64; 3] {
        let r = self.matrix();
        let mut out = self.position;
        for (i, o) in out.iter_mut().enumerate() {
            *o += r[i][0] * local[0] + r[i][1] * local[1] + r[i][2] * local[2];
        }
        out
    }
}

fn normalized(q: [f64; 4]) -> [f64; 4] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if n > 0.0 {
        [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
    } else {
        [1.0, 0.0, 0.0, 0.0]
    }
}

/// One rod over the run.
#[derive(Debug, Clone, PartialEq)]
pub struct RodTrack {
    /// The rod's name (any text: shown in the legend, never parsed).
    pub name: String,
    /// Material abscissae of the samples, m, strictly increasing, base to tip;
    /// at least 2. The same samples at every time.
    pub s: Vec<f64>,
    /// Outer radius of the cross-section at each sample, m, ≥ 0 (a linear taper
    /// is two different end values; the tube is linear between samples).
    pub radius: Vec<f64>,
    /// `frames[k][i]`: the centreline frame at sample `i` at output time `k`;
    /// one entry per time of [`ViewData::times`], each with `s.len()` poses.
    pub frames: Vec<Vec<Pose>>,
    /// Optional tip trace, one position per time of [`ViewData::times`]
    /// (world frame, m). `None`: the position of the last sample.
    pub tip_trace: Option<Vec<[f64; 3]>>,
}

/// A cable drawn as a polyline in the world frame.
#[derive(Debug, Clone, PartialEq)]
pub struct CableTrack {
    /// The cable's name, shown in the legend.
    pub name: String,
    /// `points[k]`: the polyline at output time `k` (world frame, m), ≥ 2
    /// points; one entry per time.
    pub points: Vec<Vec<[f64; 3]>>,
}

/// The shape of a rigid body, in its own frame, centred on its pose.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "lowercase")]
pub enum BodyShape {
    /// A box with edge lengths `size` (m) along the body's x, y, z axes.
    Box {
        /// Edge lengths, m, each > 0.
        size: [f64; 3],
    },
    /// A sphere of `radius` (m, > 0).
    Sphere {
        /// Radius, m.
        radius: f64,
    },
}

/// A rigid body over the run.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyTrack {
    /// The body's name, shown in the legend.
    pub name: String,
    /// Its shape.
    pub shape: BodyShape,
    /// Its pose at each output time (one entry per time).
    pub poses: Vec<Pose>,
}

/// Everything the 3-D view shows.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewData {
    /// Shown as the page title (e.g. the scene name).
    pub title: String,
    /// Output times, s, non-decreasing, at least one.
    pub times: Vec<f64>,
    /// The rods (at least one rod, or one body).
    pub rods: Vec<RodTrack>,
    /// Cables (optional).
    pub cables: Vec<CableTrack>,
    /// Rigid bodies (optional).
    pub bodies: Vec<BodyTrack>,
    /// Obstacles (optional): fixed, or carried with a pose per time.
    pub obstacles: Vec<crate::obstacles::ObstacleTrack>,
    /// The world direction drawn upward, e.g. `−g/|g|`; the grid lies in
    /// the plane normal to it. Default `[0, 0, 1]`.
    pub up: [f64; 3],
}

impl ViewData {
    /// An empty view with the given title and times; `up` = +z.
    pub fn new(title: impl Into<String>, times: Vec<f64>) -> Self {
        Self {
            title: title.into(),
            times,
            rods: Vec::new(),
            cables: Vec::new(),
            bodies: Vec::new(),
            obstacles: Vec::new(),
            up: [0.0, 0.0, 1.0],
        }
    }

    /// Checks sizes, orderings and finiteness; the error names what is wrong
    /// and where.
    pub fn validate(&self) -> Result<(), VizError> {
        self.validate_frames(true)
    }

    /// [`ViewData::validate`]; without `rod_poses`, the rods' frames are
    /// counted but their poses not checked (a collector checked each as it
    /// came: [`pose_valid`]).
    pub(crate) fn validate_frames(&self, rod_poses: bool) -> Result<(), VizError> {
        let m = self.times.len();
        if m == 0 {
            return Err(VizError::Empty("times"));
        }
        if self.rods.is_empty() && self.bodies.is_empty() {
            return Err(VizError::Empty("rods and bodies"));
        }
        finite("times", None, &self.times)?;
        if let Some(k) = self.times.windows(2).position(|w| w[1] < w[0]) {
            return Err(VizError::NotIncreasing {
                what: "times".into(),
                index: k + 1,
            });
        }
        finite("up", None, &self.up)?;
        if self.up.iter().map(|v| v * v).sum::<f64>() == 0.0 {
            return Err(VizError::Invalid {
                what: "up".into(),
                problem: "zero vector".into(),
            });
        }
        for (r, rod) in self.rods.iter().enumerate() {
            let what = |field: &str| format!("rods[{r}] ('{}').{field}", rod.name);
            let n = rod.s.len();
            if n < 2 {
                return Err(VizError::Invalid {
                    what: what("s"),
                    problem: format!("{n} samples (need at least 2)"),
                });
            }
            finite(&what("s"), None, &rod.s)?;
            if let Some(k) = rod.s.windows(2).position(|w| w[1] <= w[0]) {
                return Err(VizError::NotIncreasing {
                    what: what("s"),
                    index: k + 1,
                });
            }
            count(&what("radius"), rod.radius.len(), n)?;
            finite(&what("radius"), None, &rod.radius)?;
            if let Some(i) = rod.radius.iter().position(|r| *r < 0.0) {
                return Err(VizError::Invalid {
                    what: format!("{}[{i}]", what("radius")),
                    problem: format!("negative radius {}", rod.radius[i]),
                });
            }
            count(&what("frames"), rod.frames.len(), m)?;
            for (k, f) in rod.frames.iter().enumerate() {
                // The name is made only for an error: a view has a frame
                // per output time.
                if f.len() != n {
                    count(&format!("{}[{k}]", what("frames")), f.len(), n)?;
                }
                if rod_poses {
                    for (i, p) in f.iter().enumerate() {
                        pose_ok(|| format!("{}[{k}][{i}]", what("frames")), p)?;
                    }
                }
            }
            if let Some(tr) = &rod.tip_trace {
                count(&what("tip_trace"), tr.len(), m)?;
                for (k, p) in tr.iter().enumerate() {
                    finite(&what("tip_trace"), Some(k), p)?;
                }
            }
        }
        for (c, cable) in self.cables.iter().enumerate() {
            let what = format!("cables[{c}] ('{}').points", cable.name);
            count(&what, cable.points.len(), m)?;
            for (k, pl) in cable.points.iter().enumerate() {
                if pl.len() < 2 {
                    return Err(VizError::Invalid {
                        what: format!("{what}[{k}]"),
                        problem: format!("{} points (need at least 2)", pl.len()),
                    });
                }
                for p in pl {
                    finite(&what, Some(k), p)?;
                }
            }
        }
        for (b, body) in self.bodies.iter().enumerate() {
            let what = format!("bodies[{b}] ('{}')", body.name);
            let dims: Vec<f64> = match body.shape {
                BodyShape::Box { size } => size.to_vec(),
                BodyShape::Sphere { radius } => vec![radius],
            };
            if dims.iter().any(|d| !(d.is_finite() && *d > 0.0)) {
                return Err(VizError::Invalid {
                    what: format!("{what}.shape"),
                    problem: format!("sizes must be finite and > 0, got {dims:?}"),
                });
            }
            count(&format!("{what}.poses"), body.poses.len(), m)?;
            for (k, p) in body.poses.iter().enumerate() {
                pose_ok(|| format!("{what}.poses[{k}]"), p)?;
            }
        }
        for (o, obstacle) in self.obstacles.iter().enumerate() {
            obstacle.validate(&format!("obstacles[{o}]"), m)?;
        }
        Ok(())
    }
}

fn count(what: &str, got: usize, expected: usize) -> Result<(), VizError> {
    if got == expected {
        Ok(())
    } else {
        Err(VizError::Count {
            what: what.into(),
            got,
            expected,
        })
    }
}

fn finite(what: &str, at: Option<usize>, v: &[f64]) -> Result<(), VizError> {
    match v.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(VizError::NotFinite {
            what: match at {
                Some(k) => format!("{what}[{k}]"),
                None => what.into(),
            },
            index: i,
            value: v[i],
        }),
    }
}

/// Whether [`pose_ok`] accepts `p`: finite, with a rotation of squared
/// norm ≥ 1e-12.
pub(crate) fn pose_valid(p: &Pose) -> bool {
    p.position.iter().chain(&p.rotation).all(|x| x.is_finite())
        && p.rotation.iter().map(|v| v * v).sum::<f64>() >= 1e-12
}

/// `what` names the pose in an error; it is only built for one (a view
/// checks every pose of every frame).
fn pose_ok(what: impl Fn() -> String, p: &Pose) -> Result<(), VizError> {
    let ok = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if !ok(&p.position) {
        finite(&format!("{}.position", what()), None, &p.position)?;
    }
    if !ok(&p.rotation) {
        finite(&format!("{}.rotation", what()), None, &p.rotation)?;
    }
    if p.rotation.iter().map(|v| v * v).sum::<f64>() < 1e-12 {
        return Err(VizError::Invalid {
            what: format!("{}.rotation", what()),
            problem: "zero quaternion".into(),
        });
    }
    Ok(())
}

/// Interpolates the frame at material abscissa `s` along sampled frames:
/// position linear, rotation by normalized linear interpolation of the
/// quaternions (sign-aligned); clamped to the sampled range. `s_samples`
/// strictly increasing, same length as `frames`, at least one.
pub fn frame_at(s_samples: &[f64], frames: &[Pose], s: f64) -> Pose {
    let (i, u) = bracket(s_samples, s);
    between(frames, i, u)
}

/// Where `s` falls among `s_samples` (the [`frame_at`] clamping): the
/// sample `i` and the fraction `u ∈ [0, 1)` towards `i + 1`, `None` at or
/// beyond either end (the end frame itself).
fn bracket(s_samples: &[f64], s: f64) -> (usize, Option<f64>) {
    let n = s_samples.len();
    if n == 1 || s <= s_samples[0] {
        return (0, None);
    }
    if s >= s_samples[n - 1] {
        return (n - 1, None);
    }
    let i = s_samples.partition_point(|v| *v <= s).clamp(1, n - 1) - 1;
    (
        i,
        Some((s - s_samples[i]) / (s_samples[i + 1] - s_samples[i])),
    )
}

/// The frame a fraction `u` from `frames[i]` towards `frames[i + 1]`
/// (`frames[i]` itself without one).
fn between(frames: &[Pose], i: usize, u: Option<f64>) -> Pose {
    let Some(u) = u else {
        return frames[i];
    };
    let (a, b) = (&frames[i], &frames[i + 1]);
    let dot: f64 = (0..4).map(|j| a.rotation[j] * b.rotation[j]).sum();
    let sign = if dot < 0.0 { -1.0 } else { 1.0 };
    let mut position = [0.0; 3];
    for (j, p) in position.iter_mut().enumerate() {
        *p = a.position[j] + u * (b.position[j] - a.position[j]);
    }
    let mut q = [0.0; 4];
    for (j, v) in q.iter_mut().enumerate() {
        *v = (1.0 - u) * a.rotation[j] + u * sign * b.rotation[j];
    }
    Pose {
        position,
        rotation: normalized(q),
    }
}

/// The polylines of a cable routed along a rod at cross-section offsets:
/// `path` is `(s, y, z)` points (m; `y, z` in the rod's local frame), the
/// point at each is `p(s) + R(s)·(0, y, z)` with the frame interpolated by
/// [`frame_at`]. One polyline per time of the rod's frames. Between path
/// points the cable is straight in the local frame, as in the scene format's
/// `[[cable]] path`; the rod's own samples inside the span are added so the
/// cable follows the bent rod.
pub fn routed_cable(rod: &RodTrack, path: &[[f64; 3]]) -> Vec<Vec<[f64; 3]>> {
    let mut s_pts: Vec<f64> = path.iter().map(|p| p[0]).collect();
    if let (Some(&a), Some(&b)) = (s_pts.first(), s_pts.last()) {
        s_pts.extend(rod.s.iter().copied().filter(|s| *s > a && *s < b));
    }
    s_pts.sort_by(f64::total_cmp);
    s_pts.dedup();
    let offset = |s: f64| -> [f64; 2] {
        let i = path.partition_point(|p| p[0] <= s);
        if i == 0 {
            return [path[0][1], path[0][2]];
        }
        if i >= path.len() {
            let l = path[path.len() - 1];
            return [l[1], l[2]];
        }
        let (a, b) = (path[i - 1], path[i]);
        let u = (s - a[0]) / (b[0] - a[0]);
        [a[1] + u * (b[1] - a[1]), a[2] + u * (b[2] - a[2])]
    };
    // Where each point falls along the rod and its offset are the same at
    // every time: found once, not per frame.
    let stencil: Vec<(usize, Option<f64>, [f64; 3])> = s_pts
        .iter()
        .map(|&s| {
            let (i, u) = bracket(&rod.s, s);
            let [y, z] = offset(s);
            (i, u, [0.0, y, z])
        })
        .collect();
    rod.frames
        .iter()
        .map(|frames| {
            stencil
                .iter()
                .map(|&(i, u, local)| between(frames, i, u).apply(local))
                .collect()
        })
        .collect()
}
