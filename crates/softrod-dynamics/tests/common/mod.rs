//! Model builders and a seeded generator shared by the test files of the
//! shifted solve and the derivatives (every test file compiles this module
//! on its own, so not every item is used by each).
#![allow(dead_code)]

pub mod closed;

use nalgebra::{DMatrix, DVector, Matrix6xX};
use softrod_dynamics::{
    Attachment, BodyLoad, BodySpec, Curve, Data, Element, Joint, Model, Prescribed, Rod,
    RodBuilder, forward_dynamics,
};
use softrod_kinematics::{Basis, PieceSpec, RodGeometry, Strain};
use softrod_lie::{Mat3, Pose, Vec3, Vec6, exp_twist};
use softrod_mechanics::{
    Cable, DistributedLoad, Drag, LoadFrame, Material, PointLoad, RodProperties, Routing, Section,
    Tension,
};

/// Small deterministic generator (tests must be reproducible), uniform in [−1, 1).
pub struct Lcg(pub u64);
impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
    }
    pub fn vec(&mut self, n: usize, scale: f64) -> Vec<f64> {
        (0..n).map(|_| scale * self.next()).collect()
    }
}

/// Every kind of basis: all six, single strain, planar, a 3-strain
/// selection, Kirchhoff, a permuted 5-strain selection, general 6×4 and
/// 6×6 matrices (not selections).
pub fn bases() -> Vec<Basis> {
    vec![
        Basis::all(),
        Basis::select(&[Strain::Ky]).unwrap(),
        Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap(),
        Basis::select(&[Strain::Kx, Strain::Kz, Strain::Qy]).unwrap(),
        Basis::kirchhoff(),
        Basis::select(&[Strain::Qz, Strain::Kx, Strain::Qx, Strain::Kz, Strain::Ky]).unwrap(),
        Basis::from_matrix(Matrix6xX::from_fn(4, |i, j| {
            ((i * 4 + j) as f64 * 0.9 + 0.3).sin() + if i == j { 1.5 } else { 0.0 }
        }))
        .unwrap(),
        Basis::from_matrix(Matrix6xX::from_fn(6, |i, j| {
            ((i * 6 + j) as f64 * 0.7).cos() * 0.4 + if i == j { 1.0 } else { 0.0 }
        }))
        .unwrap(),
    ]
}

/// Which force terms a test model carries.
#[derive(Clone, Copy, Debug)]
pub struct Terms {
    pub gravity: bool,
    pub damping: bool,
    /// Dead (world-frame) point loads, one at the tip and one inside a piece.
    pub dead_point: bool,
    /// A follower (body-frame) point load inside a piece.
    pub follower_point: bool,
    /// A world-frame and a body-frame distributed load.
    pub distributed: bool,
    pub cable: bool,
    pub drag: bool,
}

impl Terms {
    pub const NONE: Terms = Terms {
        gravity: false,
        damping: false,
        dead_point: false,
        follower_point: false,
        distributed: false,
        cable: false,
        drag: false,
    };
    pub const ALL: Terms = Terms {
        gravity: true,
        damping: true,
        dead_point: true,
        follower_point: true,
        distributed: true,
        cable: true,
        drag: true,
    };
}

/// How the pieces of a test rod are shaped.
#[derive(Clone, Debug)]
pub struct Shape {
    pub pieces: usize,
    pub length: f64,
    /// Bases cycle through these.
    pub bases: Vec<Basis>,
    pub tapered: bool,
    /// Rest strain of every piece.
    pub rest: Vec6,
    /// Young's modulus [Pa].
    pub young: f64,
}

impl Shape {
    pub fn new(pieces: usize, bases: Vec<Basis>) -> Self {
        Self {
            pieces,
            length: 0.4,
            bases,
            tapered: false,
            rest: Vec6::new(0.1, 0.5, -0.3, 1.0, 0.0, 0.0),
            young: 2e6,
        }
    }
}

