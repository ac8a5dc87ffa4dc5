//! A run directory as files: `shape.csv` (the contract's
//! `t,rod,s,x,y,z,qw,qx,qy,qz`), `view.json` (radii, cables, bodies, title,
//! up direction) and `bodies.csv` (`t,body,x,y,z,qw,qx,qy,qz`), read and
//! written with a real CSV parser so any rod name (commas, quotes, line
//! breaks) survives. Layout of `view.json`: docs/scene-format-extensions.md,
//! "The view files".

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::data::{BodyShape, BodyTrack, CableTrack, Pose, RodTrack, ViewData, routed_cable};
use crate::error::VizError;
use crate::html::{ViewOptions, ViewStats, write_html};

/// File names inside a run directory.
pub const SHAPE_CSV: &str = "shape.csv";
/// See [`SHAPE_CSV`].
pub const VIEW_JSON: &str = "view.json";
/// See [`SHAPE_CSV`].
pub const BODIES_CSV: &str = "bodies.csv";
/// See [`SHAPE_CSV`].
pub const VIEW_HTML: &str = "view.html";
/// The contract's header of `shape.csv` (more columns may follow).
pub const SHAPE_HEADER: [&str; 10] = ["t", "rod", "s", "x", "y", "z", "qw", "qx", "qy", "qz"];
/// The header of `bodies.csv` (more columns may follow).
pub const BODIES_HEADER: [&str; 9] = ["t", "body", "x", "y", "z", "qw", "qx", "qy", "qz"];
/// Radius of a rod that `view.json` does not describe, as a fraction of its
/// sampled length (visible, and plainly not a measured radius).
pub const DEFAULT_RADIUS_FRACTION: f64 = 0.01;
/// Two samples' abscissae (or two files' times) are the same when they agree
/// to this relative tolerance: both were printed as shortest round-trip
/// decimals of the same `f64`, so they agree exactly unless rewritten.
pub const SAME_NUMBER_RTOL: f64 = 1e-12;

/// The shapes read from `shape.csv`: per rod, fixed samples over time.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeData {
    /// Output times, s, in file order.
    pub times: Vec<f64>,
    /// The rods, in order of first appearance.
    pub rods: Vec<RodShape>,
}

/// One rod of [`ShapeData`].
#[derive(Debug, Clone, PartialEq)]
pub struct RodShape {
    /// Rod name.
    pub name: String,
    /// Material abscissae of the samples, m.
    pub s: Vec<f64>,
    /// `frames[k][i]`: pose at sample `i`, time `k`.
    pub frames: Vec<Vec<Pose>>,
}

/// Writes `shape.csv` row by row (header first), as a run produces frames.
pub struct ShapeCsvWriter<W: Write> {
    w: csv::Writer<W>,
}

/// Appends `v` as CSV text: the shortest decimal that reads back to the
/// same `f64` (`0.1`, `1e-7`, `1.0`; Ryū, Adams 2018), read back exactly by
/// Rust, Python and numpy; `0` for both zeros (no `-0`). Written in place:
/// a run prints millions of numbers, and `format!` plus `core::fmt` cost
/// several times the printing itself.
pub fn push_num(out: &mut String, v: f64) {
    if v == 0.0 {
        out.push('0');
    } else {
        out.push_str(ryu::Buffer::new().format(v));
    }
}

/// [`push_num`] into a new string.
pub fn num(v: f64) -> String {
    let mut s = String::new();
    push_num(&mut s, v);
    s
}

/// Appends one CSV line: `prefix` (leading fields already in CSV form, each
/// followed by a comma; or empty), then `values` as [`push_num`] numbers
/// separated by commas, then `\n`. Numbers never need quoting.
pub fn push_csv_row(out: &mut String, prefix: &str, values: impl IntoIterator<Item = f64>) {
    out.push_str(prefix);
    let mut first = true;
    for v in values {
        if !first {
            out.push(',');
        }
        first = false;
        push_num(out, v);
    }
    out.push('\n');
}

impl<W: Write> ShapeCsvWriter<W> {
    /// Starts the file with the contract's header.
    pub fn new(inner: W) -> Result<Self, csv::Error> {
        let mut w = csv::Writer::from_writer(inner);
        w.write_record(SHAPE_HEADER)?;
        Ok(Self { w })
    }

