//! `strain_space_force` (docs/theory.md D13, D15, D53) is the whole part
//! of the inverse dynamics that depends on Young's and shear modulus,
//! viscosity and the cables' tensions: `ID + τ_s` is the same for a model
//! and for the model with those moved (what the gradient's parameter
//! products rely on, docs/theory-control.md G8), on a six-strain chain
//! with every force term, a planar rod, and a tree with joint springs,
//! bodies, an inside branch and a prescribed joint. And its damping part
//! is `−D q̇` of the separately assembled damping matrix.

mod common;

use common::{Lcg, Shape, Terms, driven_tree, model, robot, rod_spec, state};
use nalgebra::DVector;
use softrod_dynamics::*;
use softrod_kinematics::{Basis, Strain};
use softrod_lie::{Pose, Vec6};
use softrod_mechanics::{Material, RodProperties, Tension};

/// Rod `r` with `E × 3`, `G × 3` (at a fixed Poisson ratio, or given),
/// viscosity `× 2 + 5` and every cable tension value `+ 1.5`.
fn moved(m: &Model, r: usize) -> Model {
    let mut spec = m.rods()[r].spec.clone();
    let mat = spec.properties.material();
    let b = Material::builder()
        .density(mat.density())
        .young(3.0 * mat.young())
        .viscosity(2.0 * mat.viscosity() + 5.0);
    let mat = match mat.specified_poisson() {
        Some(nu) => b.poisson(nu),
        None => b.shear_modulus(3.0 * mat.shear_modulus()),
    }
    .build()
    .unwrap();
    spec.properties =
        RodProperties::new(*spec.properties.section(), mat, spec.properties.length()).unwrap();
    for c in &mut spec.cables {
        match &mut c.tension {
            Tension::Constant(v) => *v += 1.5,
            Tension::Table { values, .. } => values.iter_mut().for_each(|v| *v += 1.5),
        }
    }
    m.clone().with_rod_spec(r, spec).unwrap()
}

/// `max |(ID + τ_s)(m) − (ID + τ_s)(m')| / max(|ID|, |τ_s|)` over the
/// models with each rod moved, and the smallest relative change of `τ_s`
/// (that the check is not vacuous).
fn split_error(m: &Model, t: f64, q: &[f64], qd: &[f64], qdd: &[f64]) -> (f64, f64) {
    let rest = |m: &Model| {
        let mut d = Data::new(m);
        let id = inverse_dynamics(m, &mut d, t, q, qd, qdd).unwrap().clone();
        let sf = strain_space_force(m, &mut d, t, q, qd).unwrap().clone();
        (id, sf)
    };
    let (id0, sf0) = rest(m);
    let (mut worst, mut change) = (0.0f64, f64::INFINITY);
    for r in 0..m.rods().len() {
        let (id1, sf1) = rest(&moved(m, r));
        let scale = id0.amax().max(id1.amax()).max(sf0.amax()).max(sf1.amax());
        worst = worst.max(((&id1 + &sf1) - (&id0 + &sf0)).amax() / scale);
        change = change.min((&sf1 - &sf0).amax() / scale);
    }
    (worst, change)
}

/// Sums of the same terms in another order: round-off.
const TOL: f64 = 1e-13;

fn check(name: &str, m: &Model, t: f64, rng: &mut Lcg) {
    let (q, qd, qdd) = state(rng, m.n_dof(), 0.6, 1.5, 3.0);
    let (e, change) = split_error(m, t, &q, &qd, &qdd);
    println!("{name}: {e:.1e} (τ_s moved by {change:.1e})");
    assert!(e < TOL, "{name}: {e:e}");
    assert!(change > 1e-3, "{name}: the parameters moved nothing");
}

#[test]
fn the_strain_space_force_is_all_of_id_that_moduli_viscosity_and_tensions_change() {
    let mut rng = Lcg(41);
    let chain = model(&Shape::new(5, vec![Basis::all()]), Terms::ALL);
    check("six-strain chain, every term", &chain, 0.3, &mut rng);
    use Strain::*;
    let sel = |s: &[Strain]| Basis::select(s).unwrap();
    let mut shape = Shape::new(4, vec![sel(&[Ky, Qx, Qz]), sel(&[Ky])]);
    shape.rest = Vec6::new(0.0, 0.8, 0.0, 1.0, 0.0, 0.1);
    let terms = Terms {
        damping: true,
        cable: true,
        ..Terms::NONE
    };
    let planar = Model::new(
        vec![rod_spec("planar", &shape, terms, Pose::identity())],
        Some(softrod_lie::Vec3::new(0.0, 0.0, -9.81)),
        4,
    )
    .unwrap();
    check("planar rod", &planar, 0.1, &mut rng);
    check("robot", &robot(true, true, true, true), 0.0, &mut rng);
    // A branch inside a piece and a rod on a prescribed joint.
    let tree = driven_tree();
    check("tree with a prescribed joint", &tree, 0.37, &mut rng);
}

