//! Writes every figure kind from analytic demo data to the directory given
//! as the first argument (default `target/viz-plots`).
use softrod_viz::demo::SwingingRods;
use softrod_viz::plot::{
    self, ActuatorSeries, EnergySeries, Mode, ModeShapes, NamedSeries, RodCurve, ShapeSnapshot,
    StrainComponent, StrainProfiles,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "target/viz-plots".into());
    let dir = std::path::Path::new(&dir);
    std::fs::create_dir_all(dir)?;
    let view = SwingingRods {
        rods: 3,
        times: 201,
        ..SwingingRods::default()
    }
    .build();
    let tips: Vec<RodCurve> = view
        .rods
        .iter()
        .map(|r| RodCurve {
            name: r.name.clone(),
            points: r.frames.iter().map(|f| f[f.len() - 1].position).collect(),
        })
        .collect();
    plot::tip_trajectory("tip trajectory", &tips)?.write(&dir.join("tip_trajectory.svg"))?;
    let snaps = |rods: usize| -> Vec<ShapeSnapshot> {
        (0..6)
            .map(|k| {
                let i = k * 8;
                ShapeSnapshot {
                    t: Some(view.times[i]),
                    rods: view.rods[..rods]
                        .iter()
                        .map(|r| RodCurve {
                            name: r.name.clone(),
                            points: r.frames[i].iter().map(|p| p.position).collect(),
                        })
                        .collect(),
                    bodies: Vec::new(),
                }
            })
            .collect()
    };
    plot::shapes("rod shapes", &snaps(1))?.write(&dir.join("shapes_one.svg"))?;
    plot::shapes("rod shapes", &snaps(3))?.write(&dir.join("shapes_three.svg"))?;
    // A lightly damped oscillator: E_k + E_el exchange, gravity constant offset.
    let t: Vec<f64> = (0..400).map(|k| k as f64 * 0.005).collect();
    let amp: Vec<f64> = t.iter().map(|t| 2e-3 * (-0.3 * t).exp()).collect();
    let e = EnergySeries {
        t: t.clone(),
        kinetic: t
            .iter()
            .zip(&amp)
            .map(|(t, a)| a * (6.0 * t).sin().powi(2))
            .collect(),
        elastic: t
            .iter()
            .zip(&amp)
            .map(|(t, a)| a * (6.0 * t).cos().powi(2))
            .collect(),
        gravitational: t
            .iter()
            .map(|t| -1.0e-3 - 2e-4 * (1.0 - (-t).exp()))
            .collect(),
        extra: vec![],
    };
    plot::energy("energy", &e)?.write(&dir.join("energy.svg"))?;
    let a = ActuatorSeries {
        t: t.clone(),
        tensions: vec![
            NamedSeries {
                name: "cable 0".into(),
                values: t.iter().map(|t| 2.0 * t.min(0.5) / 0.5).collect(),
            },
            NamedSeries {
                name: "cable 1".into(),
                values: t.iter().map(|t| 1.0 + 0.5 * (3.0 * t).sin()).collect(),
            },
        ],
        power: vec![NamedSeries {
            name: "cable 0".into(),
            values: t
                .iter()
                .map(|t| 0.02 * (-3.0 * t).exp() * (8.0 * t).sin())
                .collect(),
        }],
    };
    plot::actuators("cables", &a)?.write(&dir.join("actuators.svg"))?;
    let bounds: Vec<f64> = (0..=6).map(|n| 0.5 * n as f64 / 6.0).collect();
    let per: Vec<Vec<[f64; 6]>> = (0..4)
        .map(|k| {
            (0..6)
                .map(|n| {
                    [
                        0.0,
                        3.0 * k as f64 * (1.0 - n as f64 / 6.0),
                        0.5 * k as f64,
                        1.0 + 0.002 * k as f64,
                        0.0,
                        1e-4 * k as f64,
                    ]
                })
                .collect()
        })
        .collect();
    let sp = StrainProfiles::piecewise_constant(
        "arm",
        vec![0.0, 0.25, 0.5, 0.75],
        &bounds,
        &per,
        StrainComponent::ALL.to_vec(),
    );
    plot::strains("strains along the rod", &sp)?.write(&dir.join("strains.svg"))?;
    // Euler–Bernoulli cantilever modes along x, bending in z.
    let beta: [f64; 3] = [1.875104, 4.694091, 7.854757];
    let l = 0.5;
    let xs: Vec<f64> = (0..=60).map(|i| l * i as f64 / 60.0).collect();
    let eq = RodCurve {
        name: "arm".into(),
        points: xs.iter().map(|x| [*x, 0.0, 0.0]).collect(),
    };
    let modes = beta
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let bl = *b;
            let sig = (bl.cosh() + bl.cos()) / (bl.sinh() + bl.sin());
            let phi = |x: f64| {
                let u = b * x / l;
                u.cosh() - u.cos() - sig * (u.sinh() - u.sin())
            };
            let tip = phi(l);
            Mode {
                frequency_hz: [1.12, 7.02, 19.66][k],
                displaced: vec![RodCurve {
                    name: "arm".into(),
                    points: xs
                        .iter()
                        .map(|x| [*x, 0.0, 0.1 * l * phi(*x) / tip])
                        .collect(),
                }],
            }
        })
        .collect();
    plot::modes(
        "mode shapes",
        &ModeShapes {
            equilibrium: vec![eq],
            modes,
        },
    )?
    .write(&dir.join("modes.svg"))?;
    println!("wrote {}", dir.display());
    Ok(())
}
