//! What a run directory holds besides the numbers: the view description
//! (`view.json`), the 3-D view, the run's file names, CSV fields and the
//! disk-space check.

use std::path::{Path, PathBuf};

use softrod::dynamics::Model;
use softrod::mechanics::{Routing, Section};
use softrod_viz::BodyShape;
use softrod_viz::collect::FrameCollector;
use softrod_viz::run_dir::{CableSpec, RadiusProfile, Rod, VIEW_JSON, ViewSpec};
use softrod_viz::{ViewOptions, ViewStats};

use crate::common::{CliError, failed};

/// Outer radius profile of a section over a rod of length `length` (the
/// circumscribed radius of a rectangle), as `view.json` takes it.
pub fn radius_profile(section: &Section, length: f64) -> RadiusProfile {
    match *section {
        Section::Circle { radius } | Section::Tube { radius, .. } => {
            RadiusProfile::constant(radius)
        }
        Section::Rectangle { width, height } => RadiusProfile::constant(0.5 * width.hypot(height)),
        Section::TaperedCircle {
            radius_base,
            radius_tip,
        } => RadiusProfile {
            s: vec![0.0, length],
            r: vec![radius_base, radius_tip],
        },
    }
}

/// `view.json` for a model: title, up (`−g/|g|` with gravity), rod radii,
/// cable paths as `(s, y, z)` in the rod's frame.
pub fn view_spec(model: &Model, title: &str) -> ViewSpec {
    let mut spec = ViewSpec::new(title);
    if let Some(g) = model.gravity().filter(|g| g.norm() > 0.0) {
        let u = -g / g.norm();
        // `+ 0.0` turns −0 into 0 in the file.
        spec.up = [u[0] + 0.0, u[1] + 0.0, u[2] + 0.0];
    }
    let mut cable_no = 0;
    for rm in model.rods() {
        let length = rm.spec.geometry.length();
        spec.rods.push(Rod {
            name: rm.spec.name.clone(),
            radius: radius_profile(rm.spec.properties.section(), length),
        });
        for c in &rm.spec.cables {
            let (from, to) = c.bounds(length);
            let path = match &c.routing {
                Routing::Offset { y, z } => vec![[from, *y, *z], [to, *y, *z]],
                Routing::Path(pts) => {
                    // The cable runs over [from, to] only: clip the path to it.
                    let at = |s: f64| {
                        let (d, _) = c.routing.offset(s);
                        [s, d[1], d[2]]
                    };
                    let mut v = vec![at(from)];
                    v.extend(pts.iter().filter(|p| p[0] > from && p[0] < to).copied());
                    v.push(at(to));
                    v
                }
            };
            spec.cables.push(CableSpec {
                name: format!("cable {cable_no}"),
                rod: rm.spec.name.clone(),
                path,
            });
            cable_no += 1;
        }
    }
    for o in model.obstacles() {
        spec.obstacles.push(softrod_viz::run_dir::ObstacleSpec {
            name: o.name.clone(),
            shape: crate::contact::viz_shape(&o.shape),
            parent: o.parent.clone(),
        });
    }
    for b in model.bodies() {
        spec.bodies.push(softrod_viz::run_dir::BodySpec {
            name: b.spec.name.clone(),
            shape: BodyShape::Box {
                size: equivalent_box(b.spec.mass, &b.spec.inertia),
            },
        });
    }
    spec
}

/// Edge lengths \[m\] of the uniform box with the body's mass and the
/// diagonal of its inertia (`I_xx = m (b² + c²)/12`, …), what the view draws
/// for a body: `a² = 6 (I_yy + I_zz − I_xx)/m`. Edges are kept ≥ 1 mm so a
/// point-like body stays visible.
fn equivalent_box(mass: f64, inertia: &nalgebra::Matrix3<f64>) -> [f64; 3] {
    let d = [inertia[(0, 0)], inertia[(1, 1)], inertia[(2, 2)]];
    let edge = |k: usize| {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let sq = 6.0 * (d[i] + d[j] - d[k]) / mass;
        if sq.is_finite() {
            sq.max(0.0).sqrt().max(1e-3)
        } else {
            1e-3
        }
    };
    [edge(0), edge(1), edge(2)]
}

/// Writes `DIR/view.json`, and `DIR/view.html` from the run's `frames`
/// (the page `softrod view DIR` rebuilds from the files).
pub fn write_view(
    dir: &Path,
    model: &Model,
    title: &str,
    frames: FrameCollector,
) -> Result<ViewStats, CliError> {
    let spec = view_spec(model, title);
    spec.write(&dir.join(VIEW_JSON))
        .map_err(|e| failed(softrod::report(&e)))?;
    frames
        .write_view(dir, &spec, &ViewOptions::default())
        .map(|(_, stats)| stats)
        .map_err(|e| view_failed(dir, &e))
}

