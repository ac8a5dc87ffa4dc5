//! Statics of closed models with contact (docs/theory-contact.md CT16):
//! the equilibrium against the moment balance of rigid statics and the
//! penetration bound of CT15.

use softrod_dynamics::{
    Attachment, Closure, ClosureFrame, ClosureKind, Data, Joint, Model, Rod, StaticsOptions,
    closure_statics,
};
use softrod_kinematics::Strain;
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::contact::{Obstacle, Shape};
use softrod_mechanics::{LoadFrame, Material, PointLoad};

const R: f64 = 0.01;
const L: f64 = 0.2;
const G: f64 = 9.81;
const RHO: f64 = 1000.0;

/// A rod lying on a frictionless table (its rest shape touches at zero
/// gap), hinged at its base by a revolute joint about y, its tip held on
/// a vertical line by a slider closure and pressed down by `load` \[N\]:
/// statics from the rest shape. The joint carries no moment about its
/// axis and the slider's force is horizontal (normal to its axis), so the
/// table's forces balance the moments of the weight, the load and the
/// slider's force `|λ|` at the tip's drop `Δz` below the hinge:
/// `|Σ x_i f_z,i − (m g x̄ + F x_tip)| = |λ| |Δz|` — and with CT15's
/// raises every contact sinks less than 1 % of the radius (7 % at the
/// base stiffness). The rod stretches (`q_x`): inextensible, it could not
/// reach the table at all (its chord would have to shrink below the
/// hinge-to-slider distance `L`), the closed solve stalls at load
/// fraction 0 (the slider's multiplier grows without bound).
#[test]
fn a_hinged_rod_held_by_a_slider_presses_on_a_table_with_the_moment_of_its_loads() {
    let load = 2.0;
    let rod = Rod::builder(L)
        .name("rod")
        .pieces(6)
        .strains([Strain::Ky, Strain::Kz, Strain::Qx])
        .base(Pose::new(Mat3::identity(), Vec3::new(0.0, 0.0, R)))
        .circle(R)
        .material(
            Material::builder()
                .density(RHO)
                .young(1e6)
                .poisson(0.5)
                .build()
                .unwrap(),
        )
        .point_load(PointLoad {
            s: L,
            force: Vec3::new(0.0, 0.0, -load),
            moment: Vec3::zeros(),
            frame: LoadFrame::World,
        });
    let model = Model::builder()
        .rod_on(
            rod,
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
        )
        .gravity([0.0, 0.0, -G])
        .obstacle(Obstacle::new(
            "table",
            Shape::Plane {
                point: Vec3::zeros(),
                normal: Vec3::z(),
            },
        ))
        .closure(Closure::new(
            "slider",
            ClosureKind::Slider { axis: Vec3::z() },
            ClosureFrame::on("rod", None, Pose::identity()),
            ClosureFrame::world(Pose::new(Mat3::identity(), Vec3::new(L, 0.0, R))),
        ))
        .build()
        .unwrap();
    let mut data = Data::new(&model);
    let rest = vec![0.0; model.n_dof()];
    let (res, lambda) =
        closure_statics(&model, &mut data, &rest, &StaticsOptions::default()).unwrap();
    eprintln!(
        "statics: {} iterations, {} load steps, residual {:.2e}",
        res.iterations, res.load_steps, res.residual
    );
    let q = res.q.as_slice();
    let zero = vec![0.0; q.len()];
    let contacts = model.contacts_with(&mut data, 0.0, q, &zero).unwrap();
    let moment: f64 = contacts.iter().map(|c| c.point.x * c.force.z).sum();
    let mass = RHO * std::f64::consts::PI * R * R * L;
    let n = 200;
    let mut frames = Data::new(&model);
    let mut pos = |s: f64| {
        softrod_dynamics::section_jacobian(&model, &mut frames, q, 0, s)
            .unwrap()
            .0
            .translation
    };
    let xbar = (0..=n)
        .map(|i| {
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * pos(L * i as f64 / n as f64).x
        })
        .sum::<f64>()
        / (3.0 * n as f64);
    let want = mass * G * xbar + load * pos(L).x;
    // The slider's force is horizontal (normal to its vertical axis), at
    // the tip's height: its moment about the hinge is at most |λ| times
    // the tip's drop below the hinge.
    let lever = lambda.norm() * (pos(L).z - R).abs();
    let err = (moment - want).abs();
    eprintln!(
        "moment {moment:.6e} N m, loads' {want:.6e} (error {err:.1e}, slider's lever {lever:.1e}), λ {lambda:?}, drop {:.3e}",
        pos(L).z - R
    );
    assert!((err - lever).abs() < 1e-6 * want, "{moment} vs {want}");
    let deepest = contacts.iter().fold(0.0f64, |m, c| m.max(-c.gap));
    eprintln!("deepest {:.3e} of r", deepest / R);
    assert!(deepest < 0.01 * R, "{deepest}");
}
