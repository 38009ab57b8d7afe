//! The hash-consed expression arena.
//!
//! Nodes live in one flat `Vec` (12 bytes each, plus a 4-byte structural
//! hash), children before parents; sums, products and selects keep their
//! children in a side `Vec<Id>`, float constants in a side `Vec<f64>`. A
//! `hashbrown::HashTable<u32>` keyed with `FxHasher` maps a node's structure to
//! its id, so structurally equal nodes are one node. Hashing is deterministic
//! and the table is never iterated, so ids — and everything printed or
//! lowered from them — are identical run to run.

use super::node::{Id, Node, SymId, SymKind, Symbol, View};
use super::num::Num;
use super::rules::RuleSet;
use hashbrown::HashTable;
use rustc_hash::{FxHashMap, FxHashSet, FxHasher};
use std::fmt;
use std::hash::{Hash, Hasher};

/// Default of [`Arena::flatten_limit`].
pub const DEFAULT_FLATTEN_LIMIT: usize = 8;

/// Errors from the symbolic engine (naming, parsing, derivatives).
#[derive(Clone, PartialEq, Eq, Debug)]
pub enum SymError {
    /// A name is already used by a symbol of another kind.
    NameClash {
        /// The name asked for.
        name: String,
        /// The kind it already has.
        existing: SymKind,
    },
    /// A parameter or input name that the naming convention reserves
    /// (`t`, `q<i>`, `u<i>`, `qd<i>`, `ud<i>`) or that is not an identifier.
    ReservedName(String),
    /// An s-expression could not be parsed.
    Parse {
        /// Byte offset in the input.
        offset: usize,
        /// What was wrong.
        message: String,
    },
    /// A total time derivative needs the rate of a symbol that has none.
    NoRate(String),
}

impl fmt::Display for SymError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SymError::NameClash { name, existing } => {
                write!(
                    f,
                    "name `{name}` is already a {existing}; choose another name"
                )
            }
            SymError::ReservedName(name) => write!(
                f,
                "name `{name}` is reserved or not an identifier; `t`, `q<i>`, `u<i>`, `qd<i>`, `ud<i>` name time, coordinates, speeds and their rates"
            ),
            SymError::Parse { offset, message } => write!(f, "at byte {offset}: {message}"),
            SymError::NoRate(name) => {
                write!(
                    f,
                    "no time derivative known for `{name}`; pass its rate explicitly"
                )
            }
        }
    }
}

impl std::error::Error for SymError {}

/// Sizes of an arena's storage, for the memory-per-node figure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryStats {
    /// Number of nodes.
    pub nodes: usize,
    /// Bytes used by the node vector and the structural hashes
    /// (`nodes * (size_of::<Node>() + 4)`).
    pub node_bytes: usize,
    /// Bytes used by the side vectors: children of sums, products and
    /// selects, and float constants.
    pub arg_bytes: usize,
    /// Bytes allocated by the hash table.
    pub table_bytes: usize,
}

impl MemoryStats {
    /// `(node_bytes + arg_bytes) / nodes`: bytes per node excluding the hash table.
    pub fn bytes_per_node(&self) -> f64 {
        (self.node_bytes + self.arg_bytes) as f64 / self.nodes.max(1) as f64
    }
}

/// One generation's expression store. See the [module docs](super).
#[derive(Clone)]
pub struct Arena {
    nodes: Vec<Node>,
    /// Structural hash of each node: independent of ids, so of the order in
    /// which nodes were created (see [`Arena::shash`]).
    shash: Vec<u32>,
    args: Vec<Id>,
    /// Values of float constants (rationals are stored inline).
    floats: Vec<f64>,
    table: HashTable<u32>,
    syms: Vec<Symbol>,
    sym_nodes: Vec<Id>,
    sym_by_name: FxHashMap<String, SymId>,
    pub(crate) rules: RuleSet,
    rules_uniform: bool,
    pub(crate) flatten_limit: usize,
    pub(crate) diff_memo: FxHashMap<SymId, FxHashMap<Id, Id>>,
}

impl Default for Arena {
    fn default() -> Self {
        Arena::new()
    }
}

