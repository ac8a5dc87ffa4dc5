//! A validated rod: geometry, strain basis, section, material, drag.

use serde::Serialize;

/// Names of the six strain components, in the order of the strain vector
/// `ξ = (k, q) = (kx, ky, kz, qx, qy, qz)`: torsion, two bendings, stretch,
/// two shears (angular part first, body frame, local x along the rod).
pub const STRAIN_NAMES: [&str; 6] = ["kx", "ky", "kz", "qx", "qy", "qz"];

/// Which strain components are degrees of freedom, the same for every piece.
///
/// The generalized coordinates of a piece are the selected components in the
/// canonical order [`STRAIN_NAMES`], whatever order the scene lists them in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct StrainSelection {
    /// `mask[j]` is true when strain component `j` (see [`STRAIN_NAMES`]) is free.
    pub mask: [bool; 6],
}

impl StrainSelection {
    /// All six strains free (`strains = "all"`).
    pub const ALL: StrainSelection = StrainSelection { mask: [true; 6] };

    /// Number of selected strains `k_n` (DoF per piece), 1 to 6 for a valid scene.
    pub fn count(&self) -> usize {
        self.mask.iter().filter(|&&m| m).count()
    }

    /// Indices (0..6, into [`STRAIN_NAMES`]) of the selected strains, increasing.
    /// Column `c` of the piece's strain basis `B_n` is the unit vector `e_{indices()[c]}`.
    pub fn indices(&self) -> Vec<usize> {
        (0..6).filter(|&j| self.mask[j]).collect()
    }

    /// Names of the selected strains, in canonical order.
    pub fn names(&self) -> Vec<&'static str> {
        self.indices()
            .into_iter()
            .map(|j| STRAIN_NAMES[j])
            .collect()
    }
}

/// Pose of the clamped base in the world frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pose {
    /// Base position in the world frame, m.
    pub position: [f64; 3],
    /// Rotation matrix, row-major (`rotation[i][j] = R_ij`), mapping the base's
    /// local frame to the world frame: its columns are the local axes in world
    /// coordinates. Orthonormal with determinant +1 (checked to 1e-6).
    pub rotation: [[f64; 3]; 3],
}

impl Pose {
    /// Base at the origin, local axes equal to the world axes.
    pub const IDENTITY: Pose = Pose {
        position: [0.0; 3],
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    };
}

impl Default for Pose {
    fn default() -> Self {
        Pose::IDENTITY
    }
}

/// Cross-section shape and size, m. Local y and z are the section axes.
///
/// The area moments are left to the mechanics layer; the model's convention is
/// `Jx = Jy + Jz` (polar moment) for every shape.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum Section {
    /// Solid circle of constant radius (`shape = "circle", radius`).
    Circle {
        /// Radius, m, > 0.
        radius: f64,
    },
    /// Solid circle whose radius varies linearly from base to tip
    /// (`shape = "circle", radius_base, radius_tip`).
    TaperedCircle {
        /// Radius at s = 0, m, > 0.
        radius_base: f64,
        /// Radius at s = L, m, > 0.
        radius_tip: f64,
    },
    /// Hollow circle (`shape = "tube"`).
    Tube {
        /// Outer radius, m, > 0.
        radius: f64,
        /// Inner radius, m, 0 ≤ inner_radius < radius.
        inner_radius: f64,
    },
    /// Solid rectangle (`shape = "rectangle"`).
    Rectangle {
        /// Side along local y, m, > 0.
        width: f64,
        /// Side along local z, m, > 0.
        height: f64,
    },
}

impl Section {
    /// Outer radius (half the largest side for a rectangle) at fraction `t = s/L`
    /// of the rod, m. A size scale for sanity checks.
    pub fn outer_radius_at(&self, t: f64) -> f64 {
        match *self {
            Section::Circle { radius } | Section::Tube { radius, .. } => radius,
            Section::TaperedCircle {
                radius_base,
                radius_tip,
            } => radius_base + (radius_tip - radius_base) * t,
            Section::Rectangle { width, height } => 0.5 * width.max(height),
        }
    }

    /// Whether the point `(y, z)` of the section plane at fraction `t = s/L`
    /// lies inside the outer boundary of the section (boundary included).
    /// A tube's hollow counts as inside (a cable may run in the lumen).
    pub fn contains(&self, t: f64, y: f64, z: f64) -> bool {
        match *self {
            Section::Rectangle { width, height } => {
                y.abs() <= 0.5 * width && z.abs() <= 0.5 * height
            }
            _ => y.hypot(z) <= self.outer_radius_at(t),
        }
    }
}

/// Linear elastic, linearly viscous material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Material {
    /// Mass density ρ, kg/m³, > 0.
    pub density: f64,
    /// Young's modulus E, Pa, > 0.
    pub young: f64,
    /// Shear modulus G, Pa, > 0: as given, or `E / (2 (1 + ν))` from `poisson`.
    pub shear_modulus: f64,
    /// Poisson's ratio ν when the scene gave it, in (−1, 0.5]; `None` when the
    /// scene gave `shear_modulus` instead.
    pub poisson: Option<f64>,
    /// Viscosity μ, Pa·s, ≥ 0 (0: no viscous term).
    pub viscosity: f64,
}

/// Linear drag of a surrounding fluid, per unit length, on the body velocity.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Drag {
    /// Force `−c_t v`, c_t in N·s/m², ≥ 0.
    pub translational: f64,
    /// Moment `−c_r ω`, c_r in N·m·s, ≥ 0.
    pub rotational: f64,
}

/// A validated rod: a chain of pieces of constant strain from a clamped base.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rod {
    /// Unique name, referenced by cables, loads and the reference.
    pub name: String,
    /// Unstretched length L, m, > 0.
    pub length: f64,
    /// Length of each piece, base to tip, m; each > 0, summing to `length`
    /// within 1e-9 relative. Its length is the number of pieces N ≥ 1.
    pub piece_lengths: Vec<f64>,
    /// Strain components that are DoF (same for every piece).
    pub strains: StrainSelection,
    /// Rest strain ξ̄ (kx, ky, kz, qx, qy, qz), default straight `[0,0,0,1,0,0]`.
    pub rest_strain: [f64; 6],
    /// Clamped base pose in the world frame.
    pub base: Pose,
    /// Cross-section.
    pub section: Section,
    /// Material.
    pub material: Material,
    /// Fluid drag (zero by default).
    pub drag: Drag,
}

impl Rod {
    /// Number of pieces N.
    pub fn n_pieces(&self) -> usize {
        self.piece_lengths.len()
    }

    /// Number of generalized coordinates of this rod: pieces × selected strains.
    pub fn n_dof(&self) -> usize {
        self.n_pieces() * self.strains.count()
    }

    /// Material abscissa where piece `i` starts, m (`i = n_pieces()` gives the length,
    /// up to rounding).
    ///
    /// # Panics
    /// If `i > n_pieces()`.
    pub fn piece_start(&self, i: usize) -> f64 {
        self.piece_lengths[..i].iter().sum()
    }
}
