//! The tree of a model with joints, rigid bodies or parents
//! (docs/theory.md §11, D50–D62): a list of *nodes* in topological order
//! (every parent before its children), each a rod piece, a joint's virtual
//! piece or a rigid body, hanging from its parent's tip frame (or, D62, a
//! point inside the parent piece) through a constant offset pose.

use crate::error::DynamicsError;
use crate::model::{ElementKind, Model};
use softrod_lie::{Mat6, Pose};

/// What a node is.
#[derive(Clone, Debug)]
pub(crate) enum NodeKind {
    /// A joint's virtual piece (D50): unit length, strain `B q_j`, no
    /// inertia; the joint of element `element`.
    Joint { element: usize },
    /// Piece `piece` of rod `rod`.
    Piece { rod: usize, piece: usize },
    /// Rigid body `body` (no coordinates; its frame is its tip).
    Body { body: usize },
}

/// One node of the tree.
#[derive(Clone, Debug)]
pub(crate) struct Node {
    /// Parent node (`None`: the world).
    pub parent: Option<usize>,
    /// Pose of this node's base frame in its parent's tip frame (or the
    /// world's): `X = Ad⁻¹_offset` carries twists across it (D54).
    pub offset: Pose,
    pub kind: NodeKind,
    /// First coordinate in `q` and number of coordinates `k` (zero for a
    /// prescribed joint's piece).
    pub dof: usize,
    pub k: usize,
    /// A prescribed joint's piece (D59): its first coordinate among the
    /// prescribed ones and their number (the columns of `bpad`).
    pub prescribed: Option<(usize, usize)>,
    /// Hanging inside the parent piece at local abscissa `x` \[m\] (D62)
    /// rather than at its tip.
    pub attach: Option<f64>,
    /// Strain basis zero-padded to 6×6 (joints and pieces; zero for bodies).
    pub bpad: Mat6,
}

/// The nodes of an articulated model, and where each element's nodes are.
#[derive(Clone, Debug)]
pub(crate) struct Tree {
    pub nodes: Vec<Node>,
    /// Per rod: its pieces' nodes, base to tip.
    pub rod_nodes: Vec<Vec<usize>>,
    /// Per body: its node.
    pub body_nodes: Vec<usize>,
    /// Per node: the children that hang inside it (`attach` set), in order.
    pub inner_children: Vec<Vec<usize>>,
}

