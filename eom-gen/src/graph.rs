//! The system graph (Wittenburg, *Dynamics of Multibody Systems*, ch. 5.3):
//! bodies are vertices (0 = ground), joints are arcs from parent to child.
//!
//! A spanning tree rooted at ground is chosen by a depth-first search that
//! follows joints from parent to child, siblings in file order, so bodies
//! and tree joints come out in the order coordinates are numbered: parents
//! before children. Joints the user marks `cut` are used only if a body
//! cannot be reached otherwise. Every joint outside the tree is a *cut
//! joint*; each closes one independent loop.

/// Index of a body; 0 is ground.
pub type BodyId = usize;
/// Index of a joint, in file order.
pub type JointId = usize;

/// An arc of the graph: a joint from `parent` to `child`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Arc {
    /// Parent body.
    pub parent: BodyId,
    /// Child body.
    pub child: BodyId,
    /// The user prefers this joint to be cut.
    pub prefer_cut: bool,
}

/// Why a graph has no spanning tree rooted at ground.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GraphError {
    /// No joint at all links the body to ground, in either direction.
    Disconnected(BodyId),
    /// The body is linked to ground only through joints that point towards
    /// ground (the body is their parent); the tree needs one reversed.
    OnlyReversed {
        /// The unreachable body.
        body: BodyId,
        /// A joint whose parent and child would have to be swapped.
        joint: JointId,
    },
    /// A joint joins a body to itself.
    SelfLoop(JointId),
}

impl std::fmt::Display for GraphError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GraphError::Disconnected(b) => write!(f, "body {b} is not connected to ground"),
            GraphError::OnlyReversed { body, joint } => write!(
                f,
                "body {body} is reached from ground only against the direction of joint {joint}"
            ),
            GraphError::SelfLoop(j) => write!(f, "joint {j} joins a body to itself"),
        }
    }
}

impl std::error::Error for GraphError {}

/// The system graph with its spanning tree. Immutable once built.
#[derive(Clone, Debug)]
pub struct Graph {
    arcs: Vec<Arc>,
    n_bodies: usize,
    /// Tree joints in coordinate order (depth-first, parents first).
    tree: Vec<JointId>,
    /// Joints outside the tree, in file order.
    cut: Vec<JointId>,
    /// The joint from each body's tree parent (`None` for ground).
    parent_joint: Vec<Option<JointId>>,
}

impl Graph {
    /// Builds the graph of `n_bodies` bodies (ground included) and chooses
    /// the spanning tree. Reports every body that cannot be reached.
    pub fn new(n_bodies: usize, arcs: Vec<Arc>) -> Result<Graph, Vec<GraphError>> {
        let mut errors: Vec<GraphError> = arcs
            .iter()
            .enumerate()
            .filter(|(_, a)| a.parent == a.child)
            .map(|(j, _)| GraphError::SelfLoop(j))
            .collect();
        let mut children: Vec<Vec<JointId>> = vec![Vec::new(); n_bodies];
        for (j, a) in arcs.iter().enumerate() {
            if a.parent < n_bodies && a.child < n_bodies && a.parent != a.child {
                children[a.parent].push(j);
            }
        }
        let mut parent_joint = vec![None; n_bodies];
        let mut reached = vec![false; n_bodies];
        let mut tree = Vec::new();
        if n_bodies > 0 {
            reached[0] = true;
        }
        // First pass avoids joints marked `cut`; the second admits them for
        // bodies that cannot be reached otherwise.
        for admit_preferred_cuts in [false, true] {
            let roots: Vec<BodyId> = if admit_preferred_cuts {
                (0..n_bodies).filter(|&b| reached[b]).collect()
            } else {
                vec![0]
            };
            for root in roots {
                // Iterative depth-first search, children in file order.
                let mut stack: Vec<(BodyId, usize)> = vec![(root, 0)];
                while let Some(top) = stack.last_mut() {
                    let (body, next) = *top;
                    let Some(&j) = children.get(body).and_then(|c| c.get(next)) else {
                        stack.pop();
                        continue;
                    };
                    top.1 += 1;
                    let arc = arcs[j];
                    if reached[arc.child] || (arc.prefer_cut && !admit_preferred_cuts) {
                        continue;
                    }
                    reached[arc.child] = true;
                    parent_joint[arc.child] = Some(j);
                    tree.push(j);
                    stack.push((arc.child, 0));
                }
            }
        }
        // Tree joints found in the second pass hang below the first pass's
        // tree: re-sort all of them into one depth-first order.
        let tree = Self::depth_first(&children, &parent_joint, &arcs, n_bodies, tree.len());
        for b in 1..n_bodies {
            if reached[b] {
                continue;
            }
            let reversed = arcs
                .iter()
                .position(|a| a.parent == b && a.child < n_bodies && reached[a.child]);
            match reversed {
                Some(joint) => errors.push(GraphError::OnlyReversed { body: b, joint }),
                None => errors.push(GraphError::Disconnected(b)),
            }
        }
        if !errors.is_empty() {
            return Err(errors);
        }
        let in_tree: Vec<bool> = {
            let mut v = vec![false; arcs.len()];
            tree.iter().for_each(|&j| v[j] = true);
            v
        };
        let cut = (0..arcs.len()).filter(|&j| !in_tree[j]).collect();
        Ok(Graph {
            arcs,
            n_bodies,
            tree,
            cut,
            parent_joint,
        })
    }

