//! Validated cables and point loads.

use serde::Serialize;

/// Where a cable runs in the cross-section, as a function of the abscissa s.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Routing {
    /// Constant offset `(y, z)` from the centerline in the local section frame, m.
    Offset([f64; 2]),
    /// Points `(s, y, z)`, m, with strictly increasing `s` in `[0, L]`, at least
    /// two, covering the cable's span `[from, to]`; linear between points.
    Path(Vec<[f64; 3]>),
}

impl Routing {
    /// Offset `(y, z)` at abscissa `s`, m; a path is interpolated linearly and
    /// held constant beyond its end points.
    pub fn offset_at(&self, s: f64) -> [f64; 2] {
        match self {
            Routing::Offset(o) => *o,
            Routing::Path(p) => {
                let (first, last) = (p[0], p[p.len() - 1]);
                if s <= first[0] {
                    return [first[1], first[2]];
                }
                if s >= last[0] {
                    return [last[1], last[2]];
                }
                let k = p.partition_point(|pt| pt[0] <= s).clamp(1, p.len() - 1);
                let (a, b) = (p[k - 1], p[k]);
                let w = (s - a[0]) / (b[0] - a[0]);
                [a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2])]
            }
        }
    }
}

/// Cable tension over time, N.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Tension {
    /// Constant tension ≥ 0.
    Constant(f64),
    /// Piecewise-linear in time through `(times[i], values[i])`, held constant
    /// before the first and after the last time. `times` strictly increasing,
    /// same length as `values` (≥ 1), `values` ≥ 0.
    Schedule {
        /// Times, s.
        times: Vec<f64>,
        /// Tensions, N.
        values: Vec<f64>,
    },
}

impl Tension {
    /// Tension at time `t`, N.
    pub fn at(&self, t: f64) -> f64 {
        match self {
            Tension::Constant(v) => *v,
            Tension::Schedule { times, values } => {
                let n = times.len();
                if t <= times[0] {
                    return values[0];
                }
                if t >= times[n - 1] {
                    return values[n - 1];
                }
                let k = times.partition_point(|&x| x <= t).clamp(1, n - 1);
                let w = (t - times[k - 1]) / (times[k] - times[k - 1]);
                values[k - 1] + w * (values[k] - values[k - 1])
            }
        }
    }

    /// Largest tension over all time, N.
    pub fn max(&self) -> f64 {
        match self {
            Tension::Constant(v) => *v,
            Tension::Schedule { values, .. } => values.iter().copied().fold(0.0, f64::max),
        }
    }
}

/// A cable (tendon) pulling along a rod between two anchoring abscissae.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cable {
    /// Name of the rod it acts on.
    pub rod: String,
    /// Index of that rod in [`Scene::rods`](crate::Scene::rods).
    pub rod_index: usize,
    /// Routing in the cross-section.
    pub routing: Routing,
    /// Tension, N.
    pub tension: Tension,
    /// Start of the anchoring span, m: `0 ≤ from < to` (default 0).
    pub from: f64,
    /// End of the anchoring span, m: `to ≤ L` (default L).
    pub to: f64,
}

/// Frame in which a point load's force and moment are given.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadFrame {
    /// World frame: a dead load of fixed direction (`frame = "world"`, default).
    World,
    /// Body frame at the point: a follower load (`frame = "body"`).
    Body,
}

impl LoadFrame {
    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            LoadFrame::World => "world",
            LoadFrame::Body => "body",
        }
    }
}

/// A point force and moment applied at abscissa `s` of a rod.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Load {
    /// Name of the rod.
    pub rod: String,
    /// Index of that rod in [`Scene::rods`](crate::Scene::rods).
    pub rod_index: usize,
    /// Material abscissa, m, in `[0, L]`.
    pub s: f64,
    /// Force, N, in `frame` (default zero).
    pub force: [f64; 3],
    /// Moment, N·m, in `frame` (default zero).
    pub moment: [f64; 3],
    /// Frame of `force` and `moment` (default world).
    pub frame: LoadFrame,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tension_schedule_is_piecewise_linear_and_held() {
        let t = Tension::Schedule {
            times: vec![0.0, 0.5, 1.0],
            values: vec![0.0, 2.0, 1.0],
        };
        assert_eq!(t.at(-1.0), 0.0);
        assert_eq!(t.at(0.25), 1.0);
        assert_eq!(t.at(0.5), 2.0);
        assert_eq!(t.at(0.75), 1.5);
        assert_eq!(t.at(9.0), 1.0);
        assert_eq!(t.max(), 2.0);
    }

    #[test]
    fn path_routing_interpolates() {
        let r = Routing::Path(vec![[0.0, 0.0, 0.008], [0.5, 0.004, 0.0]]);
        assert_eq!(r.offset_at(0.0), [0.0, 0.008]);
        let m = r.offset_at(0.25);
        assert!((m[0] - 0.002).abs() < 1e-15 && (m[1] - 0.004).abs() < 1e-15);
        assert_eq!(r.offset_at(1.0), [0.004, 0.0]);
    }
}