/// One rod: precurved rest strain, tilted base, soft silicone-like material.
pub fn rod_spec(name: &str, shape: &Shape, terms: Terms, base: Pose) -> Rod {
    let length = shape.length;
    let specs: Vec<PieceSpec> = (0..shape.pieces)
        .map(|i| PieceSpec {
            length: length / shape.pieces as f64,
            basis: shape.bases[i % shape.bases.len()].clone(),
            rest_strain: shape.rest,
        })
        .collect();
    let rod = RodGeometry::from_pieces(specs, base).unwrap();
    let viscosity = if terms.damping { 30.0 } else { 0.0 };
    let section = if shape.tapered {
        Section::TaperedCircle {
            radius_base: 0.016,
            radius_tip: 0.006,
        }
    } else {
        Section::Circle { radius: 0.012 }
    };
    let body = RodProperties::new(
        section,
        Material::with_poisson(1100.0, shape.young, 0.45, viscosity).unwrap(),
        length,
    )
    .unwrap();
    let mut spec = Rod::new(name, rod, body);
    if terms.dead_point {
        spec.point_loads.push(PointLoad {
            s: length,
            force: Vec3::new(0.1, -0.2, 0.3),
            moment: Vec3::new(0.01, 0.0, -0.02),
            frame: LoadFrame::World,
        });
        spec.point_loads.push(PointLoad {
            s: 0.61 * length,
            force: Vec3::new(0.07, 0.05, -0.1),
            moment: Vec3::new(0.0, -0.01, 0.015),
            frame: LoadFrame::World,
        });
    }
    if terms.follower_point {
        spec.point_loads.push(PointLoad {
            s: 0.37 * length,
            force: Vec3::new(-0.05, 0.1, 0.0),
            moment: Vec3::new(0.0, 0.01, 0.0),
            frame: LoadFrame::Body,
        });
    }
    if terms.distributed {
        spec.distributed_loads = vec![
            DistributedLoad {
                force: Vec3::new(0.0, 0.3, 0.1),
                moment: Vec3::new(0.0, 0.0, 0.02),
                frame: LoadFrame::World,
            },
            DistributedLoad {
                force: Vec3::new(0.0, 0.0, -0.2),
                moment: Vec3::new(0.01, 0.0, 0.0),
                frame: LoadFrame::Body,
            },
        ];
    }
    if terms.drag {
        spec.drag = Some(Drag {
            translational: 0.5,
            rotational: 1e-3,
        });
    }
    if terms.cable {
        spec.cables = vec![
            Cable::new(
                Routing::Path(vec![[0.0, 0.008, 0.0], [length, 0.002, 0.004]]),
                Tension::Constant(1.5),
            )
            .between(0.0, 0.8 * length),
            Cable::new(
                Routing::Offset {
                    y: -0.004,
                    z: 0.006,
                },
                Tension::Constant(0.7),
            )
            .between(0.2 * length, length),
        ];
    }
    spec
}

/// The base pose of the test rods (tilted and offset).
pub fn tilted_base() -> Pose {
    exp_twist(1.0, &Vec6::new(0.2, -0.4, 0.1, 0.0, 0.05, 0.1))
}

/// Oblique gravity, so that no component vanishes by symmetry.
pub fn gravity(terms: Terms) -> Option<Vec3> {
    terms.gravity.then(|| Vec3::new(0.3, -1.0, -9.81))
}

/// A one-rod model.
pub fn model(shape: &Shape, terms: Terms) -> Model {
    Model::new(
        vec![rod_spec("arm", shape, terms, tilted_base())],
        gravity(terms),
        4,
    )
    .unwrap()
}

/// Two rods from different bases: one with mixed bases, one tapered
/// Cosserat rod; Young's modulus `young` [Pa].
pub fn two_rods(n: usize, terms: Terms, young: f64) -> Model {
    let mut a = Shape::new(n, bases());
    a.young = young;
    let mut b = Shape::new(n + 1, vec![Basis::all()]);
    b.tapered = true;
    b.young = young;
    let second_base = exp_twist(1.0, &Vec6::new(-0.3, 0.2, 0.6, 0.1, -0.2, 0.05));
    Model::new(
        vec![
            rod_spec("first", &a, terms, tilted_base()),
            rod_spec("second", &b, terms, second_base),
        ],
        gravity(terms),
        4,
    )
    .unwrap()
}

/// A curved, moving state: strains within ±`q_scale` of the rest strain,
/// rates within ±`qd_scale`, accelerations within ±`qdd_scale`.
pub fn state(
    rng: &mut Lcg,
    n: usize,
    q_scale: f64,
    qd_scale: f64,
    qdd_scale: f64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    (
        rng.vec(n, q_scale),
        rng.vec(n, qd_scale),
        rng.vec(n, qdd_scale),
    )
}

