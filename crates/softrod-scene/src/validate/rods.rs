//! `[[rod]]`: name, pieces, strains, rest strain, base; the rod itself is
//! made by the library's builder (`Rod::builder`), which checks every
//! value.

use nalgebra::Matrix3;
use softrod_dynamics::Rod;
use softrod_kinematics::{RodGeometry, Strain};
use softrod_lie::{Pose, Vec3, Vec6};

use super::{Ctx, Result};
use crate::keys::{self, RodContext, RodKeys};
use crate::raw::{RawBase, RawRod};

/// The rest stretches `q̄_x` accepted without a warning.
const REST_STRETCH_WARN: (f64, f64) = (0.5, 1.5);

/// How the file cut the rod into pieces.
enum Pieces {
    Equal(usize),
    Lengths(Vec<f64>),
}

impl Ctx<'_> {
    /// Every `[[rod]]`, at least one, names unique.
    pub(super) fn rods(&mut self, raw: Vec<RawRod>) -> Result<Vec<Rod>> {
        if raw.is_empty() {
            return Err(self
                .r
                .missing("rod", " (a scene needs at least one [[rod]] table)"));
        }
        let mut rods: Vec<Rod> = Vec::with_capacity(raw.len());
        for (i, r) in raw.into_iter().enumerate() {
            let rod = self.rod(i, r)?;
            if let Some(j) = rods.iter().position(|o| o.name == rod.name) {
                return Err(self.r.invalid(
                    &format!("rod[{i}].name"),
                    format!("duplicate rod name {:?} (also rod[{j}])", rod.name),
                ));
            }
            rods.push(rod);
        }
        Ok(rods)
    }

    /// `rod[i]` without its cables and loads (they come from their own tables).
    fn rod(&mut self, i: usize, r: RawRod) -> Result<Rod> {
        let p = format!("rod[{i}]");
        if r.name.trim().is_empty() {
            return Err(self
                .r
                .invalid(&format!("{p}.name"), "rod name must not be empty"));
        }
        let material = self.material(&p, r.material)?;
        let section = self.section(&format!("{p}.section"), r.section)?;
        let drag = super::body::drag(r.drag);
        let given_lengths = r.piece_lengths.is_some();
        let pieces = self.pieces(&p, r.pieces, r.piece_lengths)?;
        let strains = self.strains(&format!("{p}.strains"), r.strains.as_ref())?;
        let rest_strain = r.rest_strain.unwrap_or([0.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        self.check_rest_stretch(&p, rest_strain[3])?;
        let mut b = Rod::builder(r.length)
            .name(r.name)
            .section(section)
            .material(material)
            .rest_strain(Vec6::from(rest_strain))
            .base(base(r.base));
        b = match pieces {
            Pieces::Equal(n) => b.pieces(n),
            Pieces::Lengths(v) => b.piece_lengths(&v),
        };
        if let Some(listed) = &strains {
            // Coordinates follow the canonical order, whatever the file's.
            let mut canonical = listed.clone();
            canonical.sort();
            b = b.strains(canonical);
        }
        if let Some(d) = drag {
            b = b.drag(d);
        }
        let keys = RodKeys {
            owner: p.clone(),
            pieces: r.pieces,
            piece_lengths: given_lengths,
            strains,
        };
        let spec = b.build().map_err(|e| {
            let cx = RodContext {
                owner: p.clone(),
                length: r.length,
                keys: Some(&keys),
                cables: &[],
                loads: &[],
            };
            keys::dynamics(&self.r, Some(cx), e)
        })?;
        self.warn_short_pieces(&p, given_lengths, &spec);
        self.warn_rest_validity(i, &spec);
        Ok(spec)
    }

    /// `pieces` / `piece_lengths`: which one defines the pieces, and whether
    /// they agree when both are given (their values are the library's to check).
    fn pieces(&self, p: &str, pieces: Option<i64>, lengths: Option<Vec<f64>>) -> Result<Pieces> {
        let pieces_path = format!("{p}.pieces");
        if let Some(n) = pieces
            && n < 0
        {
            return Err(self.r.out_of_range(
                &pieces_path,
                n,
                format!("in [1, {}]", RodGeometry::MAX_PIECES),
            ));
        }
        match (pieces, lengths) {
            (None, None) => Err(self.r.missing(
                &pieces_path,
                " (give pieces = N for equal pieces, or piece_lengths = [...])",
            )),
            (Some(n), None) => Ok(Pieces::Equal(n as usize)),
            (pieces, Some(v)) => {
                if let Some(n) = pieces
                    && n as usize != v.len()
                {
                    return Err(self.r.inconsistent(
                        &pieces_path,
                        format!("pieces = {n} but piece_lengths lists {} pieces", v.len()),
                    ));
                }
                Ok(Pieces::Lengths(v))
            }
        }
    }

    /// `strains`: `None` for all six (`"all"` or absent), else the names as
    /// listed; warns when they are not in canonical order.
    fn strains(&mut self, p: &str, v: Option<&toml::Value>) -> Result<Option<Vec<Strain>>> {
        let list = match v {
            None => return Ok(None),
            Some(toml::Value::String(s)) if s == "all" => return Ok(None),
            Some(toml::Value::String(s)) => {
                if s.parse::<Strain>().is_ok() {
                    return Err(self.r.wrong_type(
                        p,
                        format!("a single strain is written as a list: strains = [{s:?}]"),
                    ));
                }
                return Err(self.r.unknown_name(
                    p,
                    s,
                    &["\"all\"", "or a list of kx, ky, kz, qx, qy, qz"],
                ));
            }
            Some(toml::Value::Array(a)) => a,
            Some(other) => {
                return Err(self.r.wrong_type(
                    p,
                    format!(
                        "expected \"all\" or a list of strain names (kx, ky, kz, qx, qy, qz), \
                         found {}",
                        other.type_str()
                    ),
                ));
            }
        };
        let mut listed = Vec::with_capacity(list.len());
        for (k, v) in list.iter().enumerate() {
            let pk = format!("{p}[{k}]");
            let Some(name) = v.as_str() else {
                return Err(self.r.wrong_type(
                    &pk,
                    format!("expected a strain name, found {}", v.type_str()),
                ));
            };
            let strain = name.parse::<Strain>().map_err(|e| {
                let names = Strain::ALL.map(Strain::name);
                self.r
                    .unknown_name(&pk, name, &names)
                    .caused_by(Box::new(e))
            })?;
            listed.push(strain);
        }
        if listed.windows(2).any(|w| w[0] > w[1]) {
            let mut sorted = listed.clone();
            sorted.sort();
            sorted.dedup();
            let canonical: Vec<&str> = sorted.iter().map(|s| s.name()).collect();
            self.warn(
                p,
                format!(
                    "strains are not in canonical order; the coordinates of each piece follow \
                     the order kx, ky, kz, qx, qy, qz: {canonical:?}"
                ),
            );
        }
        Ok(Some(listed))
    }

    /// The rest stretch `q̄_x` (rest arc length per unit of material length
    /// `s`): `≤ 0` folds the rest shape onto itself (the sections' tangents
    /// point backwards or the rod has no length) and is an error; outside
    /// `[0.5, 1.5]` the rest arc length differs from `length` by more than
    /// half, which is rarely meant, and is a warning.
    fn check_rest_stretch(&mut self, p: &str, stretch: f64) -> Result<()> {
        let path = format!("{p}.rest_strain[3]");
        if stretch <= 0.0 {
            return Err(self.r.out_of_range(
                &path,
                stretch,
                "> 0 (the rest stretch q̄x; 1 for an unstretched rod)",
            ));
        }
        if !(REST_STRETCH_WARN.0..=REST_STRETCH_WARN.1).contains(&stretch) {
            self.warn(
                &path,
                format!(
                    "rest stretch {stretch} is outside [{}, {}]: the rod's rest arc length is \
                     {stretch} × length",
                    REST_STRETCH_WARN.0, REST_STRETCH_WARN.1
                ),
            );
        }
        Ok(())
    }

    /// Slenderness: a piece shorter than the section is outside what a rod
    /// model describes well.
    fn warn_short_pieces(&mut self, p: &str, given_lengths: bool, spec: &Rod) {
        let (section, length) = (spec.properties.section(), spec.properties.length());
        let short: Vec<(usize, f64, f64)> = spec
            .geometry
            .pieces()
            .iter()
            .enumerate()
            .filter_map(|(k, piece)| {
                let radius = section
                    .half_size(piece.start / length)
                    .max(section.half_size((piece.end() / length).min(1.0)));
                (piece.length < radius).then_some((k, piece.length, radius))
            })
            .collect();
        if let Some(&(k, l, radius)) = short.first() {
            let key = if given_lengths {
                format!("{p}.piece_lengths")
            } else {
                format!("{p}.pieces")
            };
            self.warn(
                &key,
                format!(
                    "{} of {} pieces are shorter than the section radius (piece {k}: \
                     length {l} m < radius {radius} m); a rod model assumes slender pieces",
                    short.len(),
                    spec.geometry.n_pieces()
                ),
            );
        }
    }
}

/// The clamped base: `position` (default origin) and the row-major
/// `rotation` (default identity), local → world.
pub(super) fn base(b: Option<RawBase>) -> Pose {
    let b = b.unwrap_or(RawBase {
        position: None,
        rotation: None,
    });
    let r = b
        .rotation
        .unwrap_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    Pose::new(
        Matrix3::from_fn(|i, j| r[i][j]),
        Vec3::from(b.position.unwrap_or([0.0; 3])),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base_rotation_is_row_major() {
        let g = base(Some(RawBase {
            position: Some([1.0, 2.0, 3.0]),
            rotation: Some([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]),
        }));
        // Local x maps to world -z.
        let x = g.rotation * Vec3::new(1.0, 0.0, 0.0);
        assert!((x - Vec3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
        assert_eq!(g.translation, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(base(None), Pose::identity());
    }
}
