//! A rod cut into PCS pieces: lengths, strain bases, rest strain, base pose.

use crate::error::KinematicsError;
use nalgebra::{DVector, Matrix6xX};
use softrod_lie::{Pose, Vec6};

/// One of the six strain components, in softrod's order `(kx, ky, kz, qx, qy, qz)`:
/// torsion, the two bendings, extension, the two shears.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Strain {
    /// Torsion (rad/m).
    Kx = 0,
    /// Bending about the local y axis (rad/m).
    Ky = 1,
    /// Bending about the local z axis (rad/m).
    Kz = 2,
    /// Extension (1 at rest).
    Qx = 3,
    /// Shear along local y.
    Qy = 4,
    /// Shear along local z.
    Qz = 5,
}

impl Strain {
    /// All six, in order.
    pub const ALL: [Strain; 6] = [
        Strain::Kx,
        Strain::Ky,
        Strain::Kz,
        Strain::Qx,
        Strain::Qy,
        Strain::Qz,
    ];

    /// The scene-file name (`"kx"` … `"qz"`).
    pub fn name(self) -> &'static str {
        ["kx", "ky", "kz", "qx", "qy", "qz"][self as usize]
    }

    /// Parses a scene-file name.
    pub fn from_name(name: &str) -> Option<Strain> {
        Strain::ALL.into_iter().find(|s| s.name() == name)
    }
}

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

    /// Selects a subset of strains, in the order given (e.g. planar `kz, qx, qy`).
    pub fn select(components: &[Strain]) -> Result<Self, KinematicsError> {
        let idx: Vec<usize> = components.iter().map(|&c| c as usize).collect();
        Self::from_indices(&idx)
    }

    /// Selects strains by index (0 = kx … 5 = qz), in the order given.
    pub fn from_indices(idx: &[usize]) -> Result<Self, KinematicsError> {
        let bad = |reason: String| KinematicsError::BadBasis { piece: 0, reason };
        if idx.is_empty() || idx.len() > 6 {
            return Err(bad(format!("needs 1 to 6 strains, got {}", idx.len())));
        }
        let mut seen = [false; 6];
        for &i in idx {
            if i >= 6 {
                return Err(bad(format!("strain index {i} is not in 0..6")));
            }
            if seen[i] {
                return Err(bad(format!(
                    "strain {} selected twice",
                    Strain::ALL[i].name()
                )));
            }
            seen[i] = true;
        }
        let mut matrix = Matrix6xX::zeros(idx.len());
        for (c, &i) in idx.iter().enumerate() {
            matrix[(i, c)] = 1.0;
        }
        Ok(Self {
            matrix,
            identity: idx == [0, 1, 2, 3, 4, 5],
            selection: Some(idx.to_vec()),
        })
    }

    /// A general basis matrix (6×k). It must be finite and of full column
    /// rank (smallest singular value > 1e-10 × largest).
    pub fn from_matrix(matrix: Matrix6xX<f64>) -> Result<Self, KinematicsError> {
        let bad = |reason: String| KinematicsError::BadBasis { piece: 0, reason };
        let k = matrix.ncols();
        if k == 0 || k > 6 {
            return Err(bad(format!("needs 1 to 6 columns, got {k}")));
        }
        if matrix.iter().any(|v| !v.is_finite()) {
            return Err(bad("contains NaN or infinity".into()));
        }
        let sv = matrix.clone().svd(false, false).singular_values;
        let (max, min) = (sv.max(), sv.min());
        if min.is_nan() || min <= 1e-10 * max {
            return Err(bad(format!(
                "not of full column rank (singular values {max:.3e} … {min:.3e})"
            )));
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

/// One PCS piece: `s ∈ [start, start + length]`, constant strain
/// `ξ_n = B_n q_n + ξ̄_n`.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// Length `ℓ_n` [m].
    pub length: f64,
    /// Abscissa of the piece base `L_{n−1}` [m].
    pub start: f64,
    /// Strain basis `B_n`.
    pub basis: Basis,
    /// Rest strain `ξ̄_n` (the strain at `q_n = 0`).
    pub rest_strain: Vec6,
    /// Index of the piece's first coordinate in `q`.
    pub dof_offset: usize,
}

impl Piece {
    /// Abscissa of the piece tip `L_n` [m].
    #[inline]
    pub fn end(&self) -> f64 {
        self.start + self.length
    }

    /// Range of the piece's coordinates in `q`.
    #[inline]
    pub fn dofs(&self) -> std::ops::Range<usize> {
        self.dof_offset..self.dof_offset + self.basis.dof()
    }

    /// The piece's strain `ξ_n = B_n q_n + ξ̄_n` for the full coordinate vector `q`.
    #[inline]
    pub fn strain(&self, q: &[f64]) -> Vec6 {
        let q = &q[self.dofs()];
        if self.basis.identity {
            // Inline, without the call into `apply` (the sweep's hot path).
            return Vec6::from_column_slice(q) + self.rest_strain;
        }
        self.basis.apply(q) + self.rest_strain
    }

    /// The strain rate `ξ̇_n = B_n q̇_n` for the full velocity vector `q̇`.
    #[inline]
    pub fn strain_rate(&self, qd: &[f64]) -> Vec6 {
        self.basis.apply(&qd[self.dofs()])
    }
}

/// Description of one piece for [`Rod::from_pieces`].
#[derive(Clone, Debug)]
pub struct PieceSpec {
    /// Length [m].
    pub length: f64,
    /// Strain basis.
    pub basis: Basis,
    /// Rest strain `ξ̄_n`.
    pub rest_strain: Vec6,
}

/// The rest strain of a straight, unstretched rod: `(0, 0, 0, 1, 0, 0)`.
pub fn straight() -> Vec6 {
    Vec6::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
}

/// A rod clamped at `base`, cut into PCS pieces (seed section 0.3).
///
/// Generalized coordinates `q = (q_1, …, q_N)`, `n_dof = Σ k_n`.
#[derive(Clone, Debug, PartialEq)]
pub struct Rod {
    pieces: Vec<Piece>,
    base: Pose,
    length: f64,
    n_dof: usize,
}

impl Rod {
    /// `n` equal pieces over `length`, the same basis and rest strain on each.
    pub fn uniform(
        length: f64,
        n: usize,
        basis: Basis,
        rest_strain: Vec6,
        base: Pose,
    ) -> Result<Self, KinematicsError> {
        if n == 0 {
            return Err(KinematicsError::NoPieces);
        }
        check_length("rod length", length)?;
        let lengths = vec![length / n as f64; n];
        Self::with_lengths(&lengths, basis, rest_strain, base)
    }

    /// Pieces of the given lengths, the same basis and rest strain on each.
    pub fn with_lengths(
        lengths: &[f64],
        basis: Basis,
        rest_strain: Vec6,
        base: Pose,
    ) -> Result<Self, KinematicsError> {
        let specs: Vec<PieceSpec> = lengths
            .iter()
            .map(|&length| PieceSpec {
                length,
                basis: basis.clone(),
                rest_strain,
            })
            .collect();
        Self::from_pieces(specs, base)
    }

    /// General constructor: each piece with its own basis and rest strain.
    pub fn from_pieces(specs: Vec<PieceSpec>, base: Pose) -> Result<Self, KinematicsError> {
        if specs.is_empty() {
            return Err(KinematicsError::NoPieces);
        }
        let finite = |what: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(KinematicsError::NotFinite {
                    what: what.to_string(),
                    value: v,
                })
            }
        };
        for v in base.rotation.iter().chain(base.translation.iter()) {
            finite("base pose", *v)?;
        }
        let mut pieces = Vec::with_capacity(specs.len());
        let mut start = 0.0;
        let mut off = 0;
        for (i, spec) in specs.into_iter().enumerate() {
            check_length(&format!("piece {i} length"), spec.length)?;
            for v in spec.rest_strain.iter() {
                finite(&format!("piece {i} rest strain"), *v)?;
            }
            let k = spec.basis.dof();
            pieces.push(Piece {
                length: spec.length,
                start,
                basis: spec.basis,
                rest_strain: spec.rest_strain,
                dof_offset: off,
            });
            start += spec.length;
            off += k;
        }
        Ok(Self {
            pieces,
            base,
            length: start,
            n_dof: off,
        })
    }

    /// The pieces, base to tip.
    #[inline]
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces
    }

    /// Number of pieces `N`.
    #[inline]
    pub fn n_pieces(&self) -> usize {
        self.pieces.len()
    }

    /// Number of generalized coordinates `Σ k_n`.
    #[inline]
    pub fn n_dof(&self) -> usize {
        self.n_dof
    }

    /// Total (material, unstretched) length `L` [m].
    #[inline]
    pub fn length(&self) -> f64 {
        self.length
    }

    /// The clamped base pose `g_r` (world).
    #[inline]
    pub fn base(&self) -> &Pose {
        &self.base
    }

    /// The piece containing `s` and the local abscissa `x = s − L_{n−1}`.
    /// Interior piece boundaries belong to the piece that ends there
    /// (`x = ℓ_n`), except `s = 0` which is `x = 0` of the first piece.
    /// Abscissae within 1e-12·L outside `[0, L]` are clamped (round-off).
    pub fn locate(&self, s: f64) -> Result<(usize, f64), KinematicsError> {
        let tol = 1e-12 * self.length;
        if !(s >= -tol && s <= self.length + tol) {
            return Err(KinematicsError::OutOfRod {
                s,
                length: self.length,
            });
        }
        let s = s.clamp(0.0, self.length);
        // First piece whose end is ≥ s.
        let n = self
            .pieces
            .partition_point(|p| p.end() < s)
            .min(self.pieces.len() - 1);
        let p = &self.pieces[n];
        // `s − start` can miss `ℓ_n` by an ulp at s = L_n; return the tip exactly.
        let x = if s >= p.end() {
            p.length
        } else {
            (s - p.start).clamp(0.0, p.length)
        };
        Ok((n, x))
    }

    /// The strain of piece `n` for coordinates `q`.
    #[inline]
    pub fn strain(&self, n: usize, q: &[f64]) -> Vec6 {
        self.pieces[n].strain(q)
    }

    /// The coordinates that put every piece at its rest strain (all zeros).
    pub fn rest_q(&self) -> DVector<f64> {
        DVector::zeros(self.n_dof)
    }

    /// Checks that `v` has `n_dof` entries, all finite.
    pub fn check_coordinates(&self, what: &'static str, v: &[f64]) -> Result<(), KinematicsError> {
        if v.len() != self.n_dof {
            return Err(KinematicsError::SizeMismatch {
                what,
                got: v.len(),
                expected: self.n_dof,
            });
        }
        if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(KinematicsError::NotFinite {
                what: format!("{what}[{i}]"),
                value: *x,
            });
        }
        Ok(())
    }
}

fn check_length(what: &str, v: f64) -> Result<(), KinematicsError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(KinematicsError::BadLength {
            what: what.to_string(),
            value: v,
        })
    }
}
