//! The rows of a run's files: `trajectory.csv`, `shape.csv`,
//! `bodies.csv` and `contacts.csv` written as each record arrives, and `trajectory.npz` from
//! the same numbers at the end. Only formatting: every number comes from
//! the facade's [`Record`], every column name from its [`Columns`].

use std::fs::File;
use std::io::Write;
use std::path::Path;

use softrod::dynamics::Model;
use softrod::mechanics::{ContactPoint, Contactee};
use softrod::record::{Columns, Record, position, quaternion};
use softrod_viz::collect::FrameCollector;
use softrod_viz::run_dir::{BODIES_HEADER, SHAPE_HEADER};
use softrod_viz::{Pose, ViewOptions};

use crate::common::{CliError, failed};
use crate::npz;
use crate::outputs::{csv_field, csv_line, num, push_csv_row};

/// The NumPy archive of the trajectory (`--npz`), and its temporary name.
pub const NPZ: &str = "trajectory.npz";
/// See [`NPZ`].
pub const NPZ_TMP: &str = "trajectory.npz.tmp";
/// The contacts of a run with contact (scene-format.md, "Contact").
pub const CONTACTS_CSV: &str = "contacts.csv";
/// Its header, the contract's.
pub const CONTACTS_HEADER: [&str; 16] = [
    "t", "a", "s", "b", "b_s", "x", "y", "z", "nx", "ny", "nz", "gap", "fx", "fy", "fz", "state",
];

/// An output file written row by row, unbuffered (each row is one write),
/// that knows how many bytes hold whole rows: after a failed write (a full
/// disk) it is cut back there, so it never ends in half a row.
struct OutFile {
    name: &'static str,
    file: File,
    committed: u64,
}

impl OutFile {
    fn create(dir: &Path, name: &'static str, header: &str) -> Result<Self, CliError> {
        let path = dir.join(name);
        let mut file = File::create(&path)
            .map_err(|e| CliError::Input(format!("cannot create {}: {e}", path.display())))?;
        file.write_all(header.as_bytes())
            .map_err(|e| failed(format!("writing {}: {e}", path.display())))?;
        Ok(Self {
            name,
            file,
            committed: header.len() as u64,
        })
    }

    fn append(&mut self, text: &str) -> Result<(), String> {
        self.file
            .write_all(text.as_bytes())
            .map_err(|e| format!("writing {}: {e}", self.name))
    }

    /// Cuts the file back to its whole rows.
    fn rollback(&mut self) -> bool {
        self.file.set_len(self.committed).is_ok()
    }

    fn commit(&mut self, bytes: usize) {
        self.committed += bytes as u64;
    }
}

/// One output time's numbers for the files, copied out of a [`Record`]
/// so that they can be formatted and written on another thread while the
/// integration goes on (its buffers are reused from row to row).
#[derive(Default)]
pub struct RowData {
    /// Time \[s\].
    pub t: f64,
    /// The row of `trajectory.csv`, in its column order.
    values: Vec<f64>,
    /// Per rod: the samples' abscissae \[m\] and world poses `[x, y, z,
    /// qw, qx, qy, qz]` (m; unit quaternion with `qw ≥ 0`).
    s: Vec<Vec<f64>>,
    samples: Vec<Vec<[f64; 7]>>,
    /// The rigid bodies' world poses, as the samples'.
    bodies: Vec<[f64; 7]>,
    /// The active contacts.
    contacts: Vec<ContactPoint>,
}

/// A pose as `[x, y, z, qw, qx, qy, qz]`.
fn pose7(g: &softrod::lie::Pose) -> [f64; 7] {
    let [x, y, z] = position(g);
    let [qw, qx, qy, qz] = quaternion(g);
    [x, y, z, qw, qx, qy, qz]
}

