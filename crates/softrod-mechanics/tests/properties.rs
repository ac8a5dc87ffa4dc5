//! Sections, materials, bodies, load wrenches, tension tables, validation.

mod common;

use approx::assert_relative_eq;
use common::*;
use softrod_lie::{Pose, Vec3, Vec6};
use softrod_mechanics::reference::gravity_wrench_density;
use softrod_mechanics::*;
use std::f64::consts::PI;

/// Midpoint-rule area and second moments of a section given by an indicator,
/// over the square [−h, h]² with n×n cells: an independent check.
fn grid_moments(half: f64, n: usize, inside: impl Fn(f64, f64) -> bool) -> (f64, f64, f64) {
    let d = 2.0 * half / n as f64;
    let (mut a, mut jy, mut jz) = (0.0, 0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let y = -half + (i as f64 + 0.5) * d;
            let z = -half + (j as f64 + 0.5) * d;
            if inside(y, z) {
                a += d * d;
                jy += z * z * d * d;
                jz += y * y * d * d;
            }
        }
    }
    (a, jy, jz)
}

#[test]
fn tube_matches_textbook() {
    // Textbook (hollow circular shaft, diameters): A = π(D² − d²)/4,
    // I = π(D⁴ − d⁴)/64, J_polar = π(D⁴ − d⁴)/32.
    let (big_d, small_d) = (0.04, 0.03);
    let p = Section::Tube {
        radius: big_d / 2.0,
        inner_radius: small_d / 2.0,
    }
    .properties(0.3);
    let area = PI * (big_d * big_d - small_d * small_d) / 4.0;
    let i = PI * (big_d.powi(4) - small_d.powi(4)) / 64.0;
    assert_relative_eq!(p.area, area, max_relative = 1e-15);
    assert_relative_eq!(p.jy, i, max_relative = 1e-15);
    assert_relative_eq!(p.jz, i, max_relative = 1e-15);
    assert_relative_eq!(p.jx, 2.0 * i, max_relative = 1e-15);
    // Independent: cell integration.
    let (a, jy, jz) = grid_moments(0.02, 2000, |y, z| {
        let r2 = y * y + z * z;
        r2 <= 0.02f64.powi(2) && r2 >= 0.015f64.powi(2)
    });
    assert_relative_eq!(a, p.area, max_relative = 2e-3);
    assert_relative_eq!(jy, p.jy, max_relative = 2e-3);
    assert_relative_eq!(jz, p.jz, max_relative = 2e-3);
    // A tube with zero bore is the circle.
    let t0 = Section::Tube {
        radius: 0.02,
        inner_radius: 0.0,
    }
    .properties(0.0);
    let c = Section::Circle { radius: 0.02 }.properties(0.0);
    assert_relative_eq!(t0.area, c.area, max_relative = 1e-15);
    assert_relative_eq!(t0.jx, c.jx, max_relative = 1e-15);
}

#[test]
fn rectangle_matches_textbook() {
    // Width 30 mm along y, height 10 mm along z: I_y = b h³/12 about y
    // (distances along z), I_z = h b³/12.
    let p = Section::Rectangle {
        width: 0.03,
        height: 0.01,
    }
    .properties(0.0);
    assert_relative_eq!(p.area, 3e-4, max_relative = 1e-15);
    assert_relative_eq!(p.jy, 2.5e-9, max_relative = 1e-14);
    assert_relative_eq!(p.jz, 2.25e-8, max_relative = 1e-14);
    assert_relative_eq!(p.jx, 2.5e-9 + 2.25e-8, max_relative = 1e-14);
    let (a, jy, jz) = grid_moments(0.015, 600, |y, z| y.abs() <= 0.015 && z.abs() <= 0.005);
    assert_relative_eq!(a, p.area, max_relative = 1e-9);
    assert_relative_eq!(jy, p.jy, max_relative = 1e-4);
    assert_relative_eq!(jz, p.jz, max_relative = 1e-4);
    let r = Section::Rectangle {
        width: 0.03,
        height: 0.04,
    };
    assert_relative_eq!(r.outer_radius(0.0), 0.025, max_relative = 1e-15);
}

