//! Errors of constitutive, load and actuator descriptions.

use std::fmt;

/// A named physical quantity of a description, for error messages and for
/// callers that map errors back to their input (a scene loader's table
/// `Quantity::YoungsModulus → material.young`). `Display` is the human name
/// with its unit.
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Quantity {
    /// Material density `ρ`.
    Density,
    /// Young's modulus `E`.
    YoungsModulus,
    /// Shear modulus `G`.
    ShearModulus,
    /// Poisson ratio `ν`.
    PoissonRatio,
    /// Kelvin–Voigt viscosity `μ`.
    Viscosity,
    /// Radius of a circle, or the outer radius of a tube.
    Radius,
    /// Inner radius of a tube.
    InnerRadius,
    /// Rectangle extent along local y.
    Width,
    /// Rectangle extent along local z.
    Height,
    /// Radius of a tapered circle at `s = 0`.
    BaseRadius,
    /// Radius of a tapered circle at `s = L`.
    TipRadius,
    /// Undeformed rod length `L`.
    RodLength,
    /// Translational drag coefficient `c_t`.
    TranslationalDrag,
    /// Rotational drag coefficient `c_r`.
    RotationalDrag,
    /// Start `from` of a cable's span.
    CableFrom,
    /// End `to` (the anchor) of a cable's span.
    CableTo,
    /// Constant cable offset along local y.
    OffsetY,
    /// Constant cable offset along local z.
    OffsetZ,
    /// The points of a cable path (the table as a whole).
    Path,
    /// Component `component` (0 = s, 1 = y, 2 = z) of point `index` of a cable path.
    PathPoint {
        /// Point index (0-based).
        index: usize,
        /// 0 = s, 1 = y, 2 = z.
        component: usize,
    },
    /// A constant cable tension.
    Tension,
    /// The times of a tension table (as a whole).
    TensionTimes,
    /// Time `i` of a tension table.
    TensionTime(usize),
    /// The values of a tension table (as a whole).
    TensionValues,
    /// Value `i` of a tension table.
    TensionValue(usize),
    /// A cable's friction coefficient along its channel.
    CableFriction,
    /// Abscissa `s` of a point load.
    LoadPosition,
    /// Component (0 = x, 1 = y, 2 = z) of a point-load force.
    Force(usize),
    /// Component of a point-load moment.
    Moment(usize),
    /// Component of a distributed force density.
    ForceDensity(usize),
    /// Component of a distributed moment density.
    MomentDensity(usize),
}

const XYZ: [&str; 3] = ["x", "y", "z"];

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let axis = |c: usize| XYZ.get(c).copied().unwrap_or("?");
        match *self {
            Quantity::Density => f.write_str("density [kg/m^3]"),
            Quantity::YoungsModulus => f.write_str("Young's modulus [Pa]"),
            Quantity::ShearModulus => f.write_str("shear modulus [Pa]"),
            Quantity::PoissonRatio => f.write_str("Poisson ratio"),
            Quantity::Viscosity => f.write_str("viscosity [Pa s]"),
            Quantity::Radius => f.write_str("section radius [m]"),
            Quantity::InnerRadius => f.write_str("tube inner radius [m]"),
            Quantity::Width => f.write_str("rectangle width [m]"),
            Quantity::Height => f.write_str("rectangle height [m]"),
            Quantity::BaseRadius => f.write_str("tapered section base radius [m]"),
            Quantity::TipRadius => f.write_str("tapered section tip radius [m]"),
            Quantity::RodLength => f.write_str("rod length [m]"),
            Quantity::TranslationalDrag => f.write_str("translational drag coefficient [N s/m^2]"),
            Quantity::RotationalDrag => f.write_str("rotational drag coefficient [N m s/m]"),
            Quantity::CableFrom => f.write_str("cable span start `from` [m]"),
            Quantity::CableTo => f.write_str("cable span end `to` [m]"),
            Quantity::OffsetY => f.write_str("cable offset y [m]"),
            Quantity::OffsetZ => f.write_str("cable offset z [m]"),
            Quantity::Path => f.write_str("cable path"),
            Quantity::PathPoint { index, component } => write!(
                f,
                "cable path point {index} {} [m]",
                ["s", "y", "z"].get(component).copied().unwrap_or("?")
            ),
            Quantity::Tension => f.write_str("cable tension [N]"),
            Quantity::TensionTimes => f.write_str("cable tension times"),
            Quantity::TensionTime(i) => write!(f, "cable tension time {i} [s]"),
            Quantity::TensionValues => f.write_str("cable tension values"),
            Quantity::TensionValue(i) => write!(f, "cable tension value {i} [N]"),
            Quantity::CableFriction => f.write_str("cable friction coefficient"),
            Quantity::LoadPosition => f.write_str("point load abscissa s [m]"),
            Quantity::Force(c) => write!(f, "point load force {} [N]", axis(c)),
            Quantity::Moment(c) => write!(f, "point load moment {} [N m]", axis(c)),
            Quantity::ForceDensity(c) => write!(f, "distributed force {} [N/m]", axis(c)),
            Quantity::MomentDensity(c) => write!(f, "distributed moment {} [N m/m]", axis(c)),
        }
    }
}

