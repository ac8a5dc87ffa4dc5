//! The dynamics study: the temporal study (integrators and tolerances
//! against a tight reference run) and the spatial study (pieces and
//! quadrature against a Richardson-extrapolated reference).

use softrod_integrate::{Integrator, Options};
use softrod_scene::{Built, Scene};

use super::runs::{build_variant, dist, max_dist, pieces, simulate};
use super::{N_COMPARE, Outcome, Row, StudyOptions, mark_pareto};
use crate::GENERALIZED_ALPHA_RHO_INF;
use crate::error::{Error, Result};

/// One temporal-study configuration: integrator name, setting text,
/// method and options.
type Config = (&'static str, String, Integrator, Options);

/// The analytic reference of a scene: tip \[m\], time \[s\], note.
pub type Analytic = ([f64; 3], f64, Option<String>);

/// A tight integrator setting and its description.
#[derive(Clone, Debug)]
pub struct Tight {
    /// The method.
    pub method: Integrator,
    /// Its options.
    pub opts: Options,
    /// What it is, for a person.
    pub text: String,
}

/// The spatial study and its reference.
#[derive(Clone, Debug)]
pub struct Spatial {
    /// Its rows, errors against `reference`.
    pub rows: Vec<Row>,
    /// The Richardson-extrapolated tips at the comparison times \[m\].
    pub reference: Vec<[f64; 3]>,
    /// The observed order of convergence in the piece length.
    pub observed_order: f64,
    /// The fixed step of its runs \[s\].
    pub dt: f64,
}

/// What [`dynamics_study`] measured.
#[derive(Clone, Debug)]
pub struct DynamicsStudy {
    /// The temporal study's rows, errors against `temporal_ref`.
    pub temporal: Vec<Row>,
    /// The spatial study.
    pub spatial: Spatial,
    /// The temporal reference's setting.
    pub tight: Tight,
    /// The temporal reference run.
    pub temporal_ref: Outcome,
    /// The reference settings tried before the one that finished.
    pub notes: Vec<String>,
    /// Temporal error of the spatial study's integrator at the scene's
    /// pieces \[m\].
    pub sp_temporal: f64,
    /// The scene's analytic reference, if any.
    pub analytic: Option<Analytic>,
    /// The index of its time among the comparison times.
    pub t_analytic: Option<usize>,
    /// Repeats per configuration.
    pub repeats: usize,
    /// Wall-time budget of a configuration \[s\].
    pub budget: f64,
    /// The scene's pieces (all rods) and quadrature.
    pub pieces: usize,
    /// See `pieces`.
    pub quadrature: usize,
}

/// How the study runs and tells its progress.
struct Ctx<'a> {
    scene: &'a Scene,
    repeats: usize,
    budget: f64,
    ref_budget: f64,
    /// The comparison times.
    times: Vec<f64>,
    n0: usize,
    q0: usize,
    progress: &'a dyn Fn(&str),
}

impl Ctx<'_> {
    fn say(&self, m: String) {
        (self.progress)(&m);
    }
}

/// Runs the dynamics study of `scene` (see the [module docs](super)),
/// telling `progress` what it starts.
pub fn dynamics_study(
    scene: &Scene,
    o: StudyOptions,
    progress: &dyn Fn(&str),
) -> Result<DynamicsStudy> {
    let repeats = o.repeats();
    let budget = if o.quick { 10.0 } else { 60.0 };
    let ref_budget = if o.quick { 120.0 } else { 300.0 };
    let (times, analytic, t_analytic) = comparison_times(scene);
    let ctx = Ctx {
        scene,
        repeats,
        budget,
        ref_budget,
        times,
        n0: pieces(scene),
        q0: scene.run.quadrature,
        progress,
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
    Ok(DynamicsStudy {
        temporal,
        spatial: sp,
        tight,
        temporal_ref,
        notes,
        sp_temporal,
        analytic,
        t_analytic,
        repeats,
        budget,
        pieces: ctx.n0,
        quadrature: ctx.q0,
    })
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
    for rtol in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
        configs.push((
            "esdirk5",
            format!("rtol {rtol:e}"),
            Integrator::Esdirk5,
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
) -> Result<(Tight, Outcome, Vec<String>)> {
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
        return Err(Error::Study(format!(
            "no reference run succeeded: {}",
            notes.join("; ")
        )));
    };
    Ok((tight, temporal_ref, notes))
}

/// Pieces x{1, 2, 4} and quadrature {2, 4, 6} against the Richardson
/// extrapolation of the x2 and x4 runs (errors filled in by the caller).
fn spatial_study(ctx: &Ctx<'_>) -> Result<Spatial> {
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
    let tips_of = |k: usize, q: usize| -> Result<&Vec<[f64; 3]>> {
        spatial
            .iter()
            .find(|r| r.pieces == n0 * k && r.quadrature == q)
            .and_then(|r| r.result.as_ref().ok())
            .map(|o| &o.tips)
            .ok_or_else(|| {
                Error::Study(format!(
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
