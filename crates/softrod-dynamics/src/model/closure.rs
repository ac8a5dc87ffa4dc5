//! Loop closures as a model holds them (docs/theory.md §11, D63): two
//! frames of an articulated model held together — a weld (all six relative
//! motions), a ball (the three relative translations) or a slider (a's
//! origin stays on a line through b) — placed on the model's tree, and the
//! Baumgarte rate of the constrained dynamics (D68). Their residual,
//! Jacobian and the constrained solve are in `crate::constraints`.

use crate::error::DynamicsError;
use crate::model::tree::Tree;
use crate::model::{ElementKind, Model};
use softrod_lie::{Pose, Vec3};

/// What a closure holds (D63).
#[derive(Clone, Debug, PartialEq)]
pub enum ClosureKind {
    /// All six relative motions: 6 constraints, `φ = (r, d)` with `r` the
    /// rotation vector of `R_bᵀR_a` and `d = R_bᵀ(p_a − p_b)` (b's axes).
    Weld,
    /// The relative position only: 3 constraints, `φ = d`; rotations free.
    Ball,
    /// a's origin stays on the line through b's origin along `axis` (b's
    /// axes; normalized when the model is built): 2 constraints, the
    /// components of `d` orthogonal to the axis; rotations and the motion
    /// along the axis free.
    Slider {
        /// Direction of the line in b's frame (nonzero).
        axis: Vec3,
    },
}

impl ClosureKind {
    /// Number of scalar constraints (6, 3, 2).
    pub fn n_constraints(&self) -> usize {
        match self {
            ClosureKind::Weld => 6,
            ClosureKind::Ball => 3,
            ClosureKind::Slider { .. } => 2,
        }
    }

    /// The scene's name of the kind: "weld", "ball", "slider".
    pub fn name(&self) -> &'static str {
        match self {
            ClosureKind::Weld => "weld",
            ClosureKind::Ball => "ball",
            ClosureKind::Slider { .. } => "slider",
        }
    }
}

/// One end of a closure: a frame on an element (or the world), then a
/// constant offset pose.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosureFrame {
    /// Name of a rod or body of the model, or "world".
    pub element: String,
    /// For a rod: arc length `s` \[m\] of the frame (any `s` in `[0, L]`,
    /// not only piece boundaries); `None`: the tip. Not used otherwise.
    pub at: Option<f64>,
    /// Pose of the closure frame relative to the element's frame there
    /// (the world frame, the rod's frame at `s`, the body frame).
    pub base: Pose,
}

impl ClosureFrame {
    /// The world frame, offset by `base`.
    pub fn world(base: Pose) -> Self {
        Self {
            element: "world".into(),
            at: None,
            base,
        }
    }

    /// A rod's frame at `at` (`None`: its tip) or a body's frame, offset by
    /// `base`.
    pub fn on(element: impl Into<String>, at: Option<f64>, base: Pose) -> Self {
        Self {
            element: element.into(),
            at,
            base,
        }
    }
}

/// A loop closure between frames `a` and `b` (docs/theory.md D63).
#[derive(Clone, Debug, PartialEq)]
pub struct Closure {
    /// A name for messages and outputs.
    pub name: String,
    /// Weld, ball or slider.
    pub kind: ClosureKind,
    /// The frame that is held.
    pub a: ClosureFrame,
    /// The frame it is held to (the slider's axis is in b's frame).
    pub b: ClosureFrame,
}

impl Closure {
    /// A closure named `name`.
    pub fn new(
        name: impl Into<String>,
        kind: ClosureKind,
        a: ClosureFrame,
        b: ClosureFrame,
    ) -> Self {
        Self {
            name: name.into(),
            kind,
            a,
            b,
        }
    }
}

/// Where a closure frame sits on the tree.
#[derive(Clone, Debug)]
pub(crate) enum Target {
    World,
    /// Rod `rod`, piece node `node`, at local abscissa `x` of piece `piece`.
    Rod {
        rod: usize,
        piece: usize,
        x: f64,
        node: usize,
    },
    Body {
        node: usize,
    },
}

#[derive(Clone, Debug)]
pub(crate) struct ResolvedFrame {
    pub target: Target,
    pub offset: Pose,
}

/// A closure of a built model: its spec (axis normalized), its frames on
/// the tree, its first row in `φ`, and the slider's two normals.
#[derive(Clone, Debug)]
pub(crate) struct ResolvedClosure {
    pub spec: Closure,
    pub a: ResolvedFrame,
    pub b: ResolvedFrame,
    pub row: usize,
    pub normals: [Vec3; 2],
}

