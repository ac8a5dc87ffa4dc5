//! Rod–rod and self contact as the model holds it (docs/theory-contact.md
//! CT8–CT11): which pairs of rod points may touch (the self-contact
//! exclusion and the pieces a joint holds together), and the buffers of the
//! broadphase and the friction anchors of touching pairs — built only when
//! `[contact] rods` or `self` is on, so a model without them holds none.

use crate::model::Model;
use nalgebra::DVector;
use softrod_lie::{Mat3, Vec3};
use softrod_mechanics::contact::contact_radius;

/// Extra clearance of the broadphase's bounding spheres, as a fraction of
/// the segment's surface radius (the spheres bound the swept surface
/// exactly; the margin only absorbs the closest-point refinement moving a
/// little past its segment).
pub(crate) const BROADPHASE_MARGIN: f64 = 0.1;

/// The arc length along one rod \[m\] within which two of its points never
/// count as touching (CT9): `π (r_a + r_b) / 2`, the shortest stretch of
/// centreline that can turn by a half circle without its surface folding
/// onto itself (curvature radius ≥ the mean radius).
#[inline]
pub(crate) fn exclusion(ra: f64, rb: f64) -> f64 {
    0.5 * std::f64::consts::PI * (ra + rb)
}

/// The radius of rod `rod`'s contact surface at `s` \[m\] (CT1).
pub(crate) fn radius_at(model: &Model, rod: usize, s: f64) -> f64 {
    let spec = &model.rods[rod].spec;
    let length = spec.geometry.length();
    spec.contact_radius
        .unwrap_or_else(|| contact_radius(spec.properties.section(), s.clamp(0.0, length), length))
}

/// `∂r/∂s` of rod `rod`'s contact radius (CT14): the taper's slope for
/// a tapered circle, zero for a uniform section or a fixed `contact_radius`.
pub(crate) fn radius_slope(model: &Model, rod: usize) -> f64 {
    let spec = &model.rods[rod].spec;
    let length = spec.geometry.length();
    match (spec.contact_radius, *spec.properties.section()) {
        (
            None,
            softrod_mechanics::Section::TaperedCircle {
                radius_base,
                radius_tip,
            },
        ) if length > 0.0 => (radius_tip - radius_base) / length,
        _ => 0.0,
    }
}

/// Whether the points `(a, sa)` and `(b, sb)` may touch (CT9): different
/// rods with `rods` on, except a child rod's base against its parent rod
/// near the attachment; the same rod with `self` on, farther apart along
/// it than [`exclusion`].
pub(crate) fn may_touch(
    model: &Model,
    a: usize,
    sa: f64,
    b: usize,
    sb: f64,
    ra: f64,
    rb: f64,
) -> bool {
    let settings = &model.contact.settings;
    let reach = exclusion(ra, rb);
    if a == b {
        return settings.self_contact && (sa - sb).abs() >= reach;
    }
    if !settings.rods {
        return false;
    }
    !model.contact.joined.iter().any(|&(child, parent, at)| {
        (child == a && parent == b && sa < reach && (sb - at).abs() < reach)
            || (child == b && parent == a && sb < reach && (sa - at).abs() < reach)
    })
}

/// One segment of a rod's polyline of contact points in the broadphase:
/// the bounding sphere of the swept surface of its true arc.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SegmentBox {
    pub rod: usize,
    /// Index of the segment's first contact point.
    pub seg: usize,
    pub center: Vec3,
    pub radius: f64,
}