    /// The rows of one rod at time `t`: one per sample, base to tip.
    /// `s.len()` must equal `poses.len()`.
    pub fn write_frame(
        &mut self,
        t: f64,
        rod: &str,
        s: &[f64],
        poses: &[Pose],
    ) -> Result<(), csv::Error> {
        debug_assert_eq!(s.len(), poses.len());
        let t = num(t);
        for (sv, p) in s.iter().zip(poses) {
            let [x, y, z] = p.position;
            let [qw, qx, qy, qz] = p.rotation;
            self.w.write_record([
                t.as_str(),
                rod,
                &num(*sv),
                &num(x),
                &num(y),
                &num(z),
                &num(qw),
                &num(qx),
                &num(qy),
                &num(qz),
            ])?;
        }
        Ok(())
    }

    /// Flushes buffered rows (call after each output time so an
    /// interrupted run leaves whole rows).
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.w.flush()
    }

    /// Flushes and returns the inner writer.
    pub fn into_inner(self) -> Result<W, VizError> {
        self.w.into_inner().map_err(|e| VizError::Io {
            path: PathBuf::from(SHAPE_CSV),
            source: e.into_error(),
        })
    }
}

/// Writes `bodies.csv` row by row.
pub struct BodiesCsvWriter<W: Write> {
    w: csv::Writer<W>,
}

impl<W: Write> BodiesCsvWriter<W> {
    /// Starts the file with [`BODIES_HEADER`].
    pub fn new(inner: W) -> Result<Self, csv::Error> {
        let mut w = csv::Writer::from_writer(inner);
        w.write_record(BODIES_HEADER)?;
        Ok(Self { w })
    }

    /// One body's pose at time `t`.
    pub fn write_pose(&mut self, t: f64, body: &str, p: &Pose) -> Result<(), csv::Error> {
        let [x, y, z] = p.position;
        let [qw, qx, qy, qz] = p.rotation;
        self.w.write_record([
            num(t).as_str(),
            body,
            &num(x),
            &num(y),
            &num(z),
            &num(qw),
            &num(qx),
            &num(qy),
            &num(qz),
        ])
    }

    /// Flushes buffered rows.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.w.flush()
    }
}

fn csv_err(path: &Path, line: u64, problem: impl Into<String>) -> VizError {
    VizError::Csv {
        path: path.to_path_buf(),
        line,
        problem: problem.into(),
    }
}

/// Streams the data rows of a CSV file with a required header prefix,
/// `n_num` numbers after the name column, to `row(line, time, name,
/// numbers)`: nothing of the file is kept here, so its size does not bound
/// what can be read.
fn for_each_row(
    path: &Path,
    header: &[&str],
    n_num: usize,
    mut row: impl FnMut(u64, f64, &str, &[f64]) -> Result<(), VizError>,
) -> Result<(), VizError> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_path(path)
        .map_err(|e| match e.into_kind() {
            csv::ErrorKind::Io(source) => VizError::Io {
                path: path.to_path_buf(),
                source,
            },
            other => csv_err(path, 0, format!("{other:?}")),
        })?;
    let head = rdr
        .headers()
        .map_err(|e| csv_err(path, 1, e.to_string()))?
        .clone();
    let got: Vec<&str> = head.iter().take(header.len()).collect();
    if got != header {
        return Err(csv_err(
            path,
            1,
            format!(
                "header starts {:?}, expected {:?}",
                got.join(","),
                header.join(",")
            ),
        ));
    }
    let mut rec = csv::StringRecord::new();
    let mut nums = vec![0.0; n_num];
    loop {
        match rdr.read_record(&mut rec) {
            Ok(true) => {}
            Ok(false) => return Ok(()),
            Err(e) => {
                let line = e.position().map_or(0, |p| p.line());
                return Err(csv_err(path, line, e.to_string()));
            }
        }
        let line = rec.position().map_or(0, |p| p.line());
        if rec.len() < header.len() {
            return Err(csv_err(
                path,
                line,
                format!("{} fields, expected at least {}", rec.len(), header.len()),
            ));
        }
        let parse = |i: usize| -> Result<f64, VizError> {
            let text = &rec[i];
            match text.trim().parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(csv_err(
                    path,
                    line,
                    format!("column {}: not a finite number: {text:?}", header[i]),
                )),
            }
        };
        let t = parse(0)?;
        for (j, v) in nums.iter_mut().enumerate() {
            *v = parse(2 + j)?;
        }
        row(line, t, &rec[1], &nums)?;
    }
}

