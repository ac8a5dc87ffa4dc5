//! The planar (se(2)) path of the O(N) forward and the inverse dynamics
//! (docs/theory.md §13, D71–D75).
//!
//! A rod whose every piece selects strains among `(κ_a, q_b, q_c)` — the
//! bending about one body axis `a` and the two strains in the plane
//! normal to it, `(a, b, c)` a cyclic permutation of `(x, y, z)` — and
//! whose rest strain has no other component stays in the `b, c` plane of
//! its base frame. The subspace `P = (ω_a, v_b, v_c)` of twists is
//! invariant under `ad_ξ`, `Ad_g`, `T₋` for `ξ ∈ P` and `g = exp(ξ)`, and
//! `Ad_g`, the diagonal section inertia and `ad*` are block diagonal on
//! `P ⊕ P⊥` (D71). Every term the forward dynamics projects on the
//! coordinates therefore lives in `P`: the per-point twists, biases and
//! wrenches are 3-vectors and every inertia a 3×3 matrix, where the
//! general path carries 6-vectors and 6×6 blocks. Loads with components
//! in `P⊥` (gravity or a world load out of the plane) are held by the
//! section's rigidity in those directions and do no work: they are
//! dropped by the projection on `P`, exactly as the general path drops
//! them in `Sᵀ`.

use crate::data::Data;
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::{Model, PieceData, RodModel, RodSpec};
use crate::passes::{external_density, gravity_base_acceleration};
use nalgebra::Vector2;
use softrod_lie::{Mat3, Pose, Vec3, Vec6};

