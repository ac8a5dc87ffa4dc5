//! The dynamics report: the temporal study (integrators and tolerances
//! against a tight reference run) and the spatial study (pieces and
//! quadrature against a Richardson-extrapolated reference).

use std::fmt::Write as _;
use std::path::Path;

use softrod::GENERALIZED_ALPHA_RHO_INF;
use softrod_integrate::{Integrator, Options};
use softrod_scene::{Built, Scene};

use super::chart::work_precision_svg;
use super::runs::{Outcome, Tight, build_variant, dist, max_dist, pieces, simulate};
use super::table::{CSV_HEADER, Row, csv_rows, mark_pareto, md_table, sci, wall};
use super::{N_COMPARE, ReportOptions, command, write};
use crate::common::{CliError, failed};

/// One temporal-study configuration: integrator name, setting text,
/// method and options.
type Config = (&'static str, String, Integrator, Options);

/// The analytic reference of a scene: tip (m), time (s), note.
type Analytic = ([f64; 3], f64, Option<String>);

/// How the report runs and talks.
struct Ctx<'a> {
    scene: &'a Scene,
    o: ReportOptions,
    repeats: usize,
    budget: f64,
    ref_budget: f64,
    /// The comparison times.
    times: Vec<f64>,
    n0: usize,
    q0: usize,
}

impl Ctx<'_> {
    fn say(&self, m: String) {
        if !self.o.quiet {
            eprintln!("softrod report: {m}");
        }
    }
}

/// The spatial study and its reference.
struct Spatial {
    rows: Vec<Row>,
    reference: Vec<[f64; 3]>,
    observed_order: f64,
    /// The fixed step of its runs, s.
    dt: f64,
}

pub(super) fn dynamics_report(
    scene: &Scene,
    dir: &Path,
    o: ReportOptions,
) -> Result<String, CliError> {
    let repeats = if o.quick { 1 } else { 3 };
    let budget = if o.quick { 10.0 } else { 60.0 };
    let ref_budget = if o.quick { 120.0 } else { 300.0 };
    let (times, analytic, t_analytic) = comparison_times(scene);
    let ctx = Ctx {
        scene,
        o,
        repeats,
        budget,
        ref_budget,
        times,
        n0: pieces(scene),
        q0: scene.run.quadrature,
    };
    let last = ctx.times.len() - 1;
    let base = build_variant(scene, 1, ctx.q0)?;
    let mut temporal = temporal_study(&ctx, &base, temporal_configs(scene.run.duration));
    let (tight, temporal_ref, notes) = temporal_reference(&ctx, &base, &temporal)?;
    let err_an = |tips: &[[f64; 3]]| {
        analytic
            .as_ref()
            .zip(t_analytic)
            .map(|((tip, ..), i)| dist(&tips[i], tip))
    };
    let mut sp = spatial_study(&ctx)?;
    let spatial_ref = &sp.reference;
    let sp_temporal = sp
        .rows
        .iter()
        .find(|r| r.pieces == ctx.n0 && r.quadrature == ctx.q0)
        .and_then(|r| r.result.as_ref().ok())
        .map(|o| max_dist(&o.tips, &temporal_ref.tips))
        .unwrap_or(f64::NAN);
    for r in &mut sp.rows {
        if let Ok(out) = &r.result {
            r.err_final = dist(&out.tips[last], &spatial_ref[last]);
            r.err_max = max_dist(&out.tips, spatial_ref);
            r.err_analytic = err_an(&out.tips);
        }
    }
    mark_pareto(&mut sp.rows);
    // Temporal errors, against the temporal reference.
    for r in &mut temporal {
        if let Ok(out) = &r.result {
            r.err_final = dist(&out.tips[last], &temporal_ref.tips[last]);
            r.err_max = max_dist(&out.tips, &temporal_ref.tips);
            r.err_analytic = err_an(&out.tips);
        }
    }
    mark_pareto(&mut temporal);

    write_outputs(&ctx, dir, &sp.rows, &temporal)?;
    Ok(markdown(
        &ctx,
        &Results {
            temporal: &temporal,
            spatial: &sp,
            tight: &tight,
            temporal_ref: &temporal_ref,
            notes: &notes,
            sp_temporal,
            analytic: &analytic,
            t_analytic,
        },
    ))
}