/// Which output times a bounded read keeps: every `stride`-th, the stride
/// doubling whenever `2·cap` are kept, and the last one. Memory stays
/// between `cap` and `2·cap` times however long the run, and two files of
/// the same times (`shape.csv`, `bodies.csv`) keep the same ones, because
/// the choice depends only on a time's index.
#[derive(Debug, Clone, Copy)]
pub struct Thinning {
    cap: usize,
    stride: usize,
}

impl Thinning {
    /// Keeps every time until `2·cap` are kept.
    pub fn new(cap: usize) -> Self {
        Self {
            cap: cap.max(1),
            stride: 1,
        }
    }

    /// Whether the time of index `k` (0-based, in order) is kept.
    pub fn keeps(&self, k: usize) -> bool {
        k % self.stride == 0
    }

    /// After keeping a time: whether every other kept time is now dropped
    /// (the caller then drops the odd positions of its lists).
    pub fn full(&mut self, kept: usize) -> bool {
        if kept >= self.cap.saturating_mul(2) {
            self.stride *= 2;
            true
        } else {
            false
        }
    }
}

/// Keeps the even positions of `v` (what [`Thinning::full`] asks for).
pub fn halve<T>(v: &mut Vec<T>) {
    let mut i = 0;
    v.retain(|_| {
        i += 1;
        (i - 1) % 2 == 0
    });
}

fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= SAME_NUMBER_RTOL * a.abs().max(b.abs()).max(1e-300)
}

fn pose_of(v: &[f64]) -> Pose {
    Pose {
        position: [v[0], v[1], v[2]],
        rotation: [v[3], v[4], v[5], v[6]],
    }
}

/// Reads `shape.csv`. Rows of one time come together (rods in any order,
/// each rod's samples base to tip); every rod has the same samples `s` at
/// every time. Columns after the contract's ten are ignored.
pub fn read_shape_csv(path: &Path) -> Result<ShapeData, VizError> {
    read_shape_csv_thinned(path, usize::MAX)
}