fn view_of<'a>(nodes: &[Node], args: &'a [Id], floats: &[f64], id: u32) -> View<'a> {
    match nodes[id as usize] {
        Node::Rat(p, q) => View::Num(Num::Rat(p, q)),
        Node::Float(i) => View::Num(Num::Float(floats[i as usize])),
        Node::Sym(s) => View::Sym(s),
        Node::Add(s, l) => View::Add(&args[s as usize..(s + l) as usize]),
        Node::Mul(s, l) => View::Mul(&args[s as usize..(s + l) as usize]),
        Node::Pow(a, n) => View::Pow(a, n),
        Node::Sqrt(a) => View::Sqrt(a),
        Node::Sin(a) => View::Sin(a),
        Node::Cos(a) => View::Cos(a),
        Node::Tan(a) => View::Tan(a),
        Node::Exp(a) => View::Exp(a),
        Node::Ln(a) => View::Ln(a),
        Node::Abs(a) => View::Abs(a),
        Node::Atan2(a, b) => View::Atan2(a, b),
        Node::Select(s) => {
            let s = s as usize;
            View::Select(args[s], args[s + 1], args[s + 2])
        }
    }
}

fn hash_view(v: &View<'_>) -> u64 {
    let mut h = FxHasher::default();
    v.hash(&mut h);
    h.finish()
}

impl Arena {
    /// An empty arena with all construction-time simplifications on
    /// ([`RuleSet::ALL`]).
    pub fn new() -> Arena {
        Arena::with_rules(RuleSet::ALL)
    }

    /// An empty arena whose smart constructors apply only `rules`.
    /// `RuleSet::NONE` gives a "raw" arena that only flattens, orders and
    /// hash-conses (used by tests to build unsimplified expressions).
    pub fn with_rules(rules: RuleSet) -> Arena {
        Arena {
            nodes: Vec::new(),
            shash: Vec::new(),
            args: Vec::new(),
            floats: Vec::new(),
            table: HashTable::new(),
            syms: Vec::new(),
            sym_nodes: Vec::new(),
            sym_by_name: FxHashMap::default(),
            rules,
            rules_uniform: true,
            flatten_limit: DEFAULT_FLATTEN_LIMIT,
            diff_memo: FxHashMap::default(),
        }
    }

    /// The construction-time rules in force.
    pub fn rules(&self) -> RuleSet {
        self.rules
    }

    /// Change the construction-time rules for nodes built from now on.
    pub fn set_rules(&mut self, rules: RuleSet) {
        if rules != self.rules && !self.is_empty() {
            self.rules_uniform = false;
        }
        self.rules = rules;
    }

    /// True if every node was built under the current rules (they were
    /// never changed while the arena had nodes), so all nodes are canonical.
    pub fn rules_uniform(&self) -> bool {
        self.rules_uniform
    }

    /// Sums with more than this many terms are not flattened into an
    /// enclosing sum (nor multiplied out by a numeric coefficient): they
    /// stay one shared child, so recursively built quantities
    /// (`v_i = v_{i-1} + ω_i × r_i`) grow linearly instead of quadratically.
    /// Like terms are not collected across such a boundary.
    pub fn flatten_limit(&self) -> usize {
        self.flatten_limit
    }

    /// Set [`Arena::flatten_limit`] (`usize::MAX` flattens always).
    pub fn set_flatten_limit(&mut self, n: usize) {
        self.flatten_limit = n;
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True if no node has been created.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The structure of node `id`.
    pub fn view(&self, id: Id) -> View<'_> {
        view_of(&self.nodes, &self.args, &self.floats, id.0)
    }

    /// The constant value of `id`, if it is a constant.
    pub fn num(&self, id: Id) -> Option<Num> {
        match self.nodes[id.index()] {
            Node::Rat(p, q) => Some(Num::Rat(p, q)),
            Node::Float(i) => Some(Num::Float(self.floats[i as usize])),
            _ => None,
        }
    }

    /// Find an existing node with this structure, without creating it.
    pub(crate) fn lookup(&self, v: &View<'_>) -> Option<Id> {
        let hash = hash_view(v);
        let (nodes, args, floats) = (&self.nodes, &self.args, &self.floats);
        self.table
            .find(hash, |&i| view_of(nodes, args, floats, i) == *v)
            .map(|&i| Id(i))
    }