    fn depth_first(
        children: &[Vec<JointId>],
        parent_joint: &[Option<JointId>],
        arcs: &[Arc],
        n_bodies: usize,
        capacity: usize,
    ) -> Vec<JointId> {
        let mut order = Vec::with_capacity(capacity);
        if n_bodies == 0 {
            return order;
        }
        let mut stack: Vec<(BodyId, usize)> = vec![(0, 0)];
        while let Some(top) = stack.last_mut() {
            let (body, next) = *top;
            let Some(&j) = children[body].get(next) else {
                stack.pop();
                continue;
            };
            top.1 += 1;
            let child = arcs[j].child;
            if parent_joint[child] == Some(j) {
                order.push(j);
                stack.push((child, 0));
            }
        }
        order
    }

    /// Number of bodies, ground included.
    pub fn n_bodies(&self) -> usize {
        self.n_bodies
    }

    /// Number of joints (arcs).
    pub fn n_joints(&self) -> usize {
        self.arcs.len()
    }

    /// The arc of joint `j`.
    pub fn arc(&self, j: JointId) -> Arc {
        self.arcs[j]
    }

    /// Tree joints, parents before children, siblings in file order.
    pub fn tree_joints(&self) -> &[JointId] {
        &self.tree
    }

    /// Joints outside the tree (each closes a loop), in file order.
    pub fn cut_joints(&self) -> &[JointId] {
        &self.cut
    }

    /// True if `j` is a tree joint.
    pub fn is_tree_joint(&self, j: JointId) -> bool {
        self.parent_joint[self.arcs[j].child] == Some(j)
    }

    /// The tree joint above body `b` (`None` for ground).
    pub fn parent_joint(&self, b: BodyId) -> Option<JointId> {
        self.parent_joint.get(b).copied().flatten()
    }

    /// The tree parent of body `b`.
    pub fn parent_body(&self, b: BodyId) -> Option<BodyId> {
        self.parent_joint(b).map(|j| self.arcs[j].parent)
    }

    /// Bodies in tree order: ground, then each tree joint's child.
    pub fn body_order(&self) -> Vec<BodyId> {
        std::iter::once(0)
            .chain(self.tree.iter().map(|&j| self.arcs[j].child))
            .collect()
    }

    /// Tree joints on the path from ground to body `b`, ground first.
    pub fn path_to(&self, b: BodyId) -> Vec<JointId> {
        let mut path = Vec::new();
        let mut body = b;
        while let Some(j) = self.parent_joint(body) {
            path.push(j);
            body = self.arcs[j].parent;
        }
        path.reverse();
        path
    }

    /// Incidence matrix `S` (bodies × joints, ground is row 0): `S[i][a]`
    /// is +1 if body `i` is the parent of joint `a`, −1 if it is the child,
    /// 0 otherwise (Wittenburg eq. 5.6 with arcs pointing parent → child).
    pub fn incidence(&self) -> Vec<Vec<i8>> {
        let mut s = vec![vec![0i8; self.arcs.len()]; self.n_bodies];
        for (a, arc) in self.arcs.iter().enumerate() {
            s[arc.parent][a] = 1;
            s[arc.child][a] = -1;
        }
        s
    }

    /// Path matrix `T` (tree joints in tree order × bodies): `T[k][i]` is 1
    /// if the k-th tree joint lies on the path from ground to body `i`
    /// (Wittenburg eq. 5.13; all tree arcs point away from ground, so there
    /// are no −1 entries). Column 0 (ground) is zero.
    pub fn path_matrix(&self) -> Vec<Vec<i8>> {
        let row_of: Vec<Option<usize>> = {
            let mut v = vec![None; self.arcs.len()];
            self.tree
                .iter()
                .enumerate()
                .for_each(|(k, &j)| v[j] = Some(k));
            v
        };
        let mut t = vec![vec![0i8; self.n_bodies]; self.tree.len()];
        let paths = (0..self.n_bodies).map(|b| (b, self.path_to(b)));
        for (b, path) in paths {
            for k in path.into_iter().filter_map(|j| row_of[j]) {
                t[k][b] = 1;
            }
        }
        t
    }

