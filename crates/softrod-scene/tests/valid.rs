//! Valid scenes parse with the right values and defaults; the example scenes
//! in `examples/` validate; suspicious input warns without failing.

use std::path::Path;

use softrod_kinematics::{Basis, Strain, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{LoadFrame, Routing, Section, Span, Tension};
use softrod_scene::{Integrator, Mode, Run, Scene, Warning};

const CONTRACT: &str = include_str!("contract_example.toml");

fn parse(text: &str) -> (Scene, Vec<Warning>) {
    Scene::from_str(text, "test.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// A minimal rod; `extra` lines go into its table.
fn minimal(extra: &str) -> String {
    format!(
        "[[rod]]\nname = \"r\"\nlength = 0.4\npieces = 2\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1200, young = 2e6, poisson = 0.45 }}\n{extra}\n"
    )
}

#[test]
fn contract_example_has_the_written_values() {
    let (s, warnings) = parse(CONTRACT);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(s.source, "test.toml");
    assert_eq!(s.world.gravity, [0.0, 0.0, -9.81]);
    assert!(s.has_gravity());

    assert_eq!(s.rods.len(), 1);
    let r = &s.rods[0];
    assert_eq!(r.name, "arm");
    assert_eq!(r.properties.length(), 0.5);
    assert_eq!(
        r.geometry.piece_lengths().collect::<Vec<_>>(),
        vec![0.125; 4]
    );
    assert_eq!(r.geometry.n_pieces(), 4);
    assert_eq!(r.geometry.uniform_basis(), Some(&Basis::all()));
    assert!(
        r.geometry
            .pieces()
            .iter()
            .all(|p| p.rest_strain == straight())
    );
    assert_eq!(*r.geometry.base(), Pose::identity());
    assert_eq!(*r.properties.section(), Section::Circle { radius: 0.01 });
    let m = r.properties.material();
    assert_eq!(m.density(), 1000.0);
    assert_eq!(m.young(), 1.0e6);
    assert_eq!(m.specified_poisson(), Some(0.5));
    // G = E / (2 (1 + ν)) = 1e6 / 3 for incompressible silicone.
    assert_eq!(m.shear_modulus(), 1.0e6 / 3.0);
    assert_eq!(m.viscosity(), 0.0);
    // Zero drag coefficients: no drag term at all.
    assert_eq!(r.drag, None);

    // The [[cable]] naming "arm" is the cable of rod 0.
    assert_eq!(s.n_cables(), 1);
    let c = &s.rods[0].cables[0];
    assert_eq!(c.routing, Routing::Offset { y: 0.0, z: 0.008 });
    assert_eq!(c.tension, Tension::Constant(2.0));
    assert_eq!(c.span, Span::Whole);
    assert_eq!(c.bounds(r.properties.length()), (0.0, 0.5));

    assert_eq!(s.n_point_loads(), 1);
    let l = &s.rods[0].point_loads[0];
    assert_eq!(l.s, 0.5);
    assert_eq!(l.force, Vec3::new(0.0, 0.0, -1.0));
    assert_eq!(l.moment, Vec3::zeros());
    assert_eq!(l.frame, LoadFrame::World);

    assert_eq!(s.initial.q, None);
    assert_eq!(s.initial.qdot, None);
    assert_eq!(
        s.run,
        Run {
            mode: Mode::Dynamics,
            duration: 1.0,
            integrator: Integrator::Dopri5,
            rtol: 1e-6,
            atol: 1e-9,
            dt: 1e-4,
            output_every: 1e-3,
            quadrature: 4,
            error_control: false,
            linearly_implicit: false,
            steps_to_outputs: false,
            project_closures: false,
            energy_tolerance: Run::DEFAULT_ENERGY_TOLERANCE,
            shape_points_per_piece: None,
            memory_limit_gib: None,
        }
    );
    assert_eq!(s.reference, None);
    assert_eq!(s.n_dof(), 24);
    assert_eq!(s.rod_dof_offset(0), 0);
    assert_eq!(s.rod_dof_offset(1), 24);
}

#[test]
fn minimal_scene_gets_the_defaults() {
    let (s, warnings) = parse(&minimal(""));
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(s.world.gravity, [0.0; 3]);
    assert!(!s.has_gravity());
    let r = &s.rods[0];
    assert_eq!(r.geometry.uniform_basis().unwrap().dof(), 6);
    assert!(
        r.geometry
            .pieces()
            .iter()
            .all(|p| p.rest_strain == straight())
    );
    assert_eq!(*r.geometry.base(), Pose::identity());
    assert_eq!(r.properties.material().viscosity(), 0.0);
    assert_eq!(r.properties.material().shear_modulus(), 2e6 / (2.0 * 1.45));
    assert!(s.n_cables() == 0 && s.n_point_loads() == 0);
    assert_eq!(s.initial.q, None);
    assert_eq!(s.run, Run::default());
    assert_eq!(s.run.mode, Mode::Dynamics);
    assert_eq!(s.run.duration, 1.0);
    assert_eq!(s.run.integrator, Integrator::DEFAULT);
    assert_eq!(s.run.output_every, 1.0 / 1000.0);
    assert_eq!(s.run.quadrature, 4);
    assert_eq!(s.n_dof(), 12);
}

#[test]
fn output_every_defaults_to_a_thousandth_of_the_duration() {
    let (s, _) = parse(&(minimal("") + "[run]\nduration = 2.5\n"));
    assert_eq!(s.run.output_every, 2.5e-3);
    assert_eq!(s.run.rtol, Run::DEFAULT_RTOL);
}

#[test]
fn atol_follows_a_tighter_rtol_unless_it_is_set() {
    // (rtol line, atol line) → (rtol, atol).
    let cases = [
        ("", "", 1e-3, 1e-6),
        ("rtol = 1e-8\n", "", 1e-8, 1e-8),
        ("rtol = 1e-6\n", "", 1e-6, 1e-6),
        // A looser rtol keeps the default atol.
        ("rtol = 1e-2\n", "", 1e-2, 1e-6),
        ("rtol = 1e-8\n", "atol = 1e-5\n", 1e-8, 1e-5),
        ("", "atol = 1e-12\n", 1e-3, 1e-12),
    ];
    for (rtol, atol, want_r, want_a) in cases {
        let (s, _) = parse(&(minimal("") + "[run]\n" + rtol + atol));
        assert_eq!((s.run.rtol, s.run.atol), (want_r, want_a), "{rtol}{atol}");
    }
}

#[test]
fn integers_are_accepted_where_numbers_are_expected() {
    let (s, _) = parse(
        "[[rod]]\nname = \"r\"\nlength = 1\npieces = 1\n\
         section = { shape = \"circle\", radius = 1 }\n\
         material = { density = 1000, young = 1000000, shear_modulus = 300000 }\n",
    );
    assert_eq!(s.rods[0].properties.length(), 1.0);
    assert_eq!(s.rods[0].properties.material().shear_modulus(), 3e5);
    assert_eq!(s.rods[0].properties.material().specified_poisson(), None);
}

#[test]
fn strain_subsets_are_stored_in_canonical_order() {
    let (s, warnings) = parse(&minimal("strains = [\"qx\", \"ky\"]"));
    let sel = s.rods[0].geometry.uniform_basis().unwrap();
    assert_eq!(sel.selection(), Some(&[1, 3][..]));
    assert_eq!(sel.strains(), Some(vec![Strain::Ky, Strain::Qx]));
    assert_eq!(s.n_dof(), 4);
    // Listing them out of order is legal but the q layout deserves a warning.
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0].path, "rod[0].strains");
    assert!(warnings[0].message.contains("canonical order"));

    let (s, warnings) = parse(&minimal("strains = [\"ky\", \"qx\", \"qz\"]"));
    assert!(warnings.is_empty());
    assert_eq!(
        s.rods[0].geometry.uniform_basis().unwrap().strains(),
        Some(vec![Strain::Ky, Strain::Qx, Strain::Qz])
    );
    let names = Strain::ALL.map(Strain::name);
    assert_eq!(names, ["kx", "ky", "kz", "qx", "qy", "qz"]);
}

#[test]
fn piece_lengths_within_relative_tolerance() {
    // 0.1 + 0.15 + 0.25 is not exactly 0.5 in binary; it must still pass.
    let text = minimal("").replace("pieces = 2", "piece_lengths = [0.1, 0.15, 0.25]");
    let text = text.replace("length = 0.4", "length = 0.5");
    let (s, _) = parse(&text);
    assert_eq!(
        s.rods[0].geometry.piece_lengths().collect::<Vec<_>>(),
        vec![0.1, 0.15, 0.25]
    );
    assert_eq!(s.rods[0].geometry.pieces()[2].start, 0.25);
    // 1e-10 relative off passes, 1e-8 fails.
    assert!(Scene::from_str(&text.replace("0.25]", "0.25000000005]"), "t").is_ok());
    assert!(Scene::from_str(&text.replace("0.25]", "0.250000005]"), "t").is_err());
    // `pieces` may be given too when it agrees.
    let both = text.replace("piece_lengths", "pieces = 3\npiece_lengths");
    assert_eq!(parse(&both).0.rods[0].geometry.n_pieces(), 3);
}

#[test]
fn section_shapes() {
    let cases = [
        (
            "{ shape = \"circle\", radius_base = 0.02, radius_tip = 0.01 }",
            Section::TaperedCircle {
                radius_base: 0.02,
                radius_tip: 0.01,
            },
        ),
        (
            "{ shape = \"tube\", radius = 0.01, inner_radius = 0.006 }",
            Section::Tube {
                radius: 0.01,
                inner_radius: 0.006,
            },
        ),
        (
            "{ shape = \"rectangle\", width = 0.02, height = 0.01 }",
            Section::Rectangle {
                width: 0.02,
                height: 0.01,
            },
        ),
    ];
    for (toml, want) in cases {
        let text = minimal("").replace("{ shape = \"circle\", radius = 0.01 }", toml);
        assert_eq!(*parse(&text).0.rods[0].properties.section(), want, "{toml}");
    }
    let tapered = Section::TaperedCircle {
        radius_base: 0.02,
        radius_tip: 0.01,
    };
    assert_eq!(tapered.half_size(0.5), 0.015);
    let rect = Section::Rectangle {
        width: 0.02,
        height: 0.01,
    };
    assert!(rect.contains(0.0, 0.01, 0.005));
    assert!(!rect.contains(0.0, 0.0, 0.006));
}

#[test]
fn base_pose_rotation_about_y() {
    // Ry(90°): the rod points down (local x → world −z).
    let text =
        minimal("base = { position = [0, 0, 1], rotation = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]] }");
    let (s, _) = parse(&text);
    assert_eq!(
        s.rods[0].geometry.base().translation,
        Vec3::new(0.0, 0.0, 1.0)
    );
    assert_eq!(s.rods[0].geometry.base().rotation[(2, 0)], -1.0);
    // A rotation good to 1e-7 (rounded cos/sin of 30°) passes.
    let text =
        minimal("base = { rotation = [[0.8660254, -0.5, 0], [0.5, 0.8660254, 0], [0, 0, 1]] }");
    assert!(Scene::from_str(&text, "t").is_ok());
}

#[test]
fn cables_with_paths_schedules_and_spans() {
    let text = minimal("")
        + "[[cable]]\nrod = \"r\"\npath = [[0.0, 0.0, 0.008], [0.4, 0.004, 0.0]]\n\
           tension = { times = [0, 0.5, 1], values = [0, 2, 2] }\nfrom = 0.1\nto = 0.3\n";
    let (s, warnings) = parse(&text);
    assert!(warnings.is_empty(), "{warnings:?}");
    let c = &s.rods[0].cables[0];
    assert_eq!(
        c.routing,
        Routing::Path(vec![[0.0, 0.0, 0.008], [0.4, 0.004, 0.0]])
    );
    assert_eq!(
        c.tension,
        Tension::Table {
            times: vec![0.0, 0.5, 1.0],
            values: vec![0.0, 2.0, 2.0]
        }
    );
    assert_eq!(c.tension.at(0.25), 1.0);
    assert_eq!(c.span, Span::Between { from: 0.1, to: 0.3 });
}

#[test]
fn body_frame_loads_and_moments() {
    let text =
        minimal("") + "[[load]]\nrod = \"r\"\ns = 0.2\nmoment = [0, 0.01, 0]\nframe = \"body\"\n";
    let (s, _) = parse(&text);
    let l = &s.rods[0].point_loads[0];
    assert_eq!(l.frame, LoadFrame::Body);
    assert_eq!(l.force, Vec3::zeros());
    assert_eq!(l.moment, Vec3::new(0.0, 0.01, 0.0));
}

#[test]
fn several_rods_and_initial_state() {
    let second = "[[rod]]\nname = \"s\"\nlength = 0.2\npieces = 3\nstrains = [\"kz\"]\n\
                  section = { shape = \"circle\", radius = 0.01 }\n\
                  material = { density = 1000, young = 1e6, poisson = 0.5 }\n";
    let q: Vec<String> = (0..15).map(|i| format!("{}", i as f64 * 0.01)).collect();
    let text = format!(
        "{}{second}[initial]\nq = [{}]\nqdot = [{}]\n",
        minimal(""),
        q.join(", "),
        q.join(", ")
    );
    let (s, warnings) = parse(&text);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(s.n_dof(), 12 + 3);
    assert_eq!(s.rod_dof_offset(1), 12);
    assert_eq!(s.rod_dof_offset(2), 15);
    assert_eq!(s.rod_index("s"), Some(1));
    assert_eq!(s.initial.q.as_ref().unwrap()[14], 0.14);
    assert_eq!(s.initial.qdot.as_ref().unwrap().len(), 15);
}

#[test]
fn reference_table() {
    let text = minimal("")
        + "[run]\nmode = \"statics\"\n[reference]\ntip = [0.4, 0, -0.001]\n\
           tolerance = 1e-5\nfrequencies_hz = [1.5, 9.4]\nnote = \"hand computed\"\n";
    let (s, warnings) = parse(&text);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(s.run.mode, Mode::Statics);
    let r = s.reference.unwrap();
    assert_eq!((r.rod.as_str(), r.rod_index), ("r", 0));
    assert_eq!(r.tip, Some([0.4, 0.0, -0.001]));
    assert_eq!(r.tolerance, Some(1e-5));
    assert_eq!(r.time, None);
    assert_eq!(r.frequencies_hz, Some(vec![1.5, 9.4]));
    assert_eq!(r.note.as_deref(), Some("hand computed"));
}

#[test]
fn integrator_names_round_trip() {
    for i in Integrator::ALL {
        assert_eq!(i.name().parse::<Integrator>(), Ok(i));
        assert_eq!(i.to_string(), i.name());
    }
    let e = "euler".parse::<Integrator>().unwrap_err();
    assert!(e.to_string().contains("generalized-alpha"));
    assert!(Integrator::Dopri5.is_adaptive() && !Integrator::Dopri5.is_implicit());
    assert!(!Integrator::Rk4.is_adaptive());
    assert!(Integrator::Rosenbrock.is_implicit() && Integrator::GeneralizedAlpha.is_implicit());
    assert!(Integrator::Radau5.is_adaptive() && Integrator::Esdirk.is_implicit());
    assert_eq!("radau5".parse::<Integrator>(), Ok(Integrator::Radau5));
}

// --- warnings

fn warning_paths(text: &str) -> Vec<(String, String)> {
    parse(text)
        .1
        .into_iter()
        .map(|w| (w.path, w.message))
        .collect()
}

#[test]
fn cable_outside_the_section_warns() {
    let w = warning_paths(
        &(minimal("") + "[[cable]]\nrod = \"r\"\noffset = [0.0, 0.015]\ntension = 1\n"),
    );
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].0, "cable[0].offset");
    assert!(w[0].1.contains("outside the cross-section"), "{}", w[0].1);
    // On the boundary is inside.
    let w = warning_paths(
        &(minimal("") + "[[cable]]\nrod = \"r\"\noffset = [0.0, 0.01]\ntension = 1\n"),
    );
    assert!(w.is_empty(), "{w:?}");
    // A tapered rod: inside at the base, outside near the tip.
    let text = minimal("").replace(
        "{ shape = \"circle\", radius = 0.01 }",
        "{ shape = \"circle\", radius_base = 0.01, radius_tip = 0.005 }",
    ) + "[[cable]]\nrod = \"r\"\noffset = [0.0, 0.008]\ntension = 1\n";
    let w = warning_paths(&text);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].1.contains("s = 0.4"), "{}", w[0].1);
}