#[test]
fn taper_interpolates_linearly() {
    let s = Section::TaperedCircle {
        radius_base: 0.02,
        radius_tip: 0.01,
    };
    assert!(!s.is_uniform());
    assert_relative_eq!(s.outer_radius(0.5), 0.015, max_relative = 1e-15);
    assert_eq!(
        s.properties(0.5),
        Section::Circle { radius: 0.015 }.properties(0.0)
    );
    assert_eq!(
        s.properties(1.7),
        Section::Circle { radius: 0.01 }.properties(0.0)
    );
    assert!(Section::Circle { radius: 0.1 }.is_uniform());
}

#[test]
fn body_diagonals_follow_the_model() {
    let m = Material::builder()
        .density(1200.0)
        .young(2e6)
        .poisson(0.25)
        .viscosity(50.0)
        .build()
        .unwrap();
    assert_relative_eq!(m.shear_modulus(), 2e6 / 2.5, max_relative = 1e-15);
    assert_relative_eq!(m.poisson(), 0.25, max_relative = 1e-14);
    assert_eq!(m.specified_poisson(), Some(0.25));
    let by_shear = Material::builder()
        .density(1200.0)
        .young(2e6)
        .shear_modulus(0.8e6)
        .build()
        .unwrap();
    assert_eq!(by_shear.specified_poisson(), None);
    assert_relative_eq!(by_shear.poisson(), 0.25, max_relative = 1e-14);
    assert_eq!(by_shear.viscosity(), 0.0);
    let sec = Section::Rectangle {
        width: 0.02,
        height: 0.01,
    };
    let b = RodProperties::new(sec, m, 0.4).unwrap();
    let p = sec.properties(0.0);
    let (rho, e, g, mu) = (1200.0, 2e6, 0.8e6, 50.0);
    let expect_m = Vec6::new(
        rho * p.jx,
        rho * p.jy,
        rho * p.jz,
        rho * p.area,
        rho * p.area,
        rho * p.area,
    );
    let expect_k = Vec6::new(
        g * p.jx,
        e * p.jy,
        e * p.jz,
        e * p.area,
        g * p.area,
        g * p.area,
    );
    let expect_v = Vec6::new(
        mu * p.jx,
        3.0 * mu * p.jy,
        3.0 * mu * p.jz,
        3.0 * mu * p.area,
        mu * p.area,
        mu * p.area,
    );
    assert_relative_eq!(b.screw_inertia(0.1), expect_m, max_relative = 1e-14);
    assert_relative_eq!(b.stiffness(0.1), expect_k, max_relative = 1e-14);
    assert_relative_eq!(b.viscosity(0.1), expect_v, max_relative = 1e-14);
    assert_relative_eq!(b.mass_per_length(0.2), rho * p.area, max_relative = 1e-15);
    // A taper is evaluated at u = s/L.
    let t = taper_body(0.5);
    let r = 0.02 + (0.008 - 0.02) * 0.3;
    assert_relative_eq!(
        t.mass_per_length(0.15),
        1000.0 * PI * r * r,
        max_relative = 1e-14
    );
}