/// The comparison times (N_COMPARE + 1 evenly spaced, and the analytic
/// reference's time), the analytic reference and the index of its time.
fn comparison_times(scene: &Scene) -> (Vec<f64>, Option<Analytic>, Option<usize>) {
    let d = scene.run.duration;
    let mut times: Vec<f64> = (0..=N_COMPARE)
        .map(|k| d * k as f64 / N_COMPARE as f64)
        .collect();
    // The analytic reference, if any, at its time.
    let analytic = scene
        .reference
        .as_ref()
        .filter(|r| r.rod_index == 0)
        .and_then(|r| r.tip.map(|tip| (tip, r.time.unwrap_or(d), r.note.clone())));
    let t_analytic =
        analytic.as_ref().map(
            |a| match times.iter().position(|t| (t - a.1).abs() <= 1e-12 * d) {
                Some(i) => i,
                None => {
                    times.push(a.1);
                    times.sort_by(f64::total_cmp);
                    times.iter().position(|t| *t == a.1).expect("inserted")
                }
            },
        );
    (times, analytic, t_analytic)
}

/// The temporal study's configurations, each integrator cheap to expensive.
fn temporal_configs(d: f64) -> Vec<Config> {
    let mut configs: Vec<Config> = Vec::new();
    for rtol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
        configs.push((
            "dopri5",
            format!("rtol {rtol:e}"),
            Integrator::Dopri5,
            Options::tol(rtol, rtol * 1e-3),
        ));
    }
    for rtol in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7] {
        configs.push((
            "rosenbrock",
            format!("rtol {rtol:e}"),
            Integrator::Rosenbrock,
            Options::tol(rtol, rtol * 1e-3),
        ));
    }
    for rtol in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
        configs.push((
            "esdirk",
            format!("rtol {rtol:e}"),
            Integrator::Esdirk,
            Options::tol(rtol, rtol * 1e-3),
        ));
    }
    for div in [100.0, 300.0, 1000.0, 3000.0, 10000.0] {
        let dt = d / div;
        configs.push((
            "generalized-alpha",
            format!("dt {dt:.3e}"),
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: GENERALIZED_ALPHA_RHO_INF,
                ..Options::fixed(dt)
            },
        ));
    }
    configs
}

/// The scene's pieces and quadrature under every configuration (errors are
/// filled in once the reference is known).
fn temporal_study(ctx: &Ctx<'_>, base: &Built, configs: Vec<Config>) -> Vec<Row> {
    let (times, budget, repeats, n0, q0) = (&ctx.times, ctx.budget, ctx.repeats, ctx.n0, ctx.q0);
    let mut temporal = Vec::new();
    // Configurations of one integrator go from cheap to expensive: once one is
    // over the time budget, the tighter ones are skipped.
    let mut over: Vec<&str> = Vec::new();
    for (name, setting, method, opts) in configs {
        let res = if over.contains(&name) {
            Err("skipped: a looser setting of this integrator was over the time budget".to_string())
        } else {
            ctx.say(format!("temporal: {name} {setting}"));
            simulate(base, method, &opts, times, budget, repeats)
        };
        if matches!(&res, Err(e) if e.contains("time budget")) && !over.contains(&name) {
            over.push(name);
        }
        temporal.push(Row {
            study: "temporal",
            integrator: name.into(),
            setting,
            pieces: n0,
            quadrature: q0,
            result: res,
            err_final: f64::NAN,
            err_max: f64::NAN,
            err_analytic: None,
            pareto: false,
        });
    }
    temporal
}

