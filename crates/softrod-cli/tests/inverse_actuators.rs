//! `softrod inverse` with the unknowns beside cable tensions
//! (docs/theory-control.md IS13–IS14): a point load marked
//! `unknown = true` and an actuated joint's torque, each recovered from
//! targets a forward `softrod statics` solve put where they are (the
//! forward load and actuator paths, independent of the inverse's columns);
//! bad input refused with exit 2 naming the key.

mod common;

use common::*;

fn write(name: &str, text: &str) -> String {
    let dir = tmp(&format!("inverse-act-{name}"));
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_owned()
}

/// A cantilever bending in x–z (no gravity, no cable), and `extra`.
fn cantilever(extra: &str) -> String {
    format!(
        "[[rod]]\nname = \"arm\"\nlength = 0.5\npieces = 10\nstrains = [\"ky\"]\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}\n{extra}"
    )
}

/// A short rod clamped to the world, a link body on a revolute joint with
/// a spring at its tip, gravity along −z; `actuator` the joint's.
fn link(actuator: &str, extra: &str) -> String {
    format!(
        "[world]\ngravity = [0.0, 0.0, -9.81]\n\
         [[rod]]\nname = \"base\"\nlength = 0.2\npieces = 2\nstrains = [\"kx\", \"ky\", \"kz\"]\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5 }}\n\
         [[body]]\nname = \"link\"\nparent = \"base\"\n\
         joint = {{ type = \"revolute\", axis = [0, 1, 0], stiffness = 0.2, actuator = {actuator} }}\n\
         mass = 0.2\ninertia = [1e-4, 1e-4, 1e-4]\ncenter_of_mass = [0.1, 0, 0]\n{extra}"
    )
}

fn position(v: &serde_json::Value) -> [f64; 3] {
    [0, 1, 2].map(|k| v[k].as_f64().unwrap())
}

/// The tip force of a forward solve (a given `[[load]]`) is recovered by
/// `softrod inverse` from the tip's and the middle section's positions,
/// with the loads' JSON entries.
#[test]
fn unknown_load_of_a_forward_solve_is_recovered() {
    let force = -0.02;
    let given = write(
        "given",
        &cantilever(&format!(
            "[[load]]\nrod = \"arm\"\ns = 0.5\nforce = [0.0, 0.0, {force}]\n"
        )),
    );
    let o = run(&["statics", &given, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let tip = position(&stdout_json(&o)["tip"]["position"]);
    assert!(tip[2] < -0.01, "the load bends the rod: {tip:?}");

    let unknown = write(
        "unknown",
        &cantilever(&format!(
            "[[load]]\nrod = \"arm\"\ns = 0.5\nunknown = true\nmax_force = [0.0, 0.0, 1.0]\n\
             [[target]]\nelement = \"arm\"\nposition = [{}, {}, {}]\n",
            tip[0], tip[1], tip[2]
        )),
    );
    let o = run(&["inverse", &unknown, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = stdout_json(&o);
    assert_eq!(v["converged"], true);
    assert_eq!(v["reached"], true, "{v}");
    let f = position(&v["loads"][0]["force"]);
    // Bounds [0, 0, 1]: a vertical force, f_x and f_y held at 0 (free,
    // f_x would move the bent tip through its small arm only, and the
    // default effort term bias such a weakly seen component, IS2).
    assert!((f[2] - force).abs() < 1e-7 * force.abs(), "{f:?}");
    assert_eq!((f[0], f[1]), (0.0, 0.0));
    assert_eq!(v["loads"][0]["load"], 0);
    assert_eq!(v["loads"][0]["rod"], "arm");
    assert_eq!(v["loads"][0]["max_force"][2], 1.0);
    assert_eq!(v["loads"][0]["bounds"][0], "lower");
    assert_eq!(v["loads"][0]["bounds"][2], "free");
    assert!(v["tensions"].as_array().unwrap().is_empty());
    // The text form names the load.
    let o = run(&["inverse", &unknown]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("load[0] on arm"), "{}", stdout(&o));
}

/// The joint torque of a forward solve is recovered from the link's
/// position (the body's frame from `statics --json`).
#[test]
fn joint_torque_of_a_forward_solve_is_recovered() {
    let tau = -0.1;
    let given = write("link-given", &link(&format!("{{ force = {tau} }}"), ""));
    let o = run(&["statics", &given, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let p = position(&stdout_json(&o)["bodies"][0]["position"]);
    let scene = link(
        "{ max_force = 1.0 }",
        &format!(
            "[[target]]\nelement = \"link\"\nposition = [{}, {}, {}]\n",
            p[0], p[1], p[2]
        ),
    );
    let unknown = write("link-unknown", &scene);
    let o = run(&["inverse", &unknown, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = stdout_json(&o);
    assert_eq!(v["reached"], true, "{v}");
    let j = &v["joints"][0];
    assert_eq!(j["element"], "link");
    assert_eq!(j["type"], "revolute");
    assert_eq!(j["max_force"][0], 1.0);
    assert_eq!(j["bounds"][0], "free");
    let f = j["forces"][0].as_f64().unwrap();
    assert!((f - tau).abs() < 1e-8, "{f} vs {tau}");
    assert_eq!(v["joint_forces"][0], j["forces"][0]);
}

/// Bad actuators and unknown loads: exit 2, the key path in the message.
#[test]
fn bad_actuators_and_unknown_loads_name_the_key() {
    let target = "[[target]]\nelement = \"arm\"\nposition = [0.5, 0, 0]\n";
    let cases = [
        (
            "negmax",
            link("{ max_force = -1.0 }", ""),
            "body[0].joint.actuator.max_force",
        ),
        (
            "length",
            link("{ force = [0.1, 0.2] }", ""),
            "body[0].joint.actuator.force",
        ),
        (
            "nan",
            link("{ force = nan }", ""),
            "body[0].joint.actuator.force",
        ),
        (
            "fixed",
            cantilever(&format!(
                "{target}[[body]]\nname = \"b\"\nparent = \"arm\"\njoint = {{ type = \"fixed\", \
                 actuator = {{ force = 1.0 }} }}\nmass = 0.1\ninertia = [1e-4, 1e-4, 1e-4]\n"
            )),
            "body[0].joint.actuator",
        ),
        (
            "loadneg",
            cantilever(&format!(
                "[[load]]\nrod = \"arm\"\ns = 0.5\nunknown = true\nmax_force = [1.0, -1.0, 1.0]\n{target}"
            )),
            "load[0].max_force[1]",
        ),
        (
            "loadforce",
            cantilever(&format!(
                "[[load]]\nrod = \"arm\"\ns = 0.5\nunknown = true\nforce = [0, 0, 1.0]\n{target}"
            )),
            "load[0].force",
        ),
        (
            "loadoff",
            cantilever(&format!(
                "[[load]]\nrod = \"arm\"\ns = 0.7\nunknown = true\n{target}"
            )),
            "load[0].s",
        ),
        (
            "maxknown",
            cantilever(&format!(
                "[[load]]\nrod = \"arm\"\ns = 0.5\nforce = [0, 0, 1.0]\nmax_force = 2.0\n{target}"
            )),
            "load[0].max_force",
        ),
        ("nothing", cantilever(target), "cable"),
    ];
    for (name, text, key) in cases {
        let p = write(name, &text);
        let o = run(&["inverse", &p]);
        assert_eq!(o.status.code(), Some(2), "{name}: {}", stderr(&o));
        assert!(stderr(&o).contains(key), "{name}: {}", stderr(&o));
        assert!(stdout(&o).is_empty(), "{name}: {}", stdout(&o));
    }
}