    /// Hash-cons a node exactly as given (no simplification). Children of
    /// `v` must already exist. Used by the smart constructors once they have
    /// reached a canonical form.
    pub(crate) fn intern(&mut self, v: View<'_>) -> Id {
        let hash = hash_view(&v);
        let (nodes, args, floats) = (&self.nodes, &self.args, &self.floats);
        if let Some(&i) = self
            .table
            .find(hash, |&i| view_of(nodes, args, floats, i) == v)
        {
            return Id(i);
        }
        let id = u32::try_from(self.nodes.len()).expect("arena exceeds u32::MAX nodes");
        let node = match v {
            View::Num(Num::Rat(p, q)) => Node::Rat(p, q),
            View::Num(Num::Float(x)) => {
                self.floats.push(x);
                Node::Float(self.floats.len() as u32 - 1)
            }
            View::Sym(s) => Node::Sym(s),
            View::Add(s) | View::Mul(s) => {
                debug_assert!(s.iter().all(|c| c.0 < id));
                let start = self.args.len() as u32;
                self.args.extend_from_slice(s);
                if matches!(v, View::Add(_)) {
                    Node::Add(start, s.len() as u32)
                } else {
                    Node::Mul(start, s.len() as u32)
                }
            }
            View::Pow(a, n) => Node::Pow(a, n),
            View::Sqrt(a) => Node::Sqrt(a),
            View::Sin(a) => Node::Sin(a),
            View::Cos(a) => Node::Cos(a),
            View::Tan(a) => Node::Tan(a),
            View::Exp(a) => Node::Exp(a),
            View::Ln(a) => Node::Ln(a),
            View::Abs(a) => Node::Abs(a),
            View::Atan2(a, b) => Node::Atan2(a, b),
            View::Select(a, b, c) => {
                self.args.extend_from_slice(&[a, b, c]);
                Node::Select(self.args.len() as u32 - 3)
            }
        };
        let sh = self.struct_hash(&v);
        self.nodes.push(node);
        self.shash.push(sh);
        let (nodes, args, floats) = (&self.nodes, &self.args, &self.floats);
        self.table
            .insert_unique(hash, id, |&i| hash_view(&view_of(nodes, args, floats, i)));
        Id(id)
    }

    /// A 32-bit structural hash of node `id`, computed from its operation,
    /// constant value or symbol name and its children's structural hashes —
    /// never from ids. Canonical orders sort by it, so printed text and
    /// programs do not depend on the order in which nodes were created.
    pub fn shash(&self, id: Id) -> u32 {
        self.shash[id.index()]
    }

    fn struct_hash(&self, v: &View<'_>) -> u32 {
        let mut h = FxHasher::default();
        std::mem::discriminant(v).hash(&mut h);
        match *v {
            View::Num(n) => n.hash(&mut h),
            View::Sym(s) => self.syms[s.index()].name.hash(&mut h),
            View::Pow(a, n) => {
                self.shash[a.index()].hash(&mut h);
                n.hash(&mut h);
            }
            _ => {
                for c in v.children() {
                    self.shash[c.index()].hash(&mut h);
                }
            }
        }
        let x = h.finish();
        (x ^ (x >> 32)) as u32
    }

    /// Compare two nodes in canonical order: constants first by value, then
    /// by structural hash; ids only break (rare) hash ties.
    pub(crate) fn canonical_cmp(&self, x: Id, y: Id) -> std::cmp::Ordering {
        use std::cmp::Ordering;
        match (self.num(x), self.num(y)) {
            (Some(m), Some(n)) => m.total_cmp(n).then(x.cmp(&y)),
            (Some(_), None) => Ordering::Less,
            (None, Some(_)) => Ordering::Greater,
            (None, None) => self.shash(x).cmp(&self.shash(y)).then(x.cmp(&y)),
        }
    }

