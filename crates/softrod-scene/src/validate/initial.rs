//! `[initial]`: `q` and `qdot` of the right length, shapes with distinct
//! points (the strains they start from are checked with the rest of the
//! initial state, `super::start`).

use std::path::Path;

use softrod_dynamics::Rod;

use super::{Ctx, Result};
use crate::raw::{RawInitial, RawShape};
use crate::robot::Robot;
use crate::scene::{Initial, InitialShape};

/// Relative round-off allowed past the rod's length in a shape's `s`.
const SHAPE_END_TOL: f64 = 1e-12;

impl Ctx<'_> {
    pub(super) fn initial(
        &mut self,
        raw: Option<RawInitial>,
        rods: &[Rod],
        robot: &Robot,
    ) -> Result<Initial> {
        let Some(raw) = raw else {
            return Ok(Initial::default());
        };
        let joints = robot.joint_dofs();
        let n_dof: usize = rods.iter().map(|r| r.geometry.n_dof()).sum::<usize>() + joints;
        let per_rod = rods
            .iter()
            .map(|r| {
                format!(
                    "{}: {} pieces × {} strains",
                    r.name,
                    r.geometry.n_pieces(),
                    r.geometry.pieces()[0].basis.dof()
                )
            })
            .chain((joints > 0).then(|| format!("joints: {joints}")))
            .collect::<Vec<_>>()
            .join(", ");
        if raw.row.is_some() && raw.trajectory.is_none() {
            return Err(self.r.invalid(
                "initial.row",
                "needs initial.trajectory (the file it is a row of)",
            ));
        }
        let mut raw = raw;
        if let Some(file) = raw.trajectory.take() {
            if raw.q.is_some() || raw.qdot.is_some() {
                return Err(self.r.invalid(
                    "initial.trajectory",
                    "conflicting keys: give initial.trajectory (with row) or q/qdot, not both",
                ));
            }
            // Relative to the scene file, so a scene and its runs move together.
            let path = match Path::new(self.r.file()).parent() {
                Some(dir) if Path::new(&file).is_relative() => dir.join(&file),
                _ => Path::new(&file).to_path_buf(),
            };
            let (q, qdot) = trajectory_row(&path, raw.row.unwrap_or(-1), n_dof).map_err(|m| {
                self.r
                    .invalid("initial.trajectory", format!("{}: {m}", path.display()))
            })?;
            if qdot.is_none() {
                self.warn(
                    "initial.trajectory",
                    format!(
                        "{}: no qdot columns: starting from q at rest",
                        path.display()
                    ),
                );
            }
            raw.q = Some(q);
            raw.qdot = qdot;
        }
        for (key, v) in [("q", &raw.q), ("qdot", &raw.qdot)] {
            if let Some(v) = v
                && v.len() != n_dof
            {
                return Err(self.r.inconsistent(
                    &format!("initial.{key}"),
                    format!(
                        "{} values but the scene has n_dof = {n_dof} ({per_rod})",
                        v.len()
                    ),
                ));
            }
        }
        let shape = match raw.shape {
            None => Vec::new(),
            // With `q` (or a trajectory row) as well, the shapes replace
            // their rods' strains and `q` gives the rest (joints, others).
            Some(shapes) => self.shapes(shapes, rods)?,
        };
        Ok(Initial {
            q: raw.q,
            qdot: raw.qdot,
            shape,
        })
    }

    /// `[initial] shape`: per entry a known rod (each at most once) and its
    /// centreline, `[x, y, z]` rows equally spaced in arc length base to
    /// tip (at least two) or `[s, x, y, z]` rows with `s` strictly
    /// increasing in `[0, L]` (at least one).
    fn shapes(&self, shapes: Vec<RawShape>, rods: &[Rod]) -> Result<Vec<InitialShape>> {
        let mut out: Vec<InitialShape> = Vec::with_capacity(shapes.len());
        for (k, sh) in shapes.into_iter().enumerate() {
            let p = format!("initial.shape[{k}]");
            let Some(rod) = rods.iter().position(|r| r.name == sh.rod) else {
                return Err(self.r.unknown_rod(
                    &format!("{p}.rod"),
                    &sh.rod,
                    rods.iter().map(|r| r.name.clone()).collect(),
                ));
            };
            if out.iter().any(|o| o.rod == rod) {
                return Err(self.r.invalid(
                    &format!("{p}.rod"),
                    format!("rod {:?} has a shape already", sh.rod),
                ));
            }
            let cp = format!("{p}.centerline");
            let length = rods[rod].geometry.length();
            let width = sh.centerline.first().map_or(0, Vec::len);
            if width != 3 && width != 4 {
                return Err(self.r.inconsistent(
                    &cp,
                    format!(
                        "rows must be [x, y, z] (equally spaced in arc length) or [s, x, y, z]; \
                         the first has {width} values"
                    ),
                ));
            }
            if let Some(i) = sh.centerline.iter().position(|r| r.len() != width) {
                return Err(self.r.inconsistent(
                    &format!("{cp}[{i}]"),
                    format!(
                        "{} values, but the first row has {width}",
                        sh.centerline[i].len()
                    ),
                ));
            }
            let n = sh.centerline.len();
            if width == 3 && n < 2 {
                return Err(self.r.invalid(
                    &cp,
                    "[x, y, z] rows need at least two points (base and tip)",
                ));
            }
            let mut points: Vec<(f64, [f64; 3])> = Vec::with_capacity(n);
            for (i, row) in sh.centerline.iter().enumerate() {
                let (mut s, xyz) = if width == 4 {
                    (row[0], [row[1], row[2], row[3]])
                } else {
                    (length * i as f64 / (n - 1) as f64, [row[0], row[1], row[2]])
                };
                if width == 4 {
                    let sp = format!("{cp}[{i}][0]");
                    // The rod's length is the sum of its pieces', which rounds
                    // a few ulps below the scene's `length` (0.1 * 10 < 1.0):
                    // an s within that round-off of the end is the end.
                    if !(0.0..=length * (1.0 + SHAPE_END_TOL)).contains(&s) {
                        return Err(self.r.out_of_range(
                            &sp,
                            s,
                            format!("in [0, {length}] (the rod's length)"),
                        ));
                    }
                    s = s.min(length);
                    if let Some(&(prev, _)) = points.last()
                        && s <= prev
                    {
                        return Err(self
                            .r
                            .invalid(&sp, format!("s must increase strictly: {s} after {prev}")));
                    }
                }
                // Two points at one place would have the rod cover a
                // positive arc length without moving: stretch zero there.
                if let Some(&(_, prev)) = points.last() {
                    let d = (0..3)
                        .map(|c| (xyz[c] - prev[c]).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    if d <= 1e-12 * length {
                        return Err(self.r.invalid(
                            &format!("{cp}[{i}]"),
                            format!(
                                "repeats point {} {prev:?}: consecutive points must differ \
                                 (the rod cannot cover arc length without moving)",
                                i - 1
                            ),
                        ));
                    }
                }
                points.push((s, xyz));
            }
            out.push(InitialShape { rod, points });
        }
        Ok(out)
    }
}