/// A failed view: the page is removed (never a truncated one after a
/// full disk) and the error says why.
fn view_failed(dir: &Path, e: &softrod_viz::VizError) -> CliError {
    let _ = std::fs::remove_file(dir.join(softrod_viz::run_dir::VIEW_HTML));
    failed(format!("3-D view: {}", softrod::report(e)))
}

/// The files `softrod run` writes (besides `strains_R.svg`): removed at the
/// start of a run, so that a directory never mixes two runs' outputs.
pub const RUN_OUTPUTS: [&str; 22] = [
    "trajectory.csv",
    "contacts.csv",
    "trajectory.npz",
    "trajectory.npz.tmp",
    "shape.csv",
    "bodies.csv",
    "summary.json",
    "summary.json.tmp",
    "view.json",
    "view.html",
    "tip_trajectory.svg",
    "energy.svg",
    "shapes.svg",
    "strains.svg",
    "actuators.svg",
    "shape.svg",
    "tip_trajectory.png",
    "energy.png",
    "shapes.png",
    "strains.png",
    "actuators.png",
    "shape.png",
];

/// Whether `name` is a file `softrod run` writes.
fn is_run_output(name: &str) -> bool {
    RUN_OUTPUTS.contains(&name)
        || name
            .strip_prefix("strains_")
            .and_then(|r| r.strip_suffix(".svg").or_else(|| r.strip_suffix(".png")))
            .is_some_and(|r| !r.is_empty() && r.bytes().all(|b| b.is_ascii_digit()))
}

