//! Table-driven tests over malformed scenes: each edit of the contract's
//! example must fail with a message naming the file, the key path and the problem.

use softrod_scene::{Scene, SceneError};

const BASE: &str = include_str!("contract_example.toml");
const FILE: &str = "case.toml";

/// One malformed scene: edits to [`BASE`] and what the error must say.
struct Case {
    name: &'static str,
    /// `(old, new)` replacements applied to the base text in order; `old = ""`
    /// appends `new` at the end.
    edits: &'static [(&'static str, &'static str)],
    /// Key path the error must name (and return from `SceneError::path`).
    path: &'static str,
    /// Substrings the message must contain (the problem, the value).
    says: &'static [&'static str],
}

fn apply(edits: &[(&str, &str)]) -> String {
    let mut text = BASE.to_owned();
    for (old, new) in edits {
        if old.is_empty() {
            text.push_str(new);
        } else {
            assert!(text.contains(old), "edit target {old:?} not in base scene");
            text = text.replacen(old, new, 1);
        }
    }
    text
}

const CASES: &[Case] = &[
    // --- missing keys
    Case {
        name: "missing length",
        edits: &[("length = 0.5\n", "")],
        path: "rod[0].length",
        says: &["missing required key"],
    },
    Case {
        name: "missing material",
        edits: &[(
            "material = { density = 1000.0, young = 1.0e6, poisson = 0.5, viscosity = 0.0 }\n",
            "",
        )],
        path: "rod[0].material",
        says: &["missing required key"],
    },
    Case {
        name: "missing young",
        edits: &[("young = 1.0e6, ", "")],
        path: "rod[0].material.young",
        says: &["missing required key"],
    },
    Case {
        name: "missing poisson and shear modulus",
        edits: &[("poisson = 0.5, ", "")],
        path: "rod[0].material.poisson",
        says: &["missing required key", "shear_modulus"],
    },
    Case {
        name: "missing pieces",
        edits: &[("pieces = 4\n", "")],
        path: "rod[0].pieces",
        says: &["missing required key", "piece_lengths"],
    },
    Case {
        name: "missing section radius",
        edits: &[("shape = \"circle\", radius = 0.01", "shape = \"circle\"")],
        path: "rod[0].section.radius",
        says: &["missing required key"],
    },
    Case {
        name: "missing cable routing",
        edits: &[("offset = [0.0, 0.008]\n", "")],
        path: "cable[0].offset",
        says: &["missing required key", "path"],
    },
    Case {
        name: "unknown top-level table",
        edits: &[("[[rod]]", "[not_a_rod]")],
        path: "not_a_rod",
        says: &["unknown key"],
    },
    // --- wrong types
    Case {
        name: "length is a string",
        edits: &[("length = 0.5", "length = \"0.5\"")],
        path: "rod[0].length",
        says: &["wrong type", "string \"0.5\", expected a number"],
    },
    Case {
        name: "pieces is a float",
        edits: &[("pieces = 4", "pieces = 4.5")],
        path: "rod[0].pieces",
        says: &["wrong type", "4.5", "expected an integer"],
    },
    Case {
        name: "gravity has two components",
        edits: &[("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, -9.81]")],
        path: "world.gravity",
        says: &[
            "wrong type",
            "array of length 2, expected an array of length 3",
        ],
    },
    Case {
        name: "rod name is a number",
        edits: &[("name = \"arm\"", "name = 3")],
        path: "rod[0].name",
        says: &["wrong type", "integer"],
    },
    Case {
        name: "tension is a string",
        edits: &[("tension = 2.0", "tension = \"2 N\"")],
        path: "cable[0].tension",
        says: &["wrong type", "string"],
    },
    Case {
        name: "single strain not in a list",
        edits: &[("strains = \"all\"", "strains = \"ky\"")],
        path: "rod[0].strains",
        says: &["strains = [\"ky\"]"],
    },
    // --- out of range
    Case {
        name: "negative length",
        edits: &[("length = 0.5", "length = -0.5")],
        path: "rod[0].length",
        says: &["out of range", "-0.5", "> 0"],
    },
    Case {
        name: "zero pieces",
        edits: &[("pieces = 4", "pieces = 0")],
        path: "rod[0].pieces",
        says: &["out of range", ": 0 "],
    },
    Case {
        name: "poisson above 0.5",
        edits: &[("poisson = 0.5", "poisson = 0.6")],
        path: "rod[0].material.poisson",
        says: &["out of range", "0.6", "(-1, 0.5]"],
    },
    Case {
        name: "poisson at -1",
        edits: &[("poisson = 0.5", "poisson = -1.0")],
        path: "rod[0].material.poisson",
        says: &["out of range", "-1"],
    },
    Case {
        name: "negative young",
        edits: &[("young = 1.0e6", "young = -1.0e6")],
        path: "rod[0].material.young",
        says: &["out of range", "-1000000"],
    },
    Case {
        name: "negative viscosity",
        edits: &[("viscosity = 0.0", "viscosity = -1.0")],
        path: "rod[0].material.viscosity",
        says: &["out of range", "-1", ">= 0"],
    },
    Case {
        name: "negative drag",
        edits: &[("translational = 0.0", "translational = -0.1")],
        path: "rod[0].drag.translational",
        says: &["out of range", "-0.1"],
    },
    Case {
        name: "tube inner radius too big",
        edits: &[(
            "shape = \"circle\", radius = 0.01",
            "shape = \"tube\", radius = 0.01, inner_radius = 0.01",
        )],
        path: "rod[0].section.inner_radius",
        says: &["out of range", "0.01"],
    },
    Case {
        name: "negative tension",
        edits: &[("tension = 2.0", "tension = -2.0")],
        path: "cable[0].tension",
        says: &["out of range", "-2", ">= 0"],
    },
    Case {
        name: "negative scheduled tension",
        edits: &[(
            "tension = 2.0",
            "tension = { times = [0, 1], values = [0, -1] }",
        )],
        path: "cable[0].tension.values[1]",
        says: &["out of range", "-1"],
    },
    Case {
        name: "cable span reversed",
        edits: &[("tension = 2.0", "tension = 2.0\nfrom = 0.3\nto = 0.2")],
        path: "cable[0].to",
        says: &["out of range", "0.2", "from = 0.3"],
    },
    Case {
        name: "cable path beyond the rod",
        edits: &[(
            "offset = [0.0, 0.008]",
            "path = [[0.0, 0.0, 0.008], [0.6, 0.0, 0.008]]",
        )],
        path: "cable[0].path[1][0]",
        says: &["out of range", "0.6"],
    },
    Case {
        name: "load beyond the rod",
        edits: &[("s = 0.5", "s = 0.7")],
        path: "load[0].s",
        says: &["out of range", "0.7", "length = 0.5"],
    },
    Case {
        name: "zero duration",
        edits: &[("duration = 1.0", "duration = 0.0")],
        path: "run.duration",
        says: &["out of range", "> 0"],
    },
    Case {
        name: "negative dt",
        edits: &[("dt = 1.0e-4", "dt = -1.0e-4")],
        path: "run.dt",
        says: &["out of range", "-0.0001"],
    },
    Case {
        name: "zero quadrature",
        edits: &[("quadrature = 4", "quadrature = 0")],
        path: "run.quadrature",
        says: &["out of range", ">= 1"],
    },
    Case {
        name: "zero shape points per piece",
        edits: &[(
            "quadrature = 4",
            "quadrature = 4\nshape_points_per_piece = 0",
        )],
        path: "run.shape_points_per_piece",
        says: &["out of range", "[1, 1000]"],
    },
    Case {
        name: "too many shape points per piece",
        edits: &[(
            "quadrature = 4",
            "quadrature = 4\nshape_points_per_piece = 5000",
        )],
        path: "run.shape_points_per_piece",
        says: &["out of range", "5000"],
    },
    Case {
        name: "initial row without a trajectory",
        edits: &[("", "\n[initial]\nrow = 3\n")],
        path: "initial.row",
        says: &["needs initial.trajectory"],
    },
    Case {
        name: "initial trajectory that does not exist",
        edits: &[("", "\n[initial]\ntrajectory = \"no/such/trajectory.csv\"\n")],
        path: "initial.trajectory",
        says: &["no/such/trajectory.csv", "cannot read"],
    },
    Case {
        name: "reference time after the run",
        edits: &[("", "\n[reference]\ntip = [0.5, 0, 0]\ntime = 2.0\n")],
        path: "reference.time",
        says: &["out of range", "2", "run.duration = 1"],
    },
    Case {
        name: "too many pieces",
        edits: &[("pieces = 4", "pieces = 2000000")],
        path: "rod[0].pieces",
        says: &["out of range", "2000000", "in [1, 1000000]"],
    },
    Case {
        name: "negative pieces",
        edits: &[("pieces = 4", "pieces = -3")],
        path: "rod[0].pieces",
        says: &["out of range", "-3"],
    },
    Case {
        name: "negative piece length",
        edits: &[("pieces = 4", "piece_lengths = [0.25, -0.25, 0.5]")],
        path: "rod[0].piece_lengths[1]",
        says: &["out of range", "-0.25", "> 0"],
    },
    Case {
        name: "negative shear modulus",
        edits: &[("poisson = 0.5", "shear_modulus = -3e5")],
        path: "rod[0].material.shear_modulus",
        says: &["out of range", "-300000", "> 0"],
    },
    Case {
        name: "negative rectangle width",
        edits: &[(
            "shape = \"circle\", radius = 0.01",
            "shape = \"rectangle\", width = -0.02, height = 0.01",
        )],
        path: "rod[0].section.width",
        says: &["out of range", "-0.02"],
    },
    Case {
        name: "cable starting beyond the rod",
        edits: &[("tension = 2.0", "tension = 2.0\nfrom = 0.6")],
        path: "cable[0].from",
        says: &["out of range", "0.6", "in [0, length = 0.5)"],
    },
    Case {
        name: "negative rotational drag",
        edits: &[("rotational = 0.0", "rotational = -1e-3")],
        path: "rod[0].drag.rotational",
        says: &["out of range", "-0.001", ">= 0"],
    },
    // --- unknown names
    Case {
        name: "unknown rod in a cable",
        edits: &[("rod = \"arm\"\noffset", "rod = \"amr\"\noffset")],
        path: "cable[0].rod",
        says: &["unknown rod name", "\"amr\"", "arm"],
    },
    Case {
        name: "unknown rod in a load",
        edits: &[("rod = \"arm\"\ns = 0.5", "rod = \"hand\"\ns = 0.5")],
        path: "load[0].rod",
        says: &["unknown rod name", "\"hand\""],
    },
    Case {
        name: "unknown rod in the reference",
        edits: &[("", "\n[reference]\nrod = \"other\"\ntip = [0.5, 0, 0]\n")],
        path: "reference.rod",
        says: &["unknown rod name", "\"other\""],
    },
    Case {
        name: "unknown integrator",
        edits: &[("integrator = \"dopri5\"", "integrator = \"euler\"")],
        path: "run.integrator",
        says: &[
            "unknown value \"euler\"",
            "rk4",
            "dopri5",
            "rosenbrock",
            "generalized-alpha",
        ],
    },
    Case {
        name: "unknown mode",
        edits: &[("mode = \"dynamics\"", "mode = \"static\"")],
        path: "run.mode",
        says: &["unknown value \"static\"", "statics"],
    },
    Case {
        name: "unknown load frame",
        edits: &[("frame = \"world\"", "frame = \"local\"")],
        path: "load[0].frame",
        says: &["unknown value \"local\"", "world, body"],
    },
    Case {
        name: "unknown shape",
        edits: &[("shape = \"circle\"", "shape = \"square\"")],
        path: "rod[0].section.shape",
        says: &["unknown value \"square\"", "rectangle"],
    },
    Case {
        name: "unknown strain name",
        edits: &[("strains = \"all\"", "strains = [\"ky\", \"kw\"]")],
        path: "rod[0].strains[1]",
        says: &["unknown value \"kw\"", "kx, ky, kz, qx, qy, qz"],
    },
    // --- not finite
    Case {
        name: "nan young",
        edits: &[("young = 1.0e6", "young = nan")],
        path: "rod[0].material.young",
        says: &["not a finite number", "nan"],
    },
    Case {
        name: "inf in gravity",
        edits: &[("-9.81]", "-inf]")],
        path: "world.gravity[2]",
        says: &["not a finite number", "-inf"],
    },
    Case {
        name: "overflowing length",
        edits: &[("length = 0.5", "length = 1e400")],
        path: "rod[0].length",
        says: &["not a finite number", "1e400"],
    },
    Case {
        name: "nan in initial q",
        edits: &[("", "\n[initial]\nq = [0, 0, nan]\n")],
        path: "initial.q[2]",
        says: &["not a finite number"],
    },
    // --- unknown keys
    Case {
        name: "typo lenght",
        edits: &[("length = 0.5", "lenght = 0.5")],
        path: "rod[0].lenght",
        says: &["unknown key", "`length`"],
    },
    Case {
        name: "typo in an inline table",
        edits: &[("density = 1000.0", "densty = 1000.0")],
        path: "rod[0].material.densty",
        says: &["unknown key", "`density`"],
    },
    Case {
        name: "typo in a table header",
        edits: &[("[run]", "[runn]")],
        path: "runn",
        says: &["unknown key", "`run`"],
    },
    Case {
        name: "typo in a tension schedule",
        edits: &[(
            "tension = 2.0",
            "tension = { times = [0, 1], value = [0, 1] }",
        )],
        path: "cable[0].tension.value",
        says: &["unknown key", "`values`"],
    },
    Case {
        name: "key of another shape",
        edits: &[("radius = 0.01", "radius = 0.01, width = 0.02")],
        path: "rod[0].section.width",
        says: &["does not apply to shape \"circle\""],
    },
    // --- inconsistent lengths
    Case {
        name: "initial q of the wrong length",
        edits: &[("", "\n[initial]\nq = [0.0, 0.0, 0.0]\n")],
        path: "initial.q",
        says: &[
            "inconsistent lengths",
            "3 values",
            "n_dof = 24",
            "4 pieces × 6 strains",
        ],
    },
    Case {
        name: "initial qdot of the wrong length",
        edits: &[
            ("strains = \"all\"", "strains = [\"ky\", \"kz\"]"),
            ("", "\n[initial]\nqdot = [0.0]\n"),
        ],
        path: "initial.qdot",
        says: &["inconsistent lengths", "1 values", "n_dof = 8"],
    },
    Case {
        name: "piece lengths not summing to length",
        edits: &[("pieces = 4", "piece_lengths = [0.1, 0.2, 0.3]")],
        path: "rod[0].piece_lengths",
        says: &["inconsistent lengths", "0.6", "length = 0.5"],
    },
    Case {
        name: "pieces disagreeing with piece lengths",
        edits: &[("pieces = 4", "pieces = 4\npiece_lengths = [0.2, 0.3]")],
        path: "rod[0].pieces",
        says: &["inconsistent lengths", "pieces = 4", "2 pieces"],
    },
    Case {
        name: "tension schedule lengths differ",
        edits: &[(
            "tension = 2.0",
            "tension = { times = [0, 1, 2], values = [0, 1] }",
        )],
        path: "cable[0].tension.values",
        says: &["inconsistent lengths", "2 values for 3 times"],
    },
    // --- other invalid values
    Case {
        name: "rotation not orthonormal",
        edits: &[("[[1,0,0],[0,1,0],[0,0,1]]", "[[1,0,0],[0,2,0],[0,0,1]]")],
        path: "rod[0].base.rotation",
        says: &["orthonormal", "det R = 2"],
    },
    Case {
        name: "rotation is a reflection",
        edits: &[("[[1,0,0],[0,1,0],[0,0,1]]", "[[1,0,0],[0,1,0],[0,0,-1]]")],
        path: "rod[0].base.rotation",
        says: &["determinant +1", "det R = -1"],
    },
    Case {
        name: "path s not increasing",
        edits: &[(
            "offset = [0.0, 0.008]",
            "path = [[0.0, 0.0, 0.008], [0.3, 0.0, 0.008], [0.2, 0.0, 0.008], [0.5, 0.0, 0.0]]",
        )],
        path: "cable[0].path[2]",
        says: &["strictly increase", "s = 0.2", "s = 0.3"],
    },
    Case {
        name: "path not covering the span",
        edits: &[(
            "offset = [0.0, 0.008]",
            "path = [[0.1, 0.0, 0.008], [0.5, 0.0, 0.0]]",
        )],
        path: "cable[0].path",
        says: &["covers s in [0.1, 0.5]", "from = 0"],
    },
    Case {
        name: "path of one point",
        edits: &[("offset = [0.0, 0.008]", "path = [[0.0, 0.0, 0.008]]")],
        path: "cable[0].path",
        says: &["at least two points", "found 1", "use offset"],
    },
    Case {
        name: "empty piece lengths",
        edits: &[("pieces = 4", "piece_lengths = []")],
        path: "rod[0].piece_lengths",
        says: &["at least one piece"],
    },
    Case {
        name: "offset and path together",
        edits: &[(
            "offset = [0.0, 0.008]",
            "offset = [0.0, 0.008]\npath = [[0.0, 0.0, 0.008], [0.5, 0.0, 0.0]]",
        )],
        path: "cable[0].path",
        says: &["either offset or path"],
    },
    Case {
        name: "tension times not increasing",
        edits: &[(
            "tension = 2.0",
            "tension = { times = [0, 1, 1], values = [0, 1, 2] }",
        )],
        path: "cable[0].tension.times[2]",
        says: &["strictly increase"],
    },
    Case {
        name: "poisson and shear modulus together",
        edits: &[("poisson = 0.5", "poisson = 0.5, shear_modulus = 3e5")],
        path: "rod[0].material.shear_modulus",
        says: &["either poisson or shear_modulus"],
    },
    Case {
        name: "duplicate strain",
        edits: &[("strains = \"all\"", "strains = [\"ky\", \"ky\"]")],
        path: "rod[0].strains[1]",
        says: &["listed twice"],
    },
    Case {
        name: "no strain selected",
        edits: &[("strains = \"all\"", "strains = []")],
        path: "rod[0].strains",
        says: &["at least one strain"],
    },
    Case {
        name: "duplicate rod name",
        edits: &[(
            "",
            "\n[[rod]]\nname = \"arm\"\nlength = 0.2\npieces = 1\n\
             section = { shape = \"circle\", radius = 0.01 }\n\
             material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n",
        )],
        path: "rod[1].name",
        says: &["duplicate rod name \"arm\"", "rod[0]"],
    },
    Case {
        name: "error in the second rod",
        edits: &[(
            "",
            "\n[[rod]]\nname = \"hand\"\nlength = -0.2\npieces = 1\n\
             section = { shape = \"circle\", radius = 0.01 }\n\
             material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n",
        )],
        path: "rod[1].length",
        says: &["out of range", "-0.2"],
    },
];

