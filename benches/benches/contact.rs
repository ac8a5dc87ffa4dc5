//! Criterion bench of contact at rest (issue 24, docs/theory-contact.md
//! CT15, docs/performance.md "Contact"): a free 20-piece rod (r = 1 cm,
//! L = 0.5 m, E = 1 MPa) lying on a table, integrated 0.5 s with the
//! default integrator and settings of `Simulation`, against the same rod
//! free in the air (no table). The target of issue 24: the rod on the
//! table integrates with steps no smaller than the free rod's. The steps
//! each run takes are printed before the timings.
//!
//! `cargo bench -p softrod-benches --bench contact -- --warm-up-time 1 --measurement-time 5`

use criterion::{Criterion, criterion_group, criterion_main};
use softrod::Simulation;
use softrod_dynamics::{Attachment, Joint, JointKind, Model, Rod};
use softrod_kinematics::Strain;
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::Material;
use softrod_mechanics::contact::{Obstacle, Shape};

const R: f64 = 0.01;
const DURATION: f64 = 0.5;

fn rod(table: bool) -> Simulation {
    let rod = Rod::builder(0.5)
        .name("rod")
        .pieces(20)
        .strains([Strain::Ky, Strain::Kz])
        .base(Pose::new(Mat3::identity(), Vec3::new(0.0, 0.0, R)))
        .circle(R)
        .material(
            Material::builder()
                .density(1000.0)
                .young(1.0e6)
                .poisson(0.5)
                .build()
                .unwrap(),
        );
    let mut b = Model::builder()
        .rod_on(rod, Attachment::world_joint(Joint::new(JointKind::Free)))
        .gravity([0.0, 0.0, -9.81]);
    if table {
        b = b.obstacle(Obstacle::new(
            "table",
            Shape::Plane {
                point: Vec3::zeros(),
                normal: Vec3::z(),
            },
        ));
    }
    Simulation::new(b.build().unwrap())
}

fn bench_rest(c: &mut Criterion) {
    for (name, table) in [("free", false), ("on_table", true)] {
        let mut sim = rod(table);
        let t = sim.simulate(DURATION).unwrap();
        eprintln!(
            "contact_rest/{name}: {} steps, {} rejected, {} Jacobians over {DURATION} s",
            t.summary.stats.steps,
            t.summary.stats.rejected_steps,
            t.summary.stats.jacobian_evaluations
        );
    }
    let mut g = c.benchmark_group("contact_rest");
    g.sample_size(10);
    for (name, table) in [("free", false), ("on_table", true)] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut sim = rod(table);
                sim.simulate(DURATION).unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_rest);
criterion_main!(benches);