type V2 = Vector2<f64>;

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
    pub(crate) fn detect(spec: &RodSpec, pieces: &[PieceData]) -> Option<Self> {
        [1usize, 2, 0].into_iter().find_map(|a| {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let idx = [a, 3 + b, 3 + c];
            let planar_pieces = spec
                .rod
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
    fn gather(&self, v: &Vec6) -> Vec3 {
        Vec3::new(v[self.idx[0]], v[self.idx[1]], v[self.idx[2]])
    }

    #[inline(always)]
    fn scatter(&self, v: &Vec3) -> Vec6 {
        let mut out = Vec6::zeros();
        for (i, &j) in self.idx.iter().enumerate() {
            out[j] = v[i];
        }
        out
    }

    /// The 3-D pose of a planar one, in the rod's base frame.
    fn embed(&self, g: &Pose2) -> Pose {
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

/// An element of SE(2): rotation by the angle with cosine `c`, sine `s`
/// about the bending axis, translation `p` in the plane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pose2 {
    c: f64,
    s: f64,
    p: V2,
}

/// `J u`, the quarter turn: `e_a × u` for `u` in the plane.
#[inline(always)]
fn perp(u: &V2) -> V2 {
    V2::new(-u[1], u[0])
}

/// `(αI + βJ) u`.
#[inline(always)]
fn rot_like(alpha: f64, beta: f64, u: &V2) -> V2 {
    V2::new(alpha * u[0] - beta * u[1], beta * u[0] + alpha * u[1])
}

/// The scalar (out-of-plane) cross product `u × w · e_a`.
#[inline(always)]
fn cross2(u: &V2, w: &V2) -> f64 {
    u[0] * w[1] - u[1] * w[0]
}

#[inline(always)]
fn lin(v: &Vec3) -> V2 {
    V2::new(v[1], v[2])
}

#[inline(always)]
fn join(w: f64, v: V2) -> Vec3 {
    Vec3::new(w, v[0], v[1])
}

impl Pose2 {
    const IDENTITY: Self = Self {
        c: 1.0,
        s: 0.0,
        p: V2::new(0.0, 0.0),
    };

    #[inline(always)]
    fn rot(&self, u: &V2) -> V2 {
        rot_like(self.c, self.s, u)
    }

    #[inline(always)]
    fn rot_tr(&self, u: &V2) -> V2 {
        rot_like(self.c, -self.s, u)
    }

    #[inline(always)]
    fn compose(&self, o: &Self) -> Self {
        Self {
            c: self.c * o.c - self.s * o.s,
            s: self.s * o.c + self.c * o.s,
            p: self.p + self.rot(&o.p),
        }
    }

    /// `Ad⁻¹_g η = (ω, Rᵀ(v + ω J p))`, the planar block of (D4).
    #[inline(always)]
    fn ad_inv_vec(&self, eta: &Vec3) -> Vec3 {
        let w = eta[0];
        join(w, self.rot_tr(&(lin(eta) + perp(&self.p) * w)))
    }

    /// `Ad⁻ᵀ_g 𝓕 = (M + p × RF, RF)`: a wrench carried from the frame `g`
    /// to its reference.
    #[inline(always)]
    fn ad_inv_tr_vec(&self, f: &Vec3) -> Vec3 {
        let rf = self.rot(&lin(f));
        join(f[0] + cross2(&self.p, &rf), rf)
    }

    /// `Ad⁻¹_g` as a matrix: `[[1, 0], [RᵀJp, Rᵀ]]`.
    #[inline(always)]
    fn ad_inv(&self) -> Mat3 {
        let h = self.rot_tr(&perp(&self.p));
        Mat3::new(1.0, 0.0, 0.0, h[0], self.c, self.s, h[1], -self.s, self.c)
    }
}

/// `ad_a b` in `P`: `(0, ω_a J v_b − ω_b J v_a)`.
#[inline(always)]
fn ad2(a: &Vec3, b: &Vec3) -> Vec3 {
    join(0.0, perp(&lin(b)) * a[0] - perp(&lin(a)) * b[0])
}

/// `ad*_η 𝓕 = (v × F, ω J F)` in `P` (the moment of the planar force and
/// its rotation with the section).
#[inline(always)]
fn coad2(eta: &Vec3, f: &Vec3) -> Vec3 {
    let fl = lin(f);
    join(cross2(&lin(eta), &fl), perp(&fl) * eta[0])
}

/// Horner in `u`.
#[inline(always)]
fn horner(c: &[f64], u: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &k| acc * u + k)
}

// Taylor coefficients in u = θ² (D73): a = sinθ/θ, c = (1 − cosθ)/θ²,
// d/θ = (θ − sinθ)/θ³, a'/θ, c'/θ, d'. Ten terms leave < 1e-17 at |θ| = 1.
const SA: [f64; 10] = [
    1.0,
    -0.16666666666666666,
    0.008333333333333333,
    -0.0001984126984126984,
    2.7557319223985893e-06,
    -2.505210838544172e-08,
    1.6059043836821613e-10,
    -7.647163731819816e-13,
    2.8114572543455206e-15,
    -8.22063524662433e-18,
];
const SC: [f64; 10] = [
    0.5,
    -0.041666666666666664,
    0.001388888888888889,
    -2.48015873015873e-05,
    2.755731922398589e-07,
    -2.08767569878681e-09,
    1.1470745597729725e-11,
    -4.779477332387385e-14,
    1.5619206968586225e-16,
    -4.110317623312165e-19,
];
const SD: [f64; 10] = [
    0.16666666666666666,
    -0.008333333333333333,
    0.0001984126984126984,
    -2.7557319223985893e-06,
    2.505210838544172e-08,
    -1.6059043836821613e-10,
    7.647163731819816e-13,
    -2.8114572543455206e-15,
    8.22063524662433e-18,
    -1.9572941063391263e-20,
];
const SA1: [f64; 9] = [
    -0.3333333333333333,
    0.03333333333333333,
    -0.0011904761904761906,
    2.2045855379188714e-05,
    -2.505210838544172e-07,
    1.9270852604185937e-09,
    -1.0706029224547743e-11,
    4.498331606952833e-14,
    -1.4797143443923793e-16,
];
const SC1: [f64; 9] = [
    -0.08333333333333333,
    0.005555555555555556,
    -0.00014880952380952382,
    2.204585537918871e-06,
    -2.08767569878681e-08,
    1.376489471727567e-10,
    -6.691268265342339e-13,
    2.499073114973796e-15,
    -7.398571721961897e-18,
];
const SD1: [f64; 10] = [
    0.16666666666666666,
    -0.025,
    0.000992063492063492,
    -1.9290123456790123e-05,
    2.2546897546897547e-07,
    -1.7664948220503776e-09,
    9.941312851365761e-12,
    -4.217185881518281e-14,
    1.3975079919261362e-16,
    -3.7188588020443397e-19,
];

/// The functions of `θ` in the planar exponential, tangent and its
/// derivative (D72–D73), with their `θ`-derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Coeffs {
    pub cos: f64,
    pub sin: f64,
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub d: f64,
    pub da: f64,
    pub db: f64,
    pub dc: f64,
    pub dd: f64,
}

impl Coeffs {
    /// Series for `|θ| < 1` (the closed forms lose up to `1e-16/θ⁴` to
    /// cancellation in `c'`), closed forms beyond.
    #[inline(always)]
    pub(crate) fn new(theta: f64) -> Self {
        let u = theta * theta;
        if u < 1.0 {
            let a = horner(&SA, u);
            let c = horner(&SC, u);
            let dc = theta * horner(&SC1, u);
            Self {
                cos: 1.0 - u * c,
                sin: theta * a,
                a,
                b: theta * c,
                c,
                d: theta * horner(&SD, u),
                da: theta * horner(&SA1, u),
                db: c + theta * dc,
                dc,
                dd: horner(&SD1, u),
            }
        } else {
            let (s, co) = theta.sin_cos();
            let (t2, t3) = (u, u * theta);
            let c = (1.0 - co) / t2;
            let dc = (theta * s - 2.0 * (1.0 - co)) / t3;
            Self {
                cos: co,
                sin: s,
                a: s / theta,
                b: theta * c,
                c,
                d: (theta - s) / t2,
                da: (theta * co - s) / t2,
                db: c + theta * dc,
                dc,
                dd: (2.0 * s - theta - theta * co) / t3,
            }
        }
    }
}

/// The planar piece maps at `x` for the strain `ξ = (ω, v)` and its rate
/// `ξ̇ = (ω̇, v̇)` (D72–D74): `g(x) = exp(xξ)`, `T₋(x)` and
/// `∂_ξ(T₋ξ̇)[ξ̇]`, the strain-rate part of the velocity bias.
#[inline(always)]
pub(crate) fn maps(xi: &Vec3, dxi: &Vec3, x: f64, with_bias: bool) -> (Pose2, Mat3, Vec3) {
    let w = xi[0];
    let v = lin(xi);
    let k = Coeffs::new(w * x);
    let g = Pose2 {
        c: k.cos,
        s: k.sin,
        p: rot_like(k.a, k.b, &v) * x,
    };
    let x2 = x * x;
    let col = rot_like(k.d, k.c, &v) * x2;
    let (xa, xb) = (x * k.a, x * k.b);
    let t = Mat3::new(x, 0.0, 0.0, col[0], xa, xb, col[1], -xb, xa);
    let bias = if with_bias {
        let wd = dxi[0];
        let vd = lin(dxi);
        join(
            0.0,
            rot_like(k.dd, k.dc, &v) * (x2 * x * wd * wd)
                + rot_like(k.d + k.da, k.c - k.db, &vd) * (x2 * wd),
        )
    } else {
        Vec3::zeros()
    };
    (g, t, bias)
}

/// Per-piece work of the planar path (the 3×3 counterparts of
/// `PieceWork`'s forward-dynamics fields).
#[derive(Clone, Debug)]
pub(crate) struct PlanarWork {
    tip: Pose2,
    tm_tip: Mat3,
    acc_tip: Vec3,
    p_big: Vec3,
    p_small: Vec3,
    /// `𝓤ᶠ = ∫Aᵀ𝓜T₋` (3×3), then `W = ÛL⁻ᵀ` in its first `k` columns.
    ut: Mat3,
    /// `𝓓ᶠ = ∫T₋ᵀ𝓜T₋` (3×3), then the factor `L` of `D̂` (k×k).
    dt: Mat3,
    mt: Mat3,
    u: Vec3,
}

impl PlanarWork {
    pub(crate) fn new() -> Self {
        Self {
            tip: Pose2::IDENTITY,
            tm_tip: Mat3::zeros(),
            acc_tip: Vec3::zeros(),
            p_big: Vec3::zeros(),
            p_small: Vec3::zeros(),
            ut: Mat3::zeros(),
            dt: Mat3::zeros(),
            mt: Mat3::zeros(),
            u: Vec3::zeros(),
        }
    }
}

/// `diag(d) M`.
#[inline(always)]
fn scale_rows(d: &Vec3, m: &Mat3) -> Mat3 {
    Mat3::from_fn(|i, j| d[i] * m[(i, j)])
}

/// The outward sweep of the planar rod `r` (D7–D10 in `P`). For the
/// forward dynamics (`inverse = false`): the per-piece integrals
/// `𝓤ᶠ, 𝓓ᶠ, 𝓜ᵗ` and bias sums of pass 1 (D20, D23). For the inverse
/// dynamics: the wrench sums of (D17) with `f = 𝓜η̇ + ad*_η𝓜η − 𝓕_ext`,
/// gravity as the base acceleration. Both: tip maps and accelerations,
/// the external terms as `forces` asks.
/// `q`, `qd` (`None`: at rest), `qdd` (`None`: zero): the model's full
/// vectors.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn outward(
    model: &Model,
    rm: &RodModel,
    pr: &PlanarRod,
    data: &mut Data,
    r: usize,
    q: &[f64],
    qd: Option<&[f64]>,
    qdd: Option<&[f64]>,
    inverse: bool,
    forces: Forces,
) {
    let scale = forces.load_scale;
    let only_gravity = forces.gravity_only;
    let rod = &rm.spec.rod;
    let base = rod.base();
    let range = rm.dofs();
    let qr = &q[range.clone()];
    let qdr = qd.map(|v| &v[range.clone()]);
    let qddr = qdd.map(|v| &v[range]);
    let has_ext =
        !only_gravity && (rm.spec.drag.is_some() || !rm.spec.distributed_loads.is_empty());
    let need_world = rm.needs_world_pose_at_points;
    let mut pose = Pose2::IDENTITY;
    let mut eta0 = Vec3::zeros();
    let mut etadot0 = if inverse {
        pr.gather(&gravity_base_acceleration(model, rm, scale))
    } else {
        Vec3::zeros()
    };
    let pieces = rod.pieces().iter().zip(&rm.pieces).zip(&pr.pieces);
    for (n, ((piece, pd), pp)) in pieces.enumerate() {
        let w = &mut data.planar[r][n];
        let xi = pr.gather(&piece.strain(qr));
        let dxi = qdr.map_or(Vec3::zeros(), |v| pr.gather(&piece.strain_rate(v)));
        let ddxi = qddr.map_or(Vec3::zeros(), |v| pr.gather(&piece.strain_rate(v)));
        // At rest (ξ̇ = 0, η(0) = 0) every velocity and bias term vanishes.
        let has_vel = dxi != Vec3::zeros() || eta0 != Vec3::zeros();
        let (mut p_big, mut p_small) = (Vec3::zeros(), Vec3::zeros());
        let (mut uf, mut df, mut mt) = (Mat3::zeros(), Mat3::zeros(), Mat3::zeros());
        for (qp, m) in pd.points.iter().zip(&pp.inertia) {
            let (gl, tm, dbias) = maps(&xi, &dxi, qp.x, has_vel);
            let carried = gl.ad_inv_vec(&eta0);
            let sv = tm * dxi;
            let eta = carried + sv;
            let bias = if has_vel {
                ad2(&carried, &sv) + dbias
            } else {
                Vec3::zeros()
            };
            let mut f = coad2(&eta, &m.component_mul(&eta));
            if inverse {
                let etadot = gl.ad_inv_vec(&etadot0) + tm * ddxi + bias;
                f += m.component_mul(&etadot);
            } else if has_vel {
                f += m.component_mul(&bias);
            }
            if has_ext {
                let world = if need_world {
                    base.compose(&pr.embed(&pose.compose(&gl)))
                } else {
                    Pose::identity()
                };
                f -= pr.gather(&external_density(rm, scale, &world, &pr.scatter(&eta)));
            }
            let fw = f * qp.w;
            p_big += gl.ad_inv_tr_vec(&fw);
            p_small += tm.tr_mul(&fw);
            if !inverse {
                let mw = m * qp.w;
                let a = gl.ad_inv();
                uf += a.tr_mul(&scale_rows(&mw, &tm));
                df += tm.tr_mul(&scale_rows(&mw, &tm));
                mt += a.tr_mul(&scale_rows(&mw, &a));
            }
        }
        if !only_gravity {
            for pl in &pd.loads {
                let load = &rm.spec.point_loads[pl.index];
                let (gl, tm, _) = maps(&xi, &dxi, pl.x, false);
                let world = base.compose(&pr.embed(&pose.compose(&gl)));
                let f = pr.gather(&(load.wrench(&world) * scale));
                p_big -= gl.ad_inv_tr_vec(&f);
                p_small -= tm.tr_mul(&f);
            }
        }
        let (gl, tm, dbias) = maps(&xi, &dxi, piece.length, has_vel);
        let carried = gl.ad_inv_vec(&eta0);
        let sv = tm * dxi;
        let acc = if has_vel {
            ad2(&carried, &sv) + dbias
        } else {
            Vec3::zeros()
        };
        if inverse {
            etadot0 = gl.ad_inv_vec(&etadot0) + tm * ddxi + acc;
        }
        w.acc_tip = acc;
        w.tip = gl;
        w.tm_tip = tm;
        w.p_big = p_big;
        w.p_small = p_small;
        w.ut = uf;
        w.dt = df;
        w.mt = mt;
        eta0 = carried + sv;
        pose = pose.compose(&gl);
    }
}

