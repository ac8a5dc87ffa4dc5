//! Cables (tendons) routed through the cross-section (D15).
//!
//! A cable runs inside the rod over `s ∈ [from, to]` at the section offset
//! `d(s) = (0, y(s), z(s))` (body frame) and is anchored at `to`. Its length is
//! `ℓ_c(q) = ∫_from^to |q + k × d + d′| ds` (the body-frame tangent of the
//! cable's path is `v = q + k × d + d′`, `t̂ = v/|v|`), and with tension `T ≥ 0`
//! its generalized force is `τ_c = −T ∂ℓ_c/∂q`,
//! `τ_c,n = −T ∫_{piece n ∩ [from, to]} B_nᵀ (d × t̂; t̂) ds` (D15).

use crate::error::{MechanicsError, Quantity, finite, non_negative};
use softrod_kinematics::{GaussLegendre, Piece, RodGeometry};
use softrod_lie::{Vec3, Vec6, Wrench, angular, join, linear};

/// Path of a cable in the cross-section, as a function of the abscissa `s`.
#[derive(Clone, Debug, PartialEq)]
pub enum Routing {
    /// Constant offset `d = (0, y, z)` \[m\] over the span (`d′ = 0`).
    Offset {
        /// Offset along local y \[m\].
        y: f64,
        /// Offset along local z \[m\].
        z: f64,
    },
    /// Piecewise-linear offset through the points `(s, y, z)` \[m\]: at least
    /// two, `s` strictly increasing within the rod, covering the cable's span.
    Path(Vec<[f64; 3]>),
}

impl Routing {
    /// Offset `d(s) = (0, y(s), z(s))` \[m\] and its derivative `d′(s)` (body
    /// frame). A path is linear between its points; at a point the
    /// derivative of the segment to the right is returned; beyond the ends
    /// `d` is held and `d′ = 0`.
    #[inline]
    pub fn offset(&self, s: f64) -> (Vec3, Vec3) {
        match self {
            Routing::Offset { y, z } => (Vec3::new(0.0, *y, *z), Vec3::zeros()),
            Routing::Path(pts) => path_offset(pts, s),
        }
    }

    /// Largest `|d(s)|` over the routing \[m\].
    pub fn max_offset(&self) -> f64 {
        match self {
            Routing::Offset { y, z } => y.hypot(*z),
            Routing::Path(pts) => pts.iter().map(|p| p[1].hypot(p[2])).fold(0.0, f64::max),
        }
    }

    /// The points of a path (none for a constant offset): where `d′` jumps.
    fn points(&self) -> &[[f64; 3]] {
        match self {
            Routing::Offset { .. } => &[],
            Routing::Path(pts) => pts,
        }
    }
}

/// Cable tension `T(t)` \[N\] as a function of time.
#[derive(Clone, Debug, PartialEq)]
pub enum Tension {
    /// Constant tension `T ≥ 0` \[N\].
    Constant(f64),
    /// Piecewise-linear in time through `(times[i], values[i])` [s, N],
    /// times strictly increasing, values `≥ 0`; held constant beyond the ends.
    Table {
        /// Times \[s\], strictly increasing.
        times: Vec<f64>,
        /// Tensions \[N\], `≥ 0`.
        values: Vec<f64>,
    },
}

impl Tension {
    /// `T(t)` \[N\]: the constant, or linear interpolation in the table,
    /// held at the first/last value outside it.
    #[inline]
    pub fn at(&self, t: f64) -> f64 {
        match self {
            Tension::Constant(v) => *v,
            Tension::Table { times, values } => interpolate(times, values, t),
        }
    }

    /// The times where `T(t)` has a kink (a table's times; none for a
    /// constant) \[s\]: steps should end there, not cross them.
    pub fn breakpoints(&self) -> &[f64] {
        match self {
            Tension::Constant(_) => &[],
            Tension::Table { times, .. } => times,
        }
    }

    /// Largest tension over all time \[N\].
    pub fn max(&self) -> f64 {
        match self {
            Tension::Constant(v) => *v,
            Tension::Table { values, .. } => values.iter().copied().fold(0.0, f64::max),
        }
    }

