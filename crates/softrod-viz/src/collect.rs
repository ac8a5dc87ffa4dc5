//! The view of a run built from the frames the run produces, as it writes
//! them: what `softrod run` draws, without reading `shape.csv` and
//! `bodies.csv` back (parsing them was half the cost of the view of a short
//! run). [`FrameCollector`] keeps the same output times, the same numbers
//! and therefore the same page as [`crate::run_dir::write_view`] reading the
//! files afterwards: the files hold each number as its shortest round-trip
//! decimal, which reads back to the same `f64`.

use std::path::{Path, PathBuf};

use crate::data::{Pose, pose_valid};
use crate::error::VizError;
use crate::html::{
    DEFAULT_MAX_BYTES, DEFAULT_MAX_FRAMES, Prepared, ROTATION_TEXT, RotationText, ViewOptions,
    ViewStats, write_prepared,
};
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
    /// The page's work on the kept times done as they come (the text of
    /// the rotations, the extent of the positions, the checks): while
    /// every kept time is in it; dropped once the times are thinned or it
    /// outgrows `limits`, and the page is then made from the frames alone.
    prepared: Option<Preparing>,
    /// Most kept times and most bytes of rotation text it holds.
    limits: (usize, usize),
}

/// See [`FrameCollector::prepared`].
#[derive(Debug, Clone)]
struct Preparing {
    /// Per rod: the rotation text of every kept pose.
    rotations: Vec<RotationText>,
    /// Per kept time: the lowest and highest coordinates of the rods'
    /// sample positions.
    boxes: Vec<[[f64; 3]; 2]>,
}