/// [`read_shape_csv`] keeping between `cap` and `2·cap` of the times
/// (evenly spaced, the first and the last among them) whatever the file's
/// length: what a view of a run of 10⁸ output rows is built from. Every
/// row is still checked.
pub fn read_shape_csv_thinned(path: &Path, cap: usize) -> Result<ShapeData, VizError> {
    let mut thin = Thinning::new(cap);
    let mut times: Vec<f64> = Vec::new();
    let mut rods: Vec<RodShape> = Vec::new();
    // The time being read: its index, value and, per rod, its samples.
    let mut k = 0usize;
    let mut t_now: Option<f64> = None;
    let mut now: Vec<Vec<Pose>> = Vec::new();
    // Whether the previous time's frames were kept (else they are the
    // pending last time, appended at the end).
    let mut pending: Option<(f64, Vec<Vec<Pose>>)> = None;
    let mut finish_time = |t: f64,
                           k: usize,
                           now: &mut Vec<Vec<Pose>>,
                           rods: &mut Vec<RodShape>,
                           times: &mut Vec<f64>,
                           line: u64|
     -> Result<(), VizError> {
        for (r, f) in rods.iter().zip(now.iter()) {
            if f.len() != r.s.len() {
                return Err(csv_err(
                    path,
                    line,
                    format!(
                        "rod {:?} has {} of its {} samples at t = {t}",
                        r.name,
                        f.len(),
                        r.s.len()
                    ),
                ));
            }
        }
        if thin.keeps(k) {
            times.push(t);
            for (r, f) in rods.iter_mut().zip(now.iter_mut()) {
                r.frames.push(std::mem::take(f));
            }
            pending = None;
            if thin.full(times.len()) {
                halve(times);
                rods.iter_mut().for_each(|r| halve(&mut r.frames));
            }
        } else {
            pending = Some((t, std::mem::take(now)));
            *now = vec![Vec::new(); rods.len()];
        }
        for f in now.iter_mut() {
            f.clear();
        }
        Ok(())
    };
    for_each_row(path, &SHAPE_HEADER, 8, |line, t, name, v| {
        match t_now {
            Some(last) if same(last, t) => {}
            Some(last) => {
                if t < last {
                    return Err(csv_err(path, line, format!("time {t} after {last}")));
                }
                finish_time(last, k, &mut now, &mut rods, &mut times, line)?;
                k += 1;
                t_now = Some(t);
            }
            None => t_now = Some(t),
        }
        let r = match rods.iter().position(|r| r.name == name) {
            Some(r) => r,
            None => {
                if k > 0 {
                    return Err(csv_err(
                        path,
                        line,
                        format!("rod {name:?} first appears at t = {t}, not at the first time"),
                    ));
                }
                rods.push(RodShape {
                    name: name.to_string(),
                    s: Vec::new(),
                    frames: Vec::new(),
                });
                now.push(Vec::new());
                rods.len() - 1
            }
        };
        let rod = &mut rods[r];
        let i = now[r].len();
        let s = v[0];
        if k == 0 {
            if rod.s.last().is_some_and(|last| s <= *last) {
                return Err(csv_err(
                    path,
                    line,
                    format!("rod {name:?}: s = {s} does not increase"),
                ));
            }
            rod.s.push(s);
        } else if i >= rod.s.len() || !same(rod.s[i], s) {
            return Err(csv_err(
                path,
                line,
                format!(
                    "rod {name:?} at t = {t}: sample {i} at s = {s}, the first time had {}",
                    rod.s
                        .get(i)
                        .map_or("no such sample".into(), |v| format!("s = {v}"))
                ),
            ));
        }
        now[r].push(pose_of(&v[1..8]));
        Ok(())
    })?;
    let Some(last) = t_now else {
        return Err(csv_err(path, 2, "no rows"));
    };
    finish_time(last, k, &mut now, &mut rods, &mut times, 0)?;
    if let Some((t, frames)) = pending {
        times.push(t);
        for (r, f) in rods.iter_mut().zip(frames) {
            r.frames.push(f);
        }
    }
    Ok(ShapeData { times, rods })
}

/// A body's poses over time, as read from `bodies.csv`.
pub type BodyPoses = (String, Vec<Pose>);

/// Reads `bodies.csv`: the times, and per body (in order of first
/// appearance) its name and pose at each time.
pub fn read_bodies_csv(path: &Path) -> Result<(Vec<f64>, Vec<BodyPoses>), VizError> {
    read_bodies_csv_thinned(path, usize::MAX)
}

/// [`read_bodies_csv`] keeping the times [`read_shape_csv_thinned`] keeps
/// of a `shape.csv` of the same times and the same `cap`.
pub fn read_bodies_csv_thinned(
    path: &Path,
    cap: usize,
) -> Result<(Vec<f64>, Vec<BodyPoses>), VizError> {
    let mut thin = Thinning::new(cap);
    let mut times: Vec<f64> = Vec::new();
    let mut bodies: Vec<(String, Vec<Pose>)> = Vec::new();
    // Index of the time being read, its value, and the poses read at it.
    let mut k = 0usize;
    let mut t_now: Option<f64> = None;
    let mut pending: Option<(f64, Vec<Pose>)> = None;
    let mut now: Vec<Option<Pose>> = Vec::new();
    let mut finish_time = |t: f64,
                           k: usize,
                           now: &mut Vec<Option<Pose>>,
                           bodies: &mut Vec<(String, Vec<Pose>)>,
                           times: &mut Vec<f64>,
                           line: u64|
     -> Result<(), VizError> {
        let mut poses = Vec::with_capacity(now.len());
        for (b, p) in bodies.iter().zip(now.iter_mut()) {
            match p.take() {
                Some(p) => poses.push(p),
                None => {
                    return Err(csv_err(
                        path,
                        line,
                        format!("body {:?}: no pose at t = {t}", b.0),
                    ));
                }
            }
        }
        if thin.keeps(k) {
            times.push(t);
            for (b, p) in bodies.iter_mut().zip(poses) {
                b.1.push(p);
            }
            pending = None;
            if thin.full(times.len()) {
                halve(times);
                bodies.iter_mut().for_each(|b| halve(&mut b.1));
            }
        } else {
            pending = Some((t, poses));
        }
        Ok(())
    };
    for_each_row(path, &BODIES_HEADER, 7, |line, t, name, v| {
        match t_now {
            Some(last) if same(last, t) => {}
            Some(last) => {
                finish_time(last, k, &mut now, &mut bodies, &mut times, line)?;
                k += 1;
                t_now = Some(t);
            }
            None => t_now = Some(t),
        }
        let b = match bodies.iter().position(|b| b.0 == name) {
            Some(b) => b,
            None => {
                if k > 0 {
                    return Err(csv_err(
                        path,
                        line,
                        format!("body {name:?} first appears at t = {t}, not at the first time"),
                    ));
                }
                bodies.push((name.to_string(), Vec::new()));
                now.push(None);
                bodies.len() - 1
            }
        };
        if now[b].replace(pose_of(v)).is_some() {
            return Err(csv_err(
                path,
                line,
                format!("body {name:?}: two poses at t = {t}"),
            ));
        }
        Ok(())
    })?;
    if let Some(last) = t_now {
        finish_time(last, k, &mut now, &mut bodies, &mut times, 0)?;
    }
    if let Some((t, poses)) = pending {
        times.push(t);
        for (b, p) in bodies.iter_mut().zip(poses) {
            b.1.push(p);
        }
    }
    Ok((times, bodies))
}