impl Tree {
    /// Resolves parents (by name), orders the elements parents first
    /// (rejecting cycles), and lays out the nodes (D51).
    pub(crate) fn build(model: &Model) -> Result<Self, DynamicsError> {
        let els = &model.elements;
        let n = els.len();
        let mut parent = vec![None; n];
        for (i, e) in els.iter().enumerate() {
            let Some(name) = &e.attachment.parent else {
                continue;
            };
            if name == "world" {
                continue;
            }
            let found: Vec<usize> = (0..n).filter(|&j| &els[j].name == name).collect();
            match found.as_slice() {
                [j] => parent[i] = Some(*j),
                [] => {
                    return Err(DynamicsError::UnknownParent {
                        element: e.name.clone(),
                        parent: name.clone(),
                        reason: "not a rod or body of the model".into(),
                    });
                }
                _ => {
                    return Err(DynamicsError::UnknownParent {
                        element: e.name.clone(),
                        parent: name.clone(),
                        reason: format!("ambiguous ({} elements have this name)", found.len()),
                    });
                }
            }
        }
        // Topological order by depth-first search (0 new, 1 open, 2 done).
        let mut state = vec![0u8; n];
        let mut order = Vec::with_capacity(n);
        for start in 0..n {
            let mut path = Vec::new();
            let mut i = start;
            loop {
                match state[i] {
                    2 => break,
                    1 => {
                        return Err(DynamicsError::ParentCycle {
                            element: els[i].name.clone(),
                        });
                    }
                    _ => {}
                }
                state[i] = 1;
                path.push(i);
                match parent[i] {
                    Some(p) => i = p,
                    None => break,
                }
            }
            for &j in path.iter().rev() {
                state[j] = 2;
                order.push(j);
            }
        }
        let mut tree = Tree {
            nodes: Vec::new(),
            rod_nodes: vec![Vec::new(); model.rods.len()],
            body_nodes: vec![0; model.bodies.len()],
            inner_children: Vec::new(),
        };
        // Per rod: (parent node, offset) of its first piece — where a child
        // at s = 0 hangs.
        let mut rod_base = vec![(None, Pose::identity()); model.rods.len()];
        for &e in &order {
            let info = &els[e];
            let mut inner = None;
            let (node, attach) = match parent[e] {
                None => (None, Pose::identity()),
                Some(p) => match els[p].kind {
                    ElementKind::Body(b) => (Some(tree.body_nodes[b]), Pose::identity()),
                    ElementKind::Rod(r) => {
                        let rod = &model.rods[r].spec.geometry;
                        let len = rod.length();
                        let at = info.attachment.at.unwrap_or(len);
                        let tol = 1e-9 * len;
                        if !(at >= -tol && at <= len + tol) {
                            return Err(DynamicsError::AttachOutsideRod {
                                element: info.name.clone(),
                                parent: els[p].name.clone(),
                                at,
                                length: len,
                            });
                        }
                        if at.abs() <= tol {
                            rod_base[r]
                        } else if let Some(pn) = rod
                            .pieces()
                            .iter()
                            .position(|pc| (pc.end() - at).abs() <= tol)
                        {
                            (Some(tree.rod_nodes[r][pn]), Pose::identity())
                        } else {
                            // Inside a piece (D62).
                            let pn = rod
                                .pieces()
                                .iter()
                                .position(|pc| at < pc.end())
                                .unwrap_or(rod.n_pieces() - 1);
                            let pc = &rod.pieces()[pn];
                            inner = Some(at - pc.start);
                            (Some(tree.rod_nodes[r][pn]), Pose::identity())
                        }
                    }
                },
            };
            let base = match info.kind {
                ElementKind::Rod(r) => *model.rods[r].spec.geometry.base(),
                ElementKind::Body(b) => model.bodies[b].spec.base,
            };
            let mut cur = (node, attach.compose(&base));
            for (basis, local) in info.attachment.joint.kind.segments() {
                let k = basis.ncols();
                let bpad = Mat6::from_fn(|i, j| if j < k { basis[(i, j)] } else { 0.0 });
                let driven = info.attachment.joint.prescribed.is_some();
                tree.nodes.push(Node {
                    parent: cur.0,
                    offset: cur.1,
                    kind: NodeKind::Joint { element: e },
                    dof: if driven {
                        0
                    } else {
                        info.joint_dofs.start + local
                    },
                    k: if driven { 0 } else { k },
                    prescribed: driven.then_some((info.prescribed_dofs.start + local, k)),
                    attach: inner.take(),
                    bpad,
                });
                cur = (Some(tree.nodes.len() - 1), Pose::identity());
            }
            match info.kind {
                ElementKind::Rod(r) => {
                    rod_base[r] = cur;
                    let rm = &model.rods[r];
                    for (pn, piece) in rm.spec.geometry.pieces().iter().enumerate() {
                        let k = piece.basis.dof();
                        let bpad =
                            Mat6::from_fn(
                                |i, j| if j < k { piece.basis.column(j)[i] } else { 0.0 },
                            );
                        tree.nodes.push(Node {
                            parent: cur.0,
                            offset: cur.1,
                            kind: NodeKind::Piece { rod: r, piece: pn },
                            dof: rm.dof_offset + piece.dof_offset,
                            k,
                            prescribed: None,
                            attach: inner.take(),
                            bpad,
                        });
                        cur = (Some(tree.nodes.len() - 1), Pose::identity());
                        tree.rod_nodes[r].push(tree.nodes.len() - 1);
                    }
                }
                ElementKind::Body(b) => {
                    tree.nodes.push(Node {
                        parent: cur.0,
                        offset: cur.1,
                        kind: NodeKind::Body { body: b },
                        dof: 0,
                        k: 0,
                        prescribed: None,
                        attach: inner.take(),
                        bpad: Mat6::zeros(),
                    });
                    tree.body_nodes[b] = tree.nodes.len() - 1;
                }
            }
        }
        tree.inner_children = vec![Vec::new(); tree.nodes.len()];
        for (i, n) in tree.nodes.iter().enumerate() {
            if let (Some(p), Some(_)) = (n.parent, n.attach) {
                tree.inner_children[p].push(i);
            }
        }
        Ok(tree)
    }

    /// A node as messages name it.
    pub(crate) fn describe(&self, model: &Model, i: usize) -> String {
        match self.nodes[i].kind {
            NodeKind::Joint { element } => {
                format!("the joint of '{}'", model.elements[element].name)
            }
            NodeKind::Piece { rod, piece } => {
                format!("rod '{}', piece {piece}", model.rods[rod].spec.name)
            }
            NodeKind::Body { body } => format!("body '{}'", model.bodies[body].spec.name),
        }
    }
}
