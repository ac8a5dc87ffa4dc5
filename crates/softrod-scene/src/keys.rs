//! From the library's structured errors to key paths of the file.
//!
//! The lower crates check every value (one check, where it enters); the
//! scene only says where in the file the value came from. Each error is
//! matched by variant and [`Quantity`], never by its message text, and the
//! library error is kept as the [`SceneError`]'s source.

use softrod_dynamics::{DynamicsError, Rod};
use softrod_kinematics::{KinematicsError, LengthOf, RodGeometry, Strain};
use softrod_mechanics::{MechanicsError, Quantity, RodProperties};

use crate::error::SceneError;
use crate::locate::join;
use crate::reporter::Reporter;
use crate::scene::Origins;

/// The key of a mechanics quantity below the table that holds it (`rod[i]`,
/// `cable[j]`, `load[j]`); `None` for quantities a scene file does not have.
fn quantity_key(q: Quantity) -> Option<String> {
    let key = match q {
        Quantity::Density => "material.density",
        Quantity::YoungsModulus => "material.young",
        Quantity::ShearModulus => "material.shear_modulus",
        Quantity::PoissonRatio => "material.poisson",
        Quantity::Viscosity => "material.viscosity",
        Quantity::Radius => "section.radius",
        Quantity::InnerRadius => "section.inner_radius",
        Quantity::Width => "section.width",
        Quantity::Height => "section.height",
        Quantity::BaseRadius => "section.radius_base",
        Quantity::TipRadius => "section.radius_tip",
        Quantity::RodLength => "length",
        Quantity::TranslationalDrag => "drag.translational",
        Quantity::RotationalDrag => "drag.rotational",
        Quantity::CableFrom => "from",
        Quantity::CableTo => "to",
        Quantity::OffsetY => "offset[0]",
        Quantity::OffsetZ => "offset[1]",
        Quantity::Path => "path",
        Quantity::PathPoint { index, component } => {
            return Some(format!("path[{index}][{component}]"));
        }
        Quantity::Tension => "tension",
        Quantity::CableFriction => "friction",
        Quantity::TensionTimes => "tension.times",
        Quantity::TensionTime(i) => return Some(format!("tension.times[{i}]")),
        Quantity::TensionValues => "tension.values",
        Quantity::TensionValue(i) => return Some(format!("tension.values[{i}]")),
        Quantity::LoadPosition => "s",
        Quantity::Force(c) => return Some(format!("force[{c}]")),
        Quantity::Moment(c) => return Some(format!("moment[{c}]")),
        _ => return None,
    };
    Some(key.to_owned())
}

/// The last component of a quantity's key (`poisson`, `shear_modulus`), for
/// messages that name keys.
fn key_name(q: Quantity) -> String {
    let key = quantity_key(q).unwrap_or_else(|| q.to_string());
    key.rsplit('.').next().unwrap_or(&key).to_owned()
}

/// `owner.key` of a quantity, or `owner` when the file has no such key.
fn path_of(owner: &str, q: Quantity) -> String {
    quantity_key(q).map_or_else(|| owner.to_owned(), |k| format!("{owner}.{k}"))
}

