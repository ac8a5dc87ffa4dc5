//! What `statics` and `modes` say of the equilibrium they report (issue
//! 26): the validity rules of a run's watch, in its words (`warnings`), and
//! rigid (zero) modes told apart from unstable ones. The genuinely
//! unstable upright rod is `cli.rs`'s `statics_flags_an_unstable_equilibrium`
//! and `modes_json_marks_unstable_equilibria`.

mod common;

use common::*;

/// A 0.3 m rubber rod under `load` at its tip (the scene of D01 with a
/// 1 MN force).
fn cantilever(load: &str) -> String {
    format!(
        "[world]\ngravity = [0.0, 0.0, -9.81]\n[[rod]]\nname = \"arm\"\nlength = 0.3\n\
         pieces = 4\nstrains = [\"ky\", \"qx\", \"qz\"]\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5, viscosity = 100.0 }}\n\
         [[load]]\nrod = \"arm\"\ns = 0.3\n{load}\n"
    )
}

/// `statics --json` of `scene`, written as `dir/name.toml`.
fn statics_json(dir: &std::path::Path, name: &str, scene: &str) -> (serde_json::Value, String) {
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, scene).unwrap();
    let o = run(&["statics", p.to_str().unwrap(), "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    (stdout_json(&o), stderr(&o))
}

fn warnings(v: &serde_json::Value) -> Vec<String> {
    serde_json::from_value(v["warnings"].clone()).unwrap()
}

#[test]
fn statics_warns_of_an_equilibrium_beyond_the_models_validity() {
    // D01: shear strain ~1e4 under 1 MN; a run of it warns the same way.
    let dir = tmp("validity");
    let (v, err) = statics_json(&dir, "d01", &cantilever("force = [0, 0, -1e6]"));
    let w = warnings(&v);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("strain beyond the model's validity at the equilibrium: rod \"arm\""),
        "{w:?}"
    );
    assert!(err.contains(&w[0]), "{err}");
    // A couple M bends every piece to κ ≈ M/EI (EI = E π r⁴/4; the rod's
    // weight adds ~1% at the base): M = 1 N·m gives a radius of ~7.9 mm,
    // below the 10 mm half size.
    let (v, _) = statics_json(&dir, "curl", &cantilever("moment = [0, 1.0, 0]"));
    let w = warnings(&v);
    assert!(
        w.iter().any(|m| m.starts_with(
            "curvature beyond the model's validity at the equilibrium: rod \"arm\" piece 0 \
             bends with radius 7.8"
        ) && m.contains("less than the section's half size 1.000e-2 m")),
        "{w:?}"
    );
    // A small load: nothing to say.
    let (v, err) = statics_json(&dir, "small", &cantilever("force = [0, 0, -1e-3]"));
    assert!(warnings(&v).is_empty(), "{v}");
    assert!(!err.contains("warning"), "{err}");
}

/// D05: a body on a free joint that nothing holds has six zero modes:
/// rigid, not unstable, and the equilibrium is not called unstable.
#[test]
fn a_free_body_has_rigid_modes_not_unstable_ones() {
    let scene = "[[rod]]\nname = \"a\"\nlength = 0.2\npieces = 2\n\
                 strains = [\"ky\", \"kz\", \"qx\"]\n\
                 section = { shape = \"circle\", radius = 0.008 }\n\
                 material = { density = 1100.0, young = 1.0e6, poisson = 0.5, viscosity = 500.0 }\n\
                 [[body]]\nname = \"b0\"\nparent = \"a\"\nmass = 0.01\n\
                 inertia = [1e-6, 1e-6, 1e-6]\njoint = { type = \"free\" }\n\
                 [run]\nduration = 0.1\noutput_every = 0.01\n";
    let dir = tmp("rigid");
    let (v, err) = statics_json(&dir, "d05", scene);
    assert_eq!(v["stable"], true, "{v}");
    assert_eq!(v["rigid_modes"], 6, "{v}");
    assert!(!err.contains("unstable"), "{err}");
    let p = dir.join("d05.toml");
    let o = run(&["modes", p.to_str().unwrap(), "--json", "--count", "12"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let m = stdout_json(&o);
    assert_eq!(m["unstable"], false, "{m}");
    assert_eq!(m["rigid_modes"], 6, "{m}");
    let f: Vec<f64> = serde_json::from_value(m["frequencies_hz"].clone()).unwrap();
    assert!(
        f[..6].iter().all(|x| *x == 0.0) && f[6..].iter().all(|x| *x > 0.0),
        "{f:?}"
    );
    assert!(m["rigid_tolerance_omega2"].as_f64().unwrap() > 0.0);
    assert!(warnings(&m).is_empty());
}

/// An output directory that cannot be created is reported as such (exit
/// 2), not as a disk without space (issue 26).
#[test]
fn an_uncreatable_out_dir_is_named() {
    let dir = tmp("uncreatable");
    let p = dir.join("small.toml");
    std::fs::write(&p, cantilever("force = [0, 0, -1e-3]")).unwrap();
    let o = run(&[
        "run",
        p.to_str().unwrap(),
        "--out",
        "/proc/self/zz",
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("cannot create it"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("MB free"), "{}", stderr(&o));
}

/// A run its settings refuse (D06: 1e19 fixed steps) is refused before its
/// output directory exists, in `check`'s words: nothing is left that looks
/// like a killed run.
#[test]
fn a_refused_run_leaves_no_output() {
    let dir = tmp("refused");
    let p = dir.join("d06.toml");
    let scene = cantilever("force = [0, 0, -1e-3]")
        + "[run]\nintegrator = \"rk4\"\ndt = 1e-15\nduration = 1e4\n";
    std::fs::write(&p, &scene).unwrap();
    let out = dir.join("out");
    let o = run(&[
        "run",
        p.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("run.dt"), "{}", stderr(&o));
    assert!(!out.exists(), "a refused run created {}", out.display());
    let c = run(&["check", p.to_str().unwrap()]);
    assert_eq!(c.status.code(), Some(2), "{}", stderr(&c));
    assert!(
        stderr(&c).contains("more than 1e12 steps"),
        "{}",
        stderr(&c)
    );
}
