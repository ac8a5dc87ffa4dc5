//! What the gradient test files share: central differences of whole runs
//! and the comparison of an adjoint entry with them.

/// Central difference of `f` at `x` with relative step 1e-6 (absolute
/// `floor` for a zero `x`).
pub fn central(x: f64, floor: f64, f: impl Fn(f64) -> f64) -> f64 {
    let d = (1e-6 * x.abs()).max(floor);
    (f(x + d) - f(x - d)) / (2.0 * d)
}

/// Asserts that the gradient entry `adjoint` equals the central difference
/// `differences` to 1e-6, relative to the larger of `|differences|` and
/// `scale` (for entries near zero).
pub fn agree(name: &str, adjoint: f64, differences: f64, scale: f64) {
    let err = (adjoint - differences).abs() / differences.abs().max(scale);
    eprintln!("{name}: adjoint {adjoint:e}, differences {differences:e}, relative {err:e}");
    assert!(
        err < 1e-6,
        "{name}: adjoint {adjoint:e}, differences {differences:e}, relative {err:e}"
    );
}

/// `base` for the runs of `s`: Radau IIA measures its Newton iteration
/// against its internal tolerance `0.1·rtol^(2/3)` (RADAU5's), 46× the
/// `rtol = 1e-8` of the test scenes; `newton_tol` scaled by
/// `rtol / (0.1·rtol^(2/3))` solves its stage equations to the same
/// absolute accuracy as the ESDIRK runs, so the differences carry the
/// same Newton noise (error / step) — with `base`'s 1e-3 as is, it is
/// 4e-7 relative on a q0 entry with a 1e-6 step (measured).
#[allow(dead_code)]
pub fn options_for(
    s: &softrod::Simulation,
    base: softrod::GradientOptions,
) -> softrod::GradientOptions {
    let settings = s.settings();
    if settings.integrator.name() != "radau5" {
        return base;
    }
    let internal = 0.1 * settings.rtol.powf(2.0 / 3.0);
    softrod::GradientOptions {
        newton_tol: base.newton_tol.map(|t| t * settings.rtol / internal),
        ..base
    }
}

/// The soft four-bar the closed-chain gradient tests share: ground pins at
/// (0, 0, 0) and (0.3, 0, −0.15); the crank `a` (0.3 m, 2 pieces, revolute
/// about y, `crank_joint` the rest of its joint table: damping, actuator,
/// prescribed) along x, the rocker `b` (0.15 m) along z; their tips meet
/// at (0.3, 0, 0), where `hand` (mass `hand_mass`, `hand_extra` more keys)
/// sits on `b` and a ball closure holds `a`'s tip to it. `a_strains`,
/// `a_material` (the inside of its material table), `b_shear` set the
/// rods; `after_a` is TOML placed after rod `a` (its cables).
#[allow(dead_code)]
pub struct FourBar<'a> {
    pub crank_joint: &'a str,
    pub a_strains: &'a str,
    pub a_material: &'a str,
    pub after_a: &'a str,
    pub b_shear: f64,
    pub hand_mass: f64,
    pub hand_extra: &'a str,
}

#[allow(dead_code)]
impl FourBar<'_> {
    /// The scene's TOML, run at rtol 1e-8, atol 1e-10.
    pub fn toml(&self) -> String {
        format!(
            r#"
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "a"
joint = {{ type = "revolute", axis = [0, 1, 0]{crank_joint} }}
length = 0.3
pieces = 2
strains = {a_strains}
section = {{ shape = "circle", radius = 0.01 }}
material = {{ {a_material} }}
{after_a}
[[rod]]
name = "b"
base = {{ position = [0.3, 0.0, -0.15], rotation = [[0, 0, -1], [0, 1, 0], [1, 0, 0]] }}
joint = {{ type = "revolute", axis = [0, 1, 0] }}
length = 0.15
pieces = 2
strains = ["ky", "qx", "qz"]
section = {{ shape = "circle", radius = 0.008 }}
material = {{ density = 1100.0, young = 2.0e6, shear_modulus = {b_shear:e}, viscosity = 1.0e3 }}
[[body]]
name = "hand"
parent = "b"
mass = {hand_mass:e}
inertia = [1e-6, 1e-6, 1e-6]
{hand_extra}
[[closure]]
type = "ball"
a = {{ element = "a" }}
b = {{ element = "hand" }}
[run]
rtol = 1e-8
atol = 1e-10
"#,
            crank_joint = self.crank_joint,
            a_strains = self.a_strains,
            a_material = self.a_material,
            after_a = self.after_a,
            b_shear = self.b_shear,
            hand_mass = self.hand_mass,
            hand_extra = self.hand_extra,
        )
    }
}

/// [`FourBar`] with the defaults of the tests that vary only the crank's
/// joint: strains `ky, kz, qx`, E 1 MPa, ρ 1000, Poisson 0.5, viscosity
/// 300 on `a`, no cables, shear modulus 0.6 MPa on `b`, a 10 g hand.
#[allow(dead_code)]
pub const FOUR_BAR: FourBar<'static> = FourBar {
    crank_joint: "",
    a_strains: r#"["ky", "kz", "qx"]"#,
    a_material: "density = 1000.0, young = 1.0e6, poisson = 0.5, viscosity = 300.0",
    after_a: "",
    b_shear: 6.0e5,
    hand_mass: 0.01,
    hand_extra: "",
};