fn resolve_frame(
    model: &Model,
    tree: &Tree,
    closure: &str,
    end: &'static str,
    f: &ClosureFrame,
) -> Result<ResolvedFrame, DynamicsError> {
    let err = |reason: String| DynamicsError::ClosureFrame {
        closure: closure.to_string(),
        end,
        element: f.element.clone(),
        reason,
    };
    if let Some((i, v)) = f
        .base
        .rotation
        .iter()
        .chain(f.base.translation.iter())
        .enumerate()
        .find(|(_, v)| !v.is_finite())
    {
        return Err(err(format!("base pose entry {i} is not finite ({v})")));
    }
    if f.base.orthonormality_error() > 1e-9 || f.base.rotation.determinant() < 0.0 {
        return Err(err(format!(
            "base rotation is not a rotation (‖RᵀR − I‖ = {:.3e})",
            f.base.orthonormality_error()
        )));
    }
    if f.element == "world" {
        return Ok(ResolvedFrame {
            target: Target::World,
            offset: f.base,
        });
    }
    let found: Vec<_> = model
        .elements
        .iter()
        .filter(|e| e.name == f.element)
        .collect();
    let info = match found.as_slice() {
        [e] => *e,
        [] => return Err(err("not a rod or body of the model (nor \"world\")".into())),
        _ => {
            return Err(err(format!(
                "ambiguous ({} elements have this name)",
                found.len()
            )));
        }
    };
    let target = match info.kind {
        ElementKind::Body(b) => Target::Body {
            node: tree.body_nodes[b],
        },
        ElementKind::Rod(r) => {
            let rod = &model.rods[r].spec.geometry;
            let len = rod.length();
            let s = f.at.unwrap_or(len);
            if !s.is_finite() || s < -1e-12 * len || s > len * (1.0 + 1e-12) {
                return Err(err(format!("at = {s} is outside the rod [0, {len}]")));
            }
            let (piece, x) = rod
                .locate(s.clamp(0.0, len))
                .map_err(|e| err(e.to_string()))?;
            Target::Rod {
                rod: r,
                piece,
                x,
                node: tree.rod_nodes[r][piece],
            }
        }
    };
    Ok(ResolvedFrame {
        target,
        offset: f.base,
    })
}

/// Checks and places the closures on the model's tree (D63).
pub(crate) fn resolve(
    model: &Model,
    closures: Vec<Closure>,
) -> Result<Vec<ResolvedClosure>, DynamicsError> {
    let tree = model.tree.as_ref().expect("closures need the tree");
    let mut out = Vec::with_capacity(closures.len());
    let mut row = 0;
    for mut c in closures {
        let a = resolve_frame(model, tree, &c.name, "a", &c.a)?;
        let b = resolve_frame(model, tree, &c.name, "b", &c.b)?;
        if matches!(a.target, Target::World) && matches!(b.target, Target::World) {
            return Err(DynamicsError::ClosureFrame {
                closure: c.name.clone(),
                end: "b",
                element: c.b.element.clone(),
                reason: "both ends are the world (nothing to constrain)".into(),
            });
        }
        let mut normals = [Vec3::zeros(); 2];
        if let ClosureKind::Slider { axis } = &mut c.kind {
            let n = axis.norm();
            if !(n.is_finite() && n > 1e-12) || axis.iter().any(|v| !v.is_finite()) {
                return Err(DynamicsError::ClosureAxis {
                    closure: c.name.clone(),
                    axis: *axis,
                });
            }
            *axis /= n;
            // Any orthonormal pair completing the axis: the residual's
            // norm does not depend on the choice.
            let helper = if axis.x.abs() < 0.9 {
                Vec3::x()
            } else {
                Vec3::y()
            };
            let e1 = axis.cross(&helper).normalize();
            let e2 = axis.cross(&e1);
            normals = [e1, e2];
        }
        let m = c.kind.n_constraints();
        out.push(ResolvedClosure {
            spec: c,
            a,
            b,
            row,
            normals,
        });
        row += m;
    }
    Ok(out)
}

/// `β / ω₁` of [`baumgarte_rate`] (D68).
pub(crate) const BAUMGARTE_FACTOR: f64 = 10.0;

/// The Baumgarte rate `α = β = ω_c` \[1/s\] (D68): the first cantilever
/// bending frequency `1.8751² √(EI/(ρA L⁴))` of the stiffest rod (largest
/// over the rods, at each rod's base section).
pub(crate) fn baumgarte_rate(model: &Model) -> f64 {
    let mut w: f64 = 0.0;
    for rm in &model.rods {
        let l = rm.spec.geometry.length();
        let k = rm.spec.properties.stiffness(0.0);
        let m = rm.spec.properties.screw_inertia(0.0);
        let ei = k[1].min(k[2]);
        let rho_a = m[3];
        if ei > 0.0 && rho_a > 0.0 && l > 0.0 {
            w = w.max(
                BAUMGARTE_FACTOR
                    * 1.875_104_068_711_961_f64.powi(2)
                    * (ei / (rho_a * l.powi(4))).sqrt(),
            );
        }
    }
    w
}