/// A mechanics error about a value of the table `owner` (`rod[0]`,
/// `cable[1]`, `load[2]`) of a rod of length `length` [m] (as the file gave
/// it, for messages).
pub(crate) fn mechanics(r: &Reporter, owner: &str, length: f64, e: MechanicsError) -> SceneError {
    let err = match &e {
        MechanicsError::NotPositive { quantity, value } => {
            r.out_of_range(&path_of(owner, *quantity), value, "> 0")
        }
        MechanicsError::Negative { quantity, value } => {
            r.out_of_range(&path_of(owner, *quantity), value, ">= 0")
        }
        MechanicsError::NotFinite { quantity, value } => {
            r.not_finite(&path_of(owner, *quantity), value)
        }
        MechanicsError::Missing { quantity } => {
            let note = if *quantity == Quantity::PoissonRatio {
                " (or shear_modulus)"
            } else {
                ""
            };
            r.missing(&path_of(owner, *quantity), note)
        }
        MechanicsError::Conflict { quantity, other } => r.invalid(
            &path_of(owner, *quantity),
            format!(
                "give either {} or {}, not both",
                key_name(*other),
                key_name(*quantity)
            ),
        ),
        MechanicsError::PoissonRatio { value } => r.out_of_range(
            &path_of(owner, Quantity::PoissonRatio),
            value,
            "in (-1, 0.5]",
        ),
        MechanicsError::InnerRadius { inner, outer } => r.out_of_range(
            &path_of(owner, Quantity::InnerRadius),
            inner,
            format!("in [0, radius = {outer})"),
        ),
        MechanicsError::CableFrom { from, .. } => r.out_of_range(
            &path_of(owner, Quantity::CableFrom),
            from,
            format!("in [0, length = {length})"),
        ),
        MechanicsError::CableTo { from, to, .. } => r.out_of_range(
            &path_of(owner, Quantity::CableTo),
            to,
            format!("in (from = {from}, length = {length}]"),
        ),
        MechanicsError::PathTooShort { points } => r.invalid(
            &path_of(owner, Quantity::Path),
            format!(
                "a path needs at least two points [s, y, z], found {points}; use offset for a \
                 constant routing"
            ),
        ),
        MechanicsError::PathOutsideRod { index, s, .. } => r.out_of_range(
            &format!("{owner}.path[{index}][0]"),
            s,
            format!("in [0, length = {length}] (s of point {index})"),
        ),
        MechanicsError::PathCoverage {
            first,
            last,
            from,
            to,
        } => r.invalid(
            &path_of(owner, Quantity::Path),
            format!(
                "path covers s in [{first}, {last}] but the cable spans [from = {from}, \
                 to = {to}]; extend the path or set from/to"
            ),
        ),
        MechanicsError::NotIncreasing {
            quantity: Quantity::Path,
            index,
            value,
            previous,
        } => r.invalid(
            &format!("{owner}.path[{index}]"),
            format!(
                "path abscissae must strictly increase: s = {value} at point {index} is not \
                 greater than s = {previous} at point {}",
                index - 1
            ),
        ),
        MechanicsError::NotIncreasing {
            quantity,
            index,
            value,
            previous,
        } => r.invalid(
            &format!("{}[{index}]", path_of(owner, *quantity)),
            format!("times must strictly increase: {value} is not greater than {previous}"),
        ),
        MechanicsError::Empty { quantity } => r.invalid(
            &path_of(owner, *quantity),
            "a tension schedule needs at least one point",
        ),
        MechanicsError::SizeMismatch {
            quantity,
            got,
            expected,
        } => r.inconsistent(
            &path_of(owner, *quantity),
            format!("{got} values for {expected} times"),
        ),
        MechanicsError::LengthMismatch { body, rod } => r.inconsistent(
            &format!("{owner}.piece_lengths"),
            piece_sum_message(*rod, *body),
        ),
        MechanicsError::OutOfRod { quantity, s, .. } => r.out_of_range(
            &path_of(owner, *quantity),
            s,
            format!("in [0, length = {length}]"),
        ),
        MechanicsError::UnknownLoadFrame { name } => {
            r.unknown_name(&join(owner, "frame"), name, &["world", "body"])
        }
        other => r.invalid(owner, other),
    };
    err.caused_by(Box::new(e))
}

fn piece_sum_message(sum: f64, length: f64) -> String {
    format!(
        "piece_lengths sum to {sum} m but length = {length} m (must agree within {:e} relative)",
        RodProperties::LENGTH_RTOL
    )
}

/// How the file described a rod's pieces and strains: what kinematics
/// errors point at.
pub(crate) struct RodKeys {
    /// `rod[i]`.
    pub owner: String,
    /// `pieces` as written, when given.
    pub pieces: Option<i64>,
    /// Whether `piece_lengths` was given (it then defines the pieces).
    pub piece_lengths: bool,
    /// The strains as listed (`None`: `"all"` or absent).
    pub strains: Option<Vec<Strain>>,
}