#[test]
fn short_pieces_warn() {
    let text = minimal("").replace("pieces = 2", "pieces = 50");
    let w = warning_paths(&text);
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].0, "rod[0].pieces");
    assert!(
        w[0].1.contains("shorter than the section radius"),
        "{}",
        w[0].1
    );
    assert!(w[0].1.contains("50 of 50"), "{}", w[0].1);
}

#[test]
fn large_initial_strains_warn() {
    // 2 pieces of 0.2 m, bending ky only; 20 1/m bends a piece by 4 rad > π.
    let text = minimal("strains = [\"ky\"]") + "[initial]\nq = [0.5, 20.0]\n";
    let w = warning_paths(&text);
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].0, "initial.q[1]");
    assert!(w[0].1.contains("more than π"), "{}", w[0].1);
    // A stretch that inverts the piece.
    let text = minimal("strains = [\"qx\"]") + "[initial]\nq = [0.0, -1.5]\n";
    let w = warning_paths(&text);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].1.contains("inverted"), "{}", w[0].1);
}

#[test]
fn zero_load_and_empty_reference_warn() {
    let w = warning_paths(&(minimal("") + "[[load]]\nrod = \"r\"\ns = 0.1\n[reference]\n"));
    let paths: Vec<&str> = w.iter().map(|(p, _)| p.as_str()).collect();
    assert_eq!(paths, vec!["load[0]", "reference"], "{w:?}");
}

