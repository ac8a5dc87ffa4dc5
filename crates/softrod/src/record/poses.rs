//! World poses of a model's rods and bodies: the one definition the
//! recorder, the kinematics queries of [`Simulation`](crate::Simulation)
//! and the front ends read.
//!
//! A rod's kinematics (D7) give poses from its own base
//! (`softrod_kinematics::RodGeometry::base`); a rod on a joint or a parent is
//! carried into the world by the map `rod_to_world` of its element
//! (`softrod_dynamics::frames`, D51; prescribed joints at the time given).
//! A clamped rod's base is already in the world, and its map is the
//! identity.

use softrod_dynamics::{Data, Model};
use softrod_kinematics::{RodGeometry, RodKinematics};
use softrod_lie::{Pose, Vec6};

use crate::error::{Error, Result};

/// Where one rod is sampled along its length: `m` points per piece at the
/// local fractions `0, 1/m, …, (m−1)/m` of each piece, then the tip; `s`
/// strictly increasing from 0 to L and holding every piece boundary (the
/// contract's N + 1 frames of `shape.csv`). Each sample lies on the piece's
/// exact PCS arc (constant strain: a helix), not on a chord.
#[derive(Clone, Debug, PartialEq)]
pub struct RodSampling {
    /// Fractions within a piece, `[0, 1)`.
    pub fractions: Vec<f64>,
    /// Material abscissae \[m\] (`n_pieces · m + 1`).
    pub s: Vec<f64>,
}

/// Points per piece when `[run] shape_points_per_piece` is not given: a rod
/// gets about [`SMOOTH_SAMPLES_PER_ROD`] samples, at least one per piece
/// (the piece boundaries) and at most [`MAX_DEFAULT_POINTS_PER_PIECE`] (a
/// piece is one exact arc: 16 chords of a quarter turn deviate from it by
/// 0.1 % of the radius).
pub fn default_points_per_piece(pieces: usize) -> usize {
    SMOOTH_SAMPLES_PER_ROD
        .div_ceil(pieces.max(1))
        .clamp(1, MAX_DEFAULT_POINTS_PER_PIECE)
}

/// See [`default_points_per_piece`].
pub const SMOOTH_SAMPLES_PER_ROD: usize = 64;
/// See [`default_points_per_piece`].
pub const MAX_DEFAULT_POINTS_PER_PIECE: usize = 16;

impl RodSampling {
    /// `per_piece` points per piece of `rod` (at least one).
    pub fn new(rod: &RodGeometry, per_piece: usize) -> Self {
        let m = per_piece.max(1);
        let fractions: Vec<f64> = (0..m).map(|j| j as f64 / m as f64).collect();
        let mut s = Vec::with_capacity(rod.n_pieces() * m + 1);
        let mut start = 0.0;
        for p in rod.pieces() {
            let len = p.end() - start;
            // j = 0 is exactly the boundary (start), so boundaries keep
            // their values exactly.
            s.extend(fractions.iter().map(|f| start + f * len));
            start = p.end();
        }
        s.push(rod.length());
        Self { fractions, s }
    }

    /// The default sampling of every rod of `model`
    /// ([`default_points_per_piece`]), or `per_piece` points per piece.
    pub fn of_model(model: &Model, per_piece: Option<usize>) -> Vec<Self> {
        model
            .rods()
            .iter()
            .map(|r| {
                let rod = &r.spec.geometry;
                Self::new(
                    rod,
                    per_piece.unwrap_or_else(|| default_points_per_piece(rod.n_pieces())),
                )
            })
            .collect()
    }
}

/// The poses of every rod and body of a model at one configuration, in
/// the world frame: each rod's piece boundaries and tip, its strains, the
/// bodies' frames and, with a [`RodSampling`] per rod, the rods sampled
/// along their arcs. Buffers are allocated once, in [`WorldPoses::new`];
/// [`WorldPoses::update`] allocates nothing.
#[derive(Clone, Debug)]
pub struct WorldPoses {
    kin: Vec<RodKinematics>,
    /// Articulated models: the dynamics buffers that hold the frames, and
    /// the world poses of each rod's piece boundaries.
    robot: Option<(Data, Vec<Vec<Pose>>)>,
    sampling: Vec<RodSampling>,
    /// Per rod, the sampled world poses (`sampling[r].s.len()` each, empty
    /// without sampling).
    samples: Vec<Vec<Pose>>,
}

impl WorldPoses {
    /// The poses of `model`'s rods (boundaries, tips, strains) and bodies.
    pub fn new(model: &Model) -> Self {
        Self {
            kin: model
                .rods()
                .iter()
                .map(|r| RodKinematics::new(&r.spec.geometry))
                .collect(),
            robot: model.is_articulated().then(|| {
                let world = model
                    .rods()
                    .iter()
                    .map(|r| vec![Pose::identity(); r.spec.geometry.n_pieces() + 1])
                    .collect();
                (Data::new(model), world)
            }),
            sampling: Vec::new(),
            samples: Vec::new(),
        }
    }

    /// As [`WorldPoses::new`], each rod also sampled at `sampling` (one per
    /// rod, in model order).
    pub fn with_sampling(model: &Model, sampling: Vec<RodSampling>) -> Self {
        debug_assert_eq!(sampling.len(), model.rods().len());
        let samples = sampling
            .iter()
            .map(|s| vec![Pose::identity(); s.s.len()])
            .collect();
        Self {
            sampling,
            samples,
            ..Self::new(model)
        }
    }