    fn validate(&self) -> Result<(), MechanicsError> {
        match self {
            Tension::Constant(t) => non_negative(Quantity::Tension, *t),
            Tension::Table { times, values } => {
                if times.is_empty() {
                    return Err(MechanicsError::Empty {
                        quantity: Quantity::TensionTimes,
                    });
                }
                if values.len() != times.len() {
                    return Err(MechanicsError::SizeMismatch {
                        quantity: Quantity::TensionValues,
                        got: values.len(),
                        expected: times.len(),
                    });
                }
                for (i, (&t, &v)) in times.iter().zip(values).enumerate() {
                    finite(Quantity::TensionTime(i), t)?;
                    non_negative(Quantity::TensionValue(i), v)?;
                    if i > 0 && t <= times[i - 1] {
                        return Err(MechanicsError::NotIncreasing {
                            quantity: Quantity::TensionTimes,
                            index: i,
                            value: t,
                            previous: times[i - 1],
                        });
                    }
                }
                Ok(())
            }
        }
    }
}

/// Where along the rod a cable runs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Span {
    /// The whole rod, `[0, L]`, anchored at the tip.
    #[default]
    Whole,
    /// `[from, to]` \[m\], `0 ≤ from < to ≤ L`, anchored at `to`.
    Between {
        /// Where the cable enters the rod \[m\].
        from: f64,
        /// The anchor \[m\].
        to: f64,
    },
}

/// A cable: routing, span (anchored at its end), tension and friction along
/// its sheath.
///
/// ```
/// use softrod_mechanics::{Cable, Routing, Tension};
///
/// // 8 mm off the centreline along local z, 2 N, over the whole rod.
/// let c = Cable::new(Routing::Offset { y: 0.0, z: 0.008 }, Tension::Constant(2.0));
/// assert_eq!(c.bounds(0.5), (0.0, 0.5));
/// assert!(c.validate(0.5).is_ok());
/// // Over the distal half only.
/// let distal = c.clone().between(0.25, 0.5);
/// assert_eq!(distal.bounds(0.5), (0.25, 0.5));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Cable {
    /// Offset of the cable in the section along `s`.
    pub routing: Routing,
    /// Tension schedule.
    pub tension: Tension,
    /// Where along the rod it runs.
    pub span: Span,
    /// Coulomb coefficient `μ ≥ 0` between the cable and its channel (0:
    /// frictionless). The cable is taken as being pulled (sliding toward
    /// the actuated end, `from`): its tension decays along the span as
    /// `T(s) = T e^{−μ φ(s)}`, `φ(s)` the angle the cable's path has turned
    /// through from `from` to `s` (the capstan equation; docs/theory.md D15f).
    pub friction: f64,
}

impl Cable {
    /// A cable over the whole rod.
    pub fn new(routing: Routing, tension: Tension) -> Self {
        Self {
            routing,
            tension,
            span: Span::Whole,
            friction: 0.0,
        }
    }

    /// The same cable with friction coefficient `mu` along its channel
    /// ([`Cable::friction`]).
    #[must_use]
    pub fn with_friction(mut self, mu: f64) -> Self {
        self.friction = mu;
        self
    }

    /// The same cable over `[from, to]` \[m\] only (anchored at `to`).
    #[must_use]
    pub fn between(mut self, from: f64, to: f64) -> Self {
        self.span = Span::Between { from, to };
        self
    }

    /// The span `(from, to)` \[m\] on a rod of length `rod_length`.
    #[inline]
    pub fn bounds(&self, rod_length: f64) -> (f64, f64) {
        match self.span {
            Span::Whole => (0.0, rod_length),
            Span::Between { from, to } => (from, to),
        }
    }

    /// Checks, on a rod of length `rod_length` (abscissae to 1e-12·L): the
    /// span `0 ≤ from < to ≤ L`; a finite routing, a path of at least two
    /// points with strictly increasing `s` in `[0, L]` covering the span;
    /// strictly increasing tension times and non-negative tensions.
    pub fn validate(&self, rod_length: f64) -> Result<(), MechanicsError> {
        let tol = 1e-12 * rod_length;
        let (from, to) = self.bounds(rod_length);
        if !(from.is_finite() && from >= -tol && from < rod_length) {
            return Err(MechanicsError::CableFrom {
                from,
                length: rod_length,
            });
        }
        if !(to.is_finite() && to > from && to <= rod_length + tol) {
            return Err(MechanicsError::CableTo {
                from,
                to,
                length: rod_length,
            });
        }
        match &self.routing {
            Routing::Offset { y, z } => {
                finite(Quantity::OffsetY, *y)?;
                finite(Quantity::OffsetZ, *z)?;
            }
            Routing::Path(pts) => validate_path(pts, rod_length, from, to)?,
        }
        non_negative(Quantity::CableFriction, self.friction)?;
        self.tension.validate()
    }

