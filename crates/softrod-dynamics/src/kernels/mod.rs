//! Floor 0, the kernels: fixed-size arithmetic on one piece or one
//! evaluation point, with no knowledge of a model — 6×6 blocks kept as 3×3
//! ([`blocks`]), the small Cholesky solves of a piece's `k×k` block
//! ([`chol`]), the inertia sums over a piece's points ([`inertia`]), the
//! strain derivatives of the piece maps ([`piece_derivs`], D30–D36), the
//! planar se(2) maps (`planar`, D71–D75) and the run-time choice of the
//! AVX2 copies of the hot algorithms ([`simd`]).
//!
//! A faster way to compute something per piece goes here; everything above
//! calls it.

pub(crate) mod blocks;
pub(crate) mod chol;
pub(crate) mod inertia;
pub(crate) mod mat6;
pub(crate) mod piece_derivs;
pub(crate) mod planar;
// The AVX2 copies: the crate's one `unsafe` call (after the CPU check) is
// in its dispatch macro, and its test calls the copies directly.
#[allow(unsafe_code)]
pub(crate) mod simd;
