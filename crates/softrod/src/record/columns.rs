//! The columns of `trajectory.csv`: their names and order, defined once
//! here and read by every writer (the CLI's CSV and NumPy archive, the
//! Python `Trajectory`), so that a new quantity is added in one place.
//!
//! The order is the contract's nine columns (`t`, the first rod's tip
//! position and rotation quaternion, the total `energy`), then `q0…`
//! (docs/scene-format.md), then the additions of
//! docs/scene-format-extensions.md: `qdot0…`, the energy components
//! `kinetic, elastic, gravitational` (J; they sum to `energy`), with cables
//! `tension0…` (N) and `power0…` (W, the power each cable puts into the
//! rods), and with prescribed joints (D59) `prescribed0…` (their
//! coordinates, rad or m) and `prescribed_force0…` (the generalized force
//! each drive applies, N·m or N).

use softrod_dynamics::Model;

use softrod_dynamics::Energies;
use softrod_lie::Pose;

use super::poses::{position, quaternion};

/// The contract's first columns of `trajectory.csv` (the `q` columns follow).
pub const CONTRACT_COLUMNS: [&str; 9] = [
    "t", "tip_x", "tip_y", "tip_z", "tip_qw", "tip_qx", "tip_qy", "tip_qz", "energy",
];

/// The shape of `trajectory.csv` for one model: how many columns of each
/// kind, hence every column's name and index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Columns {
    /// Generalized coordinates.
    pub n_dof: usize,
    /// Cables (model order).
    pub n_cables: usize,
    /// Prescribed joint coordinates (D59).
    pub n_prescribed: usize,
}

/// The values of one row of `trajectory.csv`, borrowed from a
/// [`Record`](super::Record) or a [`Trajectory`](super::Trajectory).
#[derive(Clone, Copy, Debug)]
pub struct Row<'a> {
    /// Time \[s\].
    pub t: f64,
    /// The first rod's tip pose (world frame).
    pub tip: &'a Pose,
    /// The energies \[J\].
    pub energies: &'a Energies,
    /// Coordinates (n_dof).
    pub q: &'a [f64],
    /// Velocities (n_dof).
    pub qdot: &'a [f64],
    /// Cable tensions \[N\] (n_cables).
    pub tensions: &'a [f64],
    /// Power of each cable \[W\] (n_cables).
    pub cable_power: &'a [f64],
    /// Prescribed joint coordinates (n_prescribed).
    pub prescribed_q: &'a [f64],
    /// Their drives' generalized forces (n_prescribed).
    pub prescribed_force: &'a [f64],
}

/// A named block of columns: one array of `trajectory.npz` (and of the
/// Python `Trajectory`), `(n_samples, columns.len())` or `(n_samples,)`
/// when `vector` is false.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColumnGroup {
    /// The array's name (`t`, `q`, `qdot`, `tip`, `energy`, `tension`,
    /// `power`, `prescribed`, `prescribed_force`).
    pub name: &'static str,
    /// Its columns' indices in `trajectory.csv`, in order.
    pub columns: Vec<usize>,
    /// Whether the array has a second axis (false only for `t`).
    pub vector: bool,
}

impl Columns {
    /// The columns of a run of `model`.
    pub fn of(model: &Model) -> Self {
        Self {
            n_dof: model.n_dof(),
            n_cables: model.n_cables(),
            n_prescribed: model.n_prescribed(),
        }
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        CONTRACT_COLUMNS.len() + 2 * self.n_dof + 3 + 2 * self.n_cables + 2 * self.n_prescribed
    }