impl RowData {
    /// Copies `rec`'s numbers (`columns`: the run's [`Columns`]).
    pub fn fill(&mut self, columns: &Columns, rec: &Record) {
        self.t = rec.t;
        self.values.clear();
        columns.push_row(rec.row(), &mut self.values);
        let n_rods = rec.poses.n_rods();
        self.s.resize_with(n_rods, Vec::new);
        self.samples.resize_with(n_rods, Vec::new);
        for r in 0..n_rods {
            self.s[r].clear();
            self.s[r].extend_from_slice(&rec.poses.sampling(r).s);
            self.samples[r].clear();
            self.samples[r].extend(rec.poses.samples(r).iter().map(pose7));
        }
        self.bodies.clear();
        self.bodies.extend(rec.poses.bodies().iter().map(pose7));
        self.contacts.clear();
        self.contacts.extend_from_slice(&rec.contacts);
    }
}

/// Writes each record's rows to the run's CSV files (every file gets a
/// time's rows, or none does) and keeps them for `trajectory.npz`. A new
/// per-time file (e.g. `contacts.csv`, from the record's contact forces)
/// is one more [`OutFile`] here, written and rolled back with the others.
pub struct RowWriter {
    columns: Columns,
    traj: OutFile,
    shape: OutFile,
    /// `bodies.csv` (t, body, pose), for a model with rigid bodies.
    bodies: Option<OutFile>,
    /// `contacts.csv` (one row per active contact), for a model with contact.
    contacts: Option<OutFile>,
    contacts_text: String,
    /// The obstacles' names as CSV fields (a contact's `b`).
    obstacle_fields: Vec<String>,
    traj_text: String,
    shape_text: String,
    bodies_text: String,
    /// The rods' and bodies' names as CSV fields, and the current row's
    /// leading fields (allocated once).
    rod_fields: Vec<String>,
    body_fields: Vec<String>,
    prefix: String,
    /// Per rod, per sample: its abscissa `s` and that number as CSV text
    /// with its comma (the same at every time: formatted once, not at
    /// every row of `shape.csv`).
    s_fields: Vec<Vec<(f64, String)>>,
    /// With `--npz`: every written row's numbers, in `trajectory.csv`'s
    /// column order (kept for `trajectory.npz`, written at the end).
    npz_rows: Option<Vec<f64>>,
    /// The frames of the 3-D view, kept as the rows are written (the view
    /// is built from them, not from `shape.csv` read back).
    view: Option<FrameCollector>,
}

impl RowWriter {
    /// Creates the files in `dir` with their headers.
    pub fn create(dir: &Path, model: &Model, npz: bool) -> Result<Self, CliError> {
        let columns = Columns::of(model);
        let traj = OutFile::create(dir, "trajectory.csv", &csv_line(columns.names()))?;
        let shape = OutFile::create(dir, "shape.csv", &csv_line(SHAPE_HEADER))?;
        let bodies = if model.bodies().is_empty() {
            None
        } else {
            Some(OutFile::create(
                dir,
                "bodies.csv",
                &csv_line(BODIES_HEADER),
            )?)
        };
        let contacts = if model.has_contact() {
            Some(OutFile::create(
                dir,
                CONTACTS_CSV,
                &csv_line(CONTACTS_HEADER),
            )?)
        } else {
            None
        };
        Ok(Self {
            columns,
            traj,
            shape,
            bodies,
            contacts,
            contacts_text: String::new(),
            obstacle_fields: model
                .obstacles()
                .iter()
                .map(|o| csv_field(&o.name))
                .collect(),
            traj_text: String::new(),
            shape_text: String::new(),
            bodies_text: String::new(),
            rod_fields: model
                .rods()
                .iter()
                .map(|r| csv_field(&r.spec.name))
                .collect(),
            body_fields: model
                .bodies()
                .iter()
                .map(|b| csv_field(&b.spec.name))
                .collect(),
            prefix: String::new(),
            s_fields: vec![Vec::new(); model.rods().len()],
            npz_rows: npz.then(Vec::new),
            view: None,
        })
    }

