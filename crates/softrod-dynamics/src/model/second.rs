//! The buffers of the analytic contact linearization
//! (docs/theory-contact.md CT12–CT14): the path of a contact point to the
//! root — one block per node whose coordinates move it, with the frame
//! where that node's spatial columns are taken — and the 3 × n rows the
//! assembly writes. Sized once with the contact work; an evaluation only
//! clears and refills them (their `Vec`s keep their capacity).

use nalgebra::DMatrix;
use softrod_lie::{Mat6, Pose, Vec3, Vec6};

/// One node on a point's path to the root (CT12): its coordinates
/// `dof..dof + k`, the world pose `G` of the frame where its spatial
/// columns `Ad_G T₋(x) B` are taken (the point's own section, the node's
/// tip, or the point inside it a child hangs from), the node's strain `ξ`,
/// the abscissa `x` of that frame in the node, its padded basis, and the
/// frame's spatial twist (world axes, at the world origin).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Block {
    pub dof: usize,
    pub k: usize,
    pub pose: Pose,
    pub xi: Vec6,
    pub x: f64,
    pub bpad: Mat6,
    pub vel: Vec6,
    /// Index of the block's first column in [`PointPath::cols`].
    pub first: usize,
    /// Angular velocity of the frame the block hangs from, and the velocity
    /// of the point as if carried rigidly by the block's frame (CT12).
    pub omega_pre: Vec3,
    pub pdot_frame: Vec3,
}

/// One coordinate on the path: its index in `q`, its block, and the world
/// angular velocity `ω_i` and point velocity `j_i` per unit rate.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Col {
    pub dof: usize,
    pub block: usize,
    pub w: Vec3,
    pub j: Vec3,
}

/// A material point's path to the root with its first and second
/// derivatives (CT12), blocks from the point's own node (index 0) to the
/// root.
#[derive(Clone, Debug, Default)]
pub(crate) struct PointPath {
    pub blocks: Vec<Block>,
    pub cols: Vec<Col>,
    /// Per block, its `k × k` in-block second derivatives `∂²p/∂q_i∂q_l`
    /// (row-major, from `inner_at[block]`).
    pub inner: Vec<Vec3>,
    pub inner_at: Vec<usize>,
    /// The point \[m\] and its velocity \[m/s\], world.
    pub p: Vec3,
    pub pdot: Vec3,
    /// The section's rotation and its strain `ξ = (k, ν)` and rate (rod
    /// points; the tangent `R ν` and its derivatives, CT13).
    pub rotation: softrod_lie::Mat3,
    pub strain: Vec6,
    pub strain_rate: Vec6,
    /// `j_i × f` per column (the geometric term's work space).
    pub scratch: Vec<Vec3>,
    /// Per coordinate in increasing order, its index in `cols`.
    pub sorted: Vec<usize>,
}

/// The buffers of one linearization (CT12–CT14).
#[derive(Clone, Debug)]
pub(crate) struct SecondWork {
    pub a: PointPath,
    pub b: PointPath,
    /// First-order paths of the friction anchor's two material points
    /// (rod pairs, CT14).
    pub ea: PointPath,
    pub eb: PointPath,
    /// 3 × n rows: the force's Jacobian `J_w`, the carrier's angular
    /// Jacobian, `∂v/∂q`, `∂f/∂q`, the anchor stretch's Jacobian, and the
    /// tangents' `∂t/∂q` of the two points.
    pub jw: DMatrix<f64>,
    pub jomega: DMatrix<f64>,
    pub vq: DMatrix<f64>,
    pub je: DMatrix<f64>,
    pub ta: DMatrix<f64>,
    pub tb: DMatrix<f64>,
    /// `∂s_a/∂q`, `∂s_b/∂q` of a pair's closest points (n).
    pub dsa: Vec<f64>,
    pub dsb: Vec<f64>,
    /// The coordinates the current contact touches, sorted.
    pub dofs: Vec<usize>,
    /// Per coordinate of `dofs`: `J_w` column, `∂f/∂q` column, `∂f/∂q̇ J_w`
    /// column, and two scalars or a vector the assembly pairs with them.
    pub gather: Vec<Gathered>,
}

/// One coordinate's columns, gathered for the `dofs × dofs` products.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Gathered {
    pub j: Vec3,
    pub f: Vec3,
    pub g: Vec3,
    pub u: Vec3,
    pub a: f64,
    pub b: f64,
}

impl SecondWork {
    pub(crate) fn new(n: usize) -> Self {
        let rows = || DMatrix::zeros(3, n);
        Self {
            a: PointPath::default(),
            b: PointPath::default(),
            ea: PointPath::default(),
            eb: PointPath::default(),
            jw: rows(),
            jomega: rows(),
            vq: rows(),
            je: rows(),
            ta: rows(),
            tb: rows(),
            dsa: vec![0.0; n],
            dsb: vec![0.0; n],
            dofs: Vec::with_capacity(n),
            gather: Vec::with_capacity(n),
        }
    }
}