/// The reference run of the temporal study, the tight setting it used and
/// what was tried before it.
fn temporal_reference(
    ctx: &Ctx<'_>,
    base: &Built,
    temporal: &[Row],
) -> Result<(Tight, Outcome, Vec<String>), CliError> {
    let (times, ref_budget, n0, q0) = (&ctx.times, ctx.ref_budget, ctx.n0, ctx.q0);
    // Reference integrator: dopri5 at rtol 1e-9 if it finishes within the
    // budget (non-stiff scenes), else rosenbrock at rtol 1e-8.
    let tights = [
        Tight {
            method: Integrator::Dopri5,
            opts: Options::tol(1e-9, 1e-12),
            text: "dopri5, rtol 1e-9, atol 1e-12".into(),
        },
        Tight {
            method: Integrator::Rosenbrock,
            opts: Options::tol(1e-8, 1e-11),
            text: "rosenbrock (ROS34PW2), rtol 1e-8, atol 1e-11".into(),
        },
    ];
    // The reference integrator: the one whose tightest sweep setting finished
    // (dopri5 first: it is the more accurate at tight tolerances).
    let finished = |name: &str| {
        temporal
            .iter()
            .rev()
            .find(|r| r.integrator == name)
            .is_some_and(|r| r.result.is_ok())
    };
    let mut tights = tights.to_vec();
    if !finished("dopri5") && finished("rosenbrock") {
        tights.reverse();
    }
    let mut chosen = None;
    let mut notes = Vec::new();
    for t in &tights {
        ctx.say(format!(
            "temporal reference: {} at the scene's {n0} pieces, quadrature {q0}",
            t.text
        ));
        match simulate(base, t.method, &t.opts, times, ref_budget / 2.0, 1) {
            Ok(out) => {
                chosen = Some((t.clone(), out));
                break;
            }
            Err(e) => notes.push(format!("{} failed: {e}", t.text)),
        }
    }
    let Some((tight, temporal_ref)) = chosen else {
        return Err(failed(format!(
            "no reference run succeeded: {}",
            notes.join("; ")
        )));
    };
    Ok((tight, temporal_ref, notes))
}

/// Pieces x{1, 2, 4} and quadrature {2, 4, 6} against the Richardson
/// extrapolation of the x2 and x4 runs (errors filled in by the caller).
fn spatial_study(ctx: &Ctx<'_>) -> Result<Spatial, CliError> {
    let (scene, times, ref_budget, repeats, n0) =
        (ctx.scene, &ctx.times, ctx.ref_budget, ctx.repeats, ctx.n0);
    let d = scene.run.duration;
    // Spatial study: pieces x{1,2,4}, quadrature {2,4,6}, with generalized-α
    // at a small fixed step: unconditionally stable, so refining the pieces
    // (which raises the shear/extension frequencies ~1/ℓ) does not force tiny
    // steps as it does for error-controlled methods. Its own temporal error is
    // measured below against the temporal reference.
    let sp_dt = d / 4000.0;
    let sp_method = Integrator::GeneralizedAlpha;
    let sp_opts = Options {
        rho_inf: GENERALIZED_ALPHA_RHO_INF,
        ..Options::fixed(sp_dt)
    };
    let sp_setting = format!("dt {sp_dt:.3e}");
    let mut spatial = Vec::new();
    for k in [1usize, 2, 4] {
        for q in [2usize, 4, 6] {
            let built = build_variant(scene, k, q)?;
            ctx.say(format!("spatial: {} pieces, quadrature {q}", n0 * k));
            let res = simulate(&built, sp_method, &sp_opts, times, ref_budget, repeats);
            spatial.push(Row {
                study: "spatial",
                integrator: "generalized-alpha".into(),
                setting: sp_setting.clone(),
                pieces: n0 * k,
                quadrature: q,
                result: res,
                err_final: f64::NAN,
                err_max: f64::NAN,
                err_analytic: None,
                pareto: false,
            });
        }
    }
    let tips_of = |k: usize, q: usize| -> Result<&Vec<[f64; 3]>, CliError> {
        spatial
            .iter()
            .find(|r| r.pieces == n0 * k && r.quadrature == q)
            .and_then(|r| r.result.as_ref().ok())
            .map(|o| &o.tips)
            .ok_or_else(|| {
                failed(format!(
                    "the spatial run with pieces x{k}, quadrature {q} failed"
                ))
            })
    };
    // Richardson extrapolation of x2 and x4 (quadrature 6): PCS converges at
    // order 2 in the piece length (docs/validation.md).
    let (t1q, t2q, t4q) = (tips_of(1, 6)?, tips_of(2, 6)?, tips_of(4, 6)?);
    let spatial_ref: Vec<[f64; 3]> = t2q
        .iter()
        .zip(t4q)
        .map(|(a, b)| std::array::from_fn(|i| b[i] + (b[i] - a[i]) / 3.0))
        .collect();
    let observed_order = (max_dist(t1q, t2q) / max_dist(t2q, t4q)).log2();
    Ok(Spatial {
        rows: spatial,
        reference: spatial_ref,
        observed_order,
        dt: sp_dt,
    })
}

