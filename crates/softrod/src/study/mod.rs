//! Work–precision studies of a scene: how the error of the first rod's tip
//! trades against wall time over pieces, quadrature, integrators and
//! tolerances (or steps), with the spatial (PCS pieces) and temporal
//! (integrator) error sources measured separately. `softrod report` is a
//! front end over [`dynamics_study`] and [`statics_study`]: it formats
//! the [`Row`]s as tables and draws them; nothing here prints or writes.
//!
//! Dynamics scenes ([`dynamics_study`]):
//!
//! - **spatial study**: pieces ×{1, 2, 4} of the scene's, quadrature
//!   {2, 4, 6}, each with generalized-α at a small fixed step, against the
//!   Richardson extrapolation of the ×2 and ×4 runs at quadrature 6 (PCS
//!   converges at order 2 in the piece length);
//! - **temporal study**: the scene's pieces and quadrature; dopri5,
//!   rosenbrock and esdirk over tolerances, generalized-α over steps,
//!   against a tight reference run at the same pieces;
//! - an analytic `[reference] tip` (at `[reference] time`, default the end)
//!   is compared with every run as well.
//!
//! Statics scenes ([`statics_study`]) sweep pieces and quadrature against
//! `[reference] tip`, or against pieces ×8, quadrature 6 when the scene has
//! none.
//!
//! Errors are distances of the first rod's tip: at the final time and the
//! largest over [`N_COMPARE`]` + 1` evenly spaced comparison times. Wall
//! time is the median of the repeats (3, or 1 with
//! [`StudyOptions::quick`]).

mod dynamics;
mod runs;
mod statics;

pub use dynamics::{Analytic, DynamicsStudy, Spatial, Tight, dynamics_study};
pub use runs::{dist, max_dist, variant};
pub use statics::{StaticsStudy, statics_study};

use softrod_integrate::Stats;

/// Comparison intervals over the run (`N_COMPARE + 1` times, both ends
/// included).
pub const N_COMPARE: usize = 50;

/// How a study runs.
#[derive(Clone, Copy, Debug, Default)]
pub struct StudyOptions {
    /// One repeat instead of three, and smaller wall-time budgets.
    pub quick: bool,
}

impl StudyOptions {
    /// Repeats per configuration (wall time is their median).
    pub fn repeats(&self) -> usize {
        if self.quick { 1 } else { 3 }
    }
}

/// One configuration's result.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Tip of the first rod at the comparison times \[m\].
    pub tips: Vec<[f64; 3]>,
    /// The integrator's work (statics: `steps` = Newton iterations).
    pub stats: Stats,
    /// Median wall seconds over the repeats.
    pub wall: f64,
}

/// A row of a study: one configuration, its outcome and its errors.
#[derive(Clone, Debug)]
pub struct Row {
    /// `spatial`, `temporal` or `statics`.
    pub study: &'static str,
    /// The integrator (`newton` for statics).
    pub integrator: String,
    /// Its setting (`rtol 1e-4`, `dt 1.000e-3`, `2 load step(s)`).
    pub setting: String,
    /// Pieces over all rods.
    pub pieces: usize,
    /// Gauss points per piece.
    pub quadrature: usize,
    /// The outcome, or why the configuration failed.
    pub result: Result<Outcome, String>,
    /// Tip error at the final time \[m\].
    pub err_final: f64,
    /// Largest tip error over the comparison times \[m\].
    pub err_max: f64,
    /// Tip error against the scene's `[reference] tip` \[m\].
    pub err_analytic: Option<f64>,
    /// Whether the row is on the wall–error Pareto front.
    pub pareto: bool,
}

impl Row {
    /// Median wall seconds, NaN for a failed row.
    pub fn wall(&self) -> f64 {
        self.result.as_ref().map_or(f64::NAN, |o| o.wall)
    }
}