    /// Also keeps the frames of the 3-D view (`rods`: each rod's sample
    /// abscissae, m), thinned as `softrod view` thins `shape.csv`.
    pub fn collect_view(&mut self, model: &Model, rods: Vec<Vec<f64>>) {
        let names = model.rods().iter().map(|r| r.spec.name.clone());
        self.view = Some(FrameCollector::new(
            names.zip(rods).collect(),
            model.bodies().iter().map(|b| b.spec.name.clone()).collect(),
            &ViewOptions::default(),
        ));
    }

    /// The view's frames collected so far (see [`RowWriter::collect_view`]).
    pub fn take_view(&mut self) -> Option<FrameCollector> {
        self.view.take()
    }

    /// The shape of `trajectory.csv` (to fill a [`RowData`]).
    pub fn columns(&self) -> Columns {
        self.columns
    }

    /// Appends one time's rows (`d`, filled from a record by
    /// [`RowData::fill`]) to every file; on a failed write, cuts every file
    /// back to its previous whole rows.
    pub fn write(&mut self, d: &RowData) -> Result<(), String> {
        let t = d.t;
        self.traj_text.clear();
        push_csv_row(&mut self.traj_text, "", d.values.iter().copied());
        self.shape_text.clear();
        let ts = num(t);
        for (r, name) in self.rod_fields.iter().enumerate() {
            self.prefix.clear();
            self.prefix.push_str(&ts);
            self.prefix.push(',');
            self.prefix.push_str(name);
            self.prefix.push(',');
            let s = &d.s[r];
            let cached = &mut self.s_fields[r];
            let same = cached.len() == s.len()
                && cached
                    .iter()
                    .zip(s)
                    .all(|(c, v)| c.0.to_bits() == v.to_bits());
            if !same {
                cached.clear();
                cached.extend(s.iter().map(|&v| {
                    let mut text = num(v);
                    text.push(',');
                    (v, text)
                }));
            }
            for ((_, s_text), g) in cached.iter().zip(&d.samples[r]) {
                self.shape_text.push_str(&self.prefix);
                push_csv_row(&mut self.shape_text, s_text, g.iter().copied());
            }
        }
        self.bodies_text.clear();
        for (name, g) in self.body_fields.iter().zip(&d.bodies) {
            self.prefix.clear();
            self.prefix.push_str(&ts);
            self.prefix.push(',');
            self.prefix.push_str(name);
            self.prefix.push(',');
            push_csv_row(&mut self.bodies_text, &self.prefix, g.iter().copied());
        }
        self.contacts_text.clear();
        if self.contacts.is_some() {
            for c in &d.contacts {
                self.prefix.clear();
                self.prefix.push_str(&ts);
                self.prefix.push(',');
                self.prefix.push_str(&self.rod_fields[c.a]);
                self.prefix.push(',');
                self.prefix.push_str(&num(c.s));
                self.prefix.push(',');
                match c.b {
                    Contactee::Obstacle(k) => {
                        self.prefix.push_str(&self.obstacle_fields[k]);
                        self.prefix.push_str(",,");
                    }
                    Contactee::Rod { rod, s } => {
                        self.prefix.push_str(&self.rod_fields[rod]);
                        self.prefix.push(',');
                        self.prefix.push_str(&num(s));
                        self.prefix.push(',');
                    }
                }
                push_csv_row(
                    &mut self.contacts_text,
                    &self.prefix,
                    c.point
                        .iter()
                        .chain(&c.normal)
                        .chain(std::iter::once(&c.gap))
                        .chain(&c.force)
                        .copied(),
                );
                // The state closes the row: replace its line break.
                self.contacts_text.pop();
                self.contacts_text
                    .push_str(if c.sticking { ",stick\n" } else { ",slip\n" });
            }
        }
        // Every file gets this time's rows, or none does.
        let bodies_text = &self.bodies_text;
        let contacts_text = &self.contacts_text;
        let written = self
            .shape
            .append(&self.shape_text)
            .and_then(|()| match &mut self.bodies {
                Some(f) => f.append(bodies_text),
                None => Ok(()),
            })
            .and_then(|()| match &mut self.contacts {
                Some(f) => f.append(contacts_text),
                None => Ok(()),
            })
            .and_then(|()| self.traj.append(&self.traj_text));
        if let Err(e) = written {
            let bodies_cut = self.bodies.as_mut().is_none_or(OutFile::rollback);
            let contacts_cut = self.contacts.as_mut().is_none_or(OutFile::rollback);
            let cut = self.shape.rollback() & self.traj.rollback() & bodies_cut & contacts_cut;
            return Err(format!(
                "{e} at t = {t:e}; {}",
                if cut {
                    "the partial row was removed: the files hold whole rows up to the previous time"
                } else {
                    "the partial row could not be removed either"
                }
            ));
        }
        self.shape.commit(self.shape_text.len());
        if let Some(f) = &mut self.bodies {
            f.commit(self.bodies_text.len());
        }
        if let Some(f) = &mut self.contacts {
            f.commit(self.contacts_text.len());
        }
        self.traj.commit(self.traj_text.len());
        if let Some(rows) = &mut self.npz_rows {
            // `+ 0.0` turns −0 into 0, as the CSV writes it.
            rows.extend(d.values.iter().map(|v| v + 0.0));
        }
        if let Some(view) = &mut self.view {
            let pose = |g: &[f64; 7]| Pose {
                position: [g[0], g[1], g[2]],
                rotation: [g[3], g[4], g[5], g[6]],
            };
            for (r, samples) in d.samples.iter().enumerate() {
                view.push_rod(r, samples.iter().map(pose));
            }
            for g in &d.bodies {
                view.push_body(pose(g));
            }
            // The frame is whole by construction (the rows just written).
            let _ = view.end_time(t);
        }
        Ok(())
    }

