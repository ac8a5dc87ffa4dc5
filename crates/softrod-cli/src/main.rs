//! `softrod`: simulate soft manipulators (PCS Cosserat rods) from a scene file.
//!
//! Exit codes: 0 success, 1 simulation failure (reason on stderr), 2 bad input
//! (the scene error names file:line:col and the key path).

#![forbid(unsafe_code)]

mod closures;
mod common;
mod contact;
mod inspect;
mod inverse;
mod linearize;
mod npz;
mod outputs;
mod plots;
mod report;
mod robot;
mod run;
mod signals;

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
  softrod run     examples/cantilever_gravity.toml --set run.integrator=radau5 --set run.duration=0.5

Exit codes: 0 success, 1 simulation failure, 2 bad input.";

#[derive(Parser, Debug)]
#[command(name = "softrod", version, about = "Simulate soft robot arms (PCS Cosserat rods) from a TOML scene", long_about = LONG_ABOUT)]
struct Cli {
    /// No progress bar and no informational messages on stderr.
    #[arg(long, short, global = true)]
    quiet: bool,
    /// Override one scene setting without editing the file, e.g.
    /// `--set run.integrator=esdirk --set cable[0].tension=2.0` (repeatable;
    /// the value is TOML, a bare word a string). Applied before validation,
    /// so it is checked as if written in the file, under the same key path.
    #[arg(long = "set", global = true, value_name = "KEY=VALUE")]
    set: Vec<softrod_scene::Override>,
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
        /// Also write the equilibrium's shape plot, DIR/statics_shape.svg.
        #[arg(long)]
        out: Option<PathBuf>,
        /// With --out, also write DIR/statics_shape.png (same size; text in a system font).
        #[arg(long, requires = "out")]
        png: bool,
    },
    /// Cable tensions that bring the scene's target sections to their targets (inverse statics).
    #[command(
        long_about = "Inverse statics: the cable tensions within 0 <= T <= max_tension and the \
        static equilibrium that bring the sections of the scene's [[target]] tables closest to \
        their positions and rotations, the least effort among equally close ones \
        (docs/theory-control.md). Prints the tensions, the reached poses, the residual and \
        which bounds are active. Exit 2 on bad input, 1 if the iteration did not converge; a \
        target out of reach is not a failure: the closest reachable shape is printed and said \
        to be so.\n\nExample:\n  softrod inverse examples/cable_arm_inverse.toml --json"
    )]
    Inverse {
        /// The scene file (TOML), with target tables.
        scene: PathBuf,
        /// Print one JSON object (converged, reached, message, tensions, cables, targets,
        /// residual, q, rods) on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Integrate the dynamics; write trajectory.csv, shape.csv, summary.json and SVG plots.
    #[command(
        long_about = "Integrate the dynamics with the scene's [run] settings (integrator, \
        tolerances, duration, output_every). Writes DIR/trajectory.csv (streamed row by row), \
        DIR/shape.csv, DIR/summary.json (also on failure) and SVG plots: tip_trajectory.svg, \
        energy.svg, shapes.svg, strains.svg, actuators.svg (with cables), and the 3-D view \
        DIR/view.html (with view.json, see `softrod view`). With --npz also DIR/trajectory.npz \
        (NumPy arrays of the same rows, with the column names).\n\nExample:\n  softrod run examples/cantilever_gravity.toml --out /tmp/cantilever"
    )]
    Run {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output directory (default: ./out/STEM, STEM being the scene file name without its extension).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Times (s) of the shapes and strain profiles drawn, e.g. `--snapshots 0,0.25,1`
        /// (each at the nearest output time; default six spread over the run).
        #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
        snapshots: Option<Vec<f64>>,
        /// Also write DIR/trajectory.npz: the trajectory as NumPy arrays (`t`, `q`, `qdot`,
        /// `tip`, `energy`, with cables `tension`/`power`, with prescribed joints
        /// `prescribed`/`prescribed_force`) and the column names `q_names` (`prescribed_names`),
        /// for `numpy.load`; see docs/scene-format-extensions.md.
        #[arg(long)]
        npz: bool,
        /// Also write a PNG beside each SVG figure (same size; text in a system font).
        #[arg(long)]
        png: bool,
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
        /// Also write the mode shapes (the lowest, up to 6), DIR/modes.svg.
        #[arg(long)]
        out: Option<PathBuf>,
        /// With --out, also write DIR/modes.png (same size; text in a system font).
        #[arg(long, requires = "out")]
        png: bool,
    },
    /// Rebuild DIR/view.html, the animated 3-D view, from a run directory's files.
    #[command(
        long_about = "Rebuilds DIR/view.html (one self-contained page: play/pause, time slider, \
        speed, orbit/zoom/pan, rods as tubes of their radius, cables, tip trace) from \
        DIR/shape.csv, DIR/view.json and DIR/bodies.csv, and prints its path to open in a \
        browser.\n\nExample:\n  softrod view out/cantilever_gravity"
    )]
    View {
        /// A directory written by `softrod run`.
        dir: PathBuf,
    },
    /// State-space model (A, B) of the dynamics about the static equilibrium.
    #[command(
        long_about = "Linearization x' = A x + B u of the dynamics about the static \
        equilibrium under the scene's static loads (about the rest shape when there are \
        none), from the analytic derivatives: x = (q, qdot), u = the cable tensions [N]. \
        Prints the state and input ordering, and A and B for small models (all of them with \
        --json: { equilibrium, t, state, inputs, q, u, xdot_residual, A, B }, A and B as \
        lists of rows).\n\nExample:\n  softrod linearize examples/cable_planar_arm.toml --json"
    )]
    Linearize {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Print one JSON object on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Work-precision report: error against wall time over pieces, quadrature, integrators, tolerances.
    #[command(
        long_about = "Sweeps the scene's configurations and measures wall time (median of 3 \
        repeats, 1 with --quick) and the tip error at the final time and over the run.\n\n\
        Dynamics: a spatial study (pieces x1, x2, x4 of the scene's, quadrature 2, 4, 6, at a tight \
        tolerance, against pieces x8 with quadrature 6) and a temporal study (the scene's pieces; \
        dopri5, rosenbrock and esdirk over tolerances, generalized-alpha over steps, against a tight \
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

/// Exit status of a command whose standard output was closed under it
/// (`softrod check SCENE | head`): 128 + SIGPIPE, what a shell reports for
/// a writer the signal ended.
const EXIT_BROKEN_PIPE: i32 = 141;

/// A closed standard output ends the command quietly: Rust ignores SIGPIPE,
/// so `println!` panics on the broken pipe (and restoring the signal needs
/// unsafe code, which the workspace denies). Every other panic is reported
/// as before.
fn quiet_on_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let msg = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.starts_with("failed printing to stdout") && msg.contains("Broken pipe") {
            std::process::exit(EXIT_BROKEN_PIPE);
        }
        default(info);
    }));
}

fn main() -> ExitCode {
    quiet_on_broken_pipe();
    let cli = Cli::parse();
    let quiet = cli.quiet;
    if !cli.set.is_empty() && matches!(cli.command, Command::View { .. }) {
        eprintln!("softrod: --set applies to a scene; `softrod view` reads a run directory");
        return ExitCode::from(2);
    }
    common::set_overrides(cli.set);
    let result = match cli.command {
        Command::Check { scene } => inspect::check(&scene),
        Command::Statics {
            scene,
            json,
            out,
            png,
        } => inspect::statics(&scene, json, out, png),
        Command::Run {
            scene,
            out,
            snapshots,
            npz,
            png,
        } => run::run(&scene, out, snapshots, quiet, npz, png),
        Command::Modes {
            scene,
            json,
            count,
            out,
            png,
        } => inspect::modes(&scene, json, count, out, png),
        Command::Inverse { scene, json } => inverse::inverse(&scene, json),
        Command::View { dir } => run::view(&dir, quiet),
        Command::Linearize { scene, json } => linearize::linearize(&scene, json),
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