#[test]
fn warnings_display_with_location() {
    let text = minimal("") + "[[cable]]\nrod = \"r\"\noffset = [0.0, 0.02]\ntension = 1\n";
    let (_, w) = parse(&text);
    let line = text.lines().position(|l| l.starts_with("offset")).unwrap() + 1;
    assert!(
        w[0].to_string()
            .starts_with(&format!("{line}:10: cable[0].offset: ")),
        "{}",
        w[0]
    );
}

// --- the example scenes

fn example(name: &str) -> (Scene, Vec<Warning>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name);
    Scene::from_path(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn example_cantilever_gravity() {
    let (s, w) = example("cantilever_gravity.toml");
    assert!(w.is_empty(), "{w:?}");
    assert_eq!(s.world.gravity, [0.0, 0.0, -9.81]);
    let r = &s.rods[0];
    assert_eq!((r.properties.length(), r.geometry.n_pieces()), (0.5, 8));
    assert_eq!(*r.properties.section(), Section::Circle { radius: 0.01 });
    let m = r.properties.material();
    assert_eq!((m.density(), m.young()), (1000.0, 1e7));
    assert_eq!(m.specified_poisson(), Some(0.5));
    assert_eq!(
        r.geometry.uniform_basis().unwrap().strains(),
        Some(vec![Strain::Ky, Strain::Qx, Strain::Qz])
    );
    assert_eq!(s.n_dof(), 24);
    assert_eq!(s.run.duration, 1.0);
    assert_eq!(s.run.mode, Mode::Dynamics);
}

#[test]
fn example_tip_load_statics_reference_is_timoshenko() {
    let (s, w) = example("tip_load_statics.toml");
    assert!(w.is_empty(), "{w:?}");
    assert_eq!(s.run.mode, Mode::Statics);
    assert!(!s.has_gravity());
    let r = &s.rods[0];
    let Section::Circle { radius } = *r.properties.section() else {
        panic!("circle expected")
    };
    let load = &r.point_loads[0];
    assert_eq!(
        (load.s, load.frame),
        (r.properties.length(), LoadFrame::World)
    );
    // Recompute the reference written in the file from the scene's own values.
    let p = -load.force[2];
    let m = r.properties.material();
    let (l, e, g) = (r.properties.length(), m.young(), m.shear_modulus());
    let i = std::f64::consts::PI * radius.powi(4) / 4.0;
    let a = std::f64::consts::PI * radius.powi(2);
    let bend = p * l.powi(3) / (3.0 * e * i);
    let delta = bend + p * l / (g * a);
    let shortening = 0.6 * bend * bend / l;
    let reference = s.reference.as_ref().unwrap();
    let tip = reference.tip.unwrap();
    // The file holds 8 significant digits.
    const WRITTEN_TOL: f64 = 1e-8;
    assert!((tip[2] + delta).abs() < WRITTEN_TOL, "{tip:?} vs {delta}");
    assert!((tip[0] - (l - shortening)).abs() < WRITTEN_TOL, "{tip:?}");
    assert_eq!(tip[1], 0.0);
    // The tolerance is about 1% of the deflection and above the PCS
    // discretization error delta/(4 N^2).
    let tol = reference.tolerance.unwrap();
    assert!(tol < 0.02 * delta && tol > delta / (4.0 * (r.geometry.n_pieces() as f64).powi(2)));
}

#[test]
fn example_cable_planar_arm() {
    let (s, w) = example("cable_planar_arm.toml");
    assert!(w.is_empty(), "{w:?}");
    let r = &s.rods[0];
    assert_eq!(
        r.geometry.uniform_basis().unwrap().strains(),
        Some(vec![Strain::Ky, Strain::Qx, Strain::Qz])
    );
    // Hanging: the local x axis (first column of R) points down.
    let x_axis = r.geometry.base().rotation.column(0).into_owned();
    assert_eq!(x_axis, Vec3::new(0.0, 0.0, -1.0));
    let cables = &r.cables;
    assert_eq!(cables.len(), 2);
    // Antagonistic: opposite offsets in the bending plane, equal pretension.
    assert_eq!(cables[0].routing, Routing::Offset { y: 0.0, z: 0.008 });
    assert_eq!(cables[1].routing, Routing::Offset { y: 0.0, z: -0.008 });
    assert_eq!(cables[0].tension.at(0.0), cables[1].tension.at(0.0));
    assert_eq!(cables[0].tension.at(1.0), 2.0);
    assert_eq!(cables[1].tension.at(1.0), 0.2);
    assert_eq!(cables[1].tension.at(3.0), 2.0);
    for c in cables {
        assert_eq!(
            c.bounds(r.properties.length()),
            (0.0, r.properties.length())
        );
        assert!(c.tension.max() <= 2.0);
    }
    assert!(r.properties.material().viscosity() > 0.0);
}

#[test]
fn every_example_scene_validates() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            Scene::from_path(&path).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(n >= 3, "expected the example scenes in {}", dir.display());
}

