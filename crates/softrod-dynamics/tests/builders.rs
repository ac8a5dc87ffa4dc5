//! The builders make the same model as the parts put together by hand, and
//! every bad value comes back as a structured error naming the rod, with the
//! lower layer's error as its source.

use std::error::Error;

use softrod_dynamics::*;
use softrod_kinematics::{Basis, KinematicsError, RodGeometry, Strain, straight};
use softrod_lie::{Pose, Vec3, Vec6, exp_twist};
use softrod_mechanics::{
    Cable, LoadFrame, Material, MechanicsError, PointLoad, Quantity, RodProperties, Routing,
    Section, Tension,
};

fn silicone() -> Material {
    Material::builder()
        .density(1100.0)
        .young(2e6)
        .poisson(0.45)
        .viscosity(30.0)
        .build()
        .unwrap()
}

fn tip_load() -> PointLoad {
    PointLoad {
        s: 0.4,
        force: Vec3::new(0.1, -0.2, 0.3),
        moment: Vec3::new(0.0, 0.01, 0.0),
        frame: LoadFrame::Body,
    }
}

fn cable() -> Cable {
    Cable::new(Routing::Offset { y: 0.0, z: 0.008 }, Tension::Constant(1.5))
}

/// The same rod, by hand from its parts.
fn by_hand(base: Pose, strains: &[Strain]) -> Model {
    let rod =
        RodGeometry::uniform(0.4, 5, Basis::select(strains).unwrap(), straight(), base).unwrap();
    let body = RodProperties::new(Section::Circle { radius: 0.012 }, silicone(), 0.4).unwrap();
    let mut spec = Rod::new("arm", rod, body);
    spec.point_loads.push(tip_load());
    spec.cables.push(cable().between(0.0, 0.4));
    Model::new(vec![spec], Some(Vec3::new(0.0, 0.0, -9.81)), 5).unwrap()
}

#[test]
fn builder_matches_the_parts_put_together_by_hand() {
    let base = exp_twist(1.0, &Vec6::new(0.2, -0.4, 0.1, 0.0, 0.05, 0.1));
    let strains = [Strain::Ky, Strain::Kz, Strain::Qx, Strain::Qz];
    let built = Model::builder()
        .rod(
            Rod::builder(0.4)
                .name("arm")
                .pieces(5)
                .strains(strains)
                .base(base)
                .circle(0.012)
                .material(silicone())
                .point_load(tip_load())
                .cable(cable()),
        )
        .gravity([0.0, 0.0, -9.81])
        .quadrature(5)
        .build()
        .unwrap();
    let hand = by_hand(base, &strains);
    assert_eq!(built.n_dof(), hand.n_dof());
    assert_eq!(built.terms(), hand.terms());
    let n = hand.n_dof();
    let q: Vec<f64> = (0..n).map(|i| 0.3 * ((i as f64) * 0.7).sin()).collect();
    let qd: Vec<f64> = (0..n).map(|i| 0.5 * ((i as f64) * 1.3).cos()).collect();
    let qdd = vec![0.2; n];
    let (mut a, mut b) = (Data::new(&built), Data::new(&hand));
    let ta = inverse_dynamics(&built, &mut a, 0.3, &q, &qd, &qdd)
        .unwrap()
        .clone();
    let tb = inverse_dynamics(&hand, &mut b, 0.3, &q, &qd, &qdd)
        .unwrap()
        .clone();
    // Same pieces, bodies, loads and Gauss points (the whole-rod cable span
    // is [0, L] here: 5 pieces of 0.08 sum to 0.4 exactly): the same numbers.
    assert_eq!(ta, tb);
    let ma = mass_matrix(&built, &mut a, &q).unwrap().clone();
    let mb = mass_matrix(&hand, &mut b, &q).unwrap().clone();
    assert_eq!(ma, mb);
}