/// A kinematics error about the rod `keys` describes.
pub(crate) fn kinematics(r: &Reporter, keys: &RodKeys, e: KinematicsError) -> SceneError {
    let p = |k: &str| format!("{}.{k}", keys.owner);
    let err = match &e {
        KinematicsError::BadLength {
            what: LengthOf::RodGeometry,
            value,
        } => r.out_of_range(&p("length"), value, "> 0"),
        KinematicsError::BadLength {
            what: LengthOf::Piece(k),
            value,
        } if keys.piece_lengths => {
            r.out_of_range(&format!("{}[{k}]", p("piece_lengths")), value, "> 0")
        }
        KinematicsError::NoPieces if keys.piece_lengths => r.invalid(
            &p("piece_lengths"),
            "piece_lengths must list at least one piece",
        ),
        KinematicsError::NoPieces => r.out_of_range(
            &p("pieces"),
            keys.pieces.unwrap_or(0),
            format!("in [1, {}]", RodGeometry::MAX_PIECES),
        ),
        KinematicsError::TooManyPieces { pieces, max } => {
            r.out_of_range(&p("pieces"), pieces, format!("in [1, {max}]"))
        }
        KinematicsError::BasisColumns { columns: 0 } => r.invalid(
            &p("strains"),
            "select at least one strain (kx, ky, kz, qx, qy, qz), or \"all\"",
        ),
        KinematicsError::DuplicateStrain { strain } => {
            // The second time the file lists it.
            let k = keys.strains.as_ref().and_then(|list| {
                list.iter()
                    .enumerate()
                    .filter(|(_, s)| *s == strain)
                    .nth(1)
                    .map(|(k, _)| k)
            });
            let path = k.map_or_else(|| p("strains"), |k| format!("{}[{k}]", p("strains")));
            r.invalid(&path, format!("strain {:?} listed twice", strain.name()))
        }
        KinematicsError::BaseNotRotation {
            deviation,
            determinant,
            tolerance,
        } => r.invalid(
            &p("base.rotation"),
            format!(
                "not a rotation matrix: must be orthonormal with determinant +1 within \
                 {tolerance:e} (max |R Rᵀ − I| = {deviation:.3e}, det R = {determinant})"
            ),
        ),
        KinematicsError::BaseNotFinite { value } => r.not_finite(&p("base"), value),
        KinematicsError::RestStrainNotFinite {
            component, value, ..
        } => r.not_finite(
            &format!("{}[{}]", p("rest_strain"), component.index()),
            value,
        ),
        other => r.invalid(&keys.owner, other),
    };
    err.caused_by(Box::new(e))
}

/// The rod a dynamics error is about, as the file has it.
pub(crate) struct RodContext<'a> {
    /// `rod[i]`.
    pub owner: String,
    /// Its length as the file gives it [m] (for messages).
    pub length: f64,
    /// How the file gave its pieces and strains (at validation).
    pub keys: Option<&'a RodKeys>,
    /// File index of each of its cables (`cable[j]`), in its order.
    pub cables: &'a [usize],
    /// File index of each of its point loads (`load[j]`).
    pub loads: &'a [usize],
}

/// A dynamics error (from a rod's builder, or from the model) about the rod
/// `rod` describes (`None`: the error names no rod, or one the scene does
/// not have).
pub(crate) fn dynamics(r: &Reporter, rod: Option<RodContext>, e: DynamicsError) -> SceneError {
    let owner = rod.as_ref().map_or("", |c| c.owner.as_str());
    let length = rod.as_ref().map_or(f64::NAN, |c| c.length);
    let err = match (&e, &rod) {
        (DynamicsError::RodGeometry { source, .. }, Some(cx)) => {
            let fallback = RodKeys {
                owner: cx.owner.clone(),
                pieces: None,
                piece_lengths: false,
                strains: None,
            };
            kinematics(r, cx.keys.unwrap_or(&fallback), source.clone())
        }
        (
            DynamicsError::RodProperties { source, .. } | DynamicsError::Drag { source, .. },
            Some(_),
        ) => mechanics(r, owner, length, source.clone()),
        (DynamicsError::Cable { cable, source, .. }, Some(cx)) => {
            let owner = cx
                .cables
                .get(*cable)
                .map_or_else(|| owner.to_owned(), |j| format!("cable[{j}]"));
            mechanics(r, &owner, length, source.clone())
        }
        (DynamicsError::PointLoad { load, source, .. }, Some(cx)) => {
            let owner = cx
                .loads
                .get(*load)
                .map_or_else(|| owner.to_owned(), |j| format!("load[{j}]"));
            mechanics(r, &owner, length, source.clone())
        }
        (DynamicsError::PieceLengthSum { sum, length, .. }, _) => r.inconsistent(
            &join(owner, "piece_lengths"),
            piece_sum_message(*sum, *length),
        ),
        (DynamicsError::NoRods, _) => {
            r.missing("rod", " (a scene needs at least one [[rod]] table)")
        }
        (DynamicsError::NoQuadraturePoints, _) => r.out_of_range("run.quadrature", 0, ">= 1"),
        (DynamicsError::GravityNotFinite { component, value }, _) => {
            r.not_finite(&format!("world.gravity[{component}]"), value)
        }
        (other, _) => r.invalid(owner, other),
    };
    err.caused_by(Box::new(e))
}

/// The [`RodContext`] of rod `index` of a validated scene.
pub(crate) fn rod_context<'a>(
    rods: &[Rod],
    origins: &'a Origins,
    index: usize,
) -> Option<RodContext<'a>> {
    Some(RodContext {
        owner: format!("rod[{index}]"),
        length: rods.get(index)?.properties.length(),
        keys: None,
        cables: origins.cables.get(index).map_or(&[], Vec::as_slice),
        loads: origins.loads.get(index).map_or(&[], Vec::as_slice),
    })
}