    /// Compare factor lists in canonical order (lexicographic on [`Arena::canonical_cmp`]).
    pub(crate) fn canonical_cmp_slices(&self, a: &[Id], b: &[Id]) -> std::cmp::Ordering {
        for (&x, &y) in a.iter().zip(b) {
            let o = self.canonical_cmp(x, y);
            if o.is_ne() {
                return o;
            }
        }
        a.len().cmp(&b.len())
    }

    /// The constant node for `n` (a float that is a small dyadic rational
    /// is stored as the exact rational, see [`Num::from_f64`]).
    pub fn num_node(&mut self, n: Num) -> Id {
        let n = match n {
            Num::Float(x) => Num::from_f64(x),
            n => n,
        };
        self.intern(View::Num(n))
    }

    /// The constant node for `x` (small dyadic rationals become exact).
    pub fn constant(&mut self, x: f64) -> Id {
        self.num_node(Num::from_f64(x))
    }

    /// The exact rational `p/q`; falls back to the nearest `f64` if it does not
    /// fit in `i32 / i32`. `q` must not be zero (a zero denominator gives NaN).
    pub fn ratio(&mut self, p: i64, q: i64) -> Id {
        let n = Num::ratio(p, q).unwrap_or(Num::Float(p as f64 / q as f64));
        self.num_node(n)
    }

    // ---- symbols -------------------------------------------------------

    fn declare(&mut self, kind: SymKind, name: String) -> Result<Id, SymError> {
        if let Some(&s) = self.sym_by_name.get(&name) {
            let existing = self.syms[s.index()].kind;
            if existing == kind {
                return Ok(self.sym_nodes[s.index()]);
            }
            return Err(SymError::NameClash { name, existing });
        }
        let s = SymId(self.syms.len() as u32);
        self.sym_by_name.insert(name.clone(), s);
        self.syms.push(Symbol { kind, name });
        let node = self.intern(View::Sym(s));
        self.sym_nodes.push(node);
        Ok(node)
    }

    fn indexed(&mut self, kind: SymKind) -> Id {
        let name = Symbol::conventional_name(kind).expect("indexed kind");
        // Conventional names are reserved: parameters and inputs can never
        // take them, so this cannot clash.
        self.declare(kind, name)
            .expect("conventional names are reserved")
    }

    fn check_free_name(name: &str) -> Result<(), SymError> {
        let ident = !name.is_empty()
            && name
                .chars()
                .next()
                .is_some_and(|c| c.is_alphabetic() || c == '_')
            && name
                .chars()
                .all(|c| c.is_alphanumeric() || c == '_' || c == '.');
        if !ident || Symbol::kind_from_name(name) != SymKind::Param || name == "select" {
            return Err(SymError::ReservedName(name.to_string()));
        }
        Ok(())
    }

    /// Coordinate `q_i`.
    pub fn q(&mut self, i: u32) -> Id {
        self.indexed(SymKind::Coord(i))
    }
    /// Speed `u_i`.
    pub fn u(&mut self, i: u32) -> Id {
        self.indexed(SymKind::Speed(i))
    }
    /// Coordinate rate `q̇_i`.
    pub fn qd(&mut self, i: u32) -> Id {
        self.indexed(SymKind::CoordRate(i))
    }
    /// Speed rate `u̇_i`.
    pub fn ud(&mut self, i: u32) -> Id {
        self.indexed(SymKind::SpeedRate(i))
    }
    /// Extra generalised force `τ_i`.
    pub fn tau(&mut self, i: u32) -> Id {
        self.indexed(SymKind::Tau(i))
    }
    /// Constraint multiplier `λ_i`.
    pub fn multiplier(&mut self, i: u32) -> Id {
        self.indexed(SymKind::Multiplier(i))
    }
    /// Time `t`.
    pub fn t(&mut self) -> Id {
        self.indexed(SymKind::Time)
    }
    /// A tunable parameter (same name → same node).
    pub fn param(&mut self, name: &str) -> Result<Id, SymError> {
        Self::check_free_name(name)?;
        self.declare(SymKind::Param, name.to_string())
    }
    /// An input (same name → same node).
    pub fn input(&mut self, name: &str) -> Result<Id, SymError> {
        Self::check_free_name(name)?;
        self.declare(SymKind::Input, name.to_string())
    }
    /// A symbol by name: an existing one, else one of the conventional kind
    /// (`q3` → coordinate 3, …; other identifiers → parameter).
    pub fn sym_named(&mut self, name: &str) -> Result<Id, SymError> {
        if let Some(&s) = self.sym_by_name.get(name) {
            return Ok(self.sym_nodes[s.index()]);
        }
        match Symbol::kind_from_name(name) {
            SymKind::Param => self.param(name),
            kind => Ok(self.indexed(kind)),
        }
    }
    /// Look up a symbol by name.
    pub fn find_symbol(&self, name: &str) -> Option<SymId> {
        self.sym_by_name.get(name).copied()
    }
    /// The symbol with id `s`.
    pub fn symbol(&self, s: SymId) -> &Symbol {
        &self.syms[s.index()]
    }
    /// The node of symbol `s`.
    pub fn sym_node(&self, s: SymId) -> Id {
        self.sym_nodes[s.index()]
    }
    /// The symbol a node is, if it is one.
    pub fn as_sym(&self, id: Id) -> Option<SymId> {
        match self.nodes[id.index()] {
            Node::Sym(s) => Some(s),
            _ => None,
        }
    }
    /// All symbols, in creation order (index = `SymId`).
    pub fn symbols(&self) -> &[Symbol] {
        &self.syms
    }