    /// Tension `T(t) ≥ 0` \[N\] ([`Tension::at`]); negative inputs (only
    /// possible without [`Self::validate`]) are clamped to 0.
    #[inline]
    pub fn tension_at(&self, t: f64) -> f64 {
        self.tension.at(t).max(0.0)
    }

    /// Offset `d(s)` and `d′(s)` \[m\] ([`Routing::offset`]).
    #[inline]
    pub fn offset(&self, s: f64) -> (Vec3, Vec3) {
        self.routing.offset(s)
    }

    /// Largest `|d(s)|` over the routing \[m\] ([`Routing::max_offset`]).
    pub fn max_offset(&self) -> f64 {
        self.routing.max_offset()
    }

    /// The cable's body wrench per unit tension at `s` for the strain
    /// `ξ = (k, q)` of the piece containing `s` (the `𝓦/T` of D15):
    /// `(d × t̂; t̂)`, `t̂ = v/|v|`, `v = q + k × d + d′` [m; 1].
    /// Returns zero in the degenerate case `v = 0` (cable of zero length).
    #[inline]
    pub fn wrench_per_tension(&self, xi: &Vec6, s: f64) -> Wrench {
        let (d, dp) = self.offset(s);
        let v = linear(xi) + angular(xi).cross(&d) + dp;
        let n = v.norm();
        if n == 0.0 {
            return Wrench::zeros();
        }
        let t = v / n;
        join(&d.cross(&t), &t)
    }

    /// Cable length `ℓ_c = ∫_from^to |q + k × d + d′| ds` \[m\] at coordinates `q`,
    /// with the Gauss rule on each sub-interval of `piece ∩ [from, to]` split
    /// at the routing knots.
    pub fn length(&self, rod: &RodGeometry, q: &[f64], quadrature: &GaussLegendre) -> f64 {
        let mut total = 0.0;
        for p in rod.pieces() {
            let xi = p.strain(q);
            let (k, qv) = (angular(&xi), linear(&xi));
            self.for_each_node(p, quadrature, |s, w| {
                let (d, dp) = self.offset(s);
                total += w * (qv + k.cross(&d) + dp).norm();
            });
        }
        total
    }

    /// Adds `−∂ℓ_c/∂q` (the generalized force per unit tension, D15) into `out`
    /// (length n_dof): `out_n −= ∫_{piece n ∩ [from,to]} B_nᵀ (d × t̂; t̂) ds`.
    /// Integrates `piece ∩ [from,to]` split at the routing's knots with the
    /// given Gauss rule on each sub-interval. Allocation-free. Multiply by
    /// [`Self::tension_at`] for the force [N·m or N per coordinate unit].
    pub fn add_force_per_tension(
        &self,
        rod: &RodGeometry,
        q: &[f64],
        quadrature: &GaussLegendre,
        out: &mut [f64],
    ) {
        // A constant offset without friction: `d′ = 0` and `d` constant, so
        // on a piece (constant strain) the integrand `(d × t̂; t̂)` is
        // constant and the integral is the overlap's length times its value
        // — the Gauss rule's sum up to rounding, at one evaluation instead of
        // one per node (this force is in every right-hand side of a cable
        // model).
        let constant = self.is_constant_per_piece();
        for (n, p) in rod.pieces().iter().enumerate() {
            let xi = p.strain(q);
            let mut acc = Wrench::zeros();
            if constant {
                acc = self.constant_piece_wrench(p, &xi);
            } else {
                self.for_each_weighted_node(rod, q, n, quadrature, |s, w| {
                    acc += self.wrench_per_tension(&xi, s) * w;
                });
            }
            if acc == Wrench::zeros() {
                continue;
            }
            let r = p.dofs();
            for (c, o) in out[r].iter_mut().enumerate() {
                *o -= p.basis.column(c).dot(&acc);
            }
        }
    }

    /// Whether the integrand `(d × t̂; t̂)` of the force per unit tension is
    /// constant on each piece (constant strain): a constant offset (`d′ = 0`,
    /// `d` constant) without friction. Then [`Self::constant_piece_wrench`]
    /// is the piece's integral.
    #[inline]
    pub fn is_constant_per_piece(&self) -> bool {
        self.friction == 0.0 && matches!(self.routing, Routing::Offset { .. })
    }