/// `[run] error_control` (extension): read for generalized-alpha, default
/// false, and a warning (ignored) with an integrator that does not use it.
#[test]
fn run_error_control_is_read_and_warned_where_it_does_not_apply() {
    let (s, warnings) = parse(&minimal(
        "[run]\nintegrator = \"generalized-alpha\"\nerror_control = true",
    ));
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(s.run.error_control);
    let (s, _) = parse(&minimal("[run]\nintegrator = \"generalized-alpha\""));
    assert!(!s.run.error_control);
    let (s, warnings) = parse(&minimal(
        "[run]\nintegrator = \"dopri5\"\nerror_control = true",
    ));
    assert!(s.run.error_control);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0].path, "run.error_control");
    assert!(
        warnings[0].message.contains("ignored"),
        "{}",
        warnings[0].message
    );
}

/// `[run] steps_to_outputs` (extension): read for the adaptive methods,
/// default false, a warning (ignored) with fixed steps; a non-boolean is an
/// error naming the key.
#[test]
fn run_steps_to_outputs_is_read_and_warned_with_fixed_steps() {
    let (s, warnings) = parse(&minimal(
        "[run]\nintegrator = \"esdirk\"\nsteps_to_outputs = true",
    ));
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(s.run.steps_to_outputs);
    let (s, _) = parse(&minimal("[run]\nintegrator = \"esdirk\""));
    assert!(!s.run.steps_to_outputs);
    let (_, warnings) = parse(&minimal(
        "[run]\nintegrator = \"generalized-alpha\"\nerror_control = true\nsteps_to_outputs = true",
    ));
    assert!(warnings.is_empty(), "{warnings:?}");
    let (_, warnings) = parse(&minimal(
        "[run]\nintegrator = \"rk4\"\nsteps_to_outputs = true",
    ));
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0].path, "run.steps_to_outputs");
    assert!(warnings[0].message.contains("ignored"));
    let err = Scene::from_str(&minimal("[run]\nsteps_to_outputs = \"yes\""), "t.toml")
        .unwrap_err()
        .to_string();
    assert!(err.contains("run.steps_to_outputs"), "{err}");
}

