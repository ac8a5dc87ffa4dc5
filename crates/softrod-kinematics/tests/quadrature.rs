//! Gauss–Legendre rules on [0, 1] against exact integrals.

use softrod_kinematics::GaussLegendre;

#[test]
fn rules_up_to_20_integrate_polynomials_exactly() {
    let mut worst = 0.0f64;
    for n in 1..=20 {
        let g = GaussLegendre::new(n);
        assert_eq!(g.len(), n);
        assert!(!g.is_empty());
        assert!(
            g.nodes.windows(2).all(|w| w[0] < w[1]),
            "n = {n}: nodes ascending"
        );
        assert!(g.nodes.iter().all(|x| *x > 0.0 && *x < 1.0));
        assert!(g.weights.iter().all(|w| *w > 0.0));
        // Symmetric about 1/2.
        for i in 0..n {
            assert!((g.nodes[i] + g.nodes[n - 1 - i] - 1.0).abs() < 1e-15);
            assert!((g.weights[i] - g.weights[n - 1 - i]).abs() < 1e-15);
        }
        // Monomials up to degree 2n − 1: ∫₀¹ x^d = 1/(d + 1). Also the
        // shifted monomials (x − 1/2)^d, whose odd moments vanish.
        for d in 0..2 * n {
            let num: f64 = g.on_interval(1.0).map(|(x, w)| w * x.powi(d as i32)).sum();
            let e = (num - 1.0 / (d as f64 + 1.0)).abs() * (d as f64 + 1.0);
            assert!(e < 5e-15, "n = {n}, degree {d}: rel error {e:.3e}");
            worst = worst.max(e);
            let num: f64 = g
                .on_interval(1.0)
                .map(|(x, w)| w * (x - 0.5).powi(d as i32))
                .sum();
            let exact = if d % 2 == 1 {
                0.0
            } else {
                0.5f64.powi(d as i32) / (d as f64 + 1.0)
            };
            assert!((num - exact).abs() < 5e-16, "n = {n}, shifted degree {d}");
        }
        // Not exact beyond: for f = (x − 1/2)^{2n} the n-point rule on [0, 1]
        // misses by exactly f^{(2n)}·(n!)⁴/((2n+1)((2n)!)³) = (n!)⁴/((2n+1)((2n)!)²).
        let num: f64 = g
            .on_interval(1.0)
            .map(|(x, w)| w * (x - 0.5).powi(2 * n as i32))
            .sum();
        let exact = 0.5f64.powi(2 * n as i32) / (2.0 * n as f64 + 1.0);
        let fact = |k: usize| (1..=k).map(|i| i as f64).product::<f64>();
        let remainder = fact(n).powi(4) / ((2.0 * n as f64 + 1.0) * fact(2 * n).powi(2));
        let got = exact - num;
        assert!(
            (got - remainder).abs() < 1e-2 * remainder,
            "n = {n}: degree-2n remainder {got:.6e}, theory {remainder:.6e}"
        );
    }
    println!("Gauss–Legendre monomials: worst rel error {worst:.3e}");
}

#[test]
fn cosine_on_unit_interval() {
    let exact = 1f64.sin();
    for n in 1..=20 {
        let g = GaussLegendre::new(n);
        let num: f64 = g.on_interval(1.0).map(|(x, w)| w * x.cos()).sum();
        let e = (num - exact).abs();
        if n >= 8 {
            assert!(e < 1e-15, "n = {n}: {e:.3e}");
        }
        if n == 1 {
            assert!(e > 1e-3);
        }
    }
}

#[test]
fn on_interval_scales_nodes_and_weights() {
    let g = GaussLegendre::new(5);
    let l = 0.37;
    let pts: Vec<(f64, f64)> = g.on_interval(l).collect();
    let total: f64 = pts.iter().map(|p| p.1).sum();
    assert!((total - l).abs() < 1e-16);
    // ∫₀^ℓ x³ dx = ℓ⁴/4.
    let num: f64 = pts.iter().map(|(x, w)| w * x.powi(3)).sum();
    assert!((num - l.powi(4) / 4.0).abs() < 1e-17);
    // Known 3-point rule: nodes 1/2 ∓ √(3/5)/2, weights 5/18, 8/18, 5/18.
    let g3 = GaussLegendre::new(3);
    let r = 0.5 * 0.6f64.sqrt();
    for (a, b) in g3.nodes.iter().zip([0.5 - r, 0.5, 0.5 + r]) {
        assert!((a - b).abs() < 2e-16);
    }
    for (a, b) in g3.weights.iter().zip([5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0]) {
        assert!((a - b).abs() < 2e-16);
    }
}