    /// `∫_{piece ∩ [from,to]} (d × t̂; t̂) ds` at the piece's strain `xi`
    /// for a cable whose integrand is constant on the piece
    /// ([`Self::is_constant_per_piece`]): the overlap's length times the
    /// integrand (\[m²; m\] per unit tension; zero without overlap). Its
    /// projection `−B_nᵀ(·)` is the piece's rows of
    /// [`Self::add_force_per_tension`].
    #[inline]
    pub fn constant_piece_wrench(&self, piece: &Piece, xi: &Vec6) -> Wrench {
        let mut length = 0.0;
        self.for_each_part(piece, |lo, hi| length += hi - lo);
        if length > 0.0 {
            self.wrench_per_tension(xi, piece.start) * length
        } else {
            Wrench::zeros()
        }
    }

    /// Calls `f(s, w e^{−μφ(s)})` for every quadrature node of piece `n` of
    /// `rod` at coordinates `q` ([`Cable::for_each_node`]): the weights of
    /// the cable's force with its tension decayed by friction (D15f). For a
    /// frictionless cable, exactly [`Cable::for_each_node`]; with friction
    /// it walks the cable from its entry (O(n)).
    pub fn for_each_weighted_node(
        &self,
        rod: &RodGeometry,
        q: &[f64],
        n: usize,
        quadrature: &GaussLegendre,
        mut f: impl FnMut(f64, f64),
    ) {
        let pieces = rod.pieces();
        if self.friction == 0.0 {
            self.for_each_node(&pieces[n], quadrature, f);
            return;
        }
        let mu = self.friction;
        let mut turn = Turning::default();
        for (m, p) in pieces.iter().enumerate().take(n + 1) {
            let xi = p.strain(q);
            self.walk_piece(p, &xi, quadrature, &mut turn, |s, w, phi| {
                if m == n {
                    f(s, w * (-mu * phi).exp());
                }
            });
        }
    }

    /// The angle the cable's path has turned through from its entry to its
    /// anchor at `q` \[rad\] (φ of D15f): `T(to) = T e^{−μφ}`.
    pub fn turning_angle(&self, rod: &RodGeometry, q: &[f64], quadrature: &GaussLegendre) -> f64 {
        let mut turn = Turning::default();
        for p in rod.pieces() {
            let xi = p.strain(q);
            self.walk_piece(p, &xi, quadrature, &mut turn, |_, _, _| {});
        }
        turn.phi
    }

    /// The nodes of `piece ∩ [from, to]` (as [`Cable::for_each_node`]) with
    /// the turning angle `φ` there, continuing `turn` from the pieces before.
    /// Within a sub-interval (a piece between routing knots) the path's
    /// body-frame tangent `t̂ = v/|v|`, `v = q + k × d + d′`, turns at the rate
    /// `ρ = |k × t̂ + (I − t̂t̂ᵀ)(k × d′)/|v||` (the world tangent is `R t̂`),
    /// taken at its Gauss mean over the sub-interval (exact for a constant
    /// offset, where `ρ` is constant); where `t̂` jumps (a piece boundary or
    /// a knot of the path) φ grows by the angle of the jump.
    fn walk_piece(
        &self,
        piece: &Piece,
        xi: &Vec6,
        quadrature: &GaussLegendre,
        turn: &mut Turning,
        mut f: impl FnMut(f64, f64, f64),
    ) {
        let (k, qv) = (angular(xi), linear(xi));
        self.for_each_part(piece, |lo, hi| {
            let (d0, dp) = self.offset(lo);
            let tangent = |d: Vec3| {
                let v = qv + k.cross(&d) + dp;
                let n = v.norm();
                (n > 0.0).then(|| (v / n, n))
            };
            if let (Some(prev), Some((t0, _))) = (turn.tangent, tangent(d0)) {
                turn.phi += prev.cross(&t0).norm().atan2(prev.dot(&t0));
            }
            let kd = k.cross(&dp);
            let (mut mean, mut len) = (0.0, 0.0);
            for (x, w) in quadrature.on_interval(hi - lo) {
                if let Some((t, n)) = tangent(d0 + dp * x) {
                    let tp = (kd - t * t.dot(&kd)) / n;
                    mean += w * (k.cross(&t) + tp).norm();
                }
                len += w;
            }
            let rate = if len > 0.0 { mean / len } else { 0.0 };
            for (x, w) in quadrature.on_interval(hi - lo) {
                f(lo + x, w, turn.phi + rate * x);
            }
            turn.phi += rate * (hi - lo);
            turn.tangent = tangent(d0 + dp * (hi - lo)).map(|(t, _)| t);
        });
    }