#[test]
fn its_damping_part_is_the_damping_matrix_times_the_rates() {
    let mut rng = Lcg(43);
    let m = model(&Shape::new(4, vec![Basis::all()]), Terms::ALL);
    // Fast rates: the damping force comparable with the elastic one.
    let (q, qd, _) = state(&mut rng, m.n_dof(), 0.6, 1.5e3, 3.0);
    let mut d = Data::new(&m);
    let moving = strain_space_force(&m, &mut d, 0.2, &q, &qd)
        .unwrap()
        .clone();
    let zero = vec![0.0; m.n_dof()];
    let still = strain_space_force(&m, &mut d, 0.2, &q, &zero)
        .unwrap()
        .clone();
    let dmat = damping_matrix(&m);
    let reference = -(&dmat * DVector::from_column_slice(&qd));
    // The difference cancels the elastic and cable terms: round-off of
    // those, relative to the larger of the vectors.
    let scale = moving.amax().max(still.amax());
    let e = ((&moving - &still) - &reference).amax() / scale;
    assert!(reference.amax() > 1e-3 * scale);
    assert!(e < TOL, "{e:e}");
    // Bad input names the argument.
    let mut bad = q.clone();
    bad[0] = f64::NAN;
    assert!(strain_space_force(&m, &mut d, 0.0, &bad, &qd).is_err());
}

/// With only constant-offset frictionless cables the cables' part of the
/// strain-space force is summed per piece for all cables at once (one
/// strain and one projection per piece); it is still
/// `Σ_c T_c (−∂ℓ_c/∂q)` (D15), here against central differences of each
/// cable's length `ℓ_c(q)` on a planar rod (two offset cables, one of them
/// over part of the rod).
#[test]
fn offset_cables_force_is_minus_the_length_gradient_times_the_tensions() {
    use Strain::*;
    use softrod_kinematics::GaussLegendre;
    use softrod_mechanics::{Cable, Routing};
    let mut shape = Shape::new(4, vec![Basis::select(&[Ky, Qx, Qz]).unwrap()]);
    shape.rest = Vec6::new(0.0, 0.3, 0.0, 1.0, 0.0, 0.05);
    let mut spec = rod_spec("planar", &shape, Terms::NONE, Pose::identity());
    let length = shape.length;
    let tensions = [1.5, 0.7];
    spec.cables = vec![
        Cable::new(
            Routing::Offset { y: 0.0, z: 0.008 },
            Tension::Constant(tensions[0]),
        ),
        Cable::new(
            Routing::Offset { y: 0.0, z: -0.006 },
            Tension::Constant(tensions[1]),
        )
        .between(0.3 * length, 0.9 * length),
    ];
    let m = Model::new(vec![spec], None, 4).unwrap();
    let n = m.n_dof();
    let q: Vec<f64> = (0..n).map(|i| 0.2 * ((i as f64) * 1.1).sin()).collect();
    let zero = vec![0.0; n];
    let mut data = Data::new(&m);
    let got = strain_space_force(&m, &mut data, 0.0, &q, &zero)
        .unwrap()
        .clone();
    // The elastic part, from the same model without its cables' tensions.
    data.set_cable_tensions(&m, Some(&[0.0, 0.0])).unwrap();
    let elastic = strain_space_force(&m, &mut data, 0.0, &q, &zero)
        .unwrap()
        .clone();
    let rod = &m.rods()[0].spec.geometry;
    let quad = GaussLegendre::new(4);
    let h = 1e-6;
    for i in 0..n {
        let (mut qp, mut qm) = (q.clone(), q.clone());
        qp[i] += h;
        qm[i] -= h;
        let want: f64 = m.rods()[0]
            .spec
            .cables
            .iter()
            .zip(tensions)
            .map(|(c, t)| -t * (c.length(rod, &qp, &quad) - c.length(rod, &qm, &quad)) / (2.0 * h))
            .sum();
        let cable = got[i] - elastic[i];
        assert!(
            (cable - want).abs() <= 1e-7 * (1.0 + want.abs()),
            "coordinate {i}: {cable:e} vs {want:e}"
        );
    }
}
