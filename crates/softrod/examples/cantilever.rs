//! The released cantilever of docs/theory.md §8(h) from Rust: a soft rod,
//! clamped horizontal, released under gravity. Prints the tip at
//! t = 0.25, 0.5, 1 s beside the reference values (DOP853 at rtol 1e-12 of
//! the same model) and the difference, which is the error of the default
//! integrator settings.
//!
//! `cargo run --release -p softrod --example cantilever`

use softrod::prelude::*;

fn main() -> Result<(), softrod::Error> {
    let material = Material::builder()
        .density(1000.0)
        .young(1e7)
        .poisson(0.5)
        .build()?;
    let arm = Rod::builder(0.5)
        .name("arm")
        .pieces(8)
        .circle(0.01)
        .material(material)
        .strains([Strain::Ky, Strain::Qx, Strain::Qz]);
    let model = Model::builder()
        .rod(arm)
        .gravity([0.0, 0.0, -9.81])
        .quadrature(5)
        .build()?;
    let mut sim = Simulation::new(model);
    let traj = sim.simulate(1.0)?;

    // docs/theory.md §8(h): tip (x, z) in m.
    let reference = [
        (0.25, 0.366446853, -0.314312480),
        (0.5, 0.342225557, -0.338455217),
        (1.0, 0.391295819, -0.286765539),
    ];
    println!("   t [s]   x_tip [m]     reference     z_tip [m]     reference     distance [m]");
    for (t, x, z) in reference {
        let i = traj
            .t
            .iter()
            .position(|s| (s - t).abs() < 1e-12)
            .expect("an output time");
        let p = traj.tip_position(i, 0);
        let d = ((p[0] - x).powi(2) + (p[2] - z).powi(2)).sqrt();
        println!(
            "{t:8.2} {:13.9} {x:13.9} {:13.9} {z:13.9} {d:12.3e}",
            p[0], p[2]
        );
    }
    let s = traj.summary.stats;
    println!(
        "{} steps, {} evaluations of the dynamics",
        s.steps, s.rhs_evaluations
    );
    Ok(())
}