/// Fourth-order central differences (Richardson on steps `h` and `h/2`) of
/// `eval(q, q̇)` in `q` and in `q̇`, column by column. Steps: `h = 1e-3·max(1,
/// |q_j|)` in `q` (truncation O(h⁴)); `h = 0.5·max(1, |q̇_j|)` in `q̇`, where
/// the dynamics is exactly quadratic, so central differences are exact for
/// any step and a large one keeps the round-off at ~ε‖eval‖ (a small one
/// would amplify the elastic part, ~1e4 × the velocity derivatives, by 1/h).
pub fn richardson_jacobians(
    q: &[f64],
    qd: &[f64],
    mut eval: impl FnMut(&[f64], &[f64]) -> DVector<f64>,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = q.len();
    let mut dq = DMatrix::zeros(n, n);
    let mut dqd = DMatrix::zeros(n, n);
    for j in 0..n {
        for (which, out) in [(0, &mut dq), (1, &mut dqd)] {
            let x0 = if which == 0 { q[j] } else { qd[j] };
            let h = if which == 0 { 1e-3 } else { 0.5 } * x0.abs().max(1.0);
            let mut d = |h: f64| {
                let (mut a, mut b) = (q.to_vec(), qd.to_vec());
                let (mut c, mut e) = (q.to_vec(), qd.to_vec());
                if which == 0 {
                    a[j] += h;
                    c[j] -= h;
                } else {
                    b[j] += h;
                    e[j] -= h;
                }
                (eval(&a, &b) - eval(&c, &e)) / (2.0 * h)
            };
            let d1 = d(h);
            let d2 = d(h / 2.0);
            out.set_column(j, &((d2 * 4.0 - d1) / 3.0));
        }
    }
    (dq, dqd)
}

/// [`richardson_jacobians`] of the production `inverse_dynamics` at fixed
/// `q̈` (τ is exactly quadratic in `q̇`: the large `q̇` step only meets
/// round-off, see there).
pub fn id_differences(
    m: &Model,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> (DMatrix<f64>, DMatrix<f64>) {
    let mut data = Data::new(m);
    richardson_jacobians(q, qd, |q, qd| {
        softrod_dynamics::inverse_dynamics(m, &mut data, t, q, qd, qdd)
            .unwrap()
            .clone()
    })
}

/// Largest entry error relative to the largest entry of the reference `b`.
pub fn rel(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1e-300)
}

/// An incompressible soft material (ν = 0.5) of Young's modulus `young`
/// \[Pa\] and `density` \[kg/m³\].
pub fn soft_material(young: f64, density: f64) -> Material {
    Material::builder()
        .density(density)
        .young(young)
        .poisson(0.5)
        .build()
        .unwrap()
}

/// The robots' test rod: `pieces` equal pieces over `length` \[m\], all
/// six strains, a 1 cm circle, E = 1 MPa, ρ = 1000 kg/m³.
pub fn soft_rod(name: &str, length: f64, pieces: usize) -> RodBuilder {
    Rod::builder(length)
        .name(name)
        .pieces(pieces)
        .circle(0.01)
        .material(soft_material(1e6, 1000.0))
}

/// A deterministic, varied vector (no special configuration):
/// `scale · sin(1.7 (i + 1) + seed)`.
pub fn wavy(n: usize, scale: f64, seed: f64) -> Vec<f64> {
    (0..n)
        .map(|i| scale * ((i as f64 + 1.0) * 1.7 + seed).sin())
        .collect()
}

/// One classical RK4 step of `(q, q̇)` from time `t` with the O(N) forward
/// dynamics (time-dependent: cables, prescribed joints).
pub fn rk4_step(
    model: &Model,
    data: &mut Data,
    t: f64,
    q: &mut DVector<f64>,
    v: &mut DVector<f64>,
    dt: f64,
) {
    let mut acc = |t: f64, q: &DVector<f64>, v: &DVector<f64>| {
        forward_dynamics(model, data, t, q.as_slice(), v.as_slice(), None)
            .unwrap()
            .clone()
    };
    let a1 = acc(t, q, v);
    let (q2, v2) = (&*q + &*v * (dt / 2.0), &*v + &a1 * (dt / 2.0));
    let a2 = acc(t + dt / 2.0, &q2, &v2);
    let (q3, v3) = (&*q + &v2 * (dt / 2.0), &*v + &a2 * (dt / 2.0));
    let a3 = acc(t + dt / 2.0, &q3, &v3);
    let (q4, v4) = (&*q + &v3 * dt, &*v + &a3 * dt);
    let a4 = acc(t + dt, &q4, &v4);
    *q += (&*v + &v2 * 2.0 + &v3 * 2.0 + &v4) * (dt / 6.0);
    *v += (&a1 + &a2 * 2.0 + &a3 * 2.0 + &a4) * (dt / 6.0);
}