/// The radius profile of a rod in `view.json`: `r` (m) at abscissae `s`
/// (m), linear between them, constant beyond the ends.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RadiusProfile {
    /// Abscissae, m, strictly increasing.
    pub s: Vec<f64>,
    /// Radii, m, ≥ 0; as many as `s`.
    pub r: Vec<f64>,
}

impl RadiusProfile {
    /// A constant radius.
    pub fn constant(r: f64) -> Self {
        Self {
            s: vec![0.0],
            r: vec![r],
        }
    }

    /// The radius at `s` (linear interpolation, clamped).
    pub fn at(&self, s: f64) -> f64 {
        let n = self.s.len();
        if n == 0 {
            return 0.0;
        }
        let i = self.s.partition_point(|v| *v <= s);
        if i == 0 {
            return self.r[0];
        }
        if i >= n {
            return self.r[n - 1];
        }
        let u = (s - self.s[i - 1]) / (self.s[i] - self.s[i - 1]);
        self.r[i - 1] + u * (self.r[i] - self.r[i - 1])
    }
}

/// A rod entry of `view.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rod {
    /// Name, as in `shape.csv`.
    pub name: String,
    /// Outer radius along the rod.
    pub radius: RadiusProfile,
}

/// A cable entry of `view.json`: routed through a rod's cross-sections.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CableSpec {
    /// Name shown in the legend.
    pub name: String,
    /// The rod it runs along.
    pub rod: String,
    /// `(s, y, z)` points, m: abscissa and offset in the rod's local frame,
    /// straight between points (the scene's `[[cable]] path`; a constant
    /// `offset` over `[from, to]` is the two points `(from, y, z)`, `(to, y, z)`).
    pub path: Vec<[f64; 3]>,
}

/// A body entry of `view.json`; its poses are in `bodies.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodySpec {
    /// Name, as in `bodies.csv`.
    pub name: String,
    /// Shape and size.
    #[serde(flatten)]
    pub shape: BodyShape,
}

/// `view.json`: what the 3-D view needs beyond `shape.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewSpec {
    /// Always `"softrod-view"`.
    pub format: String,
    /// Layout version, 1.
    pub version: u32,
    /// Page title (e.g. the scene's name).
    #[serde(default)]
    pub title: String,
    /// World direction drawn upward (default `[0, 0, 1]`; the CLI writes
    /// `−g/|g|` when there is gravity).
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    /// Radii of the rods (rods of `shape.csv` missing here get
    /// [`DEFAULT_RADIUS_FRACTION`] of their length).
    #[serde(default)]
    pub rods: Vec<Rod>,
    /// Cables.
    #[serde(default)]
    pub cables: Vec<CableSpec>,
    /// Rigid bodies.
    #[serde(default)]
    pub bodies: Vec<BodySpec>,
    /// Obstacles (absent from the file when there are none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacles: Vec<ObstacleSpec>,
}