    /// Calls `f(s, w)` for every quadrature node of `piece ∩ [from, to]`, the
    /// overlap split at the routing knots, the Gauss rule on each part: the
    /// nodes [`Cable::add_force_per_tension`] integrates on (so that a
    /// derivative of the discrete force can use the same ones).
    pub fn for_each_node(
        &self,
        piece: &Piece,
        quadrature: &GaussLegendre,
        mut f: impl FnMut(f64, f64),
    ) {
        self.for_each_part(piece, |lo, hi| {
            for (x, w) in quadrature.on_interval(hi - lo) {
                f(lo + x, w);
            }
        });
    }

    /// Calls `part(lo, hi)` for each sub-interval of `piece ∩ [from, to]`
    /// between the routing's knots, in order (none if they do not overlap).
    fn for_each_part(&self, piece: &Piece, mut part: impl FnMut(f64, f64)) {
        let (a, b) = match self.span {
            Span::Whole => (piece.start, piece.end()),
            Span::Between { from, to } => (piece.start.max(from), piece.end().min(to)),
        };
        if b <= a {
            return;
        }
        let mut lo = a;
        for knot in self
            .routing
            .points()
            .iter()
            .map(|p| p[0])
            .filter(|&k| k > a && k < b)
        {
            part(lo, knot);
            lo = knot;
        }
        part(lo, b);
    }
}

/// Where a walk along a cable has got to: the angle turned so far and the
/// tangent at the end of the last sub-interval.
#[derive(Default)]
struct Turning {
    phi: f64,
    tangent: Option<Vec3>,
}

fn validate_path(pts: &[[f64; 3]], length: f64, from: f64, to: f64) -> Result<(), MechanicsError> {
    if pts.len() < 2 {
        return Err(MechanicsError::PathTooShort { points: pts.len() });
    }
    let tol = 1e-12 * length;
    for (index, p) in pts.iter().enumerate() {
        for (component, &v) in p.iter().enumerate() {
            finite(Quantity::PathPoint { index, component }, v)?;
        }
        if !(p[0] >= -tol && p[0] <= length + tol) {
            return Err(MechanicsError::PathOutsideRod {
                index,
                s: p[0],
                length,
            });
        }
        if index > 0 && p[0] <= pts[index - 1][0] {
            return Err(MechanicsError::NotIncreasing {
                quantity: Quantity::Path,
                index,
                value: p[0],
                previous: pts[index - 1][0],
            });
        }
    }
    let (first, last) = (pts[0][0], pts[pts.len() - 1][0]);
    if first > from + tol || last < to - tol {
        return Err(MechanicsError::PathCoverage {
            first,
            last,
            from,
            to,
        });
    }
    Ok(())
}

fn interpolate(times: &[f64], values: &[f64], t: f64) -> f64 {
    let n = times.len();
    if n == 0 {
        return 0.0;
    }
    if t <= times[0] {
        return values[0];
    }
    if t >= times[n - 1] {
        return values[n - 1];
    }
    let i = times.partition_point(|&ti| ti <= t) - 1;
    let u = (t - times[i]) / (times[i + 1] - times[i]);
    values[i] + u * (values[i + 1] - values[i])
}

fn path_offset(pts: &[[f64; 3]], s: f64) -> (Vec3, Vec3) {
    let n = pts.len();
    let point = |p: &[f64; 3]| Vec3::new(0.0, p[1], p[2]);
    if n == 0 {
        return (Vec3::zeros(), Vec3::zeros());
    }
    if n == 1 || s < pts[0][0] {
        return (point(&pts[0]), Vec3::zeros());
    }
    if s >= pts[n - 1][0] {
        return (point(&pts[n - 1]), Vec3::zeros());
    }
    let i = pts.partition_point(|p| p[0] <= s) - 1;
    let (p0, p1) = (&pts[i], &pts[i + 1]);
    let h = p1[0] - p0[0];
    let slope = Vec3::new(0.0, (p1[1] - p0[1]) / h, (p1[2] - p0[2]) / h);
    (point(p0) + slope * (s - p0[0]), slope)
}
