//! Generalized elastic and viscous forces of PCS pieces (D13) and the elastic energy (§7).

use crate::body::RodProperties;
use nalgebra::{DMatrix, DVector};
use softrod_kinematics::{GaussLegendre, Piece, RodGeometry};
use softrod_lie::Vec6;

/// Per-piece constant matrices of the elastic and viscous forces (D13):
///
/// `τ_e,n = K_n q_n + e_n`, `τ_d,n = D_n q̇_n`, with
/// `K_n = ∫ B_nᵀ Γ B_n ds`, `D_n = ∫ B_nᵀ γ B_n ds`, `e_n = ∫ B_nᵀ Γ (ξ̄_n − ξ*_n) ds`
/// (integrals over the piece). These are the forces on the left-hand side of
/// `M q̈ + … + K q + e + D q̇ = τ`; units N·m or N per coordinate unit.
#[derive(Clone, Debug, PartialEq)]
pub struct PieceMatrices {
    /// `K_n` (k_n × k_n, symmetric positive definite).
    pub stiffness: DMatrix<f64>,
    /// `D_n` (k_n × k_n, symmetric positive semi-definite; zero when `μ = 0`).
    pub damping: DMatrix<f64>,
    /// `e_n = ∫ B_nᵀ Γ (ξ̄_n − ξ*_n) ds` (length k_n); zero when `ξ* = ξ̄`.
    pub elastic_offset: DVector<f64>,
}

impl PieceMatrices {
    /// `q̄_n = −K_n⁻¹ e_n`: the coordinates of the piece's stress-free strain
    /// projected onto its basis (§7), i.e. where `τ_e,n` vanishes.
    pub fn stress_free_coordinates(&self) -> DVector<f64> {
        let chol = self
            .stiffness
            .clone()
            .cholesky()
            .expect("K_n is positive definite for a valid body");
        -chol.solve(&self.elastic_offset)
    }
}

/// `∫_piece Γ(s) ds` and `∫_piece γ(s) ds` (diagonals, 6-vectors). Exact
/// (`ℓ_n Γ`) for a uniform section; Gauss–Legendre on the piece otherwise
/// (for the linear taper Γ is a degree-4 polynomial in s, exact from 3 points).
pub fn integrated_constitutive(
    piece: &Piece,
    body: &RodProperties,
    quadrature: &GaussLegendre,
) -> (Vec6, Vec6) {
    if body.is_uniform() {
        let s = piece.start;
        return (
            body.stiffness(s) * piece.length,
            body.viscosity(s) * piece.length,
        );
    }
    let mut gi = Vec6::zeros();
    let mut vi = Vec6::zeros();
    for (x, w) in quadrature.on_interval(piece.length) {
        let s = piece.start + x;
        gi += body.stiffness(s) * w;
        vi += body.viscosity(s) * w;
    }
    (gi, vi)
}

/// `Bᵀ diag(d) B` for the piece basis.
fn project_diag(piece: &Piece, d: &Vec6) -> DMatrix<f64> {
    let b = piece.basis.matrix();
    let k = b.ncols();
    let mut m = DMatrix::zeros(k, k);
    for i in 0..k {
        for j in i..k {
            let mut acc = 0.0;
            for r in 0..6 {
                acc += b[(r, i)] * d[r] * b[(r, j)];
            }
            m[(i, j)] = acc;
            m[(j, i)] = acc;
        }
    }
    m
}

/// Builds `K_n`, `D_n` and `e_n` for every piece (D13).
///
/// `stress_free`: the stress-free strain `ξ*_n` of each piece (one `Vec6` per
/// piece); `None` means `ξ* = ξ̄` (the rest strain is stress-free, `e_n = 0`).
/// `quadrature` is used only for non-uniform sections.
///
/// # Panics
/// If `stress_free` does not have one entry per piece.
pub fn piece_matrices(
    rod: &RodGeometry,
    body: &RodProperties,
    stress_free: Option<&[Vec6]>,
    quadrature: &GaussLegendre,
) -> Vec<PieceMatrices> {
    if let Some(sf) = stress_free {
        assert_eq!(sf.len(), rod.n_pieces(), "one stress-free strain per piece");
    }
    rod.pieces()
        .iter()
        .enumerate()
        .map(|(n, p)| {
            let (gi, vi) = integrated_constitutive(p, body, quadrature);
            let delta = stress_free.map_or(Vec6::zeros(), |sf| p.rest_strain - sf[n]);
            let mut off = vec![0.0; p.basis.dof()];
            p.basis.tr_apply(&gi.component_mul(&delta), &mut off);
            PieceMatrices {
                stiffness: project_diag(p, &gi),
                damping: project_diag(p, &vi),
                elastic_offset: DVector::from_vec(off),
            }
        })
        .collect()
}

/// Elastic energy (§7) `V_e = ½ Σ_n ∫ (ξ_n − ξ*_n)ᵀ Γ(s) (ξ_n − ξ*_n) ds` \[J\].
///
/// The strain is constant on a piece, so this is `½ Σ_n δ_nᵀ diag(∫Γ ds) δ_n`
/// with `δ_n = B_n q_n + ξ̄_n − ξ*_n`; `∫Γ` as in [`integrated_constitutive`].
/// `stress_free = None` means `ξ* = ξ̄`. Its gradient is exactly
/// `K_n q_n + e_n` of [`piece_matrices`] (same quadrature).
///
/// # Panics
/// If `stress_free` does not have one entry per piece.
pub fn elastic_energy(
    rod: &RodGeometry,
    body: &RodProperties,
    stress_free: Option<&[Vec6]>,
    q: &[f64],
    quadrature: &GaussLegendre,
) -> f64 {
    if let Some(sf) = stress_free {
        assert_eq!(sf.len(), rod.n_pieces(), "one stress-free strain per piece");
    }
    rod.pieces()
        .iter()
        .enumerate()
        .map(|(n, p)| {
            let (gi, _) = integrated_constitutive(p, body, quadrature);
            let xi_star = stress_free.map_or(p.rest_strain, |sf| sf[n]);
            let d = p.strain(q) - xi_star;
            0.5 * d.dot(&gi.component_mul(&d))
        })
        .sum()
}
