//! `softrod run`: integrate, stream the trajectory, write shape, summary, plots.

use std::fs::File;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use softrod::dynamics::{Model, actuation_matrix, energies, forward_dynamics};
use softrod::integrate::Stats;
use softrod::lie::Pose;
use softrod::{EnergyBalance, Error, Flow, Observer, Sample, output_times};
use softrod_scene::Scene;
use softrod_viz::Pose as VizPose;
use softrod_viz::run_dir::{BODIES_HEADER, SHAPE_HEADER};

use crate::common::{CliError, Poser, failed, load, out_dir, position, quaternion};
use crate::outputs::{
    self, RodSampling, csv_field, csv_line, default_points_per_piece, num, push_csv_row,
};
use crate::plots::{self, Series, Snapshot};
use crate::{npz, signals};

/// The contract's first columns of `trajectory.csv` (the `q` columns follow).
pub const TRAJECTORY_HEADER: [&str; 9] = [
    "t", "tip_x", "tip_y", "tip_z", "tip_qw", "tip_qx", "tip_qy", "tip_qz", "energy",
];

/// The columns of `trajectory.csv` after the contract's nine: `q0…` (the
/// contract's), then (added, docs/scene-format-extensions.md) `qdot0…`, the
/// energy components `kinetic, elastic, gravitational` (J; they sum to
/// `energy`), with cables `tension0…` (N) and `power0…` (W, the power
/// each cable puts into the rods), and with prescribed joints (D59)
/// `prescribed0…` (their coordinates, rad or m) and `prescribed_force0…`
/// (the generalized force each needs, N·m or N; summary.json's
/// `prescribed_names` says which is which).
pub fn extra_columns(n_dof: usize, n_cables: usize, n_prescribed: usize) -> Vec<String> {
    let mut h: Vec<String> = (0..n_dof).map(|i| format!("q{i}")).collect();
    h.extend((0..n_dof).map(|i| format!("qdot{i}")));
    h.extend(["kinetic", "elastic", "gravitational"].map(String::from));
    h.extend((0..n_cables).map(|c| format!("tension{c}")));
    h.extend((0..n_cables).map(|c| format!("power{c}")));
    h.extend((0..n_prescribed).map(|c| format!("prescribed{c}")));
    h.extend((0..n_prescribed).map(|c| format!("prescribed_force{c}")));
    h
}

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

/// The NumPy archive of the trajectory (`--npz`), and its temporary name.
pub const NPZ: &str = "trajectory.npz";
/// See [`NPZ`].
pub const NPZ_TMP: &str = "trajectory.npz.tmp";

/// Longest wall time between two writes of the running summary, s.
pub const SUMMARY_EVERY: f64 = 0.5;

/// Writes output rows as the integration produces them.
pub struct Streamer {
    traj: OutFile,
    shape: OutFile,
    /// `bodies.csv` (t, body, pose), for a model with rigid bodies.
    bodies: Option<OutFile>,
    bodies_text: String,
    summary: Summary,
    start: Instant,
    summary_written: Option<Instant>,
    /// The signal that ended the run, if one did.
    pub interrupted: Option<&'static str>,
    traj_text: String,
    shape_text: String,
    expected: usize,
    next: usize,
    snapshot_at: Vec<usize>,
    poser: Poser,
    sampling: Vec<RodSampling>,
    /// Per rod, the sampled poses of the current row (allocated once).
    poses: Vec<Vec<Pose>>,
    viz_poses: Vec<Vec<VizPose>>,
    /// The rods' and bodies' names as CSV fields, and the current row's
    /// leading fields (allocated once).
    rod_fields: Vec<String>,
    body_fields: Vec<String>,
    prefix: String,
    n: usize,
    /// The last row's snapshot, kept so the figures end where the run did.
    last_snapshot: Option<Snapshot>,
    pub series: Series,
    pub error: Option<String>,
    pub last_stats: Stats,
    pub last_t: f64,
    bar: Option<ProgressBar>,
    duration: f64,
    /// Largest closure residual over the rows written \[m\] (0 without
    /// closures), and the residual that stops the run.
    pub closure_residual_max: f64,
    closure_fail: f64,
    /// With `--npz`: every written row's numbers, in `trajectory.csv`'s
    /// column order (kept for `trajectory.npz`, written at the end).
    npz_rows: Option<Vec<f64>>,
    /// The current row's numbers (allocated once).
    values: Vec<f64>,
}