/// The O(N) `ShiftedSolver` against a dense Cholesky of
/// `M(q) + aK + bD` assembled from `mass_matrix`, `stiffness_matrix` and
/// `damping_matrix`, for shifts from none to the stiff extreme: returns the
/// largest backward error `‖S x − r‖∞ / (‖S‖∞ ‖x‖∞)` and the largest forward
/// error relative to `ε·cond(S)` (the solves are backward stable, so both
/// are O(1) multiples of ε when the recursion is right; a missing coupling
/// or armature term shows at O(1e-3 … 1)).
pub fn shifted_against_dense(model: &Model, q: &[f64], seed: u64) -> (f64, f64) {
    use softrod_dynamics::{ShiftedSolver, damping_matrix, mass_matrix, stiffness_matrix};
    let mut rng = Lcg(seed);
    let mut solver = ShiftedSolver::new(model);
    let mut data = Data::new(model);
    let mass = mass_matrix(model, &mut data, q).unwrap().clone();
    let (k, d) = (stiffness_matrix(model), damping_matrix(model));
    let (mut backward, mut forward): (f64, f64) = (0.0, 0.0);
    for (a, b) in [
        (0.0, 0.0),
        (1e-6, 1e-4),
        (1e-4, 1e-2),
        (1.0, 1.0),
        (1e6, 1e3),
    ] {
        let s = &mass + &k * a + &d * b;
        let r = DVector::from_vec(rng.vec(model.n_dof(), 1.0));
        solver.factor(model, q, a, b).unwrap();
        let mut x = r.as_slice().to_vec();
        solver.solve(model, &mut x).unwrap();
        let x = DVector::from_vec(x);
        let norm = s.row_iter().map(|r| r.abs().sum()).fold(0.0, f64::max);
        backward = backward.max((&s * &x - &r).amax() / (norm * x.amax()));
        let ev = s.clone().symmetric_eigen().eigenvalues;
        let cond = ev.max() / ev.min();
        let reference = s.cholesky().expect("S is SPD").solve(&r);
        forward = forward.max((&x - &reference).amax() / reference.amax() / (f64::EPSILON * cond));
    }
    (backward, forward)
}

/// Every joint type, bodies on rods, rods on bodies, a child at a piece
/// boundary and at a rod's base, springs and dampers, body loads. With
/// `tree`, a second branch at the first rod's tip (M2).
pub fn robot(gravity: bool, damping: bool, tree: bool, loads: bool) -> Model {
    let spring = |j: Joint, k: usize| {
        if damping {
            j.with_stiffness(&vec![0.3; k])
                .with_damping(&vec![0.01; k])
                .with_rest(&vec![0.1; k])
        } else {
            j.with_stiffness(&vec![0.3; k]).with_rest(&vec![0.1; k])
        }
    };
    let mut hand = BodySpec::new(
        "hand",
        0.03,
        Mat3::new(2e-5, 1e-6, 0.0, 1e-6, 3e-5, 2e-6, 0.0, 2e-6, 2.5e-5),
    );
    hand.center_of_mass = Vec3::new(0.01, -0.005, 0.002);
    hand.base = Pose::new(
        *nalgebra::Rotation3::from_euler_angles(0.1, -0.2, 0.3).matrix(),
        Vec3::new(0.01, 0.0, 0.0),
    );
    if loads {
        hand.loads.push(BodyLoad {
            force: Vec3::new(0.01, 0.0, -0.02),
            moment: Vec3::new(0.0, 0.001, 0.0),
            frame: LoadFrame::Body,
        });
    }
    let mut slider = BodySpec::principal("slider", 0.02, [1e-5, 2e-5, 1.5e-5]);
    slider.center_of_mass = Vec3::new(0.0, 0.01, 0.0);
    let mut b = Model::builder()
        .rod_on(
            soft_rod("upper", 0.3, 2),
            Attachment::world_joint(spring(Joint::revolute([0.0, 1.0, 0.2]), 1)),
        )
        .body(hand, Attachment::to("upper", spring(Joint::spherical(), 3)))
        .rod_on(
            soft_rod("finger", 0.2, 2).strains([Strain::Ky, Strain::Kz, Strain::Qx]),
            Attachment::to(
                "hand",
                spring(Joint::universal([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]), 2),
            ),
        )
        .body(
            slider,
            Attachment::to("finger", spring(Joint::prismatic([1.0, 0.0, 0.0]), 1)).at(0.1),
        )
        .rod_on(
            soft_rod("drone", 0.25, 2).base(Pose::new(Mat3::identity(), Vec3::new(0.0, 0.3, 0.0))),
            Attachment::world_joint(spring(Joint::free(), 6)),
        );
    if tree {
        b = b
            .rod_on(
                soft_rod("branch", 0.2, 2),
                Attachment::to("upper", Joint::revolute([0.0, 0.0, 1.0])).at(0.15),
            )
            .rod_on(
                soft_rod("root_twin", 0.15, 1),
                Attachment::to("upper", Joint::fixed()).at(0.0),
            )
            .body(
                BodySpec::principal("weight", 0.01, [1e-6, 1e-6, 1e-6]),
                Attachment::to("hand", Joint::fixed()),
            );
    }
    if gravity {
        b = b.gravity([0.3, -1.0, -9.81]);
    }
    b.build().unwrap()
}

