//! Every integrator on a closed model (the parallel robot of
//! examples/parallel_robot.toml): they take the constrained q̈ of
//! `forward_dynamics` (and finite-difference Jacobians of it), and the
//! closure residual stays small.

use softrod::Simulation;
use softrod::dynamics::{Data, max_closure_residual};
use softrod::scene::Integrator;

const SCENE: &str = include_str!("../../../examples/parallel_robot.toml");

#[test]
fn every_integrator_runs_a_closed_model_and_keeps_the_loop_closed() {
    for integrator in [
        Integrator::Rk4,
        Integrator::Dopri5,
        Integrator::Rosenbrock,
        Integrator::GeneralizedAlpha,
        Integrator::Esdirk,
        Integrator::Radau5,
    ] {
        let (mut sim, _, _) = Simulation::from_toml(SCENE, "parallel_robot.toml").unwrap();
        let mut settings = sim.settings().clone().with_integrator(integrator);
        settings.dt = 5e-6;
        settings.rtol = 1e-5;
        settings.atol = 1e-8;
        sim.set_settings(settings).unwrap();
        let traj = sim
            .simulate(0.005)
            .unwrap_or_else(|e| panic!("{integrator:?}: {e}"));
        let model = sim.model().clone();
        let mut data = Data::new(&model);
        let worst = traj
            .q
            .iter()
            .map(|q| max_closure_residual(&model, &mut data, q.as_slice()).unwrap())
            .fold(0.0, f64::max);
        // 1e-6 of the legs' length (the CLI's warning level).
        assert!(worst < 3e-7, "{integrator:?}: closure residual {worst:e} m");
        // It moved: the sideways load pushes the platform.
        let x0 = traj.tips[0][1].translation[0];
        let x1 = traj.tips.last().unwrap()[1].translation[0];
        assert!(x1 - x0 > 2e-6, "{integrator:?}: {x0} → {x1}");
    }
}
