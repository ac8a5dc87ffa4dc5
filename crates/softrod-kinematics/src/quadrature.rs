//! Gauss–Legendre quadrature on a piece.

/// Gauss–Legendre rule with `n` points on `[0, 1]`: `∫₀¹ f ≈ Σ w_i f(x_i)`,
/// exact for polynomials of degree `2n − 1`. Nodes ascending.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussLegendre {
    /// Nodes in `(0, 1)`, ascending.
    pub nodes: Vec<f64>,
    /// Weights, summing to 1.
    pub weights: Vec<f64>,
}

impl GaussLegendre {
    /// The `n`-point rule (`n ≥ 1`). Nodes are the roots of the Legendre
    /// polynomial `P_n`, found by Newton's method from Tricomi's initial
    /// guesses, to full double precision for any practical `n`.
    pub fn new(n: usize) -> Self {
        assert!(n >= 1, "a Gauss rule needs at least one point");
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        let nf = n as f64;
        for i in 0..n.div_ceil(2) {
            // i-th root of P_n on [−1, 1], descending from +1.
            let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, z);
                dp = d;
                let dz = p / d;
                z -= dz;
                if dz.abs() < 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre(n, z);
            if d != 0.0 {
                dp = d;
            }
            let w = 2.0 / ((1.0 - z * z) * dp * dp);
            // Map [−1, 1] → [0, 1]; symmetric pair.
            nodes[n - 1 - i] = 0.5 * (1.0 + z);
            nodes[i] = 0.5 * (1.0 - z);
            weights[n - 1 - i] = 0.5 * w;
            weights[i] = 0.5 * w;
        }
        Self { nodes, weights }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always false (a rule has at least one point).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// `(x_i, w_i)` scaled to `[0, ℓ]`: `∫₀^ℓ f dx ≈ Σ w_i f(x_i)`.
    pub fn on_interval(&self, length: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(move |(&x, &w)| (x * length, w * length))
    }
}

/// `(P_n(z), P_n′(z))` by the three-term recurrence.
fn legendre(n: usize, z: f64) -> (f64, f64) {
    let mut p0 = 1.0;
    let mut p1 = z;
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * z * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let nf = n as f64;
    (p1, nf * (z * p1 - p0) / (z * z - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly() {
        for n in 1..=12 {
            let g = GaussLegendre::new(n);
            for deg in 0..(2 * n) {
                let num: f64 = g
                    .nodes
                    .iter()
                    .zip(&g.weights)
                    .map(|(x, w)| w * x.powi(deg as i32))
                    .sum();
                let exact = 1.0 / (deg as f64 + 1.0);
                assert!((num - exact).abs() < 1e-14, "n = {n}, degree {deg}");
            }
            assert!(g.nodes.windows(2).all(|w| w[0] < w[1]));
        }
    }

    #[test]
    fn known_two_point_rule() {
        let g = GaussLegendre::new(2);
        let x = 0.5 - 0.5 / 3f64.sqrt();
        assert!((g.nodes[0] - x).abs() < 1e-16, "{} vs {x}", g.nodes[0]);
        assert!((g.weights[0] - 0.5).abs() < 4e-16); // a couple of ulps
    }
}