/// `cosh β cos β + 1 = 0` (clamped–free beam), Newton from a guess.
pub fn cantilever_root(mut b: f64) -> f64 {
    for _ in 0..50 {
        let f = b.cosh() * b.cos() + 1.0;
        let df = b.sinh() * b.cos() - b.cosh() * b.sin();
        b -= f / df;
    }
    b
}

/// Leading-order Ritz error constant of mode `β` (with `βL` given): for
/// piecewise-constant curvature the best energy approximation of the mode's
/// curvature `φ''` is its piece mean, missing `(h²/12)∫φ'''²`; so
/// `δλ/λ ≈ (h²/12) ∫φ'''²/∫φ''²` and `δω/ω ≈ C/N²` with
/// `C = (L²/24) ∫φ'''²/∫φ''²`, evaluated here by Simpson on the analytic
/// Euler–Bernoulli mode shape.
pub fn ritz_constant(bl: f64) -> f64 {
    let sigma = (bl.cosh() + bl.cos()) / (bl.sinh() + bl.sin());
    // Dimensionless u = s/L ∈ [0,1]; derivatives up to powers of β that cancel in the ratio.
    let d2 = |u: f64| {
        let z = bl * u;
        z.cosh() + z.cos() - sigma * (z.sinh() + z.sin())
    };
    let d3 = |u: f64| {
        let z = bl * u;
        bl * (z.sinh() - z.sin() - sigma * (z.cosh() + z.cos()))
    };
    let m = 20_000;
    let (mut a, mut b) = (0.0, 0.0);
    for i in 0..=m {
        let u = i as f64 / m as f64;
        let w = if i == 0 || i == m {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        a += w * d3(u).powi(2);
        b += w * d2(u).powi(2);
    }
    a / b / 24.0
}

/// A trunk on a revolute joint with a spring and a damper, a branch on a
/// universal joint inside its second piece, and at its tip a rod on a
/// prescribed prismatic joint (a sine drive), every rod with cables and
/// dead loads (`Terms::ALL`), under gravity.
pub fn driven_tree() -> Model {
    let trunk = rod_spec(
        "trunk",
        &Shape::new(3, vec![Basis::all()]),
        Terms::ALL,
        tilted_base(),
    );
    let mut bs = Shape::new(2, bases());
    bs.length = 0.2;
    let branch = rod_spec("branch", &bs, Terms::ALL, Pose::identity());
    let mut ts = Shape::new(2, vec![Basis::all()]);
    ts.length = 0.15;
    let tail = rod_spec("tail", &ts, Terms::ALL, Pose::identity());
    let drive =
        Joint::prismatic([0.0, 1.0, 0.3]).with_prescribed(Prescribed::new(vec![Curve::Sine {
            amplitude: 0.02,
            frequency: 1.3,
            phase: 0.4,
            offset: 0.01,
        }]));
    Model::with_elements(
        vec![
            Element::Rod(
                trunk,
                Attachment::world_joint(
                    Joint::revolute([0.0, 1.0, 0.3])
                        .with_stiffness(&[0.2])
                        .with_damping(&[0.01]),
                ),
            ),
            Element::Rod(
                branch,
                Attachment::to("trunk", Joint::universal([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]))
                    .at(0.17),
            ),
            Element::Rod(tail, Attachment::to("trunk", drive)),
        ],
        Some(softrod_lie::Vec3::new(0.0, 0.0, -9.81)),
        4,
    )
    .unwrap()
}
