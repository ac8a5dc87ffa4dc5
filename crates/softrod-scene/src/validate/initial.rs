//! `[initial]`: `q` and `qdot` of the right length; warnings about strains
//! far outside the small-strain range.

use std::f64::consts::PI;

use softrod_dynamics::RodSpec;
use softrod_kinematics::Strain;

use super::{Ctx, Result};
use crate::raw::RawInitial;
use crate::robot::Robot;
use crate::scene::Initial;

impl Ctx<'_> {
    pub(super) fn initial(
        &mut self,
        raw: Option<RawInitial>,
        rods: &[RodSpec],
        robot: &Robot,
    ) -> Result<Initial> {
        let Some(raw) = raw else {
            return Ok(Initial::default());
        };
        let joints = robot.joint_dofs();
        let n_dof: usize = rods.iter().map(|r| r.rod.n_dof()).sum::<usize>() + joints;
        let per_rod = rods
            .iter()
            .map(|r| {
                format!(
                    "{}: {} pieces × {} strains",
                    r.name,
                    r.rod.n_pieces(),
                    r.rod.pieces()[0].basis.dof()
                )
            })
            .chain((joints > 0).then(|| format!("joints: {joints}")))
            .collect::<Vec<_>>()
            .join(", ");
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
        if let Some(q) = &raw.q {
            self.warn_large_strains(q, rods, robot);
        }
        Ok(Initial {
            q: raw.q,
            qdot: raw.qdot,
        })
    }

    /// Warns (once per rod) about initial strains far outside the small-strain range.
    fn warn_large_strains(&mut self, q: &[f64], rods: &[RodSpec], robot: &Robot) {
        for (i, rod) in rods.iter().enumerate() {
            let offset = robot.rod_dof_offset(rods, i);
            if let Some((at, why)) = large_strain(&q[offset..offset + rod.rod.n_dof()], rod) {
                self.warn(
                    &format!("initial.q[{}]", offset + at),
                    format!("rod {:?}: {why}", rod.name),
                );
            }
        }
    }
}

/// The first coordinate of `q` (the rod's own) that bends a piece by more
/// than π, inverts it, or deviates from rest by more than 0.5 in a stretch or
/// shear, with the reason.
fn large_strain(q: &[f64], rod: &RodSpec) -> Option<(usize, String)> {
    for (k, piece) in rod.rod.pieces().iter().enumerate() {
        let Some(sel) = piece.basis.selection() else {
            continue;
        };
        let l = piece.length;
        for (c, &j) in sel.iter().enumerate() {
            let at = piece.dof_offset + c;
            let xi = piece.rest_strain[j] + q[at];
            let name = Strain::ALL[j].name();
            let why = if j < 3 && (xi * l).abs() > PI {
                Some(format!(
                    "{name} = {xi} 1/m turns piece {k} ({l} m) by {:.2} rad, more than π",
                    (xi * l).abs()
                ))
            } else if j == 3 && xi <= 0.0 {
                Some(format!(
                    "stretch qx = {xi} ≤ 0 in piece {k}: the piece is inverted"
                ))
            } else if j >= 3 && q[at].abs() > 0.5 {
                Some(format!(
                    "{name} deviates from rest by {} in piece {k}: a very large strain",
                    q[at]
                ))
            } else {
                None
            };
            if let Some(why) = why {
                return Some((at, why));
            }
        }
    }
    None
}