impl FrameCollector {
    /// A collector for rods `(name, sample abscissae s in m)` and bodies
    /// (names), keeping as many times as `write_view` with `opts` keeps.
    pub fn new(rods: Vec<(String, Vec<f64>)>, bodies: Vec<String>, opts: &ViewOptions) -> Self {
        let per_time = rods.iter().map(|r| r.1.len()).sum();
        let mut c = Self::with_cap(rods, bodies, view_cap(per_time, opts));
        c.limits = (opts.max_frames, opts.max_bytes);
        c
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
            prepared: Some(Preparing {
                rotations: vec![RotationText::default(); n_rods],
                boxes: Vec::new(),
            }),
            limits: (DEFAULT_MAX_FRAMES, DEFAULT_MAX_BYTES),
        }
    }

    /// Prepares the page's part of the time being kept (the poses in
    /// `now_rods`), or drops what was prepared: when a pose would not pass
    /// the page's checks (the page then checks and names it), or when the
    /// kept times or their text outgrow the limits.
    fn prepare(&mut self) {
        let Some(p) = &mut self.prepared else {
            return;
        };
        let (max_times, max_bytes) = self.limits;
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let mut ok = p.boxes.len() < max_times;
        for (f, text) in self.now_rods.iter().zip(&mut p.rotations) {
            if !ok {
                break;
            }
            for pose in f {
                ok &= pose_valid(pose) && text.push(pose);
                for ((l, h), &x) in lo.iter_mut().zip(&mut hi).zip(&pose.position) {
                    // Finite (else dropped): comparisons are `min`, `max`.
                    if x < *l {
                        *l = x;
                    }
                    if x > *h {
                        *h = x;
                    }
                }
            }
            ok &= text.slots.len() * ROTATION_TEXT <= max_bytes;
        }
        if ok {
            p.boxes.push([lo, hi]);
        } else {
            self.prepared = None;
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
            self.prepare();
            self.times.push(t);
            for (r, f) in self.rods.iter_mut().zip(&mut self.now_rods) {
                r.frames.push(std::mem::take(f));
            }
            for (b, p) in self.bodies.iter_mut().zip(&self.now_bodies) {
                b.1.push(*p);
            }
            self.pending = None;
            if self.thin.full(self.times.len()) {
                self.prepared = None;
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
            self.prepared = None;
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
    pub fn finish(self) -> (ShapeData, Vec<BodyPoses>) {
        let (shape, bodies, _) = self.finish_prepared();
        (shape, bodies)
    }

    /// [`FrameCollector::finish`], and what was prepared for the page if
    /// it holds every kept time.
    fn finish_prepared(mut self) -> (ShapeData, Vec<BodyPoses>, Option<Preparing>) {
        if let Some(t) = self.pending.take() {
            self.times.push(t);
            for (r, f) in self.rods.iter_mut().zip(&mut self.pending_rods) {
                r.frames.push(std::mem::take(f));
            }
            for (b, p) in self.bodies.iter_mut().zip(&self.pending_bodies) {
                b.1.push(*p);
            }
        }
        let prepared = self.prepared.filter(|p| p.boxes.len() == self.times.len());
        (
            ShapeData {
                times: self.times,
                rods: self.rods,
            },
            self.bodies,
            prepared,
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
        let (shape, bodies, prepared) = self.finish_prepared();
        let view = view_from_parts(spec, &dir.join(crate::run_dir::VIEW_JSON), shape, bodies)?;
        let out = dir.join(VIEW_HTML);
        let pre = prepared.as_ref().map(|p| Prepared {
            rotations: &p.rotations,
            boxes: &p.boxes,
        });
        let stats = write_prepared(&out, &view, opts, pre.as_ref())?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BodyShape;
    use crate::demo::SwingingRods;
    use crate::html::render_html;
    use crate::run_dir::{BodySpec, CableSpec, ObstacleSpec};

    /// A view with two rods (one routed cable), a body and an obstacle
    /// named to be escaped; a negative zero and a tiny number among the
    /// positions, as the run's files hold them.
    fn scene(times: usize) -> (crate::ViewData, ViewSpec) {
        let mut view = SwingingRods {
            rods: 2,
            times,
            samples: 7,
            body: true,
            ..SwingingRods::default()
        }
        .build();
        view.rods[1].frames[times / 2][0].position = [-0.0, 1e-300, -2.5e-7];
        let mut spec = ViewSpec::new("prepared </script>");
        spec.cables.push(CableSpec {
            name: "cable <0>".into(),
            rod: view.rods[0].name.clone(),
            path: vec![[0.05, 0.0, 0.008], [0.3, 0.004, 0.0], [0.45, 0.0, -0.006]],
        });
        spec.bodies.push(BodySpec {
            name: view.bodies[0].name.clone(),
            shape: BodyShape::Sphere { radius: 0.02 },
        });
        spec.obstacles.push(ObstacleSpec {
            name: "</script> floor".into(),
            shape: crate::ObstacleShape::Plane {
                position: [0.0, 0.0, -0.6],
                normal: [0.0, 0.0, 1.0],
            },
            parent: None,
        });
        (view, spec)
    }

    fn collected(view: &crate::ViewData, c: &mut FrameCollector) {
        for (k, t) in view.times.iter().enumerate() {
            for (r, rod) in view.rods.iter().enumerate() {
                c.push_rod(r, rod.frames[k].iter().copied());
            }
            c.push_body(view.bodies[0].poses[k]);
            c.end_time(*t).unwrap();
        }
    }

    fn collector(view: &crate::ViewData, cap: Option<usize>, opts: &ViewOptions) -> FrameCollector {
        let rods = view
            .rods
            .iter()
            .map(|r| (r.name.clone(), r.s.clone()))
            .collect();
        let bodies = vec![view.bodies[0].name.clone()];
        let mut c = match cap {
            Some(cap) => FrameCollector::with_cap(rods, bodies, cap),
            None => FrameCollector::new(rods, bodies, opts),
        };
        collected(view, &mut c);
        c
    }

    /// The page from the frames with what was prepared as they came is,
    /// byte for byte, [`render_html`] of the same frames (the path of
    /// `softrod view`, which prepares nothing): every time kept, a subset
    /// of them shown (frame and byte budgets), the times thinned (nothing
    /// prepared), and more kept times than the limits (dropped on the
    /// way).
    #[test]
    fn prepared_page_equals_the_plain_page() {
        let dir = std::env::temp_dir().join(format!("softrod-viz-prepared-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let small_bytes = ViewOptions {
            max_bytes: 300_000,
            ..ViewOptions::default()
        };
        let few_frames = ViewOptions {
            max_frames: 17,
            ..ViewOptions::default()
        };
        let cases: [(usize, Option<usize>, ViewOptions, bool); 5] = [
            (61, None, ViewOptions::default(), true),
            (301, None, small_bytes, true),
            (301, None, few_frames.clone(), false),
            (61, Some(7), ViewOptions::default(), false),
            (61, Some(1000), few_frames, true),
        ];
        for (times, cap, opts, kept) in cases {
            let (view, spec) = scene(times);
            let c = collector(&view, cap, &opts);
            let (shape, bodies, prepared) = c.clone().finish_prepared();
            assert_eq!(prepared.is_some(), kept, "{times} times, cap {cap:?}");
            let plain = view_from_parts(&spec, &dir.join("view.json"), shape, bodies).unwrap();
            let (expected, expected_stats) = render_html(&plain, &opts).unwrap();
            let (path, stats) = c.write_view(&dir, &spec, &opts).unwrap();
            let page = std::fs::read_to_string(path).unwrap();
            assert!(
                page == expected,
                "{times} times, cap {cap:?}: the pages differ"
            );
            assert_eq!(stats, expected_stats);
            // Every string of the data escapes `<`: the page's only
            // "</script>" close its own scripts.
            assert_eq!(
                page.matches("</script>").count(),
                expected.matches("<script").count()
            );
            assert!(page.contains("\"name\":\"\\u003c/script> floor\""));
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A pose the page refuses is named by the page, whichever path.
    #[test]
    fn a_bad_pose_is_named_as_before() {
        let dir = std::env::temp_dir().join(format!("softrod-viz-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (mut view, spec) = scene(11);
        view.rods[1].frames[4][2].rotation = [0.0; 4];
        let opts = ViewOptions::default();
        let c = collector(&view, None, &opts);
        let (shape, bodies, prepared) = c.clone().finish_prepared();
        assert!(prepared.is_none());
        let plain = view_from_parts(&spec, &dir.join("view.json"), shape, bodies).unwrap();
        let expected = render_html(&plain, &opts).unwrap_err().to_string();
        let e = c.write_view(&dir, &spec, &opts).unwrap_err().to_string();
        assert_eq!(e, expected);
        assert!(e.contains("frames[4][2].rotation"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
