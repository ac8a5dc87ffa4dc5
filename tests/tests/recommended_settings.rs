//! The recommended settings ([`Recommended::tolerance`]) never fail on the
//! scenes of issue 13, at sizes a test affords: the planar release against
//! the published table of docs/theory.md §8(h) at rtol 1e-3 … 1e-8, the 3-D
//! release against DOPRI5 at rtol 1e-10, the undamped steel wire against
//! Radau IIA at rtol 1e-10, energy on the undamped release, and every
//! shipped example (shortened) against Radau IIA at a tight tolerance. The
//! full-size runs are in `benches/examples/integrate_study.rs`.

use std::path::Path;

use nalgebra::DVector;
use softrod_dynamics::{Model, Rod, energies};
use softrod_integrate::{
    Integrator, NoHooks, Options, Recommended, RodSystem, Solution, Status, integrate_second_order,
};
use softrod_kinematics::{Basis, RodGeometry, RodKinematics, Strain, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{Material, RodProperties, Section};

const RTOLS: [f64; 6] = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8];

fn cantilever(
    (length, radius, density, young, poisson): (f64, f64, f64, f64, f64),
    pieces: usize,
    basis: Basis,
    gauss: usize,
) -> Model {
    let rod = RodGeometry::uniform(length, pieces, basis, straight(), Pose::identity()).unwrap();
    let mat = Material::with_poisson(density, young, poisson, 0.0).unwrap();
    let body = RodProperties::new(Section::Circle { radius }, mat, length).unwrap();
    Model::new(
        vec![Rod::new("rod", rod, body)],
        Some(Vec3::new(0.0, 0.0, -9.81)),
        gauss,
    )
    .unwrap()
}

/// The soft cantilever of issue 13 and docs/theory.md §8(h).
const SOFT: (f64, f64, f64, f64, f64) = (0.5, 0.01, 1000.0, 1e7, 0.5);
/// The steel wire of issue 13: E = 200 GPa, r = 1 mm, L = 1 m (ρ = 7800,
/// ν = 0.3).
const STEEL: (f64, f64, f64, f64, f64) = (1.0, 1e-3, 7800.0, 2e11, 0.3);

fn run(
    model: &Model,
    setting: &Recommended,
    q0: &DVector<f64>,
    qd0: &DVector<f64>,
    times: &[f64],
) -> (RodSystem, Solution) {
    let mut sys = RodSystem::new(model.clone());
    setting.configure(&mut sys);
    let opts = setting.options.clone().with_t_eval(times.to_vec());
    let t1 = *times.last().unwrap();
    let sol = integrate_second_order(
        &mut sys,
        setting.integrator,
        (0.0, t1),
        q0,
        qd0,
        &opts,
        &mut NoHooks,
    )
    .unwrap_or_else(|e| {
        panic!(
            "{:?} rtol {}: {e}",
            setting.integrator, setting.options.rtol
        )
    });
    assert_eq!(sol.status, Status::Completed);
    (sys, sol)
}

fn from_rest(model: &Model, setting: &Recommended, times: &[f64]) -> (RodSystem, Solution) {
    let z = DVector::zeros(model.n_dof());
    run(model, setting, &z, &z, times)
}

/// Tip positions (first rod) of the outputs.
fn tips(model: &Model, sol: &Solution) -> Vec<[f64; 3]> {
    let rod = &model.rods()[0].spec.geometry;
    // The first rod's own coordinates (scenes with joints put them first).
    let dofs = model.rods()[0].dofs();
    let mut kin = RodKinematics::new(rod);
    sol.y
        .iter()
        .map(|y| {
            kin.update(rod, &y.as_slice()[dofs.clone()], None, None)
                .unwrap();
            let p = kin.tip_pose().translation;
            [p.x, p.y, p.z]
        })
        .collect()
}

fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

fn linspace(t1: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|k| t1 * k as f64 / n as f64).collect()
}

/// The tip error of the recommended setting stays within this many times
/// `rtol` (in metres; the rods are 0.3–1 m long): measured 0.1–2.5× on the
/// issue's releases and up to 12× on the shipped three-section arm (four
/// strains, cables) at the sizes below, so 20× fails a setting that stops
/// tracking its tolerance while a run that tracks it passes on every scene.
const TRACKING: f64 = 20.0;

#[test]
fn planar_release_tracks_rtol_against_the_published_table() {
    // docs/theory.md §8(h): tip (x, z) at t = 0.25, 0.5, 1 s, to 1e-9 m.
    const TABLE: [(f64, f64, f64); 3] = [
        (0.25, 0.366446853, -0.314312480),
        (0.50, 0.342225557, -0.338455217),
        (1.00, 0.391295819, -0.286765539),
    ];
    // Table digits (5e-10) plus the reference's own error (5e-11).
    const TABLE_TOL: f64 = 1e-9;
    let basis = Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap();
    let model = cantilever(SOFT, 8, basis, 5);
    let times: Vec<f64> = TABLE.iter().map(|r| r.0).collect();
    for rtol in RTOLS {
        let (_, sol) = from_rest(&model, &Recommended::tolerance(rtol), &times);
        let tip = tips(&model, &sol);
        let err = tip
            .iter()
            .zip(TABLE)
            .map(|(p, (_, x, z))| ((p[0] - x).powi(2) + (p[2] - z).powi(2)).sqrt())
            .fold(0.0, f64::max);
        println!(
            "planar, rtol {rtol:e}: tip error {err:.2e} m, {:?}",
            sol.stats
        );
        assert!(err <= TRACKING * rtol + TABLE_TOL, "rtol {rtol}: {err}");
    }
}