    /// The independent loop closed by cut joint `c`: the tree joints from
    /// the loop's top body down to the cut joint's parent, then the cut
    /// joint, then the tree joints up from its child (a fundamental cycle).
    pub fn loop_of(&self, c: JointId) -> Vec<JointId> {
        let arc = self.arcs[c];
        let a = self.path_to(arc.parent);
        let b = self.path_to(arc.child);
        let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
        let mut cycle: Vec<JointId> = a[common..].to_vec();
        cycle.push(c);
        cycle.extend(b[common..].iter().rev());
        cycle
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arc(parent: BodyId, child: BodyId) -> Arc {
        Arc {
            parent,
            child,
            prefer_cut: false,
        }
    }

    /// Four-bar: ground(0), crank1(1), coupler(2), crank2(3).
    fn fourbar(prefer_cut_last: bool) -> Graph {
        let mut arcs = vec![arc(0, 1), arc(1, 2), arc(2, 3), arc(0, 3)];
        arcs[2].prefer_cut = prefer_cut_last;
        Graph::new(4, arcs).expect("connected")
    }

    #[test]
    fn fourbar_tree_and_cut() {
        // Without preference, depth-first reaches crank2 through the coupler.
        let g = fourbar(false);
        assert_eq!(g.tree_joints(), &[0, 1, 2]);
        assert_eq!(g.cut_joints(), &[3]);
        assert_eq!(g.loop_of(3), vec![3, 2, 1, 0]);
        // Marking the coupler joint cut reroutes the tree through ground.
        let g = fourbar(true);
        assert_eq!(g.tree_joints(), &[0, 1, 3]);
        assert_eq!(g.cut_joints(), &[2]);
        assert_eq!(g.loop_of(2), vec![0, 1, 2, 3]);
        assert_eq!(g.body_order(), vec![0, 1, 2, 3]);
    }

    #[test]
    fn incidence_columns_sum_to_zero_and_path_matrix_inverts_it() {
        let g = fourbar(false);
        let s = g.incidence();
        for a in 0..g.n_joints() {
            let col: i32 = s.iter().map(|row| i32::from(row[a])).sum();
            assert_eq!(col, 0, "column {a} of S");
        }
        // Wittenburg: for the tree part, T S_tree = -1 (identity up to the
        // sign of our arc direction) over the bodies other than ground.
        let t = g.path_matrix();
        for (k, &j) in g.tree_joints().iter().enumerate() {
            for (m, &jj) in g.tree_joints().iter().enumerate() {
                let dot: i32 = (1..g.n_bodies())
                    .map(|b| i32::from(t[k][b]) * i32::from(s[b][jj]))
                    .sum();
                let want = if k == m { -1 } else { 0 };
                assert_eq!(dot, want, "(T S)[{k}][{m}] for joints {j},{jj}");
            }
        }
    }

    #[test]
    fn branched_tree_orders_depth_first_siblings_in_file_order() {
        // ground -> 1 -> 3, ground -> 2, 1 -> 4
        let g = Graph::new(5, vec![arc(0, 1), arc(0, 2), arc(1, 3), arc(1, 4)]).expect("tree");
        assert_eq!(g.tree_joints(), &[0, 2, 3, 1]);
        assert_eq!(g.path_to(4), vec![0, 3]);
        assert_eq!(g.parent_body(4), Some(1));
    }

    #[test]
    fn unreachable_bodies_are_all_reported() {
        let errs = Graph::new(4, vec![arc(0, 1), arc(2, 2)]).expect_err("broken");
        assert_eq!(
            errs,
            vec![
                GraphError::SelfLoop(1),
                GraphError::Disconnected(2),
                GraphError::Disconnected(3)
            ]
        );
        let errs = Graph::new(3, vec![arc(0, 1), arc(2, 1)]).expect_err("reversed");
        assert_eq!(errs, vec![GraphError::OnlyReversed { body: 2, joint: 1 }]);
    }

    #[test]
    fn a_preferred_cut_is_used_when_nothing_else_reaches_the_body() {
        let mut arcs = vec![arc(0, 1), arc(1, 2)];
        arcs[1].prefer_cut = true;
        let g = Graph::new(3, arcs).expect("reachable through the preferred cut");
        assert_eq!(g.tree_joints(), &[0, 1]);
        assert!(g.cut_joints().is_empty());
    }

    #[test]
    fn joint_into_ground_is_always_cut() {
        let g = Graph::new(2, vec![arc(0, 1), arc(1, 0)]).expect("loop through ground");
        assert_eq!(g.cut_joints(), &[1]);
        assert_eq!(g.loop_of(1), vec![0, 1]);
    }
}
