//! The scene graph: nodes with dense indices, packed edges, and the compact, hashable
//! [`State`] that search works on.

use std::fmt;

use smallvec::SmallVec;

use crate::error::clip;
use crate::vocab::{PropSet, Relation, StateSet};

/// A node's id as written in a task file (`"id": 22`).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(transparent)]
pub struct NodeId(pub i64);

impl fmt::Display for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

/// A node's dense index inside one task (0..number of nodes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Idx(pub u16);

impl Idx {
    pub fn get(self) -> usize {
        self.0 as usize
    }
}

/// Most nodes a task may have: edges pack two indices of 14 bits.
pub const MAX_NODES: usize = 1 << 14;

/// What a node is to the rules, from its `category` (and `class_name` for robots).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NodeKind {
    Room,
    Floor,
    Door,
    Robot(RobotKind),
    /// A quadrotor's basket (`AgentTool`).
    Tool,
    Object,
}

/// The three robot types of the benchmark.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RobotKind {
    Quadrotor,
    RobotDog,
    RobotArm,
}

impl RobotKind {
    pub const ALL: [RobotKind; 3] = [
        RobotKind::Quadrotor,
        RobotKind::RobotDog,
        RobotKind::RobotArm,
    ];

    /// The `class_name` of this robot type in task files.
    pub fn class_name(self) -> &'static str {
        match self {
            RobotKind::Quadrotor => "quadrotor",
            RobotKind::RobotDog => "robot dog",
            RobotKind::RobotArm => "robot arm",
        }
    }

    pub fn from_class_name(name: &str) -> Option<RobotKind> {
        RobotKind::ALL.into_iter().find(|k| k.class_name() == name)
    }
}

impl fmt::Display for RobotKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.class_name())
    }
}

/// The static part of a node; its states and `ON_HIGH_SURFACE` live in [`State`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Node {
    pub id: NodeId,
    pub category: String,
    pub class_name: String,
    pub prefab_name: String,
    pub kind: NodeKind,
    /// Properties as read from the file; `ON_HIGH_SURFACE` changes while running, so the
    /// current value is [`State::on_high_surface`].
    pub properties: PropSet,
}

impl Node {
    /// `<class_name>(id)`, as in action strings and goals.
    pub fn label(&self) -> String {
        self.shown_label().to_string()
    }

    /// [`Node::label`] written straight into a formatter, for text that names many
    /// nodes (a prompt's facts), without a string per name.
    pub fn shown_label(&self) -> impl fmt::Display + '_ {
        Label(self)
    }

    /// [`Node::label`] with a name longer than [`crate::error::ECHO_CHARS`] cut, for messages about
    /// input.
    pub fn short_label(&self) -> String {
        format!("<{}>({})", clip(&self.class_name), self.id)
    }
}

/// See [`Node::shown_label`].
struct Label<'a>(&'a Node);

impl fmt::Display for Label<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "<{}>({})", self.0.class_name, self.0.id)
    }
}

/// A set of node indices; up to 256 nodes without a heap allocation (the search builds
/// several per expanded state).
#[derive(Debug, PartialEq, Eq)]
pub struct NodeSet(SmallVec<[u64; 4]>);

impl Clone for NodeSet {
    fn clone(&self) -> NodeSet {
        // The words copied in place when they fit inline, not a push per word.
        let words = self.0.as_slice();
        if words.len() <= INLINE_WORDS {
            let mut buf = [0u64; INLINE_WORDS];
            buf[..words.len()].copy_from_slice(words);
            NodeSet(SmallVec::from_buf_and_len(buf, words.len()))
        } else {
            NodeSet(SmallVec::from_slice(words))
        }
    }
}

/// Words a [`NodeSet`] keeps without a heap allocation (256 nodes).
const INLINE_WORDS: usize = 4;