/// A touching pair of rod points found by an evaluation (world frame).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairActive {
    pub a: usize,
    pub sa: f64,
    pub b: usize,
    pub sb: f64,
    /// Centreline point of `a`, and the unit normal from `b` to `a`.
    pub point: Vec3,
    pub normal: Vec3,
    pub gap: f64,
    /// Force on `a` (`b` feels its opposite).
    pub force: Vec3,
    pub sticking: bool,
    /// Surface radius of `a` at `sa`, the stiffness of the pair's law.
    pub radius_a: f64,
    pub k: f64,
    /// `∂f/∂r` of the law's radius `r = min(r_a, r_b)` (its stiffness,
    /// damping and `ε`, `Law::pair`) at this pair's state; zero unless
    /// that radius varies along its rod (CT14).
    pub dr: Vec3,
    /// The two segments whose closest points seeded it.
    pub seeds: (SegmentBox, SegmentBox),
    /// `∂f/∂w` (`w = p_a − p_b`, the stretch held), `∂f/∂v`, `∂f/∂e` of
    /// the force law, and the friction anchor it used (CT14).
    pub dw: Mat3,
    pub dv: Mat3,
    pub de: Mat3,
    pub anchor: Option<PairAnchor>,
    /// The tangential stretch `P e` of CT10 (`P = I − n nᵀ`; zero without
    /// an anchor) \[m\] and, only for an evaluation of
    /// `crate::friction_stop` ([`PairWork::rates`]), the stretch's own rate
    /// `ė = v_a(σ_a) − v_b(σ_b) − ω_b(σ_b) × R_b o` \[m/s\] (world axes;
    /// zero otherwise): what the stop location of CT30 reads.
    pub stretch: Vec3,
    pub stretch_rate: Vec3,
}

/// A touching pair on the slip branch sliding back toward its anchor at
/// the end of a step (CT30), keyed like [`PairAnchor`]: its slide rate
/// `v_t·ê` \[m/s\] and pre-slip `μ f_n/k` \[m\].
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairSlide {
    pub a: usize,
    pub sa: f64,
    pub b: usize,
    pub sb: f64,
    /// `r_a + r_b` at the step end \[m\]: the anchors' matching reach.
    pub reach: f64,
    pub rate: f64,
    pub pre_slip: f64,
}

/// The friction anchor of a touching pair (CT10): the material points
/// `(a, sa)`, `(b, sb)` that stuck together and the offset between them in
/// `b`'s section frame at `sb`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairAnchor {
    pub a: usize,
    pub sa: f64,
    pub b: usize,
    pub sb: f64,
    pub offset: Vec3,
}

/// The stiffness state of a touching pair (CT15), keyed like
/// [`PairAnchor`] by its rods and arc lengths.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairHold {
    pub a: usize,
    pub sa: f64,
    pub b: usize,
    pub sb: f64,
    pub hold: crate::model::contact::Hold,
}

impl PairHold {
    /// Whether this state belongs to the pair `(a, sa)`–`(b, sb)` of radii
    /// summing to `reach` (the anchors' rule, CT10).
    pub(crate) fn matches(&self, a: usize, sa: f64, b: usize, sb: f64, reach: f64) -> bool {
        self.a == a && self.b == b && (self.sa - sa).abs() < reach && (self.sb - sb).abs() < reach
    }
}

/// The buffers of rod–rod contact, all sized once.
#[derive(Clone, Debug)]
pub(crate) struct PairWork {
    /// Per rod, the world positions of its contact points.
    pub points: Vec<Vec<Vec3>>,
    /// Per rod, the length of each segment of true arc between two
    /// contact points (stretch included) \[m\].
    pub arcs: Vec<Vec<f64>>,
    /// The broadphase's segments, sorted along x each evaluation.
    pub boxes: Vec<SegmentBox>,
    /// The boxes' lowest coordinate along the sweep's axis and their
    /// index, sorted (when the sweep runs along y or z), and the candidate
    /// pairs `(i, j)`, `i < j`, of the boxes' indices.
    pub order: Vec<(f64, u32)>,
    pub candidates: Vec<(u32, u32)>,
    /// The touching pairs of the last evaluation.
    pub active: Vec<PairActive>,
    /// The generalized force of the pairs alone.
    pub tau: DVector<f64>,
    /// Friction anchors, committed after accepted steps, and the list the
    /// commit builds.
    pub anchors: Vec<PairAnchor>,
    pub next: Vec<PairAnchor>,
    /// Stiffness states of touching pairs (CT15), committed like the
    /// anchors, and the list the commit builds.
    pub holds: Vec<PairHold>,
    pub next_holds: Vec<PairHold>,
    /// Coordinates of the central differences (n_dof).
    pub scratch: Vec<f64>,
    /// The seeds of the pairs touching at the state the central
    /// differences start from: they re-evaluate only those (CT11).
    pub fd_seeds: Vec<(SegmentBox, SegmentBox)>,
    /// The step-end slides of `crate::friction_stop` (CT30).
    pub slides: Vec<PairSlide>,
    /// Whether an evaluation computes [`PairActive::stretch_rate`] (two
    /// more section velocities per anchored pair): set by
    /// `crate::friction_stop` for its own evaluations only.
    pub rates: bool,
    /// Per segment pair tested, the evaluations of the last call (for the
    /// cost checks of the tests).
    pub narrow_tests: usize,
}