#[test]
fn three_d_release_tracks_rtol_against_dopri5() {
    // 8 pieces, all six strains, the first 0.1 s (the fastest part of the
    // swing: the tip falls ~5 cm); outputs every 2 ms.
    let model = cantilever(SOFT, 8, Basis::all(), 4);
    let times = linspace(0.1, 50);
    let reference = Recommended {
        integrator: Integrator::Dopri5,
        options: Options {
            max_steps: 10_000_000,
            ..Options::tol(1e-10, 1e-12)
        },
        jacobian: Default::default(),
    };
    let (_, rs) = from_rest(&model, &reference, &times);
    let rt = tips(&model, &rs);
    for rtol in RTOLS {
        let (_, sol) = from_rest(&model, &Recommended::tolerance(rtol), &times);
        let err = max_dist(&tips(&model, &sol), &rt);
        println!("3-D, rtol {rtol:e}: tip error {err:.2e} m, {:?}", sol.stats);
        // DOPRI5 at 1e-10 is within ~1e-9 m (its tolerance over 0.1 s).
        assert!(err <= TRACKING * rtol + 1e-9, "rtol {rtol}: {err}");
    }
}

#[test]
fn steel_wire_agrees_with_radau_iia() {
    // 10 pieces, all strains, undamped: shear/extension at ~1e6 rad/s, the
    // bending under gravity at ~10 rad/s. The first 0.05 s.
    let model = cantilever(STEEL, 10, Basis::all(), 4);
    let times = linspace(0.05, 25);
    let reference = Recommended {
        integrator: Integrator::Radau5,
        options: Options {
            max_steps: 10_000_000,
            ..Options::tol(1e-10, 1e-10)
        },
        jacobian: Default::default(),
    };
    let (_, rs) = from_rest(&model, &reference, &times);
    let rt = tips(&model, &rs);
    for rtol in RTOLS {
        let (_, sol) = from_rest(&model, &Recommended::tolerance(rtol), &times);
        let err = max_dist(&tips(&model, &sol), &rt);
        println!(
            "steel wire, rtol {rtol:e}: tip error {err:.2e} m, {:?}",
            sol.stats
        );
        // Radau IIA at 1e-10 (internally 1e-8 local) is within ~1e-9 m.
        assert!(err <= TRACKING * rtol + 1e-8, "rtol {rtol}: {err}");
    }
}

#[test]
fn undamped_release_keeps_its_energy() {
    // The L-stable method damps only what it does not resolve (the
    // shear/extension ringing, a tiny share of the energy): the total energy
    // of the undamped 3-D release (E(0) = 0) stays within a multiple of
    // rtol of the largest energy seen, and never grows beyond it.
    let model = cantilever(SOFT, 6, Basis::all(), 4);
    let times = linspace(0.5, 100);
    for rtol in [1e-4, 1e-6] {
        let (mut sys, sol) = from_rest(&model, &Recommended::tolerance(rtol), &times);
        let n = model.n_dof();
        let mut scale: f64 = 0.0;
        let mut worst: f64 = 0.0;
        for y in &sol.y {
            let e = energies(
                &sys.model,
                &mut sys.data,
                &y.as_slice()[..n],
                &y.as_slice()[n..],
            )
            .unwrap();
            scale = scale.max(e.kinetic.abs()).max(e.gravitational.abs());
            worst = worst.max(e.total().abs());
        }
        println!(
            "energy, rtol {rtol:e}: max |E − E(0)| / scale = {:.2e}",
            worst / scale
        );
        // Measured 1.0e-5 (rtol 1e-4) and 2.1e-7 (1e-6): the energy error
        // tracks rtol like the tip.
        assert!(
            worst / scale <= TRACKING * rtol,
            "rtol {rtol}: {}",
            worst / scale
        );
    }
}

/// Every shipped example (`examples/*.toml`), its first 0.1 s, with the
/// recommended setting at the scene's own `rtol` and at 1e-3 and 1e-7,
/// against Radau IIA at 1e-10.
#[test]
fn shipped_examples_run_and_agree_with_radau_iia() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 5, "{paths:?}");
    for path in paths {
        let (scene, _) = softrod_scene::Scene::from_path(&path).unwrap();
        if scene.run.mode != softrod_scene::Mode::Dynamics {
            continue;
        }
        let built = scene.build().unwrap();
        let t1 = scene.run.duration.min(0.1);
        let times = linspace(t1, 20);
        let reference = Recommended {
            integrator: Integrator::Radau5,
            options: Options {
                max_steps: 10_000_000,
                ..Options::tol(1e-10, 1e-10)
            },
            jacobian: Default::default(),
        };
        let (_, rs) = run(&built.model, &reference, &built.q0, &built.qd0, &times);
        let rt = tips(&built.model, &rs);
        for rtol in [scene.run.rtol, 1e-3, 1e-7] {
            let (_, sol) = run(
                &built.model,
                &Recommended::tolerance(rtol),
                &built.q0,
                &built.qd0,
                &times,
            );
            let err = max_dist(&tips(&built.model, &sol), &rt);
            println!(
                "{}: rtol {rtol:e}: tip error {err:.2e} m, {:?}",
                path.file_name().unwrap().to_string_lossy(),
                sol.stats
            );
            assert!(err <= TRACKING * rtol + 1e-8, "{path:?} rtol {rtol}: {err}");
        }
    }
}