/// What can be wrong with a section, material, load or cable description.
///
/// Every variant names the offending [`Quantity`] (or is specific to one)
/// and carries its value, so a scene loader can point at the exact field
/// without reading the message.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MechanicsError {
    /// A quantity that must be strictly positive and finite is not.
    #[error("{quantity} must be positive and finite, got {value}")]
    NotPositive {
        /// Which quantity.
        quantity: Quantity,
        /// The offending value.
        value: f64,
    },
    /// A quantity that must be non-negative and finite is not.
    #[error("{quantity} must be non-negative and finite, got {value}")]
    Negative {
        /// Which quantity.
        quantity: Quantity,
        /// The offending value.
        value: f64,
    },
    /// A quantity that must be finite is NaN or infinite.
    #[error("{quantity} is not finite ({value})")]
    NotFinite {
        /// Which quantity.
        quantity: Quantity,
        /// The offending value.
        value: f64,
    },
    /// A required quantity was not given (material builder).
    #[error("{quantity} is required")]
    Missing {
        /// The quantity (for the elastic constants: [`Quantity::PoissonRatio`],
        /// which [`Quantity::ShearModulus`] may replace).
        quantity: Quantity,
    },
    /// Two quantities that determine the same thing were both given.
    #[error("{quantity} and {other} both given: give one of them")]
    Conflict {
        /// The quantity given second.
        quantity: Quantity,
        /// The one it conflicts with.
        other: Quantity,
    },
    /// A tube's inner radius is not smaller than its outer radius.
    #[error("tube inner radius {inner} m must be smaller than its outer radius {outer} m")]
    InnerRadius {
        /// Inner radius \[m\].
        inner: f64,
        /// Outer radius \[m\].
        outer: f64,
    },
    /// A Poisson ratio outside `(−1, 0.5]`.
    #[error("Poisson ratio must lie in (-1, 0.5], got {value}")]
    PoissonRatio {
        /// The offending value.
        value: f64,
    },
    /// A cable span that does not start in `[0, L)`.
    #[error("cable span start from = {from} m must lie in [0, rod length {length}) m")]
    CableFrom {
        /// Start of the span \[m\].
        from: f64,
        /// Rod length \[m\].
        length: f64,
    },
    /// A cable span whose end is not in `(from, L]`.
    #[error("cable span end to = {to} m must lie in (from = {from}, rod length {length}] m")]
    CableTo {
        /// Start of the span \[m\].
        from: f64,
        /// End (anchor) of the span \[m\].
        to: f64,
        /// Rod length \[m\].
        length: f64,
    },
    /// A cable path with fewer than two points.
    #[error(
        "a cable path needs at least two points (s, y, z), found {points}; use an offset for a \
         constant routing"
    )]
    PathTooShort {
        /// Points given.
        points: usize,
    },
    /// A cable path point outside the rod.
    #[error("cable path point {index}: s = {s} m lies outside the rod [0, {length}] m")]
    PathOutsideRod {
        /// Point index.
        index: usize,
        /// Its abscissa \[m\].
        s: f64,
        /// The rod length \[m\].
        length: f64,
    },
    /// A cable path that does not cover the cable's span (it is not extrapolated).
    #[error(
        "cable path covers s in [{first}, {last}] but the cable spans [from = {from}, to = {to}]; \
         extend the path or set from/to"
    )]
    PathCoverage {
        /// Abscissa of the first point \[m\].
        first: f64,
        /// Abscissa of the last point \[m\].
        last: f64,
        /// Span start \[m\].
        from: f64,
        /// Span end \[m\].
        to: f64,
    },
    /// A table's abscissae (path `s`, tension times) are not strictly increasing.
    #[error(
        "{quantity}: entry {index} ({value}) is not greater than the previous entry ({previous})"
    )]
    NotIncreasing {
        /// Which table ([`Quantity::Path`] or [`Quantity::TensionTimes`]).
        quantity: Quantity,
        /// Index of the offending entry.
        index: usize,
        /// Its abscissa.
        value: f64,
        /// The previous abscissa.
        previous: f64,
    },
    /// A table that needs at least one entry is empty.
    #[error("{quantity} needs at least one entry")]
    Empty {
        /// Which table.
        quantity: Quantity,
    },
    /// Two sizes that must agree do not.
    #[error("{quantity} has {got} entries, expected {expected}")]
    SizeMismatch {
        /// Which table.
        quantity: Quantity,
        /// The size given.
        got: usize,
        /// The size required.
        expected: usize,
    },
    /// The mechanical body and the kinematic rod disagree on the length.
    #[error("body length {body} m differs from the rod length {rod} m")]
    LengthMismatch {
        /// Length of the [`crate::RodProperties`] \[m\].
        body: f64,
        /// Length of the kinematic rod \[m\].
        rod: f64,
    },
    /// An abscissa outside the rod.
    #[error("{quantity} = {s} lies outside the rod [0, {length}] m")]
    OutOfRod {
        /// Which abscissa.
        quantity: Quantity,
        /// The abscissa \[m\].
        s: f64,
        /// The rod length \[m\].
        length: f64,
    },
    /// A load frame name that is not `world` or `body`.
    #[error("unknown load frame {name:?} (valid: world, body)")]
    UnknownLoadFrame {
        /// The name given.
        name: String,
    },
}

pub(crate) fn positive(quantity: Quantity, value: f64) -> Result<(), MechanicsError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(MechanicsError::NotPositive { quantity, value })
    }
}

pub(crate) fn non_negative(quantity: Quantity, value: f64) -> Result<(), MechanicsError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(MechanicsError::Negative { quantity, value })
    }
}

pub(crate) fn finite(quantity: Quantity, value: f64) -> Result<(), MechanicsError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(MechanicsError::NotFinite { quantity, value })
    }
}

/// Checks the three components of a vector, naming each by `quantity(c)`.
pub(crate) fn finite3(
    quantity: fn(usize) -> Quantity,
    v: &softrod_lie::Vec3,
) -> Result<(), MechanicsError> {
    for (c, &x) in v.iter().enumerate() {
        finite(quantity(c), x)?;
    }
    Ok(())
}
