//! What the contact test files share (every test file compiles this module
//! on its own, so not every item is used by each): the rod's radius,
//! length and gravity, its silicone-like material, an observer that keeps
//! every sample, and the scenes: a free rod with an obstacle (on a table,
//! across an incline), a rope over a cylinder. Each file keeps its own
//! settings.
#![allow(dead_code)]

use softrod::{EnergyBalance, Flow, Observer, Sample, Simulation};
use softrod_dynamics::{Attachment, Joint, JointKind, Model, Rod};
use softrod_kinematics::Strain;
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::contact::{Obstacle, Shape};
use softrod_mechanics::{LoadFrame, Material, PointLoad};

/// Radius of the test rods \[m\].
pub const R: f64 = 0.01;
/// Length of the test rods \[m\].
pub const L: f64 = 0.2;
/// Gravity \[m/s²\].
pub const G: f64 = 9.81;
/// Density of the test rods \[kg/m³\].
pub const RHO: f64 = 1000.0;

/// An incompressible (ν = 0.5) material of density [`RHO`], Young's
/// modulus `young` \[Pa\] and Kelvin–Voigt viscosity `viscosity` \[Pa s\].
pub fn material(young: f64, viscosity: f64) -> Material {
    Material::builder()
        .density(RHO)
        .young(young)
        .poisson(0.5)
        .viscosity(viscosity)
        .build()
        .unwrap()
}

/// The silicone of most tests: E = 1 MPa, no viscosity.
pub fn silicone() -> Material {
    material(1.0e6, 0.0)
}

/// Every sample of a run: `(t, q, q̇)`.
pub struct Keep(pub Vec<(f64, Vec<f64>, Vec<f64>)>);

impl Observer for Keep {
    fn sample(&mut self, s: Sample<'_>) -> Result<Flow, String> {
        self.0.push((s.t, s.q.to_vec(), s.qd.to_vec()));
        Ok(Flow::Continue)
    }
}

/// A plane obstacle `name` through `point` with unit `normal`.
pub fn plane(name: &str, point: Vec3, normal: Vec3) -> Obstacle {
    Obstacle::new(name, Shape::Plane { point, normal })
}

/// A free rod (6-dof joint to the world) named "rod", of length [`L`] and
/// radius [`R`] along its base's x, 4 pieces bending in `Ky`, `Kz`,
/// E = 1 MPa and `viscosity`, with the point loads `loads`, gravity −z
/// and `obstacle`.
pub fn free_rod_model(
    base: Pose,
    obstacle: Obstacle,
    loads: &[PointLoad],
    viscosity: f64,
) -> Model {
    let mut rod = Rod::builder(L)
        .name("rod")
        .pieces(4)
        .strains([Strain::Ky, Strain::Kz])
        .base(base)
        .circle(R)
        .material(material(1.0e6, viscosity));
    for l in loads {
        rod = rod.point_load(*l);
    }
    Model::builder()
        .rod_on(rod, Attachment::world_joint(Joint::new(JointKind::Free)))
        .gravity([0.0, 0.0, -G])
        .obstacle(obstacle)
        .build()
        .unwrap()
}

/// A rod of length [`L`] lying across an incline of angle `alpha` (the
/// plane through the origin): the base pose that puts its centreline at
/// [`R`] above the plane along y, centred on the origin, the plane's
/// normal and the direction down the slope.
pub fn across_incline(alpha: f64) -> (Pose, Vec3, Vec3) {
    let n = Vec3::new(alpha.sin(), 0.0, alpha.cos());
    let down = Vec3::new(alpha.cos(), 0.0, -alpha.sin());
    let rot = Mat3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
    (Pose::new(rot, n * R - Vec3::y() * (0.5 * L)), n, down)
}

/// Radius of the rope of [`rope_over_cylinder_model`] \[m\].
pub const ROPE_RADIUS: f64 = 0.002;

/// A rope (radius [`ROPE_RADIUS`], 0.2 m, 16 pieces bending in `Ky` and
/// stretching) clamped level on top of a cylinder of radius 3 cm (axis y
/// through the origin, friction `mu`), a 1 N weight at its tip, gravity −z.
pub fn rope_over_cylinder_model(mu: f64) -> Model {
    let (r, rc, l) = (ROPE_RADIUS, 0.03, 0.2);
    let base = Pose::new(Mat3::identity(), Vec3::new(-0.5 * l, 0.0, rc + r));
    let rope = Rod::builder(l)
        .name("rope")
        .pieces(16)
        .strains([Strain::Ky, Strain::Qx])
        .base(base)
        .circle(r)
        .material(material(1.0e6, 0.0))
        .point_load(PointLoad {
            s: l,
            force: Vec3::new(0.0, 0.0, -1.0),
            moment: Vec3::zeros(),
            frame: LoadFrame::World,
        });
    let cylinder = Obstacle::new(
        "capstan",
        Shape::Cylinder {
            point: Vec3::zeros(),
            axis: Vec3::y(),
            radius: rc,
        },
    )
    .friction(mu);
    Model::builder()
        .rod(rope)
        .obstacle(cylinder)
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap()
}

/// The centre `s = L/2` of the rod named "rod" at `q` \[m, world\].
pub fn centre(sim: &Simulation, q: &[f64]) -> Vec3 {
    sim.pose("rod", 0.5 * L, q).unwrap().translation
}

/// Runs `sim` for `duration` s (its settings must keep the energy watch
/// on) and returns how far the rod's centre moved along `down` at each
/// sample \[s, m\], with the run's energy balance.
pub fn path_along(
    sim: &mut Simulation,
    duration: f64,
    down: Vec3,
) -> (Vec<(f64, f64)>, EnergyBalance) {
    let mut keep = Keep(Vec::new());
    let summary = sim.simulate_with(duration, &mut keep).unwrap();
    let c0 = centre(sim, &keep.0[0].1);
    let path = keep
        .0
        .iter()
        .map(|(t, q, _)| (*t, (centre(sim, q) - c0).dot(&down)))
        .collect();
    (path, summary.energy.expect("the energy watch"))
}