#[test]
fn invalid_descriptions_are_reported_with_their_values() {
    assert!(matches!(
        Section::Circle { radius: -1.0 }.validate(),
        Err(MechanicsError::NotPositive { value, .. }) if value == -1.0
    ));
    assert!(matches!(
        Section::Tube { radius: 0.01, inner_radius: 0.01 }.validate(),
        Err(MechanicsError::InnerRadius { inner, outer }) if inner == 0.01 && outer == 0.01
    ));
    assert!(
        Section::Rectangle {
            width: 0.01,
            height: f64::NAN
        }
        .validate()
        .is_err()
    );
    let silicone = |nu: f64, mu: f64| {
        Material::builder()
            .density(1000.0)
            .young(1e6)
            .poisson(nu)
            .viscosity(mu)
            .build()
    };
    assert!(matches!(
        silicone(0.6, 0.0),
        Err(MechanicsError::PoissonRatio { value }) if value == 0.6
    ));
    assert!(silicone(-1.0, 0.0).is_err());
    assert!(silicone(0.5, 0.0).is_ok());
    assert_eq!(
        silicone(0.3, -1.0),
        Err(MechanicsError::Negative {
            quantity: Quantity::Viscosity,
            value: -1.0
        })
    );
    // Missing and conflicting constants name the quantity.
    assert_eq!(
        Material::builder().young(1e6).poisson(0.3).build(),
        Err(MechanicsError::Missing {
            quantity: Quantity::Density
        })
    );
    assert_eq!(
        Material::builder().density(1e3).young(1e6).build(),
        Err(MechanicsError::Missing {
            quantity: Quantity::PoissonRatio
        })
    );
    assert!(matches!(
        Material::builder()
            .density(1e3)
            .young(1e6)
            .poisson(0.3)
            .shear_modulus(4e5)
            .build(),
        Err(MechanicsError::Conflict { .. })
    ));
    assert_eq!(
        Material::builder()
            .density(1e3)
            .young(-1e6)
            .poisson(0.3)
            .build(),
        Err(MechanicsError::NotPositive {
            quantity: Quantity::YoungsModulus,
            value: -1e6
        })
    );
    let body = RodProperties::new(Section::Circle { radius: 0.01 }, soft_material(), 1.0).unwrap();
    let rod = mixed_rod(0.9, identity_base());
    assert!(matches!(
        body.check_rod(&rod),
        Err(MechanicsError::LengthMismatch { .. })
    ));
    let cable = |routing, from, to, tension| Cable::new(routing, tension).between(from, to);
    let off = Routing::Offset { y: 0.01, z: 0.0 };
    assert!(
        cable(off.clone(), 0.0, 1.0, Tension::Constant(1.0))
            .validate(1.0)
            .is_ok()
    );
    assert!(matches!(
        cable(off.clone(), 0.5, 0.5, Tension::Constant(1.0)).validate(1.0),
        Err(MechanicsError::CableTo { .. })
    ));
    assert!(
        cable(off.clone(), 0.0, 1.1, Tension::Constant(1.0))
            .validate(1.0)
            .is_err()
    );
    assert!(
        cable(off.clone(), 0.0, 1.0, Tension::Constant(-1.0))
            .validate(1.0)
            .is_err()
    );
    assert!(matches!(
        cable(
            Routing::Path(vec![[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.5, 1.0, 0.0]]),
            0.0,
            1.0,
            Tension::Constant(1.0)
        )
        .validate(1.0),
        Err(MechanicsError::NotIncreasing { index: 2, .. })
    ));
    assert!(matches!(
        cable(
            off.clone(),
            0.0,
            1.0,
            Tension::Table {
                times: vec![0.0, 1.0],
                values: vec![1.0]
            }
        )
        .validate(1.0),
        Err(MechanicsError::SizeMismatch {
            quantity: Quantity::TensionValues,
            got: 1,
            expected: 2,
        })
    ));
    assert!(
        cable(
            off,
            0.0,
            1.0,
            Tension::Table {
                times: vec![0.0, 1.0],
                values: vec![1.0, -0.5]
            }
        )
        .validate(1.0)
        .is_err()
    );
    assert!(matches!(
        PointLoad {
            s: 1.5,
            force: Vec3::zeros(),
            moment: Vec3::zeros(),
            frame: LoadFrame::Body
        }
        .validate(1.0),
        Err(MechanicsError::OutOfRod { s, .. }) if s == 1.5
    ));
    assert!(
        Drag {
            translational: -1.0,
            rotational: 0.0
        }
        .validate()
        .is_err()
    );
    assert!(
        DistributedLoad {
            force: Vec3::zeros(),
            moment: Vec3::zeros(),
            frame: LoadFrame::World
        }
        .validate()
        .is_ok()
    );
    // Messages name the quantity and the value.
    let msg = Section::Circle { radius: -2.5 }
        .validate()
        .unwrap_err()
        .to_string();
    assert!(msg.contains("radius") && msg.contains("-2.5"), "{msg}");
}

#[test]
fn tension_tables_interpolate_and_clamp() {
    let c = Cable {
        routing: Routing::Offset { y: 0.0, z: 0.01 },
        tension: Tension::Table {
            times: vec![0.0, 1.0, 3.0],
            values: vec![0.0, 2.0, 1.0],
        },
        friction: 0.0,
        span: Span::Between { from: 0.0, to: 1.0 },
    };
    assert_eq!(c.tension_at(-1.0), 0.0);
    assert_relative_eq!(c.tension_at(0.25), 0.5, max_relative = 1e-15);
    assert_relative_eq!(c.tension_at(1.0), 2.0, max_relative = 1e-15);
    assert_relative_eq!(c.tension_at(2.0), 1.5, max_relative = 1e-15);
    assert_eq!(c.tension_at(10.0), 1.0);
}

