//! `softrod report`: work–precision of a scene over pieces, quadrature,
//! integrators and tolerances (or steps), with the spatial (PCS pieces) and
//! temporal (integrator) error sources measured separately.
//!
//! Dynamics scenes:
//!
//! - **spatial study**: pieces ×{1, 2, 4} of the scene's, quadrature
//!   {2, 4, 6}, each at a tight tolerance, against a finer reference
//!   (pieces ×8, quadrature 6, same tight integrator);
//! - **temporal study**: the scene's pieces and quadrature; dopri5 and
//!   rosenbrock and esdirk over tolerances, generalized-α over steps, against the
//!   reference integrator at the same pieces;
//! - an analytic `[reference] tip` (at `[reference] time`, default the end) is
//!   compared with every run as well.
//!
//! Statics scenes sweep pieces and quadrature against `[reference] tip`, or
//! against pieces ×8, quadrature 6 when the scene has none.
//!
//! Errors are distances of the first rod's tip: at the final time and the
//! largest over evenly spaced comparison times. Wall time is the median of
//! the repeats (3, or 1 with `--quick`).

mod chart;
mod dynamics;
mod runs;
mod statics;
mod table;

use std::path::{Path, PathBuf};

use softrod_scene::{Mode, Scene};

use crate::common::{CliError, failed, load, out_dir};
use dynamics::dynamics_report;
use statics::statics_report;

/// Comparison intervals over the run (N_COMPARE + 1 times, both ends included).
pub(super) const N_COMPARE: usize = 50;

/// How `softrod report` runs.
#[derive(Clone, Copy, Debug)]
pub struct ReportOptions {
    /// One repeat instead of three, and smaller time budgets.
    pub quick: bool,
    /// No progress messages, no table on stdout.
    pub quiet: bool,
}

pub(super) fn write(dir: &Path, name: &str, text: &str) -> Result<(), CliError> {
    let p = dir.join(name);
    std::fs::write(&p, text).map_err(|e| failed(format!("cannot write {}: {e}", p.display())))
}

pub fn report(path: &Path, out: Option<PathBuf>, o: ReportOptions) -> Result<(), CliError> {
    let l = load(path)?;
    let dir = out_dir(path, out);
    crate::outputs::prepare_out_dir(&dir)?;
    let md = match l.scene.run.mode {
        Mode::Statics => statics_report(&l.scene, &dir, o)?,
        Mode::Dynamics => dynamics_report(&l.scene, &dir, o)?,
    };
    write(&dir, "report.md", &md)?;
    if !o.quiet {
        print!("{md}");
    }
    Ok(())
}

/// The command that regenerates a report (stated in it).
pub(super) fn command(scene: &Scene, o: ReportOptions) -> String {
    format!(
        "softrod report {}{}",
        scene.source,
        if o.quick { " --quick" } else { "" }
    )
}

#[cfg(test)]
mod tests {
    use super::runs::{Outcome, variant};
    use super::table::{Row, mark_pareto};
    use softrod_integrate::Stats;
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

    #[test]
    fn variant_splits_pieces_and_repeats_initial_values() {
        let text = "[[rod]]\nname = \"a\"\nlength = 0.4\npieces = 2\nstrains = [\"ky\", \"qx\"]\n\
                    section = { shape = \"circle\", radius = 0.01 }\n\
                    material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n\
                    [initial]\nq = [1.0, 0.1, 2.0, 0.2]\n";
        let (s, _) = Scene::from_str(text, "t.toml").unwrap();
        let v = variant(&s, 4, 6).unwrap();
        assert_eq!(v.rods[0].rod.n_pieces(), 8);
        assert_eq!(v.run.quadrature, 6);
        assert!(
            v.rods[0]
                .rod
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
