//! A rod cut into PCS pieces: lengths, strain bases, rest strain, base pose.

use crate::basis::Basis;
use crate::error::{KinematicsError, LengthOf};
use crate::strain::Strain;
use nalgebra::DVector;
use softrod_lie::{Pose, Vec6};

/// One PCS piece: `s ∈ [start, start + length]`, constant strain
/// `ξ_n = B_n q_n + ξ̄_n`.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// Length `ℓ_n` \[m\].
    pub length: f64,
    /// Abscissa of the piece base `L_{n−1}` \[m\].
    pub start: f64,
    /// Strain basis `B_n`.
    pub basis: Basis,
    /// Rest strain `ξ̄_n` (the strain at `q_n = 0`).
    pub rest_strain: Vec6,
    /// Index of the piece's first coordinate in `q`.
    pub dof_offset: usize,
}

impl Piece {
    /// Abscissa of the piece tip `L_n` \[m\].
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
        if self.basis.is_identity() {
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

/// Description of one piece for [`RodGeometry::from_pieces`].
#[derive(Clone, Debug)]
pub struct PieceSpec {
    /// Length \[m\].
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

/// A rod clamped at `base`, cut into PCS pieces (docs/theory.md §0.6, (C9)).
///
/// Generalized coordinates `q = (q_1, …, q_N)`, `n_dof = Σ k_n`.
#[derive(Clone, Debug, PartialEq)]
pub struct RodGeometry {
    pieces: Vec<Piece>,
    base: Pose,
    length: f64,
    n_dof: usize,
}

impl RodGeometry {
    /// Upper bound on the number of pieces: far beyond any useful
    /// discretization, low enough that a typo (`10000000000` pieces) is an
    /// error instead of an attempt to allocate terabytes.
    pub const MAX_PIECES: usize = 1_000_000;

    /// Tolerance on `R Rᵀ = I` (entrywise) and `det R = 1` of the base
    /// rotation: rotations typed with 7 significant digits pass, a scaled or
    /// sheared matrix does not.
    pub const ROTATION_TOL: f64 = 1e-6;

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
        if n > Self::MAX_PIECES {
            return Err(KinematicsError::TooManyPieces {
                pieces: n,
                max: Self::MAX_PIECES,
            });
        }
        check_length(LengthOf::RodGeometry, length)?;
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
    ///
    /// Checks: 1 to [`Self::MAX_PIECES`] pieces, every length positive and
    /// finite, rest strains finite, the base pose finite with a rotation
    /// orthonormal of determinant +1 (to [`Self::ROTATION_TOL`]).
    pub fn from_pieces(specs: Vec<PieceSpec>, base: Pose) -> Result<Self, KinematicsError> {
        if specs.is_empty() {
            return Err(KinematicsError::NoPieces);
        }
        if specs.len() > Self::MAX_PIECES {
            return Err(KinematicsError::TooManyPieces {
                pieces: specs.len(),
                max: Self::MAX_PIECES,
            });
        }
        check_base(&base)?;
        let mut pieces = Vec::with_capacity(specs.len());
        let mut start = 0.0;
        let mut off = 0;
        for (i, spec) in specs.into_iter().enumerate() {
            check_length(LengthOf::Piece(i), spec.length)?;
            if let Some((c, &value)) = spec
                .rest_strain
                .iter()
                .enumerate()
                .find(|(_, v)| !v.is_finite())
            {
                return Err(KinematicsError::RestStrainNotFinite {
                    piece: i,
                    component: Strain::ALL[c],
                    value,
                });
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

    /// Total (material, unstretched) length `L` \[m\].
    #[inline]
    pub fn length(&self) -> f64 {
        self.length
    }

    /// The clamped base pose `g_r` (world).
    #[inline]
    pub fn base(&self) -> &Pose {
        &self.base
    }

    /// The lengths `ℓ_n` of the pieces, base to tip \[m\].
    pub fn piece_lengths(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        self.pieces.iter().map(|p| p.length)
    }

    /// The basis shared by every piece, or `None` when the pieces differ.
    pub fn uniform_basis(&self) -> Option<&Basis> {
        let first = &self.pieces[0].basis;
        self.pieces[1..]
            .iter()
            .all(|p| p.basis == *first)
            .then_some(first)
    }

    /// The same rod with every piece cut into `k ≥ 1` equal parts (bases and
    /// rest strains repeated): a refinement of the discretization.
    pub fn subdivided(&self, k: usize) -> Result<Self, KinematicsError> {
        let specs = self
            .pieces
            .iter()
            .flat_map(|p| {
                std::iter::repeat_n(
                    PieceSpec {
                        length: p.length / k as f64,
                        basis: p.basis.clone(),
                        rest_strain: p.rest_strain,
                    },
                    k,
                )
            })
            .collect();
        Self::from_pieces(specs, self.base)
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
        if let Some((index, &value)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(KinematicsError::NotFinite { what, index, value });
        }
        Ok(())
    }
}

fn check_length(what: LengthOf, value: f64) -> Result<(), KinematicsError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(KinematicsError::BadLength { what, value })
    }
}

/// A finite base whose rotation is orthonormal with determinant +1.
fn check_base(base: &Pose) -> Result<(), KinematicsError> {
    if let Some(&value) = base
        .rotation
        .iter()
        .chain(base.translation.iter())
        .find(|v| !v.is_finite())
    {
        return Err(KinematicsError::BaseNotFinite { value });
    }
    let r = &base.rotation;
    let deviation = (r * r.transpose() - softrod_lie::Mat3::identity()).amax();
    let determinant = r.determinant();
    if deviation > RodGeometry::ROTATION_TOL
        || (determinant - 1.0).abs() > RodGeometry::ROTATION_TOL
    {
        return Err(KinematicsError::BaseNotRotation {
            deviation,
            determinant,
            tolerance: RodGeometry::ROTATION_TOL,
        });
    }
    Ok(())
}
