//! The figures of a run, drawn by `softrod-viz` (axis labels with units,
//! equal aspect for geometry, three projections or the one plane of a
//! planar scene, rods told apart): what the run kept in memory ([`Series`]) turned into plain series. The
//! work-precision chart of `softrod report` is in `report.rs`.

use std::path::Path;

use softrod::dynamics::{Energies, Model};
use softrod::record::{Record, position};
use softrod_viz::plot::{
    self, ActuatorSeries, BodyMark, EnergySeries, Figure, Mode, ModeShapes, NamedSeries, RodCurve,
    ShapeSnapshot, StrainComponent, StrainProfiles,
};
use softrod_viz::run_dir::{Thinning, halve};

use crate::common::{CliError, failed};

/// The state of every rod at one time, for the shape and strain figures.
#[derive(Clone, Debug, Default)]
pub struct Snapshot {
    /// Time, s.
    pub t: f64,
    /// Per rod: the sampled centreline (world frame, m).
    pub centrelines: Vec<Vec<[f64; 3]>>,
    /// Per rod: the strain `ξ_n` of each piece.
    pub strains: Vec<Vec<[f64; 6]>>,
    /// Per rigid body (model order): the origin of its frame (world, m),
    /// as in bodies.csv.
    pub bodies: Vec<[f64; 3]>,
    /// Per rigid body: its pose (what carries its obstacles).
    pub body_poses: Vec<softrod_viz::Pose>,
}

/// Most output rows a run keeps for its figures: between this and twice
/// this many, evenly spaced, and the last (figures are decimated to
/// sub-pixel detail anyway, so a longer run draws the same curves from
/// memory that does not grow with its rows).
pub const FIGURE_ROWS: usize = 20_000;

/// What a run keeps in memory for its figures (one value per kept output
/// row, see [`FIGURE_ROWS`]; snapshots at a few rows).
#[derive(Clone, Debug)]
pub struct Series {
    /// Output times, s.
    pub t: Vec<f64>,
    /// `tips[rod][k]`: tip position (world, m).
    pub tips: Vec<Vec<[f64; 3]>>,
    /// Energy components, J.
    pub energies: Vec<Energies>,
    /// `tensions[cable][k]`, N.
    pub tensions: Vec<Vec<f64>>,
    /// `power[cable][k]`: `T_c · (B_c · q̇)`, W (D15: the cable's generalized
    /// force per unit tension is column `c` of the actuation matrix `B`).
    pub power: Vec<Vec<f64>>,
    /// Shape snapshots, in time order.
    pub snapshots: Vec<Snapshot>,
    thin: Thinning,
    offered: usize,
    /// The latest row when it was not kept: appended by [`Series::finish`].
    pending: Option<Box<Series>>,
}

impl Snapshot {
    /// The snapshot of a record: the sampled centrelines, the strains and
    /// the bodies' origins.
    pub fn of(rec: &Record) -> Self {
        let p = &rec.poses;
        Self {
            t: rec.t,
            centrelines: (0..p.n_rods())
                .map(|r| p.samples(r).iter().map(position).collect())
                .collect(),
            strains: (0..p.n_rods())
                .map(|r| {
                    p.strains(r)
                        .iter()
                        .map(|x| [x[0], x[1], x[2], x[3], x[4], x[5]])
                        .collect()
                })
                .collect(),
            bodies: p.bodies().iter().map(position).collect(),
            body_poses: p
                .bodies()
                .iter()
                .map(|g| softrod_viz::Pose {
                    position: position(g),
                    rotation: softrod::record::quaternion(g),
                })
                .collect(),
        }
    }
}

impl Series {
    /// Empty series of `rods` rods and `cables` cables.
    pub fn new(rods: usize, cables: usize) -> Self {
        Self::with_capacity(rods, cables, FIGURE_ROWS)
    }

    fn with_capacity(rods: usize, cables: usize, cap: usize) -> Self {
        Self {
            t: Vec::new(),
            tips: vec![Vec::new(); rods],
            energies: Vec::new(),
            tensions: vec![Vec::new(); cables],
            power: vec![Vec::new(); cables],
            snapshots: Vec::new(),
            thin: Thinning::new(cap),
            offered: 0,
            pending: None,
        }
    }