    // ---- graph walks ---------------------------------------------------

    /// Nodes reachable from `roots` (roots included), in ascending id order
    /// (a topological order). Nodes for which `stop` holds are included but
    /// not descended into.
    pub fn reachable(&self, roots: &[Id], stop: impl Fn(Id) -> bool) -> Vec<Id> {
        let mut seen = FxHashSet::default();
        let mut stack: Vec<Id> = Vec::new();
        let mut out = Vec::new();
        for &r in roots {
            if seen.insert(r) {
                stack.push(r);
            }
        }
        while let Some(id) = stack.pop() {
            out.push(id);
            if stop(id) {
                continue;
            }
            for c in self.view(id).children() {
                if seen.insert(c) {
                    stack.push(c);
                }
            }
        }
        out.sort_unstable();
        out
    }

    /// Number of distinct nodes reachable from `roots` (the DAG size).
    pub fn dag_size(&self, roots: &[Id]) -> usize {
        self.reachable(roots, |_| false).len()
    }

    /// Does `e` depend on symbol `s`?
    pub fn depends_on(&self, e: Id, s: SymId) -> bool {
        let target = self.sym_node(s);
        target <= e
            && self
                .reachable(&[e], |id| id < target)
                .binary_search(&target)
                .is_ok()
    }

    /// Storage sizes (see [`MemoryStats::bytes_per_node`]).
    pub fn memory(&self) -> MemoryStats {
        MemoryStats {
            nodes: self.nodes.len(),
            node_bytes: self.nodes.len()
                * (std::mem::size_of::<Node>() + std::mem::size_of::<u32>()),
            arg_bytes: self.args.len() * std::mem::size_of::<Id>()
                + self.floats.len() * std::mem::size_of::<f64>(),
            table_bytes: self.table.allocation_size(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_structure_is_one_node() {
        let mut a = Arena::new();
        let x = a.param("x").unwrap();
        let y = a.param("y").unwrap();
        let s1 = a.intern(View::Add(&[x, y]));
        let n = a.len();
        let s2 = a.intern(View::Add(&[x, y]));
        assert_eq!(s1, s2);
        assert_eq!(a.len(), n, "no new node for an equal structure");
        let p = a.intern(View::Mul(&[x, y]));
        assert_ne!(p, s1, "sum and product differ");
    }

    #[test]
    fn names_are_checked() {
        let mut a = Arena::new();
        assert_eq!(a.param("q1"), Err(SymError::ReservedName("q1".into())));
        assert_eq!(a.param("1x"), Err(SymError::ReservedName("1x".into())));
        a.param("m").unwrap();
        assert!(matches!(a.input("m"), Err(SymError::NameClash { .. })));
        let q = a.q(1);
        assert_eq!(a.sym_named("q1").unwrap(), q);
        assert_eq!(a.symbol(a.as_sym(q).unwrap()).name, "q1");
    }
}
