//! Friction along a cable's channel (issue 24; docs/theory.md D15f): a
//! pulled cable's tension decays as `T e^{−μφ}` with the angle `φ` its path
//! has turned through (the capstan equation).
//!
//! Reference: a planar arm without gravity, one cable at offset `d` anchored
//! at the tip. A section at `s` carries the moment of the cable's tension
//! there, `EI κ(s) = T(s) d`, and the cable turns as the centreline does,
//! `φ′ = |κ|`; so `φ′ = κ₀ e^{−μφ}` with `κ₀ = T d/EI`, whose solution is
//! `φ(s) = ln(1 + μκ₀s)/μ` and `κ(s) = κ₀/(1 + μκ₀s)`. Without friction
//! the arc is uniform, `φ(L) = κ₀L`.

use softrod::Simulation;

/// Young's modulus, radius, length, offset, tension: κ₀L = 2 rad.
const E: f64 = 1.0e6;
const R: f64 = 0.01;
const L: f64 = 0.3;
const D: f64 = 0.008;

fn ei() -> f64 {
    E * std::f64::consts::PI * R.powi(4) / 4.0
}

fn tension() -> f64 {
    2.0 / L * ei() / D
}

/// The statics of the arm with `pieces` pieces and cable friction `mu`:
/// the curvature of each piece \[1/m\].
fn curvatures(pieces: usize, mu: f64) -> Vec<f64> {
    let scene = format!(
        "[world]\ngravity = [0.0, 0.0, 0.0]\n[[rod]]\nname = \"arm\"\nlength = {L}\n\
         pieces = {pieces}\nstrains = [\"ky\"]\n\
         section = {{ shape = \"circle\", radius = {R} }}\n\
         material = {{ density = 1000.0, young = {E}, poisson = 0.5 }}\n\
         [[cable]]\nrod = \"arm\"\noffset = [0.0, {D}]\ntension = {}\nfriction = {mu}\n\
         [run]\nmode = \"statics\"\n",
        tension()
    );
    let (mut sim, _, _) = Simulation::from_toml(&scene, "friction.toml").unwrap();
    let st = sim.statics().unwrap();
    assert!(st.residual.is_finite());
    st.q.iter().copied().collect()
}

#[test]
fn the_tension_decays_along_the_bend_as_the_capstan_equation_says() {
    let k0 = tension() * D / ei();
    let mu = 0.3;
    let exact = |s: f64| (1.0 + mu * k0 * s).ln() / mu;
    // Without friction: the uniform arc (the reference's μ → 0 limit).
    let free = curvatures(10, 0.0);
    for k in &free {
        assert!((k.abs() - k0).abs() < 1e-9 * k0, "{k} vs {k0}");
    }
    // With friction: the turning angle along the arm against φ(s).
    let mut errors = Vec::new();
    for n in [10, 20, 40] {
        let k = curvatures(n, mu);
        let h = L / n as f64;
        let mut phi = 0.0;
        let mut worst: f64 = 0.0;
        for (i, ki) in k.iter().enumerate() {
            phi += ki.abs() * h;
            let s = (i + 1) as f64 * h;
            worst = worst.max((phi - exact(s)).abs());
        }
        // The curvature decays toward the tip, as T(s) does.
        assert!(k.windows(2).all(|w| w[1].abs() < w[0].abs()), "{k:?}");
        errors.push(worst / exact(L));
    }
    // Second order in the piece length, and small already at 10 pieces.
    assert!(errors[0] < 3e-4, "{errors:?}");
    assert!(errors[1] < errors[0] / 3.0, "{errors:?}");
    assert!(errors[2] < errors[1] / 3.0, "{errors:?}");
}

/// Bad input names the key.
#[test]
fn a_negative_cable_friction_is_refused_by_key() {
    let scene = "[[rod]]\nname = \"arm\"\nlength = 0.3\npieces = 2\n\
                 section = { shape = \"circle\", radius = 0.01 }\n\
                 material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n\
                 [[cable]]\nrod = \"arm\"\noffset = [0.0, 0.008]\ntension = 1.0\nfriction = -0.1\n";
    let e = Simulation::from_toml(scene, "bad.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("cable[0].friction"), "{e}");
}