    /// Offers a record's time, tips, energies, tensions and powers: kept
    /// if [`FIGURE_ROWS`]' thinning keeps its row, else held as the latest.
    pub fn push(&mut self, rec: &Record) {
        let k = self.offered;
        self.offered += 1;
        if !self.thin.keeps(k) {
            let p = self.pending.get_or_insert_with(|| {
                Box::new(Self::with_capacity(self.tips.len(), self.tensions.len(), 1))
            });
            p.clear();
            p.append(rec);
            return;
        }
        self.pending = None;
        self.append(rec);
        if self.thin.full(self.t.len()) {
            halve(&mut self.t);
            self.tips.iter_mut().for_each(halve);
            halve(&mut self.energies);
            self.tensions.iter_mut().for_each(halve);
            self.power.iter_mut().for_each(halve);
        }
    }

    /// Appends the latest row if thinning skipped it, so the figures end
    /// where the run did.
    pub fn finish(&mut self) {
        if let Some(p) = self.pending.take().map(|p| *p) {
            self.t.extend(p.t);
            self.energies.extend(p.energies);
            for (a, b) in self.tips.iter_mut().zip(p.tips) {
                a.extend(b);
            }
            for (a, b) in self.tensions.iter_mut().zip(p.tensions) {
                a.extend(b);
            }
            for (a, b) in self.power.iter_mut().zip(p.power) {
                a.extend(b);
            }
        }
    }

    fn clear(&mut self) {
        self.t.clear();
        self.energies.clear();
        self.tips.iter_mut().for_each(Vec::clear);
        self.tensions.iter_mut().for_each(Vec::clear);
        self.power.iter_mut().for_each(Vec::clear);
    }

    fn append(&mut self, rec: &Record) {
        self.t.push(rec.t);
        for (r, tips) in self.tips.iter_mut().enumerate() {
            tips.push(position(rec.poses.tip(r)));
        }
        self.energies.push(rec.energies);
        for (c, (&tn, &pw)) in rec.tensions.iter().zip(&rec.cable_power).enumerate() {
            self.tensions[c].push(tn);
            self.power[c].push(pw);
        }
    }
}

/// File name of the strain figure of rod `r`.
pub fn strains_file(r: usize) -> String {
    if r == 0 {
        "strains.svg".into()
    } else {
        format!("strains_{r}.svg")
    }
}

/// The components a rod's basis selects (all six for a general basis).
fn components(model: &Model, r: usize) -> Vec<StrainComponent> {
    let rod = &model.rods()[r].spec.geometry;
    match rod.pieces()[0].basis.selection() {
        Some(sel) => sel.iter().map(|&i| StrainComponent::ALL[i]).collect(),
        None => StrainComponent::ALL.to_vec(),
    }
}

/// Piece boundaries `0, L_1, …, L` of rod `r`, m.
fn bounds(model: &Model, r: usize) -> Vec<f64> {
    let rod = &model.rods()[r].spec.geometry;
    std::iter::once(0.0)
        .chain(rod.pieces().iter().map(|p| p.end()))
        .collect()
}

/// The bodies' marks: names from the model, positions in model order.
fn body_marks(model: &Model, positions: &[[f64; 3]]) -> Vec<BodyMark> {
    model
        .bodies()
        .iter()
        .zip(positions)
        .map(|(b, p)| BodyMark {
            name: b.spec.name.clone(),
            position: *p,
        })
        .collect()
}

fn write(
    dir: &Path,
    name: &str,
    fig: Result<Figure, softrod_viz::VizError>,
) -> Result<(), CliError> {
    let path = dir.join(name);
    fig.and_then(|f| f.write(&path)).map_err(|e| {
        // Never leave a truncated figure (a full disk) behind.
        let _ = std::fs::remove_file(&path);
        failed(format!("plot {name}: {}", softrod::report(&e)))
    })
}