/// Makes `dir` ready for outputs: creates it, and checks that files can be
/// written there. Problems are bad input (exit 2) naming the directory.
pub fn prepare_out_dir(dir: &Path) -> Result<(), CliError> {
    let bad = |why: String| CliError::Input(format!("output directory {}: {why}", dir.display()));
    if dir.exists() && !dir.is_dir() {
        return Err(bad("exists and is not a directory".into()));
    }
    std::fs::create_dir_all(dir).map_err(|e| bad(format!("cannot create it: {e}")))?;
    let probe = dir.join(".softrod-write-probe");
    std::fs::write(&probe, b"").map_err(|e| bad(format!("cannot write in it: {e}")))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Removes the outputs of a previous run from `dir` (regular files with the
/// names `softrod run` writes; anything else is left alone). Returns the
/// names removed.
pub fn clear_stale(dir: &Path) -> Result<Vec<String>, CliError> {
    let mut removed = Vec::new();
    let entries = std::fs::read_dir(dir)
        .map_err(|e| CliError::Input(format!("output directory {}: {e}", dir.display())))?;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let regular = entry.file_type().is_ok_and(|t| t.is_file());
        if regular && is_run_output(&name) {
            std::fs::remove_file(entry.path()).map_err(|e| {
                CliError::Input(format!(
                    "cannot remove the previous run's {}: {e}",
                    entry.path().display()
                ))
            })?;
            removed.push(name);
        }
    }
    removed.sort();
    Ok(removed)
}

/// One CSV record (RFC 4180: fields quoted when they hold a comma, quote or
/// line break), with its line end.
pub fn csv_line<I, S>(fields: I) -> String
where
    I: IntoIterator<Item = S>,
    S: AsRef<[u8]>,
{
    let mut w = csv::Writer::from_writer(Vec::new());
    // Writing into memory cannot fail.
    let _ = w.write_record(fields);
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

pub use softrod_viz::run_dir::{num, push_csv_row};

/// A text field as CSV (quoted when it needs to be), for the prefix of
/// [`push_csv_row`].
pub fn csv_field(text: &str) -> String {
    let mut line = csv_line([text]);
    line.pop();
    line
}

/// Bytes free for an unprivileged writer on the file system holding `dir`
/// (or its nearest existing ancestor); `None` where this cannot be asked.
pub fn free_disk_bytes(dir: &Path) -> Option<u64> {
    let mut probe = dir.to_path_buf();
    while !probe.exists() {
        if !probe.pop() {
            probe = PathBuf::from(".");
            break;
        }
    }
    if probe.as_os_str().is_empty() {
        probe = PathBuf::from(".");
    }
    fs4::available_space(&probe).ok()
}

/// Bytes a CSV number takes at least once the motion has started (a
/// shortest round-trip decimal of a generic `f64` has 15–17 digits, a sign,
/// a point and often an exponent; 12 leaves room for the rounder ones).
const CSV_NUMBER_BYTES: u64 = 12;

/// What `softrod run` writes per output time \[bytes\], estimated from
/// below: the `trajectory.csv` row, the `shape.csv` rows of every rod's
/// samples (`shape_samples`, all rods), the `bodies.csv` rows, for a model
/// with contact the `contacts.csv` rows of the `contacts` active at the
/// start, and with `npz` the archive's 8 bytes per trajectory number.
pub fn output_bytes_per_row(
    model: &Model,
    shape_samples: usize,
    contacts: usize,
    npz: bool,
) -> u64 {
    let numbers = (9 + 2 * model.n_dof() + 3 + 2 * model.n_cables()) as u64;
    // t, name, s and a pose; t, name and a pose; 13 numbers, two names and
    // the state.
    let shape = shape_samples as u64 * (9 * CSV_NUMBER_BYTES + 2);
    let bodies = model.bodies().len() as u64 * (8 * CSV_NUMBER_BYTES + 2);
    let contact = contacts as u64 * (13 * CSV_NUMBER_BYTES + 6);
    let archive = if npz { 8 * numbers } else { 0 };
    CSV_NUMBER_BYTES * numbers + shape + bodies + contact + archive
}

/// The disk a run of `duration` s sampled every `every` s needs at least
/// (see [`output_bytes_per_row`]), and its number of output times.
pub fn disk_need(duration: f64, every: f64, per_row: u64) -> (u64, u64) {
    let rows = softrod::limits::output_sample_count(duration, every).unwrap_or(u64::MAX);
    (rows.saturating_mul(per_row), rows)
}

/// Refuses (exit 2, naming `run.output_every`) a run whose outputs cannot
/// fit on the disk that holds `dir`, before anything is allocated or
/// written. `per_row`: [`output_bytes_per_row`].
pub fn check_disk_space(
    dir: &Path,
    duration: f64,
    every: f64,
    per_row: u64,
) -> Result<(), CliError> {
    let (need, rows) = disk_need(duration, every, per_row);
    if let Some(free) = free_disk_bytes(dir) {
        if need > free {
            return Err(CliError::Input(format!(
                "run.output_every: {rows} output times of {every:e} s over {duration} s need at least {} on disk \
                 (trajectory, shape, bodies, contacts and archive rows), {} free at {}; sample less often",
                human(need),
                human(free),
                dir.display()
            )));
        }
    }
    Ok(())
}

/// Bytes as "12.3 MB", "4.5 GB", "1.2 TB".
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e12 {
        format!("{:.1} TB", b / 1e12)
    } else if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else {
        format!("{:.1} MB", b / 1e6)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_lines_quote_what_needs_it_and_read_back() {
        let fields = ["a,b", "say \"hi\"", "two\nlines", "plain"];
        let line = csv_line(fields);
        assert_eq!(line, "\"a,b\",\"say \"\"hi\"\"\",\"two\nlines\",plain\n");
        let mut r = csv::ReaderBuilder::new()
            .has_headers(false)
            .from_reader(line.as_bytes());
        let rec = r.records().next().unwrap().unwrap();
        assert_eq!(rec.iter().collect::<Vec<_>>(), fields);
    }

    #[test]
    fn only_run_outputs_count_as_stale() {
        for n in [
            "trajectory.csv",
            "strains.svg",
            "strains_12.svg",
            "view.html",
        ] {
            assert!(is_run_output(n), "{n}");
        }
        for n in [
            "notes.txt",
            "strains_.svg",
            "strains_a.svg",
            "report.csv",
            "mine.svg",
        ] {
            assert!(!is_run_output(n), "{n}");
        }
    }

    #[test]
    fn numbers_round_trip_and_have_no_negative_zero() {
        for v in [0.1, 1e-7, 0.07200000000000001, 1e300, -2.5, 1.0 / 3.0] {
            assert_eq!(num(v).parse::<f64>().unwrap(), v);
        }
        assert_eq!(num(-0.0), "0");
        assert_eq!(num(1e-300), "1e-300");
    }

    /// Rows written in place read back, by the csv crate, as the quoted
    /// name and the exact numbers.
    #[test]
    fn rows_written_in_place_read_back() {
        let name = "arm, \"left\"";
        let prefix = format!("{},{},", num(0.25), csv_field(name));
        let values = [0.1, -0.0, 1e-300, -2.5e17, 1.0 / 3.0, f64::MIN_POSITIVE];
        let mut text = String::new();
        push_csv_row(&mut text, &prefix, values);
        push_csv_row(&mut text, "", [7.0]);
        let mut r = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .from_reader(text.as_bytes());
        let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
        assert_eq!(rows.len(), 2);
        assert_eq!(&rows[0][1], name);
        assert_eq!(rows[0][0].parse::<f64>().unwrap(), 0.25);
        for (i, v) in values.iter().enumerate() {
            assert_eq!(rows[0][2 + i].parse::<f64>().unwrap(), *v);
        }
        assert_eq!(&rows[0][3], "0");
        assert_eq!(&rows[1][0], "7.0");
    }
}