/// Moved with the interpolation from the scene crate: exact values at the
/// knots, linear between, held outside.
#[test]
fn tension_schedule_is_piecewise_linear_and_held() {
    let t = Tension::Table {
        times: vec![0.0, 0.5, 1.0],
        values: vec![0.0, 2.0, 1.0],
    };
    assert_eq!(t.at(-1.0), 0.0);
    assert_eq!(t.at(0.25), 1.0);
    assert_eq!(t.at(0.5), 2.0);
    assert_eq!(t.at(0.75), 1.5);
    assert_eq!(t.at(9.0), 1.0);
    assert_eq!(t.max(), 2.0);
    assert_eq!(Tension::Constant(0.7).max(), 0.7);
}

#[test]
fn path_routing_is_piecewise_linear() {
    let c = Cable {
        routing: Routing::Path(vec![[0.1, 0.01, 0.0], [0.3, 0.0, 0.02]]),
        tension: Tension::Constant(1.0),
        friction: 0.0,
        span: Span::Between { from: 0.0, to: 0.5 },
    };
    let (d, dp) = c.offset(0.2);
    assert_relative_eq!(d, Vec3::new(0.0, 0.005, 0.01), max_relative = 1e-14);
    assert_relative_eq!(dp, Vec3::new(0.0, -0.05, 0.1), max_relative = 1e-14);
    assert_eq!(c.offset(0.0), (Vec3::new(0.0, 0.01, 0.0), Vec3::zeros()));
    assert_eq!(c.offset(0.4), (Vec3::new(0.0, 0.0, 0.02), Vec3::zeros()));
    assert_relative_eq!(c.max_offset(), 0.02);
    // The scene's contract example path: (s, y, z) = (0, 0, 0.008) to (0.5, 0.004, 0).
    let r = Routing::Path(vec![[0.0, 0.0, 0.008], [0.5, 0.004, 0.0]]);
    assert_eq!(r.offset(0.0).0, Vec3::new(0.0, 0.0, 0.008));
    let (m, _) = r.offset(0.25);
    assert!((m[1] - 0.002).abs() < 1e-15 && (m[2] - 0.004).abs() < 1e-15);
    assert_eq!(r.offset(1.0).0, Vec3::new(0.0, 0.004, 0.0));
}

#[test]
fn load_wrenches_in_body_frame() {
    let mut rng = Rng::new(7);
    let r = nalgebra::Rotation3::from_scaled_axis(rng.vec3(2.0)).into_inner();
    let pose = Pose::new(r, rng.vec3(1.0));
    let g = Vec3::new(0.0, 0.0, -9.81);
    let w = gravity_wrench_density(0.3, &pose, &g);
    // 𝓜 Ad⁻¹_g 𝒢 with the dense operators.
    let body = RodProperties::new(Section::Circle { radius: 0.01 }, soft_material(), 1.0).unwrap();
    let mpl = body.mass_per_length(0.0);
    let calg = Vec6::new(0.0, 0.0, 0.0, 0.0, 0.0, -9.81);
    let dense =
        nalgebra::Matrix6::from_diagonal(&body.screw_inertia(0.0)) * pose.ad_inv().to_mat6() * calg;
    assert_relative_eq!(
        gravity_wrench_density(mpl, &pose, &g),
        dense,
        epsilon = 1e-15
    );
    assert_relative_eq!(
        (r * softrod_lie::linear(&w)).z,
        -9.81 * 0.3,
        max_relative = 1e-14
    );
    assert_eq!(softrod_lie::angular(&w), Vec3::zeros());

    let (f, m) = (rng.vec3(3.0), rng.vec3(1.0));
    let dead = PointLoad {
        s: 0.5,
        force: f,
        moment: m,
        frame: LoadFrame::World,
    };
    let follower = PointLoad {
        frame: LoadFrame::Body,
        ..dead
    };
    let wd = dead.wrench(&pose);
    assert_relative_eq!(r * softrod_lie::linear(&wd), f, epsilon = 1e-14);
    assert_relative_eq!(r * softrod_lie::angular(&wd), m, epsilon = 1e-14);
    assert_eq!(follower.wrench(&pose), softrod_lie::join(&m, &f));
    let dl = DistributedLoad {
        force: f,
        moment: m,
        frame: LoadFrame::World,
    };
    assert_eq!(dl.wrench_density(&pose), wd);

    let drag = Drag {
        translational: 2.0,
        rotational: 0.5,
    };
    let eta = Vec6::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0);
    assert_eq!(
        drag.wrench_density(&eta),
        Vec6::new(-0.5, -1.0, -1.5, -8.0, -10.0, -12.0)
    );
}