/// The inward pass (D17–D18) of the planar rod `r` after an inverse
/// [`outward`]: `W_n = 𝓟_n + Ad⁻ᵀ W_{n+1}`,
/// `τ_n = Bᵀ(𝓹_n + T₋(ℓ)ᵀW_{n+1})` into `data.tau` (the strain-space forces
/// are subtracted by the caller).
#[inline(always)]
pub(crate) fn inward_inverse(rm: &RodModel, pr: &PlanarRod, data: &mut Data, r: usize) {
    let mut wv = Vec3::zeros();
    for (n, (piece, pp)) in rm
        .spec
        .rod
        .pieces()
        .iter()
        .zip(&pr.pieces)
        .enumerate()
        .rev()
    {
        let w = &data.planar[r][n];
        let v = w.p_small + w.tm_tip.tr_mul(&wv);
        let o = rm.dof_offset + piece.dof_offset;
        for i in 0..pp.k {
            data.tau[o + i] = v[pp.sel[i]];
        }
        wv = w.p_big + w.tip.ad_inv_tr_vec(&wv);
    }
}

/// In-place Cholesky of the leading `k×k` block; `false` if not positive
/// definite.
fn cholesky(m: &mut Mat3, k: usize) -> bool {
    for j in 0..k {
        let mut d = m[(j, j)];
        for p in 0..j {
            d -= m[(j, p)] * m[(j, p)];
        }
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        m[(j, j)] = d;
        for i in (j + 1)..k {
            let mut s = m[(i, j)];
            for p in 0..j {
                s -= m[(i, p)] * m[(j, p)];
            }
            m[(i, j)] = s / d;
        }
    }
    true
}