    /// Writes `DIR/trajectory.npz` from the rows written (the same rows and
    /// numbers as `trajectory.csv`, one array per column group of
    /// [`Columns::groups`]), atomically: `trajectory.npz.tmp` renamed over
    /// it, or nothing (the temporary file removed) on an error. Does
    /// nothing without `--npz`.
    pub fn write_npz(
        &self,
        dir: &Path,
        q_names: &[String],
        prescribed_names: &[String],
    ) -> Result<(), String> {
        let Some(rows) = &self.npz_rows else {
            return Ok(());
        };
        let width = self.columns.width();
        let m = rows.len() / width;
        debug_assert_eq!(rows.len(), m * width);
        // Columns `cols` of every row, as one C-order (m, cols.len()) block.
        let take = |cols: &[usize]| -> Vec<f64> {
            rows.chunks_exact(width)
                .flat_map(|r| cols.iter().map(move |&c| r[c]))
                .collect()
        };
        let mut a = npz::Archive::new();
        for g in self.columns.groups() {
            let shape = if g.vector {
                vec![m, g.columns.len()]
            } else {
                vec![m]
            };
            a.add_f64(g.name, &shape, &take(&g.columns));
        }
        a.add_strings("q_names", q_names);
        if self.columns.n_prescribed > 0 {
            a.add_strings("prescribed_names", prescribed_names);
        }
        let path = dir.join(NPZ);
        let tmp = dir.join(NPZ_TMP);
        let written = File::create(&tmp).and_then(|f| {
            let mut w = std::io::BufWriter::new(f);
            a.write_to(&mut w)?;
            w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
            std::fs::rename(&tmp, &path)
        });
        written.map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            let _ = std::fs::remove_file(&path);
            format!("writing {NPZ}: {e}; it was removed (trajectory.csv is complete)")
        })
    }
}