    /// Updates every pose at `q` (n_dof of `model`), prescribed joints at
    /// time `t` \[s\].
    pub fn update(&mut self, model: &Model, t: f64, q: &[f64]) -> Result<()> {
        if q.len() != model.n_dof() {
            return Err(Error::SizeMismatch {
                what: "q",
                got: q.len(),
                expected: model.n_dof(),
            });
        }
        for (k, r) in self.kin.iter_mut().zip(model.rods()) {
            k.update(&r.spec.geometry, &q[r.dofs()], None, None)?;
        }
        if let Some((data, world)) = &mut self.robot {
            model.set_time(data, t);
            softrod_dynamics::frames(model, data, q)?;
            for (r, (k, out)) in self.kin.iter().zip(world.iter_mut()).enumerate() {
                let to_world = data.rod_to_world(model, r);
                for (o, p) in out.iter_mut().zip(k.boundary_poses()) {
                    *o = to_world.compose(p);
                }
            }
        }
        for i in 0..self.samples.len() {
            let rod = &model.rods()[i].spec.geometry;
            let out = &mut self.samples[i];
            let n = out.len() - 1;
            self.kin[i].poses_along(rod, &self.sampling[i].fractions, &mut out[..n])?;
            if let Some((data, world)) = &self.robot {
                let to_world = data.rod_to_world(model, i);
                for p in &mut out[..n] {
                    *p = to_world.compose(p);
                }
                out[n] = *world[i].last().expect("N+1 boundaries");
            } else {
                out[n] = *self.kin[i].tip_pose();
            }
        }
        Ok(())
    }

    /// Number of rods.
    pub fn n_rods(&self) -> usize {
        self.kin.len()
    }

    /// Tip pose of rod `rod` (world frame).
    pub fn tip(&self, rod: usize) -> &Pose {
        match &self.robot {
            Some((_, world)) => world[rod].last().expect("N+1 boundaries"),
            None => self.kin[rod].tip_pose(),
        }
    }

    /// Poses of rod `rod`'s piece boundaries, base to tip (N + 1, world
    /// frame).
    pub fn boundaries(&self, rod: usize) -> &[Pose] {
        match &self.robot {
            Some((_, world)) => &world[rod],
            None => self.kin[rod].boundary_poses(),
        }
    }

    /// Strain `ξ_n` of each piece of rod `rod` (body frame).
    pub fn strains(&self, rod: usize) -> &[Vec6] {
        self.kin[rod].strains()
    }

    /// World poses of the model's bodies, in model order (empty without).
    pub fn bodies(&self) -> &[Pose] {
        self.robot.as_ref().map_or(&[], |(d, _)| &d.body_poses)
    }

    /// The sampling of rod `rod` (see [`WorldPoses::with_sampling`]).
    pub fn sampling(&self, rod: usize) -> &RodSampling {
        &self.sampling[rod]
    }

    /// Rod `rod`'s world poses at its sampling's abscissae (empty without
    /// sampling).
    pub fn samples(&self, rod: usize) -> &[Pose] {
        self.samples.get(rod).map_or(&[], Vec::as_slice)
    }

    /// The map from rod `rod`'s kinematic poses to the world: the identity
    /// for a clamped rod, else through its joint and parents (D51).
    pub fn rod_to_world(&self, model: &Model, rod: usize) -> Pose {
        match &self.robot {
            Some((data, _)) => data.rod_to_world(model, rod),
            None => Pose::identity(),
        }
    }

    /// World pose of rod `rod` at abscissa `s` \[m\] (D7).
    pub fn pose_at(&self, model: &Model, rod: usize, s: f64) -> Result<Pose> {
        let local = self.kin[rod].pose_at(&model.rods()[rod].spec.geometry, s)?;
        Ok(self.rod_to_world(model, rod).compose(&local))
    }

    /// Rod `rod`'s kinematics at the last update (poses from its own base).
    pub fn kinematics(&self, rod: usize) -> &RodKinematics {
        &self.kin[rod]
    }
}

/// `[x, y, z]` of a pose's origin \[m\].
pub fn position(p: &Pose) -> [f64; 3] {
    [p.translation[0], p.translation[1], p.translation[2]]
}

/// `[w, x, y, z]` of a pose's rotation, with `w ≥ 0` (one hemisphere, so
/// that time series do not jump between `q` and `−q`).
pub fn quaternion(p: &Pose) -> [f64; 4] {
    let q = p.quaternion();
    let (w, x, y, z) = (q.w, q.i, q.j, q.k);
    if w < 0.0 {
        [-w, -x, -y, -z]
    } else {
        [w, x, y, z]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use softrod_kinematics::Basis;

    #[test]
    fn sampling_holds_every_boundary_and_increases() {
        let rod = RodGeometry::with_lengths(
            &[0.1, 0.15, 0.25],
            Basis::all(),
            softrod_kinematics::straight(),
            Pose::identity(),
        )
        .unwrap();
        let s = RodSampling::new(&rod, 4);
        assert_eq!(s.s.len(), 3 * 4 + 1);
        assert!(s.s.windows(2).all(|w| w[1] > w[0]));
        for (k, b) in [0.0, 0.1, 0.25, 0.5].iter().enumerate() {
            assert_eq!(s.s[4 * k], *b, "boundary {k}");
        }
        assert!((s.s[1] - 0.025).abs() < 1e-15);
        let one = RodSampling::new(&rod, 1);
        assert_eq!(one.s, vec![0.0, 0.1, 0.25, 0.5]);
    }

    #[test]
    fn default_points_give_a_smooth_rod_and_never_fewer_than_the_boundaries() {
        assert_eq!(default_points_per_piece(4), 16);
        assert_eq!(default_points_per_piece(8), 8);
        assert_eq!(default_points_per_piece(1), 16);
        assert_eq!(default_points_per_piece(100), 1);
        assert_eq!(default_points_per_piece(0), 16);
    }
}
