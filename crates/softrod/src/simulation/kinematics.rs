//! Kinematics queries: world poses (through [`WorldPoses`], the one
//! definition of them) and geometric Jacobians, prescribed joints at the
//! clock's time ([`Simulation::set_time`]).

use nalgebra::Matrix6xX;
use softrod_dynamics::Data;
use softrod_kinematics::{Frame, RodKinematics};
use softrod_lie::Pose;

use super::Simulation;
use crate::error::{Error, Result};
use crate::record::WorldPoses;

/// A rod of the model, by name or by index (model order): every query of
/// [`Simulation`] takes either (`"arm"`, `0`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RodId<'a> {
    /// By position in the model (0 is the first rod).
    Index(usize),
    /// By name.
    Name(&'a str),
}

impl From<usize> for RodId<'_> {
    fn from(i: usize) -> Self {
        RodId::Index(i)
    }
}

impl<'a> From<&'a str> for RodId<'a> {
    fn from(name: &'a str) -> Self {
        RodId::Name(name)
    }
}

impl<'a> From<&'a String> for RodId<'a> {
    fn from(name: &'a String) -> Self {
        RodId::Name(name)
    }
}

impl Simulation {
    /// The index of `rod` in the model ([`Error::UnknownRod`] if none).
    pub fn rod_index<'a>(&self, rod: impl Into<RodId<'a>>) -> Result<usize> {
        let rods = self.model().rods();
        match rod.into() {
            RodId::Index(i) if i < rods.len() => Ok(i),
            RodId::Index(i) => Err(Error::UnknownRod(format!(
                "{i} (the model has {} rods)",
                rods.len()
            ))),
            RodId::Name(name) => rods
                .iter()
                .position(|r| r.spec.name == name)
                .ok_or_else(|| Error::UnknownRod(format!("'{name}'"))),
        }
    }

    /// Every world pose at `q`, prescribed joints at [`Self::time`].
    pub fn world_poses(&self, q: &[f64]) -> Result<WorldPoses> {
        self.check("q", q)?;
        let mut poses = WorldPoses::new(self.model());
        poses.update(self.model(), self.time, q)?;
        Ok(poses)
    }

    /// The map from rod `rod`'s kinematic poses (`softrod_kinematics`, which
    /// start at its `Rod::base`) to the world at `q`: the identity for a
    /// rod clamped to the world, else through its joint and parents (D51;
    /// prescribed joints at the time of [`Self::set_time`]).
    pub fn rod_to_world<'a>(&self, rod: impl Into<RodId<'a>>, q: &[f64]) -> Result<Pose> {
        let i = self.rod_index(rod)?;
        Ok(self.world_poses(q)?.rod_to_world(self.model(), i))
    }

    /// World pose of rod `rod` at abscissa `s` \[m\] for coordinates `q` (D7).
    pub fn pose<'a>(&self, rod: impl Into<RodId<'a>>, s: f64, q: &[f64]) -> Result<Pose> {
        let i = self.rod_index(rod)?;
        self.world_poses(q)?.pose_at(self.model(), i, s)
    }

    /// Tip pose of rod `rod` for coordinates `q` (world frame).
    pub fn tip_pose<'a>(&self, rod: impl Into<RodId<'a>>, q: &[f64]) -> Result<Pose> {
        let i = self.rod_index(rod)?;
        Ok(*self.world_poses(q)?.tip(i))
    }

    /// World poses of the rigid bodies' frames for coordinates `q` (one per
    /// body, in the order of `Model::bodies`; empty without bodies).
    pub fn body_poses(&self, q: &[f64]) -> Result<Vec<Pose>> {
        Ok(self.world_poses(q)?.bodies().to_vec())
    }

    /// Geometric Jacobian `J(s)` (6 × n_dof) of rod `rod` at `s` in `frame`:
    /// the twist of the section is `J q̇` (D11). On a model of clamped rods
    /// the columns of other rods are 0; on an articulated one every
    /// coordinate that moves the section has its column — its joint's and
    /// its ancestors' too (`softrod_dynamics::section_jacobian`; prescribed
    /// joints at the time of [`Self::set_time`]).
    pub fn jacobian<'a>(
        &self,
        rod: impl Into<RodId<'a>>,
        s: f64,
        q: &[f64],
        frame: Frame,
    ) -> Result<Matrix6xX<f64>> {
        let model = self.model();
        self.check("q", q)?;
        let i = self.rod_index(rod)?;
        if model.is_articulated() {
            let mut data = Data::new(model);
            model.set_time(&mut data, self.time);
            let (g, spatial) = softrod_dynamics::section_jacobian(model, &mut data, q, i, s)?;
            return Ok(match frame {
                Frame::Spatial => spatial,
                Frame::Body => g.ad_inv().to_mat6() * spatial,
                Frame::Mixed => {
                    // (R ω, R v) of the body twist.
                    let mut mixed = g.ad_inv().to_mat6() * spatial;
                    for c in 0..mixed.ncols() {
                        let w = g.rotation * mixed.fixed_view::<3, 1>(0, c);
                        let v = g.rotation * mixed.fixed_view::<3, 1>(3, c);
                        mixed.fixed_view_mut::<3, 1>(0, c).copy_from(&w);
                        mixed.fixed_view_mut::<3, 1>(3, c).copy_from(&v);
                    }
                    mixed
                }
            });
        }
        let r = &model.rods()[i];
        let mut k = RodKinematics::new(&r.spec.geometry);
        k.update(&r.spec.geometry, &q[r.dofs()], None, None)?;
        let mut local = Matrix6xX::zeros(r.n_dof());
        k.jacobian_at(&r.spec.geometry, s, frame, &mut local)?;
        let mut j = Matrix6xX::zeros(self.n_dof());
        j.columns_mut(r.dof_offset, r.n_dof()).copy_from(&local);
        Ok(j)
    }
}