    /// The header: every column's name, in order.
    pub fn names(&self) -> Vec<String> {
        let mut h: Vec<String> = CONTRACT_COLUMNS.iter().map(|s| s.to_string()).collect();
        let numbered = |h: &mut Vec<String>, prefix: &str, n: usize| {
            h.extend((0..n).map(|i| format!("{prefix}{i}")));
        };
        numbered(&mut h, "q", self.n_dof);
        numbered(&mut h, "qdot", self.n_dof);
        h.extend(["kinetic", "elastic", "gravitational"].map(String::from));
        numbered(&mut h, "tension", self.n_cables);
        numbered(&mut h, "power", self.n_cables);
        numbered(&mut h, "prescribed", self.n_prescribed);
        numbered(&mut h, "prescribed_force", self.n_prescribed);
        h
    }

    /// Index of the first `q` column.
    fn q0(&self) -> usize {
        CONTRACT_COLUMNS.len()
    }

    /// Appends `row`'s numbers to `out`, in column order (`width()` of
    /// them).
    pub fn push_row(&self, row: Row<'_>, out: &mut Vec<f64>) {
        debug_assert_eq!(row.q.len(), self.n_dof);
        debug_assert_eq!(row.tensions.len(), self.n_cables);
        debug_assert_eq!(row.prescribed_q.len(), self.n_prescribed);
        out.push(row.t);
        out.extend(position(row.tip));
        out.extend(quaternion(row.tip));
        out.push(row.energies.total());
        out.extend(row.q);
        out.extend(row.qdot);
        let e = row.energies;
        out.extend([e.kinetic, e.elastic, e.gravitational]);
        out.extend(row.tensions);
        out.extend(row.cable_power);
        out.extend(row.prescribed_q);
        out.extend(row.prescribed_force);
    }

    /// The named blocks of columns, in the order of `trajectory.npz`; the
    /// optional pairs only when the model has cables or prescribed joints.
    pub fn groups(&self) -> Vec<ColumnGroup> {
        let (n, nc, np) = (self.n_dof, self.n_cables, self.n_prescribed);
        let range = |from: usize, len: usize| (from..from + len).collect::<Vec<_>>();
        let q0 = self.q0();
        let e0 = q0 + 2 * n;
        let c0 = e0 + 3;
        let p0 = c0 + 2 * nc;
        let group = |name, columns| ColumnGroup {
            name,
            columns,
            vector: true,
        };
        let mut g = vec![
            ColumnGroup {
                name: "t",
                columns: vec![0],
                vector: false,
            },
            group("q", range(q0, n)),
            group("qdot", range(q0 + n, n)),
            group("tip", range(1, 7)),
            group("energy", vec![8, e0, e0 + 1, e0 + 2]),
        ];
        if nc > 0 {
            g.push(group("tension", range(c0, nc)));
            g.push(group("power", range(c0 + nc, nc)));
        }
        if np > 0 {
            g.push(group("prescribed", range(p0, np)));
            g.push(group("prescribed_force", range(p0 + np, np)));
        }
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every column is named once, and the groups cover every column
    /// except none twice (the energy group takes `energy` with the three
    /// components).
    #[test]
    fn names_and_groups_agree() {
        let c = Columns {
            n_dof: 3,
            n_cables: 2,
            n_prescribed: 1,
        };
        let names = c.names();
        assert_eq!(names.len(), c.width());
        assert_eq!(&names[..9], &CONTRACT_COLUMNS);
        assert_eq!(names[9], "q0");
        assert_eq!(names[12], "qdot0");
        assert_eq!(&names[15..18], &["kinetic", "elastic", "gravitational"]);
        assert_eq!(names[18], "tension0");
        assert_eq!(names[20], "power0");
        assert_eq!(names[22], "prescribed0");
        assert_eq!(names[23], "prescribed_force0");
        let mut seen = vec![0; c.width()];
        for g in c.groups() {
            for i in g.columns {
                seen[i] += 1;
            }
        }
        assert!(seen.iter().all(|&k| k == 1), "{seen:?}");
        let bare = Columns {
            n_dof: 2,
            n_cables: 0,
            n_prescribed: 0,
        };
        let names: Vec<_> = bare.groups().iter().map(|g| g.name).collect();
        assert_eq!(names, ["t", "q", "qdot", "tip", "energy"]);
    }
}