#[test]
fn builder_defaults() {
    let spec = Rod::builder(0.3)
        .circle(0.01)
        .material(silicone())
        .build()
        .unwrap();
    assert_eq!(spec.name, "");
    assert_eq!(spec.geometry.n_pieces(), 1);
    assert!(spec.geometry.uniform_basis().unwrap().is_identity());
    assert_eq!(spec.geometry.pieces()[0].rest_strain, straight());
    assert_eq!(*spec.geometry.base(), Pose::identity());
    assert_eq!(spec.properties.length(), 0.3);
    assert!(spec.stress_free.is_none() && spec.drag.is_none());
    assert!(spec.cables.is_empty() && spec.point_loads.is_empty());
    let m = Model::builder().rod(spec).build().unwrap();
    assert!(m.gravity().is_none());
    assert_eq!(m.quadrature().len(), Model::DEFAULT_QUADRATURE);
    // A uniform stress-free strain fills every piece.
    let curled = Vec6::new(0.0, 2.0, 0.0, 1.0, 0.0, 0.0);
    let spec = Rod::builder(0.3)
        .pieces(3)
        .circle(0.01)
        .material(silicone())
        .stress_free(curled)
        .build()
        .unwrap();
    assert_eq!(spec.stress_free, Some(vec![curled; 3]));
}

fn rod(length: f64) -> RodBuilder {
    Rod::builder(length)
        .name("arm")
        .circle(0.01)
        .material(silicone())
}

#[test]
fn builder_errors_name_the_rod_and_chain_the_cause() {
    let arm = RodId {
        index: None,
        name: "arm".into(),
    };
    let e = Rod::builder(0.5).name("arm").build().unwrap_err();
    assert_eq!(e, DynamicsError::MissingSection { rod: arm.clone() });
    let e = Rod::builder(0.5)
        .name("arm")
        .circle(0.01)
        .build()
        .unwrap_err();
    assert_eq!(e, DynamicsError::MissingMaterial { rod: arm.clone() });
    // The length is checked once, by the body, whether pieces are counted or listed.
    for b in [rod(-0.5).pieces(4), rod(-0.5).piece_lengths(&[0.25, 0.25])] {
        let e = b.build().unwrap_err();
        assert_eq!(
            e,
            DynamicsError::RodProperties {
                rod: arm.clone(),
                source: MechanicsError::NotPositive {
                    quantity: Quantity::RodLength,
                    value: -0.5
                }
            }
        );
        assert_eq!(e.rod(), Some(&arm));
        let src = e.source().expect("the mechanics error is the source");
        assert_eq!(
            src.to_string(),
            "rod length [m] must be positive and finite, got -0.5"
        );
    }
    assert!(matches!(
        rod(0.5).pieces(0).build(),
        Err(DynamicsError::RodGeometry {
            source: KinematicsError::NoPieces,
            ..
        })
    ));
    assert_eq!(
        rod(0.5).piece_lengths(&[0.1, 0.2]).build().unwrap_err(),
        DynamicsError::PieceLengthSum {
            rod: arm.clone(),
            sum: 0.30000000000000004,
            length: 0.5
        }
    );
    // Within the 1e-9 relative tolerance the listed pieces are the rod.
    rod(0.5)
        .piece_lengths(&[0.1, 0.15, 0.25 + 1e-11])
        .build()
        .unwrap();
    assert!(matches!(
        rod(0.5).strains([Strain::Ky, Strain::Ky]).build(),
        Err(DynamicsError::RodGeometry {
            source: KinematicsError::DuplicateStrain { strain: Strain::Ky },
            ..
        })
    ));
    let e = rod(0.5)
        .cable(cable())
        .cable(cable().between(0.1, 0.6))
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            DynamicsError::Cable {
                cable: 1,
                source: MechanicsError::CableTo { .. },
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().starts_with("rod 'arm', cable 1: "), "{e}");
    let e = rod(0.5)
        .point_load(PointLoad {
            s: 0.7,
            ..tip_load()
        })
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            DynamicsError::PointLoad {
                load: 0,
                source: MechanicsError::OutOfRod { s: 0.7, .. },
                ..
            }
        ),
        "{e}"
    );
    let e = rod(0.5)
        .pieces(2)
        .stress_free_per_piece(vec![straight()])
        .build()
        .unwrap_err();
    assert!(matches!(
        e,
        DynamicsError::StressFreeCount {
            got: 1,
            expected: 2,
            ..
        }
    ));
}