impl NodeSet {
    pub fn new(n: usize) -> NodeSet {
        let words = n.div_ceil(64);
        if words <= INLINE_WORDS {
            NodeSet(SmallVec::from_buf_and_len([0; INLINE_WORDS], words))
        } else {
            NodeSet(smallvec::smallvec![0; words])
        }
    }
    pub fn contains(&self, n: Idx) -> bool {
        self.0[n.get() / 64] >> (n.get() % 64) & 1 == 1
    }
    /// Inserts `n`; returns whether it was new.
    pub fn insert(&mut self, n: Idx) -> bool {
        let new = !self.contains(n);
        self.0[n.get() / 64] |= 1 << (n.get() % 64);
        new
    }
    pub fn remove(&mut self, n: Idx) {
        self.0[n.get() / 64] &= !(1 << (n.get() % 64));
    }
    /// Removes every node whose bit is set in `words32` (32 nodes a word, as
    /// [`State`] keeps its `ON_HIGH_SURFACE` flags).
    pub(crate) fn remove_words32(&mut self, words32: &[u32]) {
        for (i, w) in self.0.iter_mut().enumerate() {
            let lo = u64::from(words32.get(2 * i).copied().unwrap_or(0));
            let hi = u64::from(words32.get(2 * i + 1).copied().unwrap_or(0));
            *w &= !(lo | hi << 32);
        }
    }
    /// Removes every node of `other`.
    pub fn remove_all(&mut self, other: &NodeSet) {
        for (w, o) in self.0.iter_mut().zip(other.0.iter()) {
            *w &= !o;
        }
    }
    /// Keeps only the nodes of `other`.
    pub fn keep_only(&mut self, other: &NodeSet) {
        for (w, o) in self.0.iter_mut().zip(other.0.iter()) {
            *w &= o;
        }
    }
    /// Adds every node of `other`.
    pub fn insert_all(&mut self, other: &NodeSet) {
        for (w, o) in self.0.iter_mut().zip(other.0.iter()) {
            *w |= o;
        }
    }
    /// The 64-bit words of the set, node `i` at bit `i % 64` of word `i / 64`.
    pub fn words(&self) -> &[u64] {
        &self.0
    }
    /// The words, to change in a loop without the small-vector's checks on each access.
    pub(crate) fn words_mut(&mut self) -> &mut [u64] {
        &mut self.0
    }
    /// The nodes, lowest index first.
    pub fn iter(&self) -> NodeSetIter<'_> {
        NodeSetIter {
            words: &self.0,
            at: 0,
            rest: self.0.first().copied().unwrap_or(0),
        }
    }
}

/// The nodes of a [`NodeSet`], lowest index first: one step per node, not per bit.
#[derive(Clone, Debug)]
pub struct NodeSetIter<'a> {
    words: &'a [u64],
    /// The word being read, and its bits not yet returned.
    at: usize,
    rest: u64,
}

impl Iterator for NodeSetIter<'_> {
    type Item = Idx;

    fn next(&mut self) -> Option<Idx> {
        while self.rest == 0 {
            self.at += 1;
            self.rest = *self.words.get(self.at)?;
        }
        let b = self.rest.trailing_zeros() as usize;
        self.rest &= self.rest - 1;
        Some(Idx((self.at * 64 + b) as u16))
    }
}

/// One directed edge, packed as `from << 17 | relation << 14 | to` so that a sorted
/// edge list groups each node's outgoing edges by relation.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(transparent)]
pub struct Edge(u32);

impl Edge {
    pub fn new(from: Idx, rel: Relation, to: Idx) -> Edge {
        Edge((from.0 as u32) << 17 | (rel as u32) << 14 | to.0 as u32)
    }
    pub fn from(self) -> Idx {
        Idx((self.0 >> 17) as u16)
    }
    /// The packed word.
    pub(crate) fn bits(self) -> u32 {
        self.0
    }
    pub fn rel(self) -> Relation {
        Relation::from_bits(self.0 >> 14 & 0b111)
    }
    pub fn to(self) -> Idx {
        Idx((self.0 & 0x3fff) as u16)
    }
}

impl fmt::Debug for Edge {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}-{}->{}", self.from().0, self.rel(), self.to().0)
    }
}

/// Everything that changes while a task runs: node states, `ON_HIGH_SURFACE`, edges.
/// One allocation, cheap to clone and hash: the planner stores one per visited state.
///
/// Layout of `data`: `[n, states of the n nodes, ON_HIGH_SURFACE bits in ceil(n/32)
/// words, edges (sorted, no duplicates: edges are a set)]`.
#[derive(PartialEq, Eq, Hash)]
pub struct State {
    data: Vec<u32>,
}

impl Clone for State {
    fn clone(&self) -> State {
        // Room for a few more edges, so that applying an action rarely reallocates.
        let mut data = Vec::with_capacity(self.data.len() + 4);
        data.extend_from_slice(&self.data);
        State { data }
    }

    fn clone_from(&mut self, source: &State) {
        self.data.clear();
        self.data.extend_from_slice(&source.data);
    }
}

impl State {
    pub(crate) fn new(states: Vec<StateSet>, high: Vec<bool>, mut edges: Vec<Edge>) -> State {
        let n = states.len();
        let mut data = Vec::with_capacity(1 + n + n.div_ceil(32) + edges.len());
        data.push(n as u32);
        data.extend(states.iter().map(|s| s.0));
        data.extend(std::iter::repeat_n(0, n.div_ceil(32)));
        edges.sort_unstable();
        edges.dedup();
        data.extend(edges.iter().map(|e| e.0));
        let mut state = State { data };
        for (i, h) in high.iter().enumerate() {
            state.set_on_high_surface(Idx(i as u16), *h);
        }
        state
    }

    /// Bytes of the state's own block (its words, with the room a clone leaves for a few
    /// more edges).
    pub(crate) fn heap_bytes(&self) -> usize {
        self.data.capacity() * size_of::<u32>()
    }

    fn nodes(&self) -> usize {
        self.data[0] as usize
    }

    fn edges_start(&self) -> usize {
        1 + self.nodes() + self.nodes().div_ceil(32)
    }

    pub fn states(&self, n: Idx) -> StateSet {
        StateSet(self.data[1 + n.get()])
    }