/// `report.csv`, `report.svg` and `report_spatial.svg`.
fn write_outputs(
    ctx: &Ctx<'_>,
    dir: &Path,
    spatial: &[Row],
    temporal: &[Row],
) -> Result<(), CliError> {
    let (scene, n0, q0) = (ctx.scene, ctx.n0, ctx.q0);
    let mut csv = String::from(CSV_HEADER);
    csv_rows(&mut csv, spatial);
    csv_rows(&mut csv, temporal);
    write(dir, "report.csv", &csv)?;
    work_precision_svg(
        &dir.join("report.svg"),
        &format!(
            "temporal work-precision: {} ({n0} pieces, quadrature {q0})",
            scene.source
        ),
        temporal,
        |r| r.integrator.clone(),
    )?;
    work_precision_svg(
        &dir.join("report_spatial.svg"),
        &format!(
            "spatial work-precision: {} (pieces x1, x2, x4)",
            scene.source
        ),
        spatial,
        |r| format!("quadrature {}", r.quadrature),
    )?;
    Ok(())
}

/// What the Markdown report states.
struct Results<'a> {
    temporal: &'a [Row],
    spatial: &'a Spatial,
    tight: &'a Tight,
    temporal_ref: &'a Outcome,
    notes: &'a [String],
    /// Temporal error of the spatial study's integrator at the scene's
    /// pieces, m.
    sp_temporal: f64,
    analytic: &'a Option<Analytic>,
    t_analytic: Option<usize>,
}