/// Forward dynamics of one planar rod (D75): pass 1 ([`outward`]), the
/// articulated inward pass (D24–D26) and the outward pass (D27) on 3×3
/// blocks. `data.strain_force` must hold the rod's strain-space forces.
/// Inlined into the forward dynamics' baseline and AVX2 copies.
#[inline(always)]
pub(crate) fn forward_rod(
    model: &Model,
    data: &mut Data,
    r: usize,
    q: &[f64],
    qd: &[f64],
    forces: Forces,
) -> Result<(), DynamicsError> {
    let rm = &model.rods()[r];
    let pr = rm.planar.as_ref().expect("planar rod");
    outward(model, rm, pr, data, r, q, Some(qd), None, false, forces);
    let pieces = &pr.pieces;
    let mut ma_next = Mat3::zeros();
    let mut pa_next = Vec3::zeros();
    for (n, pp) in pieces.iter().enumerate().rev() {
        let k = pp.k;
        let o = rm.dof_offset + rm.spec.rod.pieces()[n].dof_offset;
        let w = &mut data.planar[r][n];
        let leaf = n + 1 == pieces.len();
        let (carried, y) = if leaf {
            (Mat3::zeros(), pa_next)
        } else {
            let a = w.tip.ad_inv();
            let at_ma = a.tr_mul(&ma_next);
            let ma_t = ma_next * w.tm_tip;
            // Û = 𝓤 + A_ℓᵀ𝓜ᴬT₋(ℓ)B, D̂ = 𝓓 + BᵀT₋(ℓ)ᵀ𝓜ᴬT₋(ℓ)B (D24).
            w.ut += a.tr_mul(&ma_t);
            w.dt += w.tm_tip.tr_mul(&ma_t);
            (at_ma * a, ma_next * w.acc_tip + pa_next)
        };
        let sty = w.tm_tip.tr_mul(&y);
        let mut u = Vec3::zeros();
        let mut hat_u = Mat3::zeros();
        let mut hat_d = Mat3::zeros();
        for i in 0..k {
            let si = pp.sel[i];
            u[i] = data.strain_force[o + i] - w.p_small[si] - sty[si];
            hat_u.set_column(i, &w.ut.column(si));
            for j in 0..k {
                hat_d[(i, j)] = w.dt[(si, pp.sel[j])];
            }
        }
        if !cholesky(&mut hat_d, k) {
            return Err(DynamicsError::Singular {
                rod: r,
                piece: n,
                what: "articulated piece inertia D̂_n",
            });
        }
        // W = ÛL⁻ᵀ, ũ = L⁻¹u: ÛD̂⁻¹Ûᵀ = WWᵀ, ÛD̂⁻¹u = Wũ.
        for i in 0..k {
            let mut col = hat_u.column(i).into_owned();
            let mut s = u[i];
            for p in 0..i {
                col -= hat_u.column(p) * hat_d[(i, p)];
                s -= hat_d[(i, p)] * u[p];
            }
            let inv = 1.0 / hat_d[(i, i)];
            hat_u.set_column(i, &(col * inv));
            u[i] = s * inv;
        }
        ma_next = w.mt + carried - hat_u * hat_u.transpose();
        pa_next = w.p_big + w.tip.ad_inv_tr_vec(&y) + hat_u * u;
        w.ut = hat_u;
        w.dt = hat_d;
        w.u = u;
    }
    let mut etadot = pr.gather(&gravity_base_acceleration(model, rm, forces.load_scale));
    for (n, pp) in pieces.iter().enumerate() {
        let k = pp.k;
        let o = rm.dof_offset + rm.spec.rod.pieces()[n].dof_offset;
        let w = &data.planar[r][n];
        let mut qn = w.u - w.ut.tr_mul(&etadot);
        for i in (0..k).rev() {
            let mut s = qn[i];
            for p in (i + 1)..k {
                s -= w.dt[(p, i)] * qn[p];
            }
            qn[i] = s / w.dt[(i, i)];
        }
        let mut bq = Vec3::zeros();
        for i in 0..k {
            bq[pp.sel[i]] = qn[i];
            data.qdd[o + i] = qn[i];
        }
        etadot = w.tip.ad_inv_vec(&etadot) + w.tm_tip * bq + w.acc_tip;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// The coefficients against their definitions, on both sides of the
    /// switch and where the closed forms are well conditioned.
    #[test]
    fn coefficients_match_definitions() {
        for &t in &[1e-9, 0.3, 0.999_999, 1.000_001, 2.5, -4.0, 40.0] {
            let k = Coeffs::new(t);
            let (s, c) = (t.sin(), t.cos());
            let tol = 1e-14;
            assert_relative_eq!(k.cos, c, epsilon = tol);
            assert_relative_eq!(k.sin, s, epsilon = tol);
            assert_relative_eq!(k.a, s / t, epsilon = tol);
            if t.abs() > 0.1 {
                assert_relative_eq!(k.c, (1.0 - c) / (t * t), epsilon = 1e-12);
                assert_relative_eq!(k.d, (t - s) / (t * t), epsilon = 1e-12);
            }
            // Derivatives against central differences of the values.
            let h = 1e-5;
            let (kp, km) = (Coeffs::new(t + h), Coeffs::new(t - h));
            for (d, p, m) in [
                (k.da, kp.a, km.a),
                (k.db, kp.b, km.b),
                (k.dc, kp.c, km.c),
                (k.dd, kp.d, km.d),
            ] {
                assert_relative_eq!(d, (p - m) / (2.0 * h), epsilon = 1e-9);
            }
        }
    }
}