/// `q` (and `qdot` when the file has those columns) of row `row` of a
/// `trajectory.csv` written by `softrod run`: data rows counted from 0,
/// negative from the end (−1 the last). Columns are found by name (`q0`…,
/// `qdot0`…), so the file's other columns do not matter.
fn trajectory_row(
    path: &Path,
    row: i64,
    n_dof: usize,
) -> std::result::Result<(Vec<f64>, Option<Vec<f64>>), String> {
    let mut rdr = csv::Reader::from_path(path).map_err(|e| format!("cannot read: {e}"))?;
    let header = rdr.headers().map_err(|e| format!("header: {e}"))?.clone();
    let column = |name: String| header.iter().position(|h| h == name);
    let q_cols: Vec<Option<usize>> = (0..n_dof).map(|i| column(format!("q{i}"))).collect();
    if let Some(i) = q_cols.iter().position(Option::is_none) {
        return Err(format!(
            "no column q{i}: the scene has n_dof = {n_dof} (a trajectory of another scene?)"
        ));
    }
    if column(format!("q{n_dof}")).is_some() {
        return Err(format!(
            "more q columns than the scene's n_dof = {n_dof} (a trajectory of another scene?)"
        ));
    }
    let qd_cols: Vec<Option<usize>> = (0..n_dof).map(|i| column(format!("qdot{i}"))).collect();
    let has_qd = qd_cols.iter().all(Option::is_some);
    let mut records = Vec::new();
    for rec in rdr.records() {
        records.push(rec.map_err(|e| format!("{e}"))?);
    }
    let n = records.len() as i64;
    let k = if row < 0 { n + row } else { row };
    if !(0..n).contains(&k) {
        return Err(format!("initial.row = {row}: the file has {n} data rows"));
    }
    let rec = &records[k as usize];
    let value = |c: usize, name: &str| -> std::result::Result<f64, String> {
        let text = rec.get(c).unwrap_or("");
        match text.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(format!(
                "data row {k}, column {name}: not a finite number: {text:?}"
            )),
        }
    };
    let q = q_cols
        .iter()
        .enumerate()
        .map(|(i, c)| value(c.unwrap_or(usize::MAX), &format!("q{i}")))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let qd = if has_qd {
        Some(
            qd_cols
                .iter()
                .enumerate()
                .map(|(i, c)| value(c.unwrap_or(usize::MAX), &format!("qdot{i}")))
                .collect::<std::result::Result<Vec<_>, _>>()?,
        )
    } else {
        None
    };
    Ok((q, qd))
}