/// The output rows nearest the times `chosen` (s, each finite and within
/// `[0, duration]`; exit 2 otherwise), or six spread evenly when none are.
pub fn chosen_rows(times: &[f64], chosen: Option<&[f64]>) -> Result<Vec<usize>, CliError> {
    let Some(chosen) = chosen else {
        return Ok(snapshot_rows(times.len()));
    };
    let end = times.last().copied().unwrap_or(0.0);
    let mut rows = Vec::with_capacity(chosen.len());
    for &t in chosen {
        if !(t.is_finite() && (0.0..=end).contains(&t)) {
            return Err(CliError::Input(format!(
                "--snapshots: {t} is not a time of the run (0 to {end} s)"
            )));
        }
        let k = times.partition_point(|x| *x < t);
        let nearest = if k == 0 {
            0
        } else if k == times.len() || t - times[k - 1] <= times[k] - t {
            k - 1
        } else {
            k
        };
        rows.push(nearest);
    }
    rows.sort_unstable();
    rows.dedup();
    Ok(rows)
}

/// Rows (indices into the output times) whose shapes and strains are drawn
/// by default: six spread evenly, first and last included.
fn snapshot_rows(m: usize) -> Vec<usize> {
    let snaps = 6.min(m);
    let mut v: Vec<usize> = (0..snaps)
        .map(|k| {
            if snaps == 1 {
                0
            } else {
                k * (m - 1) / (snaps - 1)
            }
        })
        .collect();
    v.dedup();
    v
}

impl Streamer {
    pub fn new(
        dir: &Path,
        model: &Model,
        times: Vec<f64>,
        per_piece: &[usize],
        snapshot_at: Vec<usize>,
        summary: Summary,
        bar: Option<ProgressBar>,
    ) -> Result<Self, CliError> {
        let n = model.n_dof();
        let mut header: Vec<String> = TRAJECTORY_HEADER.iter().map(|h| h.to_string()).collect();
        header.extend(extra_columns(n, model.n_cables(), model.n_prescribed()));
        let traj = OutFile::create(dir, "trajectory.csv", &csv_line(&header))?;
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
        let sampling: Vec<RodSampling> = model
            .rods()
            .iter()
            .zip(per_piece)
            .map(|(r, &m)| RodSampling::new(&r.spec.rod, m))
            .collect();
        let poses = sampling
            .iter()
            .map(|s| vec![Pose::identity(); s.s.len()])
            .collect();
        let viz_poses = sampling
            .iter()
            .map(|s| vec![VizPose::at([0.0; 3]); s.s.len()])
            .collect();
        let n_rods = model.rods().len();
        let n_cables = model.n_cables();
        let series = Series {
            tips: vec![Vec::new(); n_rods],
            tensions: vec![Vec::new(); n_cables],
            power: vec![Vec::new(); n_cables],
            ..Series::default()
        };
        Ok(Self {
            traj,
            shape,
            bodies,
            bodies_text: String::new(),
            summary,
            start: Instant::now(),
            summary_written: None,
            interrupted: None,
            traj_text: String::new(),
            shape_text: String::new(),
            next: 0,
            snapshot_at,
            poser: Poser::new(model),
            sampling,
            poses,
            viz_poses,
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
            values: Vec::with_capacity(header.len()),
            npz_rows: None,
            n,
            last_snapshot: None,
            series,
            error: None,
            last_stats: Stats::default(),
            last_t: 0.0,
            duration: times.last().copied().unwrap_or(0.0),
            expected: times.len(),
            bar,
            closure_residual_max: 0.0,
            closure_fail: crate::closures::RUN_FAIL_RELATIVE * crate::closures::length_scale(model),
        })
    }