/// `report.md`.
fn markdown(ctx: &Ctx<'_>, r: &Results<'_>) -> String {
    let (scene, o, n0, q0, budget, repeats) =
        (ctx.scene, ctx.o, ctx.n0, ctx.q0, ctx.budget, ctx.repeats);
    let d = scene.run.duration;
    let (temporal, spatial, spatial_ref) = (r.temporal, &r.spatial.rows, &r.spatial.reference);
    let (tight, temporal_ref, notes) = (r.tight, r.temporal_ref, r.notes);
    let (observed_order, sp_dt, sp_temporal) =
        (r.spatial.observed_order, r.spatial.dt, r.sp_temporal);
    let (analytic, t_analytic) = (r.analytic, r.t_analytic);
    let scene_spatial = spatial
        .iter()
        .find(|r| r.pieces == n0 && r.quadrature == q0)
        .map_or(f64::NAN, |r| r.err_max);
    let mut md = String::new();
    let _ = writeln!(md, "# softrod report: {}\n", scene.source);
    let _ = writeln!(
        md,
        "Regenerate with `{}` (release build). {} repeat(s) per configuration, wall time = median; \
         errors are distances of the first rod's tip: at the final time t = {d} s (`error final`) and \
         the largest over {} evenly spaced times (`error max`). Runs over a wall-time budget of {budget} s \
         are stopped and listed as failed.\n",
        command(scene, o),
        repeats,
        N_COMPARE + 1
    );
    md.push_str("## References\n\n");
    let _ = writeln!(
        md,
        "- **Temporal reference** (for the integrator study): {}, at the scene's {n0} pieces and \
         quadrature {q0}: {:.3} s wall, {} steps.",
        tight.text, temporal_ref.wall, temporal_ref.stats.steps
    );
    for n in notes {
        let _ = writeln!(md, "  (Tried first: {n}.)");
    }
    let _ = writeln!(
        md,
        "- **Spatial reference** (for the pieces/quadrature study): Richardson extrapolation \
         `x4 + (x4 − x2)/3` of the pieces x2 ({} pieces) and x4 ({} pieces) runs at quadrature 6, \
         order 2 (observed order from x1, x2, x4: {observed_order:.2}). The spatial runs use \
         generalized-α (ρ∞ = {GENERALIZED_ALPHA_RHO_INF}) at the fixed step {sp_dt:.3e} s; its \
         temporal error at the scene's pieces is {} m (max over the run, against the temporal \
         reference), which bounds how small a spatial error this study resolves.",
        n0 * 2,
        n0 * 4,
        sci(sp_temporal)
    );
    let _ = writeln!(
        md,
        "- The scene's pieces and quadrature are {} m (max over the run) from the spatial \
         reference: the scene's spatial error.",
        sci(scene_spatial)
    );
    if let (Some((tip, t, note)), Some(i)) = (analytic, t_analytic) {
        let _ = writeln!(
            md,
            "- **Analytic reference** (`[reference]`): tip {tip:?} m at t = {t} s{}; the spatial \
             reference is {} m from it, the temporal reference {} m.",
            note.as_ref().map_or(String::new(), |n| format!(" ({n})")),
            sci(dist(&spatial_ref[i], tip)),
            sci(dist(&temporal_ref.tips[i], tip))
        );
    }
    md.push_str(
        "\n## Spatial error: pieces and quadrature\n\nEach row against the spatial reference. \
         Plot: `report_spatial.svg` (one curve per quadrature order).\n\n",
    );
    md.push_str(&md_table(spatial, analytic.is_some()));
    md.push_str(
        "\n## Temporal error: integrators and tolerances\n\nThe scene's pieces and quadrature, each row \
         against the temporal reference (same model), so only the integrator's error is measured. \
         Plot: `report.svg` (log-log work-precision, one curve per integrator, Pareto front dashed \
         and ringed).\n\n",
    );
    md.push_str(&md_table(temporal, analytic.is_some()));
    md.push_str("\n## Cheapest setting per error target\n\n");
    let _ = writeln!(
        md,
        "The scene's own spatial error ({n0} pieces, quadrature {q0}) is {} m: integrator errors far \
         below it buy nothing.\n",
        sci(scene_spatial)
    );
    md.push_str("| target (max tip error) m | cheapest integrator setting | wall s | its error m |\n|---|---|---|---|\n");
    let mut targets = vec![1e-3, 1e-4, 1e-5, 1e-6];
    if scene_spatial.is_finite() {
        targets.insert(0, scene_spatial / 10.0);
    }
    for tgt in targets {
        let best = temporal
            .iter()
            .filter(|r| r.result.is_ok() && r.err_max <= tgt)
            .min_by(|a, b| wall(a).total_cmp(&wall(b)));
        match best {
            Some(r) => {
                let _ = writeln!(
                    md,
                    "| {} | {} {} | {:.4} | {} |",
                    sci(tgt),
                    r.integrator,
                    r.setting,
                    wall(r),
                    sci(r.err_max)
                );
            }
            None => {
                let _ = writeln!(md, "| {} | none reached it | | |", sci(tgt));
            }
        }
    }
    md.push_str("\nData: `report.csv` (both studies, column `study`).\n");
    md
}
