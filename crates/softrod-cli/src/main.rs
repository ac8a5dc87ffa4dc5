//! `softrod`: simulate soft manipulators (PCS Cosserat rods) from a scene file.
//!
//! Exit codes: 0 success, 1 simulation failure (reason on stderr), 2 bad input
//! (the scene error names file:line:col and the key path).

mod common;
mod inspect;
mod plots;
mod report;
mod robot;
mod run;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

const LONG_ABOUT: &str = "\
softrod simulates soft robot arms, tentacles and cable-driven continuum robots
with the Piecewise Constant Strain (PCS) Cosserat-rod model. A scene is a TOML
file (rods, sections, materials, cables, loads, run settings; SI units); the
format is described in docs/scene-format.md.

Example:
  softrod check   examples/cantilever_gravity.toml      # what the model holds
  softrod statics examples/tip_load_statics.toml --json # equilibrium as JSON
  softrod run     examples/cantilever_gravity.toml      # -> out/cantilever_gravity/
  softrod modes   examples/cantilever_gravity.toml      # natural frequencies

Exit codes: 0 success, 1 simulation failure, 2 bad input.";

#[derive(Parser, Debug)]
#[command(name = "softrod", version, about = "Simulate soft robot arms (PCS Cosserat rods) from a TOML scene", long_about = LONG_ABOUT)]
struct Cli {
    /// No progress bar and no informational messages on stderr.
    #[arg(long, short, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Validate a scene and print a summary: DoF, rods, pieces, strains, terms, warnings.
    Check {
        /// The scene file (TOML).
        scene: PathBuf,
    },
    /// Static equilibrium under gravity, loads and cables (Newton with load continuation).
    #[command(
        long_about = "Static equilibrium under gravity, point loads and cables at t = 0, \
        by Newton's method with line search and load continuation, from [initial].q \
        (or the rest shape).\n\nExample:\n  softrod statics examples/tip_load_statics.toml --json"
    )]
    Statics {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Print one JSON object (converged, iterations, residual, q, tip, rods) on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Integrate the dynamics; write trajectory.csv, shape.csv, summary.json and SVG plots.
    #[command(
        long_about = "Integrate the dynamics with the scene's [run] settings (integrator, \
        tolerances, duration, output_every). Writes DIR/trajectory.csv (streamed row by row), \
        DIR/shape.csv, DIR/summary.json (also on failure) and SVG plots: tip_trajectory.svg, \
        energy.svg, shapes.svg.\n\nExample:\n  softrod run examples/cantilever_gravity.toml --out /tmp/cantilever"
    )]
    Run {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output directory (default: ./out/STEM, STEM being the scene file name without its extension).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Natural frequencies of the model linearized about its static equilibrium.
    #[command(
        long_about = "Undamped natural frequencies, lowest first, about the static \
        equilibrium under the scene's static loads (gravity, loads, cables), or about the \
        rest shape when there are none.\n\nExample:\n  softrod modes examples/cantilever_gravity.toml --json"
    )]
    Modes {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Print `{ "frequencies_hz": [...], "equilibrium": "rest" | "statics" }`.
        #[arg(long)]
        json: bool,
        /// How many frequencies to print (all if the model has fewer).
        #[arg(long, default_value_t = 10)]
        count: usize,
    },
    /// Work-precision report: error against wall time over pieces, quadrature, integrators, tolerances.
    #[command(
        long_about = "Sweeps the scene's configurations and measures wall time (median of 3 \
        repeats, 1 with --quick) and the tip error at the final time and over the run.\n\n\
        Dynamics: a spatial study (pieces x1, x2, x4 of the scene's, quadrature 2, 4, 6, at a tight \
        tolerance, against pieces x8 with quadrature 6) and a temporal study (the scene's pieces; \
        dopri5 and rosenbrock over tolerances, generalized-alpha over steps, against a tight \
        reference run with the same pieces), both references stated in the report; a scene's \
        [reference] tip is compared as well. Statics: pieces and quadrature against [reference] \
        tip, or against pieces x8.\n\n\
        Writes DIR/report.md, DIR/report.csv, DIR/report.svg (log-log work-precision, one curve \
        per integrator, Pareto front marked) and DIR/report_spatial.svg.\n\n\
        Example:\n  softrod report examples/cantilever_gravity.toml --quick --out /tmp/report"
    )]
    Report {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output directory (default: ./out/STEM, STEM being the scene file name without its extension).
        #[arg(long)]
        out: Option<PathBuf>,
        /// One repeat per configuration instead of three, shorter time budgets.
        #[arg(long)]
        quick: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let quiet = cli.quiet;
    let result = match cli.command {
        Command::Check { scene } => inspect::check(&scene),
        Command::Statics { scene, json } => inspect::statics(&scene, json),
        Command::Run { scene, out } => run::run(&scene, out, quiet),
        Command::Modes { scene, json, count } => inspect::modes(&scene, json, count),
        Command::Report { scene, out, quick } => {
            report::report(&scene, out, report::ReportOptions { quick, quiet })
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("softrod: {e}");
            ExitCode::from(e.code())
        }
    }
}