/// Marks the rows on the wall–error Pareto front (no other row is both
/// faster and more accurate), by `err_max`.
pub fn mark_pareto(rows: &mut [Row]) {
    let mut idx: Vec<usize> = (0..rows.len())
        .filter(|&i| rows[i].result.is_ok() && rows[i].err_max.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        let (wa, wb) = (rows[a].wall(), rows[b].wall());
        wa.total_cmp(&wb)
            .then(rows[a].err_max.total_cmp(&rows[b].err_max))
    });
    let mut best = f64::INFINITY;
    for i in idx {
        if rows[i].err_max < best {
            best = rows[i].err_max;
            rows[i].pareto = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use softrod_scene::Scene;

    fn row(w: f64, e: f64) -> Row {
        Row {
            study: "t",
            integrator: "x".into(),
            setting: String::new(),
            pieces: 1,
            quadrature: 4,
            result: Ok(Outcome {
                tips: vec![],
                stats: Stats::default(),
                wall: w,
            }),
            err_final: e,
            err_max: e,
            err_analytic: None,
            pareto: false,
        }
    }

    #[test]
    fn pareto_front_keeps_the_undominated() {
        let mut rows = vec![
            row(1.0, 1e-3),
            row(2.0, 1e-2),
            row(0.5, 1e-2),
            row(3.0, 1e-6),
        ];
        mark_pareto(&mut rows);
        let marks: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        assert_eq!(marks, vec![true, false, true, true]);
    }

    /// Coulomb's law: a rod on a 20° incline with μ = 0.5 > tan 20° stays
    /// where it was put. The study's runs must commit the contact state
    /// after accepted steps as `softrod run` does: without the friction
    /// anchors (CT5) the rod slid 1.7 cm in 0.1 s, the frictionless
    /// g sin 20° t²/2.
    #[test]
    fn a_study_run_sticks_where_coulomb_friction_holds() {
        let (a, b) = (20f64.to_radians().sin(), 20f64.to_radians().cos());
        let text = format!(
            "[world]\ngravity = [0.0, 0.0, -9.81]\n\
             [[rod]]\nname = \"rod\"\nlength = 0.2\npieces = 4\nstrains = [\"ky\", \"kz\"]\n\
             joint = {{ type = \"free\" }}\n\
             base = {{ position = [{px:?}, -0.1, {pz:?}], rotation = [[0, -1, 0], [1, 0, 0], [0, 0, 1]] }}\n\
             section = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}\n\
             [[obstacle]]\nname = \"slope\"\nshape = \"plane\"\nposition = [0.0, 0.0, 0.0]\n\
             normal = [{a:?}, 0.0, {b:?}]\nfriction = 0.5\n",
            px = 0.01 * a,
            pz = 0.01 * b,
        );
        let (scene, _) = Scene::from_str(&text, "incline.toml").unwrap();
        let built = scene.build().unwrap();
        let opts = softrod_integrate::Options {
            rtol: 1e-6,
            atol: 1e-8,
            ..Default::default()
        };
        let times = [0.0, 0.05, 0.1];
        let out = runs::simulate(
            &built,
            softrod_integrate::Integrator::Esdirk,
            &opts,
            &times,
            60.0,
            1,
        )
        .unwrap();
        let moved = dist(&out.tips[0], &out.tips[2]);
        assert!(moved < 1e-4, "the rod moved {moved} m");
    }

    #[test]
    fn variant_splits_pieces_and_repeats_initial_values() {
        let text = "[[rod]]\nname = \"a\"\nlength = 0.4\npieces = 2\nstrains = [\"ky\", \"qx\"]\n\
                    section = { shape = \"circle\", radius = 0.01 }\n\
                    material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n\
                    [initial]\nq = [1.0, 0.1, 2.0, 0.2]\n";
        let (s, _) = Scene::from_str(text, "t.toml").unwrap();
        let v = variant(&s, 4, 6).unwrap();
        assert_eq!(v.rods[0].geometry.n_pieces(), 8);
        assert_eq!(v.run.quadrature, 6);
        assert!(
            v.rods[0]
                .geometry
                .piece_lengths()
                .all(|l| (l - 0.05).abs() < 1e-15)
        );
        let q = v.initial.q.clone().unwrap();
        assert_eq!(q.len(), 16);
        assert_eq!(&q[..2], &[1.0, 0.1]);
        assert_eq!(&q[6..8], &[1.0, 0.1]);
        assert_eq!(&q[8..10], &[2.0, 0.2]);
        assert!(v.build().is_ok());
    }
}