#[test]
fn model_errors_carry_the_rod_index() {
    let e = Model::builder()
        .rod(rod(0.5))
        .rod(rod(0.3).name("hand").pieces(0))
        .build()
        .unwrap_err();
    assert_eq!(
        e.rod(),
        Some(&RodId {
            index: Some(1),
            name: "hand".into()
        })
    );
    assert!(e.to_string().starts_with("rod 1 ('hand'): "), "{e}");
    // A spec whose public fields were changed after it was built is checked
    // again when it enters the model.
    let mut spec = rod(0.5).build().unwrap();
    spec.cables.push(cable().between(0.2, 0.1));
    let e = Model::new(vec![rod(0.2).build().unwrap(), spec], None, 4).unwrap_err();
    assert!(
        matches!(&e, DynamicsError::Cable { rod, cable: 0, .. } if rod.index == Some(1)),
        "{e}"
    );
    assert_eq!(Model::builder().build().unwrap_err(), DynamicsError::NoRods);
    assert_eq!(
        Model::builder()
            .rod(rod(0.5))
            .quadrature(0)
            .build()
            .unwrap_err(),
        DynamicsError::NoQuadraturePoints
    );
    assert!(matches!(
        Model::builder()
            .rod(rod(0.5))
            .gravity([0.0, f64::NAN, -9.81])
            .build(),
        Err(DynamicsError::GravityNotFinite { component: 1, .. })
    ));
}

/// A variant of a built model (`with_gravity`, `with_quadrature`) is the
/// model built with those settings in the first place, bit for bit; bad
/// settings are errors.
#[test]
fn model_variants_equal_models_built_with_those_settings() {
    let g = Vec3::new(0.3, -1.0, -9.81);
    let rod = || {
        Rod::builder(0.4)
            .pieces(4)
            .circle(0.01)
            .material(silicone())
            .point_load(tip_load())
            .cable(cable())
    };
    let plain = Model::builder().rod(rod()).quadrature(3).build().unwrap();
    let built = Model::builder()
        .rod(rod())
        .gravity(g)
        .quadrature(5)
        .build()
        .unwrap();
    let variant = plain
        .clone()
        .with_gravity(Some(g))
        .unwrap()
        .with_quadrature(5)
        .unwrap();
    assert_eq!(variant.gravity(), Some(g));
    assert_eq!(variant.quadrature().len(), 5);
    let n = built.n_dof();
    let q: Vec<f64> = (0..n).map(|i| 0.3 * (1.7 * i as f64).sin()).collect();
    let qd: Vec<f64> = (0..n).map(|i| 0.5 * (2.3 * i as f64).cos()).collect();
    let qdd: Vec<f64> = (0..n).map(|i| (0.9 * i as f64).sin()).collect();
    let tau = |m: &Model| {
        inverse_dynamics(m, &mut Data::new(m), 0.2, &q, &qd, &qdd)
            .unwrap()
            .clone()
    };
    assert_eq!(tau(&variant), tau(&built));
    assert_ne!(tau(&plain), tau(&built));
    // Zero gravity is none, as when building.
    let none = built.clone().with_gravity(Some(Vec3::zeros())).unwrap();
    assert!(none.gravity().is_none());
    assert!(matches!(
        built
            .clone()
            .with_gravity(Some(Vec3::new(0.0, f64::NAN, 0.0))),
        Err(DynamicsError::GravityNotFinite { component: 1, .. })
    ));
    assert!(matches!(
        built.with_quadrature(0),
        Err(DynamicsError::NoQuadraturePoints)
    ));
}