impl PairWork {
    /// The buffers for `model`, `None` without rod–rod or self contact.
    pub(crate) fn new(model: &Model) -> Option<Self> {
        if !model.contact.settings.any() {
            return None;
        }
        let samples = &model.contact.samples;
        let n_seg: usize = samples.iter().map(|s| s.len().saturating_sub(1)).sum();
        Some(Self {
            points: samples
                .iter()
                .map(|s| vec![Vec3::zeros(); s.len()])
                .collect(),
            arcs: samples
                .iter()
                .map(|s| vec![0.0; s.len().saturating_sub(1)])
                .collect(),
            boxes: Vec::with_capacity(n_seg),
            order: Vec::with_capacity(n_seg),
            candidates: Vec::with_capacity(4 * n_seg),
            active: Vec::with_capacity(64),
            tau: DVector::zeros(model.n_dof()),
            anchors: Vec::with_capacity(64),
            next: Vec::with_capacity(64),
            holds: Vec::with_capacity(64),
            next_holds: Vec::with_capacity(64),
            scratch: vec![0.0; model.n_dof()],
            fd_seeds: Vec::with_capacity(64),
            slides: Vec::with_capacity(16),
            rates: false,
            narrow_tests: 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::model::{Data, Model, Rod};
    use softrod_lie::{Pose, Vec3};
    use softrod_mechanics::Material;
    use softrod_mechanics::contact::{ContactSettings, Obstacle, Shape};

    fn rod(name: &str, y: f64) -> Rod {
        let material = Material::builder()
            .density(1000.0)
            .young(1.0e6)
            .poisson(0.5)
            .build()
            .unwrap();
        Rod::builder(0.4)
            .name(name)
            .pieces(20)
            .base(Pose::new(
                softrod_lie::Mat3::identity(),
                Vec3::new(0.0, y, 0.0),
            ))
            .circle(0.01)
            .material(material)
            .build()
            .unwrap()
    }

    /// No `[contact]`: no contact work at all; obstacles only: no
    /// broadphase (CT7).
    #[test]
    fn without_rod_contact_no_broadphase_is_built() {
        let model = Model::builder().rod(rod("a", 0.0)).build().unwrap();
        assert!(Data::new(&model).contact.is_none());
        let table = Obstacle::new(
            "table",
            Shape::Plane {
                point: Vec3::new(0.0, 0.0, -1.0),
                normal: Vec3::z(),
            },
        );
        let model = model
            .with_contact(vec![table], ContactSettings::default())
            .unwrap();
        let data = Data::new(&model);
        assert!(data.contact.as_ref().unwrap().pairs.is_none());
    }

    /// Two parallel 20-piece rods (40 segments each, 1 cm long): far apart,
    /// the broadphase hands no segment pair to the closest-point search;
    /// side by side, only segments near each other — a segment's sphere
    /// (radius ℓ/2 + 1.1 r = 1.6 cm) reaches centres 3.2 cm away, at most
    /// 7 segments of the other rod, not all 40.
    #[test]
    fn the_broadphase_tests_only_segments_near_each_other() {
        let settings = ContactSettings {
            rods: true,
            ..Default::default()
        };
        for (y, most) in [(0.5, 0), (0.019, 7 * 40)] {
            let model = Model::builder()
                .rod(rod("a", 0.0))
                .rod(rod("b", y))
                .build()
                .unwrap()
                .with_contact(Vec::new(), settings)
                .unwrap();
            let mut data = Data::new(&model);
            let zero = vec![0.0; model.n_dof()];
            let contacts = model.contacts_with(&mut data, 0.0, &zero, &zero).unwrap();
            let pw = data.contact.as_ref().unwrap().pairs.as_ref().unwrap();
            let n_seg: usize = pw.arcs.iter().map(Vec::len).sum();
            assert!(n_seg == 80, "{n_seg}");
            assert!(pw.narrow_tests <= most, "{} > {most}", pw.narrow_tests);
            assert_eq!(contacts.is_empty(), y > 0.1);
        }
    }
}
