//! Obstacles in the shape figures: each obstacle's outline is drawn in the
//! projections that show it, the panels take it in, and the legend names it.

use softrod_viz::plot::{RodCurve, ShapeSnapshot, shapes_with_obstacles};
use softrod_viz::{ObstacleShape, ObstacleTrack, Pose};

/// A rod that leaves every coordinate plane (a planar scene draws its one
/// plane only), so that all three projections are drawn.
fn rod() -> RodCurve {
    RodCurve {
        name: "arm".into(),
        points: (0..=10)
            .map(|i| {
                let x = 0.05 * i as f64;
                [x, 0.02 * x, 0.01 * x]
            })
            .collect(),
    }
}

#[test]
fn outlines_are_drawn_and_named() {
    let snaps = [
        ShapeSnapshot {
            t: Some(0.0),
            rods: vec![rod()],
            bodies: Vec::new(),
        },
        ShapeSnapshot {
            t: Some(1.0),
            rods: vec![rod()],
            bodies: Vec::new(),
        },
    ];
    let obstacles = [
        ObstacleTrack::fixed(
            "table",
            ObstacleShape::Plane {
                position: [0.0, 0.0, -0.05],
                normal: [0.0, 0.0, 1.0],
            },
        ),
        ObstacleTrack::fixed(
            "ball",
            ObstacleShape::Sphere {
                position: [0.8, 0.0, 0.3],
                radius: 0.1,
            },
        ),
        ObstacleTrack {
            name: "pad".into(),
            shape: ObstacleShape::Box {
                position: [0.0; 3],
                rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                half_extents: [0.02, 0.02, 0.02],
            },
            poses: Some(vec![Pose::at([0.1, 0.0, 0.1]), Pose::at([0.3, 0.0, 0.1])]),
        },
    ];
    let fig = shapes_with_obstacles("t", &snaps, &obstacles).unwrap();
    for name in ["table (plane)", "ball (sphere)", "pad (box)"] {
        assert!(fig.svg.contains(name), "legend lacks {name}");
    }
    // The ball lies beyond the rod: every panel that shows x reaches past
    // its far side (0.9 m), the x–z and y–z panels above its top (0.4 m).
    let (xz, yz, xy) = (&fig.panels[0], &fig.panels[1], &fig.panels[2]);
    assert!(
        xz.x_range.1 >= 0.9 && xy.x_range.1 >= 0.9,
        "{:?}",
        xz.x_range
    );
    assert!(
        xz.y_range.1 >= 0.4 && yz.y_range.1 >= 0.4,
        "{:?}",
        xz.y_range
    );
    // The table seen from the side reaches below itself (its hatches).
    assert!(xz.y_range.0 < -0.05 && yz.y_range.0 < -0.05);
    // Without obstacles the figure is the plain one.
    let plain = softrod_viz::plot::shapes("t", &snaps).unwrap();
    assert_eq!(plain, shapes_with_obstacles("t", &snaps, &[]).unwrap());
    assert!(!plain.svg.contains("obstacles"));
}

#[test]
fn a_carried_obstacle_needs_a_pose_per_snapshot() {
    let snaps = [ShapeSnapshot {
        t: None,
        rods: vec![rod()],
        bodies: Vec::new(),
    }];
    let mut o = ObstacleTrack::fixed(
        "ball",
        ObstacleShape::Sphere {
            position: [0.0; 3],
            radius: 0.1,
        },
    );
    o.poses = Some(vec![Pose::at([0.0; 3]); 2]);
    assert!(shapes_with_obstacles("t", &snaps, &[o]).is_err());
}