/// With `--png`: a PNG beside each SVG figure `names` (in `dir`), same
/// size; warns (unless `quiet`) when no font was found for the text.
pub fn rasterize(dir: &Path, names: &[String], quiet: bool) -> Result<(), CliError> {
    let paths: Vec<std::path::PathBuf> = names.iter().map(|n| dir.join(n)).collect();
    let done = softrod_viz::png::svg_to_png_all(&paths).map_err(|e| failed(format!("PNG: {e}")))?;
    if !quiet && done.iter().any(|r| !r.text_drawn) {
        eprintln!("softrod: warning: no font found on this system: the PNG figures have no text");
    }
    Ok(())
}

/// Writes every figure of a run: `tip_trajectory.svg`, `energy.svg`,
/// `shapes.svg`, `strains.svg` (`strains_R.svg` for rod R ≥ 1) and, with
/// cables, `actuators.svg`. Returns the names written (nothing without rows).
pub fn run_figures(
    dir: &Path,
    s: &Series,
    model: &Model,
    title: &str,
) -> Result<Vec<String>, CliError> {
    let mut written = Vec::new();
    if s.t.is_empty() {
        return Ok(written);
    }
    let names: Vec<String> = model.rods().iter().map(|r| r.spec.name.clone()).collect();
    let tips: Vec<RodCurve> = names
        .iter()
        .zip(&s.tips)
        .map(|(n, p)| RodCurve {
            name: n.clone(),
            points: p.clone(),
        })
        .collect();
    write(
        dir,
        "tip_trajectory.svg",
        plot::tip_trajectory(&format!("{title}: tip trajectory"), &tips),
    )?;
    written.push("tip_trajectory.svg".to_string());
    let energy = EnergySeries {
        t: s.t.clone(),
        kinetic: s.energies.iter().map(|e| e.kinetic).collect(),
        elastic: s.energies.iter().map(|e| e.elastic).collect(),
        gravitational: s.energies.iter().map(|e| e.gravitational).collect(),
        extra: Vec::new(),
    };
    write(
        dir,
        "energy.svg",
        plot::energy(&format!("{title}: energy"), &energy),
    )?;
    written.push("energy.svg".to_string());
    if !s.snapshots.is_empty() {
        let snaps: Vec<ShapeSnapshot> = s
            .snapshots
            .iter()
            .map(|sn| ShapeSnapshot {
                t: Some(sn.t),
                rods: names
                    .iter()
                    .zip(&sn.centrelines)
                    .map(|(n, p)| RodCurve {
                        name: n.clone(),
                        points: p.clone(),
                    })
                    .collect(),
                bodies: body_marks(model, &sn.bodies),
            })
            .collect();
        let poses: Vec<&[softrod_viz::Pose]> = s
            .snapshots
            .iter()
            .map(|sn| sn.body_poses.as_slice())
            .collect();
        let obstacles = crate::contact::obstacle_tracks(model, &poses);
        write(
            dir,
            "shapes.svg",
            plot::shapes_with_obstacles(&format!("{title}: rod shapes"), &snaps, &obstacles),
        )?;
        written.push("shapes.svg".to_string());
        for (r, name) in names.iter().enumerate() {
            let per_piece: Vec<Vec<[f64; 6]>> =
                s.snapshots.iter().map(|sn| sn.strains[r].clone()).collect();
            let profiles = StrainProfiles::piecewise_constant(
                name.clone(),
                s.snapshots.iter().map(|sn| sn.t).collect(),
                &bounds(model, r),
                &per_piece,
                components(model, r),
            );
            let file = strains_file(r);
            write(
                dir,
                &file,
                plot::strains(&format!("{title}: strains along {name}"), &profiles),
            )?;
            written.push(file);
        }
    }
    if !s.tensions.is_empty() {
        let named = |v: &[Vec<f64>]| -> Vec<NamedSeries> {
            v.iter()
                .enumerate()
                .map(|(c, values)| NamedSeries {
                    name: format!("cable {c}"),
                    values: values.clone(),
                })
                .collect()
        };
        let a = ActuatorSeries {
            t: s.t.clone(),
            tensions: named(&s.tensions),
            power: named(&s.power),
        };
        write(
            dir,
            "actuators.svg",
            plot::actuators(&format!("{title}: cable tensions and power"), &a),
        )?;
        written.push("actuators.svg".to_string());
    }
    Ok(written)
}

