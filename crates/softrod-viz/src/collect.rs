//! The view of a run built from the frames the run produces, as it writes
//! them: what `softrod run` draws, without reading `shape.csv` and
//! `bodies.csv` back (parsing them was half the cost of the view of a short
//! run). [`FrameCollector`] keeps the same output times, the same numbers
//! and therefore the same page as [`crate::run_dir::write_view`] reading the
//! files afterwards: the files hold each number as its shortest round-trip
//! decimal, which reads back to the same `f64`.

use std::path::{Path, PathBuf};

use crate::data::Pose;
use crate::error::VizError;
use crate::html::{ViewOptions, ViewStats, write_html};
use crate::run_dir::{
    BodyPoses, RodShape, ShapeData, Thinning, VIEW_HTML, ViewSpec, halve, view_cap, view_from_parts,
};

/// The output times of a run, thinned as [`crate::run_dir::write_view`]
/// thins `shape.csv` (between `cap` and `2·cap` evenly spaced times, the
/// last one always), with every rod's sample poses and every body's pose.
/// Its memory is bounded by [`crate::run_dir::VIEW_POSE_BUDGET`] poses however long the
/// run; pushing a time that is not kept allocates nothing.
#[derive(Debug, Clone)]
pub struct FrameCollector {
    thin: Thinning,
    /// Index of the next time.
    k: usize,
    times: Vec<f64>,
    rods: Vec<RodShape>,
    bodies: Vec<BodyPoses>,
    /// The time being pushed: per rod its sample poses, per body its pose.
    now_rods: Vec<Vec<Pose>>,
    now_bodies: Vec<Pose>,
    /// The latest time when it was not kept (appended at the end: the last
    /// output time is always in the view).
    pending: Option<f64>,
    pending_rods: Vec<Vec<Pose>>,
    pending_bodies: Vec<Pose>,
}

impl FrameCollector {
    /// A collector for rods `(name, sample abscissae s in m)` and bodies
    /// (names), keeping as many times as `write_view` with `opts` keeps.
    pub fn new(rods: Vec<(String, Vec<f64>)>, bodies: Vec<String>, opts: &ViewOptions) -> Self {
        let per_time = rods.iter().map(|r| r.1.len()).sum();
        Self::with_cap(rods, bodies, view_cap(per_time, opts))
    }

    /// [`FrameCollector::new`] keeping between `cap` and `2·cap` times (as
    /// [`crate::run_dir::read_shape_csv_thinned`] with `cap`).
    pub fn with_cap(rods: Vec<(String, Vec<f64>)>, bodies: Vec<String>, cap: usize) -> Self {
        let n_rods = rods.len();
        let n_bodies = bodies.len();
        Self {
            thin: Thinning::new(cap),
            k: 0,
            times: Vec::new(),
            rods: rods
                .into_iter()
                .map(|(name, s)| RodShape {
                    name,
                    s,
                    frames: Vec::new(),
                })
                .collect(),
            bodies: bodies.into_iter().map(|b| (b, Vec::new())).collect(),
            now_rods: vec![Vec::new(); n_rods],
            now_bodies: Vec::with_capacity(n_bodies),
            pending: None,
            pending_rods: vec![Vec::new(); n_rods],
            pending_bodies: Vec::with_capacity(n_bodies),
        }
    }

    /// Appends rod `r`'s sample poses at the current time, base to tip
    /// (position m, quaternion `[w, x, y, z]`).
    pub fn push_rod(&mut self, r: usize, poses: impl IntoIterator<Item = Pose>) {
        self.now_rods[r].extend(poses.into_iter().map(as_written));
    }

    /// Appends the next body's pose at the current time (bodies in the
    /// order given to [`FrameCollector::new`]).
    pub fn push_body(&mut self, pose: Pose) {
        self.now_bodies.push(as_written(pose));
    }

    /// Ends the current output time `t` (s). A rod with another number of
    /// poses than its samples, or a missing body, is an error naming it;
    /// the time is then dropped.
    pub fn end_time(&mut self, t: f64) -> Result<(), VizError> {
        let mismatch = self
            .rods
            .iter()
            .zip(&self.now_rods)
            .find(|(r, f)| f.len() != r.s.len())
            .map(|(r, f)| {
                format!(
                    "rod {:?}: {} poses for {} samples",
                    r.name,
                    f.len(),
                    r.s.len()
                )
            })
            .or_else(|| {
                (self.now_bodies.len() != self.bodies.len()).then(|| {
                    format!(
                        "{} body poses for {} bodies",
                        self.now_bodies.len(),
                        self.bodies.len()
                    )
                })
            });
        if let Some(problem) = mismatch {
            self.now_rods.iter_mut().for_each(Vec::clear);
            self.now_bodies.clear();
            return Err(VizError::Invalid {
                what: format!("the view's frame at t = {t}"),
                problem,
            });
        }
        let t = t + 0.0;
        if self.thin.keeps(self.k) {
            self.times.push(t);
            for (r, f) in self.rods.iter_mut().zip(&mut self.now_rods) {
                r.frames.push(std::mem::take(f));
            }
            for (b, p) in self.bodies.iter_mut().zip(&self.now_bodies) {
                b.1.push(*p);
            }
            self.pending = None;
            if self.thin.full(self.times.len()) {
                halve(&mut self.times);
                for r in &mut self.rods {
                    halve(&mut r.frames);
                }
                for b in &mut self.bodies {
                    halve(&mut b.1);
                }
            }
        } else {
            // Swap rather than copy: the buffers go round without
            // allocating.
            self.pending = Some(t);
            std::mem::swap(&mut self.pending_rods, &mut self.now_rods);
            std::mem::swap(&mut self.pending_bodies, &mut self.now_bodies);
        }
        self.now_rods.iter_mut().for_each(Vec::clear);
        self.now_bodies.clear();
        self.k += 1;
        Ok(())
    }

    /// Output times ended so far.
    pub fn times_seen(&self) -> usize {
        self.k
    }

    /// The kept times, rods' shapes and bodies' poses.
    pub fn finish(mut self) -> (ShapeData, Vec<BodyPoses>) {
        if let Some(t) = self.pending.take() {
            self.times.push(t);
            for (r, f) in self.rods.iter_mut().zip(&mut self.pending_rods) {
                r.frames.push(std::mem::take(f));
            }
            for (b, p) in self.bodies.iter_mut().zip(&self.pending_bodies) {
                b.1.push(*p);
            }
        }
        (
            ShapeData {
                times: self.times,
                rods: self.rods,
            },
            self.bodies,
        )
    }

    /// Writes `DIR/view.html` from the collected frames and `spec` (what
    /// `view.json` holds); returns its path and what it kept. The same page
    /// as [`crate::run_dir::write_view`] of a directory holding these frames.
    pub fn write_view(
        self,
        dir: &Path,
        spec: &ViewSpec,
        opts: &ViewOptions,
    ) -> Result<(PathBuf, ViewStats), VizError> {
        let (shape, bodies) = self.finish();
        let view = view_from_parts(spec, &dir.join(crate::run_dir::VIEW_JSON), shape, bodies)?;
        let out = dir.join(VIEW_HTML);
        let stats = write_html(&out, &view, opts)?;
        Ok((out, stats))
    }
}

/// The pose as the run's files hold it: `−0` is written `0`.
fn as_written(p: Pose) -> Pose {
    Pose {
        position: p.position.map(|v| v + 0.0),
        rotation: p.rotation.map(|v| v + 0.0),
    }
}