/// `[run] linearly_implicit` (extension): read for generalized-alpha,
/// default false, a warning (ignored) elsewhere; a non-boolean is an error
/// naming the key.
#[test]
fn run_linearly_implicit_is_read_and_warned_where_it_does_not_apply() {
    let (s, warnings) = parse(&minimal(
        "[run]\nintegrator = \"generalized-alpha\"\nlinearly_implicit = true",
    ));
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(s.run.linearly_implicit);
    let (s, _) = parse(&minimal("[run]\nintegrator = \"generalized-alpha\""));
    assert!(!s.run.linearly_implicit);
    let (_, warnings) = parse(&minimal(
        "[run]\nintegrator = \"rosenbrock\"\nlinearly_implicit = true",
    ));
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0].path, "run.linearly_implicit");
    assert!(warnings[0].message.contains("ignored"));
    let err = Scene::from_str(
        &minimal("[run]\nintegrator = \"generalized-alpha\"\nlinearly_implicit = 1"),
        "t.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("run.linearly_implicit"), "{err}");
}

/// `[run] project_closures` (extension, docs/theory.md D121): read for
/// ESDIRK and ESDIRK5, default false, a warning (ignored) with another
/// integrator; a non-boolean is an error naming the key.
#[test]
fn run_project_closures_is_read_and_warned_off_esdirk() {
    for integrator in ["esdirk", "esdirk5"] {
        let (s, warnings) = parse(&minimal(&format!(
            "[run]\nintegrator = \"{integrator}\"\nproject_closures = true"
        )));
        assert!(warnings.is_empty(), "{warnings:?}");
        assert!(s.run.project_closures);
    }
    let (s, _) = parse(&minimal("[run]\nintegrator = \"esdirk\""));
    assert!(!s.run.project_closures);
    let (_, warnings) = parse(&minimal(
        "[run]\nintegrator = \"radau5\"\nproject_closures = true",
    ));
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0].path, "run.project_closures");
    assert!(warnings[0].message.contains("ignored"));
    let err = Scene::from_str(&minimal("[run]\nproject_closures = 1"), "t.toml")
        .unwrap_err()
        .to_string();
    assert!(err.contains("run.project_closures"), "{err}");
}