    /// Keeps the rows for `trajectory.npz` (`--npz`).
    pub fn keep_rows_for_npz(mut self, on: bool) -> Self {
        self.npz_rows = on.then(Vec::new);
        self
    }

    pub fn rows_written(&self) -> usize {
        self.next
    }

    pub fn rows_expected(&self) -> usize {
        self.expected
    }

    /// The series for the figures; a run that stopped early gets its last
    /// row as the final snapshot, so it is drawn up to where it stopped.
    pub fn finish_series(&mut self) -> &Series {
        let stopped_early = self.next < self.expected;
        if let Some(last) = self.last_snapshot.take().filter(|_| stopped_early) {
            if self.series.snapshots.last().is_none_or(|s| s.t < last.t) {
                self.series.snapshots.push(last);
            }
        }
        &self.series
    }

    /// Writes `DIR/trajectory.npz` from the rows written (the same rows and
    /// numbers as `trajectory.csv`), atomically: `trajectory.npz.tmp`
    /// renamed over it, or nothing (the temporary file removed) on an error.
    /// Does nothing without `--npz`.
    pub fn write_npz(
        &self,
        dir: &Path,
        model: &Model,
        q_names: &[String],
        prescribed_names: &[String],
    ) -> Result<(), String> {
        let Some(rows) = &self.npz_rows else {
            return Ok(());
        };
        let (n, nc, np) = (self.n, model.n_cables(), model.n_prescribed());
        let width = TRAJECTORY_HEADER.len() + 2 * n + 3 + 2 * nc + 2 * np;
        let m = rows.len() / width;
        debug_assert_eq!(rows.len(), m * width);
        // Columns `cols` of every row, as one C-order (m, cols.len()) block.
        let take = |cols: &[usize]| -> Vec<f64> {
            rows.chunks_exact(width)
                .flat_map(|r| cols.iter().map(move |&c| r[c]))
                .collect()
        };
        let range = |from: usize, len: usize| (from..from + len).collect::<Vec<_>>();
        let q0 = TRAJECTORY_HEADER.len();
        let e0 = q0 + 2 * n;
        let c0 = e0 + 3;
        let p0 = c0 + 2 * nc;
        let mut a = npz::Archive::new();
        a.add_f64("t", &[m], &take(&[0]));
        a.add_f64("q", &[m, n], &take(&range(q0, n)));
        a.add_f64("qdot", &[m, n], &take(&range(q0 + n, n)));
        a.add_f64("tip", &[m, 7], &take(&range(1, 7)));
        a.add_f64("energy", &[m, 4], &take(&[8, e0, e0 + 1, e0 + 2]));
        if nc > 0 {
            a.add_f64("tension", &[m, nc], &take(&range(c0, nc)));
            a.add_f64("power", &[m, nc], &take(&range(c0 + nc, nc)));
        }
        if np > 0 {
            a.add_f64("prescribed", &[m, np], &take(&range(p0, np)));
            a.add_f64("prescribed_force", &[m, np], &take(&range(p0 + np, np)));
        }
        a.add_strings("q_names", q_names);
        if np > 0 {
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

    fn write_row(&mut self, s: Sample<'_>) -> Result<(), String> {
        let (t, q, qd, model) = (s.t, s.q, s.qd, s.model);
        let non_finite = |v: &[f64]| v.iter().position(|x| !x.is_finite());
        if let Some(i) = non_finite(q) {
            return Err(format!("non-finite q{i} at t = {t:e}; output stopped"));
        }
        if let Some(i) = non_finite(qd) {
            return Err(format!("non-finite qdot{i} at t = {t:e}; output stopped"));
        }
        debug_assert_eq!(q.len(), self.n);
        let e = energies(model, s.data, q, qd).map_err(|e| format!("energy at t = {t:e}: {e}"))?;
        if model.has_closures() {
            let r = crate::closures::residual(model, s.data, q)
                .map_err(|e| format!("closure residual at t = {t:e}: {e}"))?;
            self.closure_residual_max = self.closure_residual_max.max(r);
            if r.is_nan() || r > self.closure_fail {
                return Err(format!(
                    "closure residual {r:.3e} m at t = {t:e} exceeds {:.3e} m ({:e} of the \
                     longest rod): the closed loop has come apart; output stopped",
                    self.closure_fail,
                    crate::closures::RUN_FAIL_RELATIVE
                ));
            }
        }
        if !e.total().is_finite() {
            return Err(format!("non-finite energy at t = {t:e}; output stopped"));
        }
        self.poser
            .update(model, t, q)
            .map_err(|e| format!("at t = {t:e}: {e}"))?;
        let tip = *self.poser.tip(0);
        let p = position(&tip);
        let qt = quaternion(&tip);
        if p.iter().chain(qt.iter()).any(|v| !v.is_finite()) {
            return Err(format!("non-finite tip pose at t = {t:e}; output stopped"));
        }
        for r in 0..model.rods().len() {
            self.poser
                .sample(model, r, &self.sampling[r], &mut self.poses[r])
                .map_err(|e| format!("at t = {t:e}: {e}"))?;
            let rm = &model.rods()[r];
            for (i, (g, v)) in self.poses[r]
                .iter()
                .zip(self.viz_poses[r].iter_mut())
                .enumerate()
            {
                let (pp, qq) = (position(g), quaternion(g));
                if pp.iter().chain(qq.iter()).any(|v| !v.is_finite()) {
                    return Err(format!(
                        "non-finite pose of rod '{}' at s = {} m, t = {t:e}; output stopped",
                        rm.spec.name, self.sampling[r].s[i]
                    ));
                }
                *v = VizPose {
                    position: pp,
                    rotation: qq,
                };
            }
        }
        // Cables: tension and the power it puts in, T_c (B_c · q̇) (D15).
        let (mut tensions, mut power) = (Vec::new(), Vec::new());
        if model.n_cables() > 0 {
            let b = actuation_matrix(model, q).map_err(|e| format!("cables at t = {t:e}: {e}"))?;
            let qdv = nalgebra::DVectorView::from_slice(qd, qd.len());
            for rm in model.rods() {
                for (c, cable) in rm.spec.cables.iter().enumerate() {
                    let tension = cable.tension_at(t);
                    let col = rm.cable_offset + c;
                    tensions.push(tension);
                    power.push(tension * b.column(col).dot(&qdv));
                }
            }
        }
        // The row's numbers, in the column order of `trajectory.csv`.
        self.values.clear();
        self.values.push(t);
        self.values.extend(p.iter().chain(&qt));
        self.values.push(e.total());
        self.values.extend(q);
        self.values.extend(qd);
        self.values.extend([e.kinetic, e.elastic, e.gravitational]);
        self.values.extend(&tensions);
        self.values.extend(&power);
        if model.n_prescribed() > 0 {
            // The drive's force comes with the accelerations at this state.
            forward_dynamics(model, s.data, t, q, qd, None)
                .map_err(|e| format!("prescribed joint forces at t = {t:e}: {e}"))?;
            let (pq, pf) = (&s.data.prescribed_q, &s.data.prescribed_force);
            if let Some(i) = pf.iter().position(|v| !v.is_finite()) {
                return Err(format!(
                    "non-finite prescribed_force{i} at t = {t:e}; output stopped"
                ));
            }
            self.values.extend(pq.iter().chain(pf.iter()));
        }
        self.traj_text.clear();
        push_csv_row(&mut self.traj_text, "", self.values.iter().copied());
        self.shape_text.clear();
        let ts = num(t);
        for (r, name) in self.rod_fields.iter().enumerate() {
            self.prefix.clear();
            self.prefix.push_str(&ts);
            self.prefix.push(',');
            self.prefix.push_str(name);
            self.prefix.push(',');
            for (sv, p) in self.sampling[r].s.iter().zip(&self.viz_poses[r]) {
                let [x, y, z] = p.position;
                let [qw, qx, qy, qz] = p.rotation;
                push_csv_row(
                    &mut self.shape_text,
                    &self.prefix,
                    [*sv, x, y, z, qw, qx, qy, qz],
                );
            }
        }
        self.bodies_text.clear();
        for (name, g) in self.body_fields.iter().zip(self.poser.bodies()) {
            self.prefix.clear();
            self.prefix.push_str(&ts);
            self.prefix.push(',');
            self.prefix.push_str(name);
            self.prefix.push(',');
            push_csv_row(
                &mut self.bodies_text,
                &self.prefix,
                position(g).into_iter().chain(quaternion(g)),
            );
        }
        // Every file gets this time's rows, or none does.
        let bodies_text = &self.bodies_text;
        let written = self
            .shape
            .append(&self.shape_text)
            .and_then(|()| match &mut self.bodies {
                Some(f) => f.append(bodies_text),
                None => Ok(()),
            })
            .and_then(|()| self.traj.append(&self.traj_text));
        if let Err(e) = written {
            let bodies_cut = self.bodies.as_mut().is_none_or(OutFile::rollback);
            let cut = self.shape.rollback() & self.traj.rollback() & bodies_cut;
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
        self.traj.commit(self.traj_text.len());
        if let Some(rows) = &mut self.npz_rows {
            // `+ 0.0` turns −0 into 0, as the CSV writes it.
            rows.extend(self.values.iter().map(|v| v + 0.0));
        }
        self.series.t.push(t);
        for (r, tips) in self.series.tips.iter_mut().enumerate() {
            tips.push(position(self.poser.tip(r)));
        }
        self.series.energies.push(e);
        for (c, (&tn, &pw)) in tensions.iter().zip(&power).enumerate() {
            self.series.tensions[c].push(tn);
            self.series.power[c].push(pw);
        }
        let snapshot = Snapshot {
            t,
            centrelines: self
                .viz_poses
                .iter()
                .map(|ps| ps.iter().map(|p| p.position).collect())
                .collect(),
            strains: (0..model.rods().len())
                .map(|r| {
                    self.poser
                        .strains(r)
                        .iter()
                        .map(|x| [x[0], x[1], x[2], x[3], x[4], x[5]])
                        .collect()
                })
                .collect(),
            bodies: self.poser.bodies().iter().map(position).collect(),
        };
        if self.snapshot_at.contains(&self.next) {
            self.series.snapshots.push(snapshot);
            self.last_snapshot = None;
        } else {
            self.last_snapshot = Some(snapshot);
        }
        Ok(())
    }
}

impl Observer for Streamer {
    /// One output row: the integrator's dense output at the next output time.
    fn sample(&mut self, s: Sample<'_>) -> Result<Flow, String> {
        let t = s.t;
        if let Err(e) = self.write_row(s) {
            self.error = Some(e.clone());
            return Err(e);
        }
        self.next += 1;
        self.last_t = t;
        // Keep summary.json current, so a run killed with SIGKILL still
        // says how far it got (its status stays "running").
        if self
            .summary_written
            .is_none_or(|w| w.elapsed().as_secs_f64() >= SUMMARY_EVERY)
        {
            let wall = self.start.elapsed().as_secs_f64();
            if let Err(e) = self
                .summary
                .write(&self.last_stats, wall, t, "running", self.next)
            {
                let e = e.to_string();
                self.error = Some(e.clone());
                return Err(e);
            }
            self.summary_written = Some(Instant::now());
        }
        if let Some(sig) = signals::received() {
            self.interrupted = Some(sig);
            return Ok(Flow::Stop);
        }
        Ok(Flow::Continue)
    }

    fn step(&mut self, t: f64, stats: &Stats) {
        self.last_stats = *stats;
        if let Some(b) = &self.bar {
            b.set_position((t / self.duration * 1000.0) as u64);
            b.set_message(format!("{t:.4}"));
        }
    }
}

/// `summary.json`: the run's fixed facts and, at each write, its progress.
/// Written atomically (a temporary file renamed over it), so a reader never
/// sees half a file, even of a killed run.
pub struct Summary {
    path: PathBuf,
    fixed: serde_json::Map<String, serde_json::Value>,
}

impl Summary {
    pub fn new(
        dir: &Path,
        scene: &Scene,
        (q_names, prescribed_names): (Vec<String>, Vec<String>),
        rows_expected: usize,
    ) -> Self {
        let mut v = serde_json::json!({
            "pid": std::process::id(),
            "integrator": scene.run.integrator.name(),
            "duration": scene.run.duration,
            "output_rows_expected": rows_expected,
            "n_dof": scene.n_dof(),
            "q_names": q_names,
        });
        if !prescribed_names.is_empty() {
            v["prescribed_names"] = serde_json::json!(prescribed_names);
        }
        let serde_json::Value::Object(fixed) = v else {
            unreachable!("a JSON object literal")
        };
        Self {
            path: dir.join("summary.json"),
            fixed,
        }
    }

    /// Adds the run's energy balance (docs/scene-format-extensions.md,
    /// `[run] energy_tolerance`) and what the run's watch warned about.
    pub fn add_watch(&mut self, b: &EnergyBalance, warnings: &[String]) {
        for (key, value) in [
            ("energy_error", b.error),
            ("energy_error_relative", b.relative),
            ("energy_scale", b.scale),
            ("energy_change", b.change),
            ("energy_work", b.work),
        ] {
            self.fixed.insert(key.into(), serde_json::json!(value));
        }
        self.fixed
            .insert("warnings".into(), serde_json::json!(warnings));
    }

    /// Adds `closure_residual_max`, the largest closure residual norm over
    /// the output rows \[m\] (docs/scene-format-extensions.md).
    pub fn add_closures(&mut self, residual_max: f64) {
        self.fixed.insert(
            "closure_residual_max".into(),
            serde_json::json!(residual_max),
        );
    }

    /// Writes the summary with the given progress.
    pub fn write(
        &self,
        stats: &Stats,
        wall: f64,
        final_time: f64,
        status: &str,
        rows: usize,
    ) -> Result<(), CliError> {
        let mut v = serde_json::json!({
            "steps": stats.steps,
            "rejected_steps": stats.rejected_steps,
            "rhs_evaluations": stats.rhs_evaluations,
            "wall_seconds": wall,
            "final_time": final_time,
            "status": status,
            "jacobian_evaluations": stats.jacobian_evaluations,
            "factorizations": stats.factorizations,
            "output_rows": rows,
            "updated_unix_seconds": std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64()),
        });
        if let serde_json::Value::Object(m) = &mut v {
            m.extend(self.fixed.clone());
        }
        let text = serde_json::to_string_pretty(&v).map_err(failed)? + "\n";
        let tmp = self.path.with_extension("json.tmp");
        std::fs::write(&tmp, text)
            .and_then(|()| std::fs::rename(&tmp, &self.path))
            .map_err(|e| failed(format!("cannot write {}: {e}", self.path.display())))
    }
}

/// The scene's file stem: the title of figures and view.
pub fn scene_title(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
}

pub fn run(
    path: &Path,
    out: Option<PathBuf>,
    snapshots: Option<Vec<f64>>,
    quiet: bool,
    npz_out: bool,
    png: bool,
) -> Result<(), CliError> {
    let mut l = load(path)?;
    let dir = out_dir(path, out);
    let scene = &l.scene;
    let duration = scene.run.duration;
    let every = l.sim.settings().output_spacing(duration);
    outputs::check_disk_space(&dir, l.sim.model(), duration, every)?;
    let times = output_times(duration, every);
    if npz_out {
        let m = l.sim.model();
        let width =
            TRAJECTORY_HEADER.len() + 2 * m.n_dof() + 3 + 2 * m.n_cables() + 2 * m.n_prescribed();
        npz::check_size(times.len() as u64, width).map_err(CliError::Input)?;
    }
    let snapshot_at = chosen_rows(&times, snapshots.as_deref())?;
    outputs::prepare_out_dir(&dir)?;
    let stale = outputs::clear_stale(&dir)?;
    if !quiet && !stale.is_empty() {
        eprintln!(
            "softrod: removed the previous run's outputs from {}: {}",
            dir.display(),
            stale.join(", ")
        );
    }
    // Written first so that a run that never gets to its first row leaves
    // a summary that says so.
    let summary = Summary::new(
        &dir,
        scene,
        (l.sim.q_names(), l.sim.prescribed_names()),
        times.len(),
    );
    summary
        .write(&Stats::default(), 0.0, 0.0, "running", 0)
        .map_err(|e| CliError::Input(e.to_string()))?;
    let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
        let b = ProgressBar::new(1000);
        if let Ok(style) = ProgressStyle::with_template(
            "{bar:40} {percent:>3}% t = {msg} s  [{elapsed_precise} < {eta}]",
        ) {
            b.set_style(style);
        }
        b
    });
    let per_piece: Vec<usize> = l
        .sim
        .model()
        .rods()
        .iter()
        .map(|r| {
            scene
                .run
                .shape_points_per_piece
                .unwrap_or_else(|| default_points_per_piece(r.spec.rod.n_pieces()))
        })
        .collect();
    let mut summary_final = Summary::new(
        &dir,
        scene,
        (l.sim.q_names(), l.sim.prescribed_names()),
        times.len(),
    );
    let mut streamer = Streamer::new(
        &dir,
        l.sim.model(),
        times,
        &per_piece,
        snapshot_at,
        summary,
        bar,
    )?
    .keep_rows_for_npz(npz_out);
    signals::install();
    let start = Instant::now();
    // Rows are the integrator's dense output at the output times, streamed
    // to the observer as the run proceeds; nothing is kept in between.
    let result = match l.sim.simulate_with(duration, &mut streamer) {
        // Refused before it started (too large for the machine): bad input.
        Err(e) if e.is_input() => return Err(e.into()),
        r => r,
    };
    if let Some(b) = &streamer.bar {
        b.finish_and_clear();
    }
    let wall = start.elapsed().as_secs_f64();
    let (mut status, stats, t_final) = match (&result, &streamer.error) {
        (_, None) if streamer.interrupted.is_some() => (
            format!(
                "error: interrupted by {} at t = {} ({} of {} output rows written)",
                streamer.interrupted.unwrap_or("a signal"),
                streamer.last_t,
                streamer.rows_written(),
                streamer.rows_expected()
            ),
            result.as_ref().map_or(streamer.last_stats, |s| s.stats),
            streamer.last_t,
        ),
        (_, Some(e)) => (format!("error: {e}"), streamer.last_stats, streamer.last_t),
        (Err(e), None) => (format!("error: {e}"), streamer.last_stats, streamer.last_t),
        (Ok(sum), None) => {
            if streamer.rows_written() < streamer.rows_expected() {
                streamer.error = Some(format!(
                    "integration ended at t = {} before the last output time",
                    sum.t_final
                ));
            }
            match &streamer.error {
                Some(e) => (format!("error: {e}"), sum.stats, sum.t_final),
                None => ("ok".to_string(), sum.stats, sum.t_final),
            }
        }
    };
    let watch = match &result {
        Ok(sum) => sum.energy.as_ref().map(|b| (b, sum.warnings.as_slice())),
        Err(Error::EnergyBalance { balance, .. }) => Some((&**balance, &[][..])),
        Err(_) => None,
    };
    if let Some((b, warnings)) = watch {
        summary_final.add_watch(b, warnings);
        if !quiet {
            for w in warnings {
                eprintln!("softrod: warning: {w}");
            }
        }
    }
    if l.sim.model().has_closures() {
        let r = streamer.closure_residual_max;
        summary_final.add_closures(r);
        let warn =
            crate::closures::RUN_WARN_RELATIVE * crate::closures::length_scale(l.sim.model());
        if !quiet && r > warn {
            eprintln!(
                "softrod: warning: the largest closure residual {r:.3e} m exceeds {warn:.3e} m \
                 ({:e} of the longest rod): tighten rtol/atol or dt",
                crate::closures::RUN_WARN_RELATIVE
            );
        }
    }
    // The archive holds the rows the CSV holds, also after a failure; if it
    // cannot be written it is removed, and the run says so.
    if let Err(e) = streamer.write_npz(
        &dir,
        l.sim.model(),
        &l.sim.q_names(),
        &l.sim.prescribed_names(),
    ) {
        status = if status == "ok" {
            format!("error: {e}")
        } else {
            format!("{status}; {e}")
        };
    }
    summary_final.write(&stats, wall, t_final, &status, streamer.rows_written())?;
    // Plots and view of whatever was computed (also after a failure: they
    // show where it went wrong).
    let title = scene_title(path);
    let model = l.sim.model();
    let plot_result = plots::run_figures(&dir, streamer.finish_series(), model, &title)
        .and_then(|names| {
            if png {
                plots::rasterize(&dir, &names, quiet)
            } else {
                Ok(())
            }
        })
        .and_then(|()| {
            if streamer.rows_written() > 0 {
                outputs::write_view(&dir, model, &title).map(|_| ())
            } else {
                Ok(())
            }
        });
    if status != "ok" {
        return Err(failed(format!(
            "simulation failed: {} (outputs up to t = {} in {})",
            status.trim_start_matches("error: "),
            streamer.series.t.last().copied().unwrap_or(0.0),
            dir.display()
        )));
    }
    plot_result?;
    if !quiet {
        eprintln!(
            "softrod: {} s simulated in {:.3} s wall: {} steps ({} rejected), {} rhs evaluations; wrote {}",
            t_final,
            wall,
            stats.steps,
            stats.rejected_steps,
            stats.rhs_evaluations,
            dir.display()
        );
    }
    Ok(())
}

/// `softrod view DIR`: rebuilds `DIR/view.html` and prints its path.
pub fn view(dir: &Path, quiet: bool) -> Result<(), CliError> {
    if !dir.join(softrod_viz::run_dir::SHAPE_CSV).is_file() {
        return Err(CliError::Input(format!(
            "{}: not a run directory (no {}; write one with `softrod run SCENE --out DIR`)",
            dir.display(),
            softrod_viz::run_dir::SHAPE_CSV
        )));
    }
    let stats = softrod_viz::run_dir::write_view(dir, &softrod_viz::ViewOptions::default())
        .map_err(|e| CliError::Input(format!("{}: {e}", dir.display())))?
        .1;
    let page = dir.join(softrod_viz::run_dir::VIEW_HTML);
    println!("{}", page.display());
    if !quiet {
        eprintln!(
            "softrod: {} frames of {} output times, {} bytes; open it in a browser",
            stats.frames.len(),
            stats.source_frames,
            stats.bytes
        );
    }
    Ok(())
}