/// `DIR/statics_shape.svg`: the equilibrium in three projections (one for a
/// planar scene), the rigid bodies marked at `bodies` (their frame
/// origins, model order, world m).
pub fn statics_figure(
    dir: &Path,
    model: &Model,
    centrelines: &[Vec<[f64; 3]>],
    bodies: &[[f64; 3]],
    body_poses: &[softrod_viz::Pose],
    title: &str,
) -> Result<String, CliError> {
    let snap = ShapeSnapshot {
        t: None,
        rods: model
            .rods()
            .iter()
            .zip(centrelines)
            .map(|(r, p)| RodCurve {
                name: r.spec.name.clone(),
                points: p.clone(),
            })
            .collect(),
        bodies: body_marks(model, bodies),
    };
    let name = "statics_shape.svg";
    write(
        dir,
        name,
        plot::shapes_with_obstacles(
            &format!("{title}: static equilibrium"),
            &[snap],
            &crate::contact::obstacle_tracks(model, &[body_poses]),
        ),
    )?;
    Ok(name.into())
}

/// `DIR/modes.svg`: each mode as the equilibrium displaced along it.
/// `displaced[k][r]`: mode `k`, rod `r`'s centreline.
pub fn modes_figure(
    dir: &Path,
    model: &Model,
    equilibrium: &[Vec<[f64; 3]>],
    modes: Vec<(f64, Vec<Vec<[f64; 3]>>)>,
    title: &str,
) -> Result<String, CliError> {
    let curves = |c: &[Vec<[f64; 3]>]| -> Vec<RodCurve> {
        model
            .rods()
            .iter()
            .zip(c)
            .map(|(r, p)| RodCurve {
                name: r.spec.name.clone(),
                points: p.clone(),
            })
            .collect()
    };
    let shapes = ModeShapes {
        equilibrium: curves(equilibrium),
        modes: modes
            .iter()
            .map(|(f, d)| Mode {
                frequency_hz: *f,
                displaced: curves(d),
            })
            .collect(),
    };
    let name = "modes.svg";
    write(
        dir,
        name,
        plot::modes(&format!("{title}: mode shapes"), &shapes),
    )?;
    Ok(name.into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use softrod::record::Recorder;

    /// A run's figure series keeps between `cap` and `2·cap + 1` rows
    /// however many it is offered, one stride apart, with the last row.
    #[test]
    fn the_figure_series_is_bounded_and_ends_at_the_last_row() {
        let scene = "[[rod]]\nname = \"a\"\nlength = 0.3\npieces = 2\n\
                     section = { shape = \"circle\", radius = 0.01 }\n\
                     material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n";
        let (sim, _, _) = softrod::Simulation::from_toml(scene, "s").unwrap();
        let model = sim.model();
        let mut data = softrod::dynamics::Data::new(model);
        let mut rec = Recorder::new(model);
        let (q, qd) = sim.initial_state();
        let (n, cap) = (1003, 50);
        let mut series = Series::with_capacity(1, 0, cap);
        for k in 0..n {
            let r = rec
                .record(model, &mut data, k as f64, q.as_slice(), qd.as_slice())
                .unwrap();
            series.push(r);
        }
        series.finish();
        let m = series.t.len();
        assert!((cap..=2 * cap + 1).contains(&m), "{m}");
        assert_eq!(series.t[0], 0.0);
        assert_eq!(series.t[m - 1], (n - 1) as f64);
        let stride = series.t[1] - series.t[0];
        assert!(stride > 1.0);
        assert!(series.t[..m - 1].windows(2).all(|w| w[1] - w[0] == stride));
        assert_eq!(series.tips[0].len(), m);
        assert_eq!(series.energies.len(), m);
    }
}
