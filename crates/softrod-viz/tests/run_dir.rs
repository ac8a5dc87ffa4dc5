//! Run-directory files: CSV round trips with hostile names, `view.json`,
//! the view rebuilt from files alone, and clear errors on bad files.

use std::path::{Path, PathBuf};

use softrod_viz::demo::SwingingRods;
use softrod_viz::run_dir::{
    BodiesCsvWriter, BodySpec, CableSpec, RadiusProfile, Rod, ShapeCsvWriter, ViewSpec,
    read_bodies_csv, read_bodies_csv_thinned, read_shape_csv, read_shape_csv_thinned,
    view_from_dir, write_view,
};
use softrod_viz::{BodyShape, Pose, ViewOptions, VizError};

fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("softrod-viz-rundir-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const HOSTILE: [&str; 6] = [
    "arm, left",
    "the \"quoted\" rod",
    "line\nbreak",
    " leading space",
    "ünïcødé/\\;tab\t",
    "",
];

/// Written by ShapeCsvWriter and read back: every name, time, abscissa and
/// pose component identical to the bit (shortest round-trip decimals).
#[test]
fn shape_csv_round_trip_with_hostile_names() {
    let dir = scratch("shape");
    let mut view = SwingingRods {
        rods: HOSTILE.len(),
        times: 7,
        samples: 5,
        ..SwingingRods::default()
    }
    .build();
    for (r, name) in view.rods.iter_mut().zip(HOSTILE) {
        r.name = name.into();
    }
    // Values that print with exponents and many digits.
    view.rods[0].frames[3][2].position = [1e-300, -2.5e-7, 0.1 + 0.2];
    let path = dir.join("shape.csv");
    {
        let mut w = ShapeCsvWriter::new(std::fs::File::create(&path).unwrap()).unwrap();
        for (k, t) in view.times.iter().enumerate() {
            for r in &view.rods {
                w.write_frame(*t, &r.name, &r.s, &r.frames[k]).unwrap();
            }
            w.flush().unwrap();
        }
    }
    let back = read_shape_csv(&path).unwrap();
    assert_eq!(back.times, view.times);
    assert_eq!(back.rods.len(), view.rods.len());
    for (a, b) in back.rods.iter().zip(&view.rods) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.s, b.s);
        assert_eq!(a.frames, b.frames);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The file the CLI writes today (plain names, `{}` floats, extra columns
/// allowed after the contract's ten) reads as expected.
#[test]
fn reads_the_contract_layout_as_written_by_hand() {
    let dir = scratch("contract");
    let path = dir.join("shape.csv");
    std::fs::write(
        &path,
        "t,rod,s,x,y,z,qw,qx,qy,qz,extra\n\
         0,arm,0,0,0,0,1,0,0,0,9\n\
         0,arm,0.25,0.25,0,0,1,0,0,0,9\n\
         0,arm,0.5,0.5,0,0,1,0,0,0,9\n\
         0.1,arm,0,0,0,0,1,0,0,0,9\n\
         0.1,arm,0.25,0.2,0,-0.1,0.99,0,0.1,0,9\n\
         0.1,arm,0.5,0.4,0,-0.2,0.98,0,0.2,0,9\n",
    )
    .unwrap();
    let d = read_shape_csv(&path).unwrap();
    assert_eq!(d.times, [0.0, 0.1]);
    assert_eq!(d.rods[0].s, [0.0, 0.25, 0.5]);
    assert_eq!(d.rods[0].frames[1][2].position, [0.4, 0.0, -0.2]);
    assert_eq!(d.rods[0].frames[1][2].rotation, [0.98, 0.0, 0.2, 0.0]);
    let _ = std::fs::remove_dir_all(&dir);
}

fn expect_csv_error(text: &str, line: u64, contains: &str) {
    let dir = scratch("bad");
    let path = dir.join("shape.csv");
    std::fs::write(&path, text).unwrap();
    match read_shape_csv(&path) {
        Err(VizError::Csv {
            line: l, problem, ..
        }) => {
            assert_eq!(l, line, "{problem}");
            assert!(problem.contains(contains), "{problem:?} lacks {contains:?}");
        }
        other => panic!("expected a CSV error for {text:?}, got {other:?}"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_shape_files_are_clear_errors() {
    let head = "t,rod,s,x,y,z,qw,qx,qy,qz\n";
    expect_csv_error("t,name,s,x,y,z,qw,qx,qy,qz\n", 1, "header");
    expect_csv_error(&format!("{head}0,a,0,0,0,NaN,1,0,0,0\n"), 2, "column z");
    expect_csv_error(
        &format!("{head}0,a,0,0,0,zero,1,0,0,0\n"),
        2,
        "not a finite number",
    );
    expect_csv_error(&format!("{head}0,a,0,0,0,0,1,0,0\n"), 2, "fields");
    expect_csv_error(
        &format!(
            "{head}0,a,0,0,0,0,1,0,0,0\n0,a,0.5,0,0,0,1,0,0,0\n1,a,0,0,0,0,1,0,0,0\n2,a,0,0,0,0,1,0,0,0\n"
        ),
        5,
        "1 of its 2 samples",
    );
    expect_csv_error(
        &format!(
            "{head}0,a,0,0,0,0,1,0,0,0\n0,a,0.5,0,0,0,1,0,0,0\n1,a,0,0,0,0,1,0,0,0\n1,a,0.4,0,0,0,1,0,0,0\n"
        ),
        5,
        "the first time had s = 0.5",
    );
    expect_csv_error(
        &format!("{head}0,a,0,0,0,0,1,0,0,0\n0,a,0,0,0,0,1,0,0,0\n"),
        3,
        "does not increase",
    );
    expect_csv_error(
        &format!("{head}1,a,0,0,0,0,1,0,0,0\n0,a,0,0,0,0,1,0,0,0\n"),
        3,
        "after",
    );
}

/// A directory with shape.csv, view.json and bodies.csv becomes the view:
/// radii interpolated from the profile, the cable routed at its offsets
/// (checked against the straight rod's closed form), the body's poses.
#[test]
fn view_from_files_alone() {
    let dir = scratch("view");
    let demo = SwingingRods {
        times: 5,
        samples: 11,
        ..SwingingRods::default()
    };
    let view = demo.build();
    let rod = &view.rods[0];
    {
        let mut w =
            ShapeCsvWriter::new(std::fs::File::create(dir.join("shape.csv")).unwrap()).unwrap();
        let mut b =
            BodiesCsvWriter::new(std::fs::File::create(dir.join("bodies.csv")).unwrap()).unwrap();
        for (k, t) in view.times.iter().enumerate() {
            w.write_frame(*t, &rod.name, &rod.s, &rod.frames[k])
                .unwrap();
            b.write_pose(*t, "ball, 20 g", &rod.frames[k][10]).unwrap();
        }
        w.flush().unwrap();
        b.flush().unwrap();
    }
    let mut spec = ViewSpec::new("files only");
    spec.rods.push(Rod {
        name: rod.name.clone(),
        radius: RadiusProfile {
            s: vec![0.0, 0.5],
            r: vec![0.01, 0.005],
        },
    });
    let (y0, z0, z1) = (0.0, 0.008, 0.004);
    spec.cables.push(CableSpec {
        name: "c".into(),
        rod: rod.name.clone(),
        path: vec![[0.0, y0, z0], [0.5, y0, z1]],
    });
    spec.bodies.push(BodySpec {
        name: "ball, 20 g".into(),
        shape: BodyShape::Sphere { radius: 0.02 },
    });
    spec.write(&dir.join("view.json")).unwrap();
    assert_eq!(ViewSpec::read(&dir.join("view.json")).unwrap(), spec);

    let v = view_from_dir(&dir).unwrap();
    assert_eq!(v.title, "files only");
    assert_eq!(v.times, view.times);
    // Linear taper 10 mm → 5 mm over 0.5 m, sampled every 5 cm.
    for (s, r) in v.rods[0].s.iter().zip(&v.rods[0].radius) {
        assert!((r - (0.01 - 0.01 * s)).abs() < 1e-15, "r({s}) = {r}");
    }
    // t = 0: κ = 0, the rod hangs straight down from the origin with local
    // z along world x (demo base), so the cable point at s is
    // (z(s), −y(s)·0 + y0, −s) with z(s) linear from z0 to z1.
    let c0 = &v.cables[0].points[0];
    assert_eq!(c0.len(), 11);
    for (p, s) in c0.iter().zip(&v.rods[0].s) {
        let z = z0 + (z1 - z0) * s / 0.5;
        let expect = [z, y0, -s];
        for j in 0..3 {
            assert!(
                (p[j] - expect[j]).abs() < 1e-15,
                "s = {s}: {p:?} vs {expect:?}"
            );
        }
    }
    assert_eq!(v.bodies[0].name, "ball, 20 g");
    assert_eq!(v.bodies[0].poses[3], rod.frames[3][10]);

    let (html, stats) = write_view(&dir, &ViewOptions::default()).unwrap();
    assert_eq!(html, dir.join("view.html"));
    assert_eq!(stats.frames.len(), 5);
    let page = std::fs::read_to_string(&html).unwrap();
    let d = softrod_viz::html::embedded_data(&page).unwrap();
    assert_eq!(d["bodies"][0]["name"], "ball, 20 g");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Without view.json: the directory name as title, radius 1 % of length;
/// a view.json naming an unknown rod is an error naming it.
#[test]
fn defaults_and_spec_errors() {
    let dir = scratch("defaults");
    let view = SwingingRods {
        times: 2,
        samples: 3,
        ..SwingingRods::default()
    }
    .build();
    let rod = &view.rods[0];
    {
        let mut w =
            ShapeCsvWriter::new(std::fs::File::create(dir.join("shape.csv")).unwrap()).unwrap();
        for (k, t) in view.times.iter().enumerate() {
            w.write_frame(*t, &rod.name, &rod.s, &rod.frames[k])
                .unwrap();
        }
    }
    let v = view_from_dir(&dir).unwrap();
    assert!(v.title.starts_with("softrod-viz-rundir-"));
    assert_eq!(v.rods[0].radius, vec![0.005; 3]);
    let mut spec = ViewSpec::new("x");
    spec.cables.push(CableSpec {
        name: "c".into(),
        rod: "nope".into(),
        path: vec![[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]],
    });
    spec.write(&dir.join("view.json")).unwrap();
    match view_from_dir(&dir) {
        Err(VizError::Invalid { problem, .. }) => assert!(problem.contains("\"nope\"")),
        other => panic!("{other:?}"),
    }
    std::fs::write(
        dir.join("view.json"),
        "{\"format\":\"softrod-view\",\"version\":1,\"titel\":\"x\"}",
    )
    .unwrap();
    assert!(matches!(view_from_dir(&dir), Err(VizError::Json { .. })));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bodies_csv_round_trip() {
    let dir = scratch("bodies");
    let path = dir.join("bodies.csv");
    let p = Pose {
        position: [0.1, -0.2, 3e-9],
        rotation: [0.5, 0.5, -0.5, 0.5],
    };
    {
        let mut w = BodiesCsvWriter::new(std::fs::File::create(&path).unwrap()).unwrap();
        for t in [0.0, 0.5] {
            for name in HOSTILE {
                w.write_pose(t, name, &p).unwrap();
            }
        }
    }
    let (times, bodies) = read_bodies_csv(&path).unwrap();
    assert_eq!(times, [0.0, 0.5]);
    assert_eq!(bodies.len(), HOSTILE.len());
    for (b, name) in bodies.iter().zip(HOSTILE) {
        assert_eq!(b.0, name);
        assert_eq!(b.1, vec![p, p]);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A long run read for a view: between `cap` and `2·cap` of its times,
/// evenly spaced, the first and the last among them, each with exactly the
/// poses the full read has; `bodies.csv` of the same times keeps the same
/// times (issue 26, D07: the view's memory must not grow with the rows).
#[test]
fn thinned_reads_keep_evenly_spaced_times_and_the_last() {
    let dir = scratch("thinned");
    let n = 10_007;
    let s = [0.0, 0.5, 1.0];
    let pose = |k: usize, i: usize| Pose {
        position: [k as f64, i as f64, 0.25 * k as f64],
        rotation: [1.0, 0.0, 0.0, 0.0],
    };
    let (shape, bodies) = (dir.join("shape.csv"), dir.join("bodies.csv"));
    {
        let mut w = ShapeCsvWriter::new(std::fs::File::create(&shape).unwrap()).unwrap();
        let mut b = BodiesCsvWriter::new(std::fs::File::create(&bodies).unwrap()).unwrap();
        for k in 0..n {
            let t = 1e-3 * k as f64;
            let frame: Vec<Pose> = (0..s.len()).map(|i| pose(k, i)).collect();
            w.write_frame(t, "arm", &s, &frame).unwrap();
            b.write_pose(t, "ball", &pose(k, 7)).unwrap();
        }
        w.flush().unwrap();
        b.flush().unwrap();
    }
    let full = read_shape_csv(&shape).unwrap();
    assert_eq!(full.times.len(), n);
    for cap in [2, 100, 333] {
        let thin = read_shape_csv_thinned(&shape, cap).unwrap();
        let m = thin.times.len();
        assert!((cap..=2 * cap + 1).contains(&m), "cap {cap}: {m} times");
        assert_eq!(thin.times[0], full.times[0]);
        assert_eq!(thin.times[m - 1], full.times[n - 1]);
        // The kept indices (from the positions' x = k) are one stride apart
        // but for the appended last one.
        let idx: Vec<usize> = thin.rods[0]
            .frames
            .iter()
            .map(|f| f[0].position[0] as usize)
            .collect();
        let stride = idx[1] - idx[0];
        assert!(
            idx[..m - 1].windows(2).all(|w| w[1] - w[0] == stride),
            "{idx:?}"
        );
        assert!(n - 1 - idx[m - 2] <= stride);
        for (j, &k) in idx.iter().enumerate() {
            assert_eq!(thin.times[j], full.times[k]);
            assert_eq!(thin.rods[0].frames[j], full.rods[0].frames[k]);
        }
        let (bt, bp) = read_bodies_csv_thinned(&bodies, cap).unwrap();
        assert_eq!(bt, thin.times);
        assert_eq!(bp[0].1.len(), m);
        assert!(
            bp[0]
                .1
                .iter()
                .zip(&idx)
                .all(|(p, &k)| p.position[0] == k as f64)
        );
    }
}

/// The view a run builds from its frames as it writes them
/// (`FrameCollector`) keeps the times and poses the files give back when
/// read (thinned or not), and the same page as `write_view` of the
/// directory: a second path to the same numbers.
#[test]
fn collected_frames_equal_the_files_read_back() {
    use softrod_viz::collect::FrameCollector;
    let dir = scratch("collect");
    let view = SwingingRods {
        rods: 2,
        times: 61,
        samples: 9,
        body: true,
        ..SwingingRods::default()
    }
    .build();
    let ball = &view.bodies[0];
    // Negative zeros are written "0": the collector must hold what the
    // files hold.
    let mut rods = view.rods.clone();
    rods[1].frames[4][0].position = [-0.0, 1e-300, -2.5e-7];
    let rod_list = || -> Vec<(String, Vec<f64>)> {
        rods.iter().map(|r| (r.name.clone(), r.s.clone())).collect()
    };
    let collect = |mut c: FrameCollector| {
        for (k, t) in view.times.iter().enumerate() {
            for (i, r) in rods.iter().enumerate() {
                c.push_rod(i, r.frames[k].iter().copied());
            }
            c.push_body(ball.poses[k]);
            c.end_time(*t).unwrap();
        }
        c
    };
    {
        let mut w =
            ShapeCsvWriter::new(std::fs::File::create(dir.join("shape.csv")).unwrap()).unwrap();
        let mut b =
            BodiesCsvWriter::new(std::fs::File::create(dir.join("bodies.csv")).unwrap()).unwrap();
        for (k, t) in view.times.iter().enumerate() {
            for r in &rods {
                w.write_frame(*t, &r.name, &r.s, &r.frames[k]).unwrap();
            }
            b.write_pose(*t, &ball.name, &ball.poses[k]).unwrap();
        }
        w.flush().unwrap();
        b.flush().unwrap();
    }
    for cap in [1, 3, 7, 30, 1000] {
        let c = collect(FrameCollector::with_cap(
            rod_list(),
            vec![ball.name.clone()],
            cap,
        ));
        assert_eq!(c.times_seen(), view.times.len());
        let (shape, bodies) = c.finish();
        let file = read_shape_csv_thinned(&dir.join("shape.csv"), cap).unwrap();
        assert_eq!(shape, file, "cap {cap}");
        let (bt, bp) = read_bodies_csv_thinned(&dir.join("bodies.csv"), cap).unwrap();
        assert_eq!(bt, shape.times, "cap {cap}");
        assert_eq!(bodies, bp, "cap {cap}");
    }
    // A frame with a sample missing is an error naming the rod, and the
    // time is dropped.
    let mut c = FrameCollector::with_cap(rod_list(), vec![ball.name.clone()], 10);
    c.push_rod(0, rods[0].frames[0][1..].iter().copied());
    c.push_rod(1, rods[1].frames[0].iter().copied());
    c.push_body(ball.poses[0]);
    let e = c.end_time(0.0).unwrap_err().to_string();
    assert!(
        e.contains(&format!("rod {:?}: 8 poses for 9 samples", rods[0].name)),
        "{e}"
    );
    assert_eq!(c.times_seen(), 0);

    let mut spec = ViewSpec::new("collected");
    spec.bodies.push(BodySpec {
        name: ball.name.clone(),
        shape: BodyShape::Sphere { radius: 0.02 },
    });
    spec.write(&dir.join("view.json")).unwrap();
    let opts = ViewOptions::default();
    let (html, _) = write_view(&dir, &opts).unwrap();
    let from_files = std::fs::read(&html).unwrap();
    let c = collect(FrameCollector::new(
        rod_list(),
        vec![ball.name.clone()],
        &opts,
    ));
    let (html2, stats) = c.write_view(&dir, &spec, &opts).unwrap();
    assert_eq!(html2, html);
    assert_eq!(stats.source_frames, view.times.len());
    assert!(
        std::fs::read(&html).unwrap() == from_files,
        "the pages differ"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
