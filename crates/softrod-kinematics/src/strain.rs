//! The six strain components of a Cosserat rod, by name.

use crate::error::KinematicsError;
use std::fmt;
use std::str::FromStr;

/// One of the six strain components, in softrod's order `(kx, ky, kz, qx, qy, qz)`:
/// torsion, the two bendings, extension, the two shears (angular part first,
/// body frame, local x along the rod).
///
/// `Display` and [`FromStr`] use the scene-file names:
///
/// ```
/// use softrod_kinematics::Strain;
///
/// assert_eq!("ky".parse::<Strain>().unwrap(), Strain::Ky);
/// assert_eq!(Strain::Qx.to_string(), "qx");
/// assert!("kw".parse::<Strain>().is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Strain {
    /// Torsion (rad/m).
    Kx = 0,
    /// Bending about the local y axis (rad/m).
    Ky = 1,
    /// Bending about the local z axis (rad/m).
    Kz = 2,
    /// Extension (1 at rest).
    Qx = 3,
    /// Shear along local y.
    Qy = 4,
    /// Shear along local z.
    Qz = 5,
}

impl Strain {
    /// All six, in order.
    pub const ALL: [Strain; 6] = [
        Strain::Kx,
        Strain::Ky,
        Strain::Kz,
        Strain::Qx,
        Strain::Qy,
        Strain::Qz,
    ];

    /// The scene-file name (`"kx"` … `"qz"`).
    pub fn name(self) -> &'static str {
        ["kx", "ky", "kz", "qx", "qy", "qz"][self as usize]
    }

    /// Position in the strain vector `ξ` (0 = kx … 5 = qz).
    #[inline]
    pub fn index(self) -> usize {
        self as usize
    }

    /// Whether this is an angular strain (torsion or bending, rad/m).
    #[inline]
    pub fn is_angular(self) -> bool {
        self.index() < 3
    }
}

impl fmt::Display for Strain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Strain {
    type Err = KinematicsError;

    /// Parses a scene-file name; anything else is
    /// [`KinematicsError::UnknownStrain`].
    fn from_str(name: &str) -> Result<Self, Self::Err> {
        Strain::ALL
            .into_iter()
            .find(|s| s.name() == name)
            .ok_or_else(|| KinematicsError::UnknownStrain {
                name: name.to_owned(),
            })
    }
}