/// An obstacle entry of `view.json`: its shape in its carrier's frame and
/// the carrier (`parent`: a body of [`ViewSpec::bodies`], whose poses are in
/// `bodies.csv`; absent: fixed in the world).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObstacleSpec {
    /// Name (legend).
    pub name: String,
    /// Shape and size, the scene format's keys.
    #[serde(flatten)]
    pub shape: crate::obstacles::ObstacleShape,
    /// The carrying body, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parent: Option<String>,
}

fn default_up() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

impl ViewSpec {
    /// An empty spec (version 1) with a title.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            format: "softrod-view".into(),
            version: 1,
            title: title.into(),
            up: default_up(),
            rods: Vec::new(),
            cables: Vec::new(),
            bodies: Vec::new(),
            obstacles: Vec::new(),
        }
    }

    /// Writes it, pretty-printed.
    pub fn write(&self, path: &Path) -> Result<(), VizError> {
        let text = serde_json::to_string_pretty(self).map_err(|source| VizError::Json {
            path: path.to_path_buf(),
            source,
        })?;
        std::fs::write(path, text + "\n").map_err(|source| VizError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Reads it and checks `format` and `version`.
    pub fn read(path: &Path) -> Result<Self, VizError> {
        let text = std::fs::read_to_string(path).map_err(|source| VizError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let spec: Self = serde_json::from_str(&text).map_err(|source| VizError::Json {
            path: path.to_path_buf(),
            source,
        })?;
        if spec.format != "softrod-view" || spec.version != 1 {
            return Err(VizError::Invalid {
                what: path.display().to_string(),
                problem: format!(
                    "format {:?} version {} (expected \"softrod-view\" version 1)",
                    spec.format, spec.version
                ),
            });
        }
        Ok(spec)
    }
}

/// The view of a run directory from its files: `shape.csv` (required),
/// `view.json` and `bodies.csv` (optional).
pub fn view_from_dir(dir: &Path) -> Result<ViewData, VizError> {
    view_from_dir_thinned(dir, usize::MAX)
}

/// [`view_from_dir`] from between `cap` and `2·cap` evenly spaced output
/// times (see [`read_shape_csv_thinned`]).
pub fn view_from_dir_thinned(dir: &Path, cap: usize) -> Result<ViewData, VizError> {
    let shape = read_shape_csv_thinned(&dir.join(SHAPE_CSV), cap)?;
    let spec_path = dir.join(VIEW_JSON);
    let spec = if spec_path.exists() {
        ViewSpec::read(&spec_path)?
    } else {
        ViewSpec::new(
            dir.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        )
    };
    let mut body_poses = Vec::new();
    if !spec.bodies.is_empty() {
        let path = dir.join(BODIES_CSV);
        let (times, poses) = read_bodies_csv_thinned(&path, cap)?;
        if times.len() != shape.times.len()
            || !times.iter().zip(&shape.times).all(|(a, b)| same(*a, *b))
        {
            return Err(csv_err(
                &path,
                0,
                format!(
                    "{} times, not the {} times of {SHAPE_CSV}",
                    times.len(),
                    shape.times.len()
                ),
            ));
        }
        body_poses = poses;
    }
    view_from_parts(&spec, &spec_path, shape, body_poses)
}

/// The view of `spec` (what `view.json` holds, read from `spec_path`,
/// named in errors) with the rods' shapes and the bodies' poses over the
/// same times.
pub fn view_from_parts(
    spec: &ViewSpec,
    spec_path: &Path,
    shape: ShapeData,
    body_poses: Vec<BodyPoses>,
) -> Result<ViewData, VizError> {
    let mut view = ViewData::new(spec.title.clone(), shape.times.clone());
    view.up = spec.up;
    for rod in shape.rods {
        let radius: Vec<f64> = match spec.rods.iter().find(|r| r.name == rod.name) {
            Some(r) => rod.s.iter().map(|s| r.radius.at(*s)).collect(),
            None => {
                let len = rod.s.last().unwrap_or(&0.0) - rod.s.first().unwrap_or(&0.0);
                vec![DEFAULT_RADIUS_FRACTION * len; rod.s.len()]
            }
        };
        view.rods.push(RodTrack {
            name: rod.name,
            s: rod.s,
            radius,
            frames: rod.frames,
            tip_trace: None,
        });
    }
    for c in &spec.cables {
        let rod = view
            .rods
            .iter()
            .find(|r| r.name == c.rod)
            .ok_or_else(|| VizError::Invalid {
                what: format!("{}: cable {:?}", spec_path.display(), c.name),
                problem: format!("unknown rod {:?}", c.rod),
            })?;
        if c.path.len() < 2 || c.path.windows(2).any(|w| w[1][0] <= w[0][0]) {
            return Err(VizError::Invalid {
                what: format!("{}: cable {:?}.path", spec_path.display(), c.name),
                problem: "needs at least 2 points with increasing s".into(),
            });
        }
        view.cables.push(CableTrack {
            name: c.name.clone(),
            points: routed_cable(rod, &c.path),
        });
    }
    for b in &spec.bodies {
        let p = body_poses.iter().find(|p| p.0 == b.name).ok_or_else(|| {
            csv_err(
                &spec_path.with_file_name(BODIES_CSV),
                0,
                format!("no rows for body {:?} of {VIEW_JSON}", b.name),
            )
        })?;
        view.bodies.push(BodyTrack {
            name: b.name.clone(),
            shape: b.shape,
            poses: p.1.clone(),
        });
    }
    for o in &spec.obstacles {
        let poses = match &o.parent {
            None => None,
            Some(body) => Some(
                body_poses
                    .iter()
                    .find(|p| &p.0 == body)
                    .map(|p| p.1.clone())
                    .ok_or_else(|| VizError::Invalid {
                        what: format!("{}: obstacle {:?}.parent", spec_path.display(), o.name),
                        problem: format!("no body {body:?} in {VIEW_JSON} and {BODIES_CSV}"),
                    })?,
            ),
        };
        view.obstacles.push(crate::obstacles::ObstacleTrack {
            name: o.name.clone(),
            shape: o.shape,
            poses,
        });
    }
    Ok(view)
}

/// Most poses (`shape.csv` rows) [`write_view`] holds when it can keep
/// more times than the page's frames (for finer tip traces): 2·10⁶, about
/// 110 MB.
pub const VIEW_POSE_BUDGET: usize = 2_000_000;

/// How many output times a view keeps (between `cap` and `2·cap`, see
/// [`Thinning`]) when each time holds `per_time` poses: up to
/// [`ViewOptions::max_trace_points`] for the tip traces while their poses
/// fit in [`VIEW_POSE_BUDGET`], never fewer than [`ViewOptions::max_frames`].
pub fn view_cap(per_time: usize, opts: &ViewOptions) -> usize {
    (VIEW_POSE_BUDGET / per_time.max(1))
        .min(opts.max_trace_points)
        .max(opts.max_frames)
}

/// Rows of `shape.csv`'s first output time (0 if unreadable: the full read
/// reports why).
fn rows_at_first_time(path: &Path) -> usize {
    let Ok(mut rdr) = csv::ReaderBuilder::new().has_headers(true).from_path(path) else {
        return 0;
    };
    let mut rec = csv::StringRecord::new();
    let mut first: Option<String> = None;
    let mut n = 0;
    while let Ok(true) = rdr.read_record(&mut rec) {
        let t = rec.get(0).unwrap_or("").to_string();
        match &first {
            Some(f) if *f != t => break,
            Some(_) => {}
            None => first = Some(t),
        }
        n += 1;
    }
    n
}

/// Regenerates `DIR/view.html` from the directory's files (what `softrod
/// view DIR` does); returns its path and what it kept.
///
/// Its memory does not grow with the run's length: it reads the times the
/// page can show — up to [`ViewOptions::max_trace_points`] for the tip
/// traces while their poses fit in [`VIEW_POSE_BUDGET`], never fewer than
/// [`ViewOptions::max_frames`] — and streams the rest past.
pub fn write_view(dir: &Path, opts: &ViewOptions) -> Result<(PathBuf, ViewStats), VizError> {
    let cap = view_cap(rows_at_first_time(&dir.join(SHAPE_CSV)), opts);
    let view = view_from_dir_thinned(dir, cap)?;
    let out = dir.join(VIEW_HTML);
    let stats = write_html(&out, &view, opts)?;
    Ok((out, stats))
}
