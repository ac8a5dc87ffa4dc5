//! Strain bases `B_n`: which strains a piece's coordinates move.

use crate::error::KinematicsError;
use crate::strain::Strain;
use nalgebra::Matrix6xX;
use softrod_lie::Vec6;
use std::fmt;

/// A strain basis `B_n ∈ R^{6×k_n}`, `1 ≤ k_n ≤ 6`, of full column rank:
/// the strain of the piece is `ξ_n = B_n q_n + ξ̄_n`.
#[derive(Clone, Debug, PartialEq)]
pub struct Basis {
    matrix: Matrix6xX<f64>,
    /// When every column is a unit vector, the component each selects:
    /// `B q` and `Bᵀ w` then become gathers/scatters.
    selection: Option<Vec<usize>>,
    /// `B = I₆` (all six strains in order): `B q` is a copy and `op · B` is
    /// `op` itself, the common Cosserat case the hot loops special-case.
    identity: bool,
}

impl Basis {
    /// All six strains (`B = I₆`), the Cosserat rod.
    pub fn all() -> Self {
        Self::select(&Strain::ALL).expect("six distinct strains")
    }

    /// Kirchhoff rod: inextensible, unshearable (`kx, ky, kz`).
    pub fn kirchhoff() -> Self {
        Self::select(&[Strain::Kx, Strain::Ky, Strain::Kz]).expect("distinct")
    }

    /// Selects a subset of strains, in the order given (e.g. planar `kz, qx, qy`):
    /// column `c` of `B_n` is the unit vector of `components[c]`.
    pub fn select(components: &[Strain]) -> Result<Self, KinematicsError> {
        if components.is_empty() || components.len() > 6 {
            return Err(KinematicsError::BasisColumns {
                columns: components.len(),
            });
        }
        let mut seen = [false; 6];
        for &c in components {
            if seen[c.index()] {
                return Err(KinematicsError::DuplicateStrain { strain: c });
            }
            seen[c.index()] = true;
        }
        let idx: Vec<usize> = components.iter().map(|c| c.index()).collect();
        let mut matrix = Matrix6xX::zeros(idx.len());
        for (c, &i) in idx.iter().enumerate() {
            matrix[(i, c)] = 1.0;
        }
        Ok(Self {
            matrix,
            identity: idx == [0, 1, 2, 3, 4, 5],
            selection: Some(idx),
        })
    }

    /// Selects strains by index (0 = kx … 5 = qz), in the order given.
    pub fn from_indices(idx: &[usize]) -> Result<Self, KinematicsError> {
        let strains = idx
            .iter()
            .map(|&index| {
                Strain::ALL
                    .get(index)
                    .copied()
                    .ok_or(KinematicsError::StrainIndex { index })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Self::select(&strains)
    }

    /// A general basis matrix (6×k). It must be finite and of full column
    /// rank (smallest singular value > 1e-10 × largest).
    pub fn from_matrix(matrix: Matrix6xX<f64>) -> Result<Self, KinematicsError> {
        let k = matrix.ncols();
        if k == 0 || k > 6 {
            return Err(KinematicsError::BasisColumns { columns: k });
        }
        if matrix.iter().any(|v| !v.is_finite()) {
            return Err(KinematicsError::BasisNotFinite);
        }
        let sv = matrix.clone().svd(false, false).singular_values;
        let (largest, smallest) = (sv.max(), sv.min());
        if smallest.is_nan() || smallest <= 1e-10 * largest {
            return Err(KinematicsError::RankDeficient { largest, smallest });
        }
        // Recognise pure selections so they get the fast path.
        let mut sel = Vec::with_capacity(k);
        for c in 0..k {
            let col = matrix.column(c);
            let ones: Vec<usize> = (0..6).filter(|&r| col[r] == 1.0).collect();
            let nonzero = (0..6).filter(|&r| col[r] != 0.0).count();
            if ones.len() == 1 && nonzero == 1 {
                sel.push(ones[0]);
            }
        }
        let selection = (sel.len() == k).then_some(sel);
        let identity = selection.as_deref() == Some(&[0, 1, 2, 3, 4, 5][..]);
        Ok(Self {
            matrix,
            selection,
            identity,
        })
    }

    /// Number of generalized coordinates `k_n` of a piece with this basis.
    #[inline]
    pub fn dof(&self) -> usize {
        self.matrix.ncols()
    }

    /// The matrix `B_n` (6×k_n).
    #[inline]
    pub fn matrix(&self) -> &Matrix6xX<f64> {
        &self.matrix
    }

    /// The selected components if `B_n` is a column selection of `I₆`.
    pub fn selection(&self) -> Option<&[usize]> {
        self.selection.as_deref()
    }

    /// The selected strains, column by column, if `B_n` is a column
    /// selection of `I₆` (`None` for a general matrix).
    pub fn strains(&self) -> Option<Vec<Strain>> {
        self.selection
            .as_ref()
            .map(|s| s.iter().map(|&i| Strain::ALL[i]).collect())
    }

    /// Whether `B_n = I₆` (all six strains, in order).
    #[inline]
    pub fn is_identity(&self) -> bool {
        self.identity
    }

    /// `B q` for the piece's coordinates `q` (length `k_n`).
    #[inline]
    pub fn apply(&self, q: &[f64]) -> Vec6 {
        debug_assert_eq!(q.len(), self.dof());
        if self.identity {
            return Vec6::from_column_slice(q);
        }
        let mut out = Vec6::zeros();
        match &self.selection {
            Some(sel) => {
                for (&i, &qc) in sel.iter().zip(q) {
                    out[i] = qc;
                }
            }
            None => {
                for (c, qc) in q.iter().enumerate() {
                    out += self.matrix.column(c) * *qc;
                }
            }
        }
        out
    }

    /// `out = Bᵀ w` (length `k_n`).
    #[inline]
    pub fn tr_apply(&self, w: &Vec6, out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.dof());
        if self.identity {
            out.copy_from_slice(w.as_slice());
            return;
        }
        match &self.selection {
            Some(sel) => {
                for (o, &i) in out.iter_mut().zip(sel) {
                    *o = w[i];
                }
            }
            None => {
                for (c, o) in out.iter_mut().enumerate() {
                    *o = self.matrix.column(c).dot(w);
                }
            }
        }
    }

    /// Column `c` of `B_n` as a 6-vector.
    #[inline]
    pub fn column(&self, c: usize) -> Vec6 {
        self.matrix.fixed_view::<6, 1>(0, c).into_owned()
    }
}

impl fmt::Display for Basis {
    /// A selection as its strain names in column order (`ky, qx, qz`); a
    /// general matrix as `general 6×k basis`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.selection {
            Some(sel) => {
                for (c, &i) in sel.iter().enumerate() {
                    if c > 0 {
                        f.write_str(", ")?;
                    }
                    f.write_str(Strain::ALL[i].name())?;
                }
                Ok(())
            }
            None => write!(f, "general 6×{} basis", self.dof()),
        }
    }
}