#[test]
fn base_scene_is_valid() {
    let (scene, warnings) = Scene::from_str(BASE, FILE).expect("contract example must parse");
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(scene.n_dof(), 24);
}

#[test]
fn malformed_scenes_are_rejected_with_path_and_problem() {
    let mut failures = Vec::new();
    for case in CASES {
        let text = apply(case.edits);
        let msg = match Scene::from_str(&text, FILE) {
            Ok(_) => {
                failures.push(format!("{}: accepted", case.name));
                continue;
            }
            Err(e) => {
                if e.path() != Some(case.path) {
                    failures.push(format!(
                        "{}: path() = {:?}, want {:?} ({e})",
                        case.name,
                        e.path(),
                        case.path
                    ));
                }
                if e.location().is_none() {
                    failures.push(format!("{}: no line/column ({e})", case.name));
                }
                e.to_string()
            }
        };
        let mut want = vec![FILE, case.path];
        want.extend(case.says);
        for w in want {
            if !msg.contains(w) {
                failures.push(format!("{}: message lacks {w:?}: {msg}", case.name));
            }
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// Values the library rejects keep its structured error as the source: the
/// key path comes from the variant and quantity, not from the message.
#[test]
fn library_errors_are_the_source() {
    use softrod_dynamics::DynamicsError;
    use softrod_kinematics::KinematicsError;
    use softrod_mechanics::{MechanicsError, Quantity};
    use std::error::Error;

    let text = apply(&[("poisson = 0.5", "poisson = 0.7")]);
    let e = Scene::from_str(&text, FILE).unwrap_err();
    let cause = e.source().expect("chained");
    assert_eq!(
        cause.downcast_ref::<MechanicsError>(),
        Some(&MechanicsError::PoissonRatio { value: 0.7 })
    );

    let text = apply(&[("radius = 0.01", "radius = -0.01")]);
    let e = Scene::from_str(&text, FILE).unwrap_err();
    assert_eq!(e.path(), Some("rod[0].section.radius"));
    let cause = e.source().unwrap().downcast_ref::<DynamicsError>().unwrap();
    assert!(
        matches!(
            cause,
            DynamicsError::RodProperties {
                source: MechanicsError::NotPositive {
                    quantity: Quantity::Radius,
                    ..
                },
                ..
            }
        ),
        "{cause:?}"
    );

    let text = apply(&[("[[1,0,0],[0,1,0],[0,0,1]]", "[[1,0,0],[0,1,0],[0,0,-1]]")]);
    let e = Scene::from_str(&text, FILE).unwrap_err();
    let kin = e.source().and_then(|c| c.source()).unwrap();
    assert!(matches!(
        kin.downcast_ref::<KinematicsError>(),
        Some(KinematicsError::BaseNotRotation { .. })
    ));
    // Scene-only rules (which keys go together) have no library cause.
    let text = apply(&[("poisson = 0.5", "poisson = 0.5, shear_modulus = 3e5")]);
    let e = Scene::from_str(&text, FILE).unwrap_err();
    assert!(e.source().is_some(), "the builder's Conflict is the cause");
    let e = Scene::from_str(&apply(&[("[[rod]]", "[not_a_rod]")]), FILE).unwrap_err();
    assert!(e.source().is_none());
}

#[test]
fn poisson_one_half_is_valid() {
    let text = apply(&[("poisson = 0.5", "poisson = 0.5")]);
    let (scene, warnings) = Scene::from_str(&text, FILE).unwrap();
    assert!(warnings.is_empty());
    let m = scene.rods[0].properties.material();
    assert_eq!(m.specified_poisson(), Some(0.5));
    assert_eq!(m.shear_modulus(), 1.0e6 / 3.0);
    // Just inside the open end is valid too.
    let text = apply(&[("poisson = 0.5", "poisson = -0.99")]);
    assert!(Scene::from_str(&text, FILE).is_ok());
}

#[test]
fn syntax_errors_give_line_and_column() {
    let text = apply(&[("tension = 2.0", "tension = [2.0")]);
    let e = Scene::from_str(&text, FILE).unwrap_err();
    assert!(matches!(e, SceneError::Syntax { .. }), "{e:?}");
    let line = BASE.lines().position(|l| l == "tension = 2.0").unwrap() + 1;
    let at = e.location().expect("syntax errors carry a location");
    assert!(at.line >= line, "{e}");
    assert!(
        e.to_string().starts_with(&format!("{FILE}:{}:", at.line)),
        "{e}"
    );
    assert!(e.to_string().contains("TOML syntax error"), "{e}");
}

#[test]
fn duplicate_keys_are_syntax_errors() {
    let text = apply(&[("length = 0.5", "length = 0.5\nlength = 0.6")]);
    let e = Scene::from_str(&text, FILE).unwrap_err();
    assert!(matches!(e, SceneError::Syntax { .. }), "{e:?}");
}

#[test]
fn unknown_key_points_at_its_line() {
    let text = apply(&[("length = 0.5", "lenght = 0.5")]);
    let e = Scene::from_str(&text, FILE).unwrap_err();
    let line = text.lines().position(|l| l.starts_with("lenght")).unwrap() + 1;
    assert_eq!(e.location().unwrap().line, line);
    assert!(
        e.to_string()
            .starts_with(&format!("{FILE}:{line}:1: rod[0].lenght: unknown key")),
        "{e}"
    );
}

#[test]
fn validation_errors_point_at_the_value() {
    let text = apply(&[("poisson = 0.5", "poisson = 0.7")]);
    let e = Scene::from_str(&text, FILE).unwrap_err();
    let line = text
        .lines()
        .position(|l| l.contains("poisson = 0.7"))
        .unwrap()
        + 1;
    let col = text.lines().nth(line - 1).unwrap().find("0.7").unwrap() + 1;
    let at = e.location().unwrap();
    assert_eq!((at.line, at.column), (line, col), "{e}");
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let e = Scene::from_path(std::path::Path::new("/nonexistent/scene.toml")).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/scene.toml"), "{e}");
}

#[test]
fn empty_document_needs_a_rod() {
    let e = Scene::from_str("", FILE).unwrap_err();
    assert_eq!(e.path(), Some("rod"));
    assert!(e.to_string().contains("missing required key"), "{e}");
    assert!(e.to_string().contains("[[rod]]"), "{e}");
}

/// "No panic": every prefix of the example and every single-line deletion
/// yields a scene or an error, and every error names the file.
#[test]
fn truncated_and_mutilated_scenes_never_panic() {
    let mut texts: Vec<String> = BASE
        .char_indices()
        .map(|(i, _)| BASE[..i].to_owned())
        .collect();
    let lines: Vec<&str> = BASE.lines().collect();
    for k in 0..lines.len() {
        let mut l = lines.clone();
        l.remove(k);
        texts.push(l.join("\n"));
    }
    for text in texts {
        if let Err(e) = Scene::from_str(&text, FILE) {
            assert!(e.to_string().starts_with(FILE), "{e}");
        }
    }
}

/// Messages speak TOML, not Rust: a scalar where a table belongs says
/// "expected a table", never the parser's struct name; a quoted unknown key
/// appears once in its path.
#[test]
fn messages_name_toml_things_once() {
    let text = BASE.replacen(
        "material = { density = 1000.0, young = 1.0e6, poisson = 0.5, viscosity = 0.0 }",
        "material = 5",
        1,
    );
    let e = Scene::from_str(&text, FILE).unwrap_err();
    let msg = e.to_string();
    assert_eq!(e.path(), Some("rod[0].material"), "{msg}");
    assert!(msg.contains("expected a table"), "{msg}");
    assert!(!msg.contains("struct") && !msg.contains("Raw"), "{msg}");

    let text = BASE.replacen("length = 0.5\n", "length = 0.5\n\"my key\" = 3\n", 1);
    let e = Scene::from_str(&text, FILE).unwrap_err();
    assert_eq!(e.path(), Some("rod[0].\"my key\""), "{e}");
    assert_eq!(e.to_string().matches("my key").count(), 1, "{e}");
}

/// A bounded, seeded fuzz of the parser and the model builder: 3000 scenes
/// made from the example by replacing one to three numbers with hostile
/// values (zero, negatives, huge, tiny, integers where floats go and
/// back, strings) or deleting a character. Each must give a scene that
/// builds, or an error naming the file; never a panic. A fixed seed keeps
/// it reproducible; the count keeps it to a second.
#[test]
fn seeded_mutations_of_numbers_never_panic() {
    const HOSTILE: &[&str] = &[
        "0",
        "0.0",
        "-1",
        "-0.0",
        "1e308",
        "-1e308",
        "1e-308",
        "5e-324",
        "1e30",
        "1e31",
        "100000",
        "9223372036854775807",
        "-9223372036854775808",
        "\"x\"",
        "[]",
        "{}",
        "nan",
        "inf",
        "-inf",
        "1",
        "2",
        "0.5",
    ];
    // Byte offsets of every number in the base text.
    let bytes = BASE.as_bytes();
    let mut numbers = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let starts = (bytes[i].is_ascii_digit() || bytes[i] == b'-')
            && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
        if starts {
            let mut j = i + 1;
            while j < bytes.len()
                && (bytes[j].is_ascii_digit()
                    || matches!(bytes[j], b'.' | b'e' | b'E' | b'-' | b'+'))
            {
                j += 1;
            }
            numbers.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    assert!(numbers.len() > 10, "the example has numbers to mutate");
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move |n: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n as u64) as usize
    };
    for _ in 0..3000 {
        let mut text = BASE.to_owned();
        if next(10) == 0 {
            let k = next(text.len());
            if text.is_char_boundary(k) && text.is_char_boundary(k + 1) {
                text.remove(k);
            }
        } else {
            // Replace from the last chosen number backwards so offsets stay valid.
            let mut picks: Vec<usize> = (0..1 + next(3)).map(|_| next(numbers.len())).collect();
            picks.sort_unstable();
            picks.dedup();
            for &p in picks.iter().rev() {
                let (a, b) = numbers[p];
                text.replace_range(a..b, HOSTILE[next(HOSTILE.len())]);
            }
        }
        match Scene::from_str(&text, FILE) {
            Ok((scene, _)) => {
                if let Err(e) = scene.build() {
                    assert!(!e.to_string().is_empty());
                }
            }
            Err(e) => assert!(e.to_string().starts_with(FILE), "{e}"),
        }
    }
}