    pub(crate) fn set_states(&mut self, n: Idx, s: StateSet) {
        self.data[1 + n.get()] = s.0;
    }

    /// The `ON_HIGH_SURFACE` flags, node `i` at bit `i % 32` of word `i / 32`.
    pub(crate) fn high_words(&self) -> &[u32] {
        &self.data[1 + self.nodes()..self.edges_start()]
    }

    /// Whether node `n` currently has the `ON_HIGH_SURFACE` property.
    pub fn on_high_surface(&self, n: Idx) -> bool {
        self.data[1 + self.nodes() + n.get() / 32] >> (n.get() % 32) & 1 == 1
    }

    pub(crate) fn set_on_high_surface(&mut self, n: Idx, on: bool) {
        let w = 1 + self.nodes() + n.get() / 32;
        let bit = 1 << (n.get() % 32);
        if on {
            self.data[w] |= bit;
        } else {
            self.data[w] &= !bit;
        }
    }

    /// All edges, sorted by source node, then relation, then target.
    pub fn edges(&self) -> &[Edge] {
        bytemuck::cast_slice(&self.data[self.edges_start()..])
    }

    /// Outgoing edges of `n`.
    pub fn out(&self, n: Idx) -> &[Edge] {
        let edges = self.edges();
        let lo = edges.partition_point(|e| e.from() < n);
        let hi = lo + edges[lo..].partition_point(|e| e.from() == n);
        &edges[lo..hi]
    }
    /// Targets of `n`'s edges with relation `rel`.
    pub fn targets(&self, n: Idx, rel: Relation) -> impl Iterator<Item = Idx> + '_ {
        // Edges sort by (from, relation, to): one binary search finds the run.
        let edges = self.edges();
        let lo = edges.partition_point(|e| *e < Edge::new(n, rel, Idx(0)));
        edges[lo..]
            .iter()
            .take_while(move |e| e.from() == n && e.rel() == rel)
            .map(|e| e.to())
    }

    /// The first target of `n`'s `rel` edges, if any.
    pub fn target(&self, n: Idx, rel: Relation) -> Option<Idx> {
        self.targets(n, rel).next()
    }

    /// Sources of `rel` edges pointing at `n`.
    pub fn sources(&self, rel: Relation, n: Idx) -> impl Iterator<Item = Idx> + '_ {
        // A pass over every edge: compare the relation and target bits at once.
        let key = Edge::new(Idx(0), rel, n).0;
        self.edges()
            .iter()
            .filter(move |e| e.0 & 0x1_ffff == key)
            .map(|e| e.from())
    }

    pub fn has(&self, e: Edge) -> bool {
        self.edges().binary_search(&e).is_ok()
    }

    pub(crate) fn add(&mut self, e: Edge) {
        if let Err(at) = self.edges().binary_search(&e) {
            let at = self.edges_start() + at;
            self.data.insert(at, e.0);
        }
    }

    pub(crate) fn remove(&mut self, e: Edge) {
        if let Ok(at) = self.edges().binary_search(&e) {
            let at = self.edges_start() + at;
            self.data.remove(at);
        }
    }

    /// Keeps only the edges for which `keep` is true.
    pub(crate) fn retain(&mut self, mut keep: impl FnMut(Edge) -> bool) {
        // Most calls remove nothing: write only from the first edge that goes.
        let Some(first) =
            (self.edges_start()..self.data.len()).find(|&i| !keep(Edge(self.data[i])))
        else {
            return;
        };
        let mut kept = first;
        for i in first + 1..self.data.len() {
            if keep(Edge(self.data[i])) {
                self.data[kept] = self.data[i];
                kept += 1;
            }
        }
        self.data.truncate(kept);
    }

    /// Removes every outgoing edge of `n` with relation `rel`.
    pub(crate) fn remove_out(&mut self, n: Idx, rel: Relation) {
        self.remove_out_if(n, rel, |_| true);
    }

    /// Removes the outgoing `rel` edges of `n` whose target satisfies `gone`. They form
    /// one run of the sorted edges: only that run is visited.
    pub(crate) fn remove_out_if(
        &mut self,
        n: Idx,
        rel: Relation,
        mut gone: impl FnMut(Idx) -> bool,
    ) {
        let edges = self.edges();
        let lo = edges.partition_point(|e| *e < Edge::new(n, rel, Idx(0)));
        let len = edges[lo..]
            .iter()
            .take_while(|e| e.from() == n && e.rel() == rel)
            .count();
        let run = self.edges_start() + lo;
        let mut kept = run;
        for i in run..run + len {
            if !gone(Edge(self.data[i]).to()) {
                self.data[kept] = self.data[i];
                kept += 1;
            }
        }
        self.data.drain(kept..run + len);
    }
}

impl fmt::Debug for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let states: Vec<StateSet> = (0..self.nodes())
            .map(|i| self.states(Idx(i as u16)))
            .collect();
        f.debug_struct("State")
            .field("states", &states)
            .field("edges", &self.edges())
            .finish()
    }
}
