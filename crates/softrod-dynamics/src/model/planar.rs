//! Which rods take the planar (se(2)) path (docs/theory.md §13, D71), and
//! their per-piece data in planar coordinates.

use crate::kernels::planar::Pose2;
use crate::model::rod::{PieceData, Rod};
use softrod_lie::{Mat3, Pose, Vec3, Vec6};

/// A rod that takes the planar path: which strains span `P`, and the
/// per-piece data in planar coordinates.
#[derive(Clone, Debug)]
pub(crate) struct PlanarRod {
    /// Full-strain indices of `(ω_a, v_b, v_c)`: `[a, 3 + b, 3 + c]`.
    pub idx: [usize; 3],
    /// The bending axis `a` (0, 1, 2 for x, y, z).
    pub axis: usize,
    pub pieces: Vec<PlanarPiece>,
}

/// One piece in planar coordinates.
#[derive(Clone, Debug)]
pub(crate) struct PlanarPiece {
    /// Planar position (0, 1, 2 of `idx`) of each basis column.
    pub sel: [usize; 3],
    pub k: usize,
    /// `(𝓙_a, m_b, m_c)` of the section inertia at each quadrature point.
    pub inertia: Vec<Vec3>,
}

impl PlanarRod {
    /// The planar description of a rod, if it has one (D71): bending axes
    /// are tried in the order y, z, x (a rod that qualifies for several,
    /// e.g. one selecting only the stretch `q_x`, takes the first).
    pub(crate) fn detect(spec: &Rod, pieces: &[PieceData]) -> Option<Self> {
        [1usize, 2, 0].into_iter().find_map(|a| {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let idx = [a, 3 + b, 3 + c];
            let planar_pieces = spec
                .geometry
                .pieces()
                .iter()
                .zip(pieces)
                .map(|(piece, pd)| {
                    let off_plane =
                        (0..6).any(|i| !idx.contains(&i) && piece.rest_strain[i] != 0.0);
                    if off_plane {
                        return None;
                    }
                    let mut sel = [0; 3];
                    let columns = piece.basis.selection()?;
                    if columns.len() > 3 {
                        return None;
                    }
                    for (s, j) in sel.iter_mut().zip(columns) {
                        *s = idx.iter().position(|i| i == j)?;
                    }
                    Some(PlanarPiece {
                        sel,
                        k: columns.len(),
                        inertia: pd
                            .points
                            .iter()
                            .map(|p| {
                                Vec3::new(p.inertia[idx[0]], p.inertia[idx[1]], p.inertia[idx[2]])
                            })
                            .collect(),
                    })
                })
                .collect::<Option<Vec<_>>>()?;
            Some(Self {
                idx,
                axis: a,
                pieces: planar_pieces,
            })
        })
    }

    #[inline(always)]
    pub(crate) fn gather(&self, v: &Vec6) -> Vec3 {
        Vec3::new(v[self.idx[0]], v[self.idx[1]], v[self.idx[2]])
    }

    #[inline(always)]
    pub(crate) fn scatter(&self, v: &Vec3) -> Vec6 {
        let mut out = Vec6::zeros();
        for (i, &j) in self.idx.iter().enumerate() {
            out[j] = v[i];
        }
        out
    }

    /// The 3-D pose of a planar one, in the rod's base frame.
    pub(crate) fn embed(&self, g: &Pose2) -> Pose {
        let a = self.axis;
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let mut r = Mat3::zeros();
        r[(a, a)] = 1.0;
        r[(b, b)] = g.c;
        r[(c, b)] = g.s;
        r[(b, c)] = -g.s;
        r[(c, c)] = g.c;
        let mut p = Vec3::zeros();
        p[b] = g.p[0];
        p[c] = g.p[1];
        Pose::new(r, p)
    }
}
