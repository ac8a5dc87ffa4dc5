//! Times forward dynamics on the rod of the criterion bench (all six strains,
//! N pieces, 4 Gauss points, gravity + elasticity + damping); handy under
//! `valgrind --tool=callgrind` where criterion is too slow (`WHAT` = `fd`,
//! `id`, `mm`, `shifted` or `did` for forward, inverse dynamics, the mass
//! matrix, one factor + solve of `M + aK + bD` or the analytic pair
//! `∂τ/∂q, ∂τ/∂q̇`; `BASIS=planar` selects the strains
//! `ky, qx, qz` on every piece instead of all six, and `PLANAR_PATH=off`
//! runs such a rod on the general se(3) path; `JOINT=revolute` hangs the
//! rod from a revolute joint, the tree path):
//! `N_PIECES=10 N_ITER=2000 cargo run --release -p softrod-dynamics --example fd_timing`.
use softrod_dynamics::{
    Data, IdDerivatives, Model, Rod, ShiftedSolver, forward_dynamics, inverse_dynamics,
    inverse_dynamics_derivatives, mass_matrix,
};
use softrod_kinematics::{Basis, RodGeometry, Strain, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{Material, RodProperties, Section};

fn env(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    let n = env("N_PIECES", 10);
    let iters = env("N_ITER", 20000);
    let planar = std::env::var("BASIS").as_deref() == Ok("planar");
    let basis = if planar {
        Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap()
    } else {
        Basis::all()
    };
    // Position of each coordinate's strain in (kx, ky, kz, qx, qy, qz), so
    // the planar state draws curvatures and stretches as the full one does.
    let component = |i: usize| if planar { [1, 3, 5][i % 3] } else { i % 6 };
    let rod = RodGeometry::uniform(0.5, n, basis, straight(), Pose::identity()).unwrap();
    let material = Material::builder()
        .density(1000.0)
        .young(1e7)
        .shear_modulus(1e7 / 3.0)
        .viscosity(1.0)
        .build()
        .unwrap();
    let body = RodProperties::new(Section::Circle { radius: 0.01 }, material, 0.5).unwrap();
    // JOINT=revolute: the same rod on a revolute joint (the tree path).
    let elements = vec![softrod_dynamics::Element::Rod(
        Rod::new("arm", rod, body),
        if std::env::var("JOINT").as_deref() == Ok("revolute") {
            softrod_dynamics::Attachment::world_joint(softrod_dynamics::Joint::revolute([
                0.0, 1.0, 0.0,
            ]))
        } else {
            softrod_dynamics::Attachment::world()
        },
    )];
    let model = Model::with_elements(elements, Some(Vec3::new(0.0, 0.0, -9.81)), 4)
        .unwrap()
        .with_planar_path(std::env::var("PLANAR_PATH").as_deref() != Ok("off"));
    let mut data = Data::new(&model);
    let (q, qd): (Vec<f64>, Vec<f64>) = if std::env::var("STATE").as_deref() == Ok("bench") {
        let mut st: u64 = 7;
        let mut next = || {
            st = st.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = st;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        };
        let q = (0..model.n_dof())
            .map(|i| if component(i) < 3 { 2.0 } else { 0.02 } * next())
            .collect();
        let qd = (0..model.n_dof()).map(|_| next()).collect();
        (q, qd)
    } else {
        (
            (0..model.n_dof())
                .map(|i| if component(i) < 3 { 0.3 } else { 0.01 } * ((i * 7 % 5) as f64 - 2.0))
                .collect(),
            (0..model.n_dof())
                .map(|i| 0.1 * ((i * 3 % 7) as f64 - 3.0))
                .collect(),
        )
    };
    let what = std::env::var("WHAT").unwrap_or_else(|_| "fd".into());
    let qdd = vec![0.5; model.n_dof()];
    let t0 = std::time::Instant::now();
    let mut acc = 0.0;
    let mut solver = ShiftedSolver::new(&model);
    let mut derivs = IdDerivatives::new(&model);
    let mut x = qd.clone();
    for _ in 0..iters {
        acc += match what.as_str() {
            "id" => inverse_dynamics(&model, &mut data, 0.0, &q, &qd, &qdd).unwrap()[0],
            "mm" => mass_matrix(&model, &mut data, &q).unwrap()[(0, 0)],
            "did" => {
                inverse_dynamics_derivatives(&model, &mut derivs, 0.0, &q, &qd, &qdd)
                    .unwrap()
                    .dtau_dq[(0, 0)]
            }
            "shifted" => {
                solver.factor(&model, &q, 2.5e-7, 5e-4).unwrap();
                x.copy_from_slice(&qd);
                solver.solve(&model, &mut x).unwrap();
                x[0]
            }
            _ => forward_dynamics(&model, &mut data, 0.0, &q, &qd, None).unwrap()[0],
        };
    }
    println!(
        "N = {n}: {:.2} µs per {what} (checksum {acc:.6e})",
        t0.elapsed().as_secs_f64() / iters as f64 * 1e6
    );
}
