//! A task: the scene graph at the start, the robots, the goal and what is known of the
//! ground truth. Both file formats (the paper's and ours) build a [`Task`] through
//! `Task::build`, so structural checks live in one place.

use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, Site, ensure, quoted};
use crate::graph::{Edge, Idx, MAX_NODES, Node, NodeId, NodeKind, NodeSet, RobotKind, State};
use crate::vocab::{PropSet, Relation, StateSet, Vocabulary};

/// A node as written in a task file (the original format's field names).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawNode {
    pub id: i64,
    pub category: String,
    pub class_name: String,
    #[serde(default)]
    pub prefab_name: String,
    #[serde(default)]
    pub properties: Vec<String>,
    #[serde(default)]
    pub states: Vec<String>,
}

/// An edge as written in a task file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawEdge {
    pub from_id: i64,
    pub to_id: i64,
    pub relation_type: String,
}

/// A scene graph as written in a task file: `{"nodes": [...], "edges": [...]}`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawGraph {
    pub nodes: Vec<RawNode>,
    pub edges: Vec<RawEdge>,
}

/// One goal predicate: `count` edges `(subject, relation, target)` must exist
/// (`on_<a>(i)_<b>(j)` / `inside_<a>(i)_<b>(j)` in the original format).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct GoalPredicate {
    pub relation: Relation,
    pub subject: Idx,
    pub target: Idx,
    pub count: u32,
}

/// Which rules a task runs under. Imported original tasks run under the compatible
/// rules of docs/semantics.md.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RuleSet {
    #[default]
    Compatible,
    /// The project's own benchmark: the compatible rules, with the height labels derived
    /// from the task's geometry (`heights::derive_heights`) and one quirk
    /// dropped: what a fixed arm puts down is `ON_HIGH_SURFACE` only when the place it
    /// puts it is high, not always (`docs/semantics-notes.md`).
    Geometric,
}

/// Where an imported task came from, kept so that export gives back the original fields.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Source {
    /// Always `coherent-original` for now.
    pub format: String,
    /// The file name it was read from.
    pub file: String,
    /// The task's position in that file's list.
    pub index: usize,
    /// The original `env_id` field, kept verbatim (it is unreliable: the scene comes
    /// from the file name).
    pub env_id: serde_json::Value,
}

/// A robot of the team.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Robot {
    pub node: Idx,
    pub kind: RobotKind,
}

/// Everything about a task that is not the graph, as read by a format.
#[derive(Clone, Debug, PartialEq)]
pub struct TaskMeta {
    pub scene: String,
    pub task_id: i64,
    pub name: String,
    pub instruction: String,
    pub gt_steps: Option<u32>,
    pub rules: RuleSet,
    /// Geometry for the physics (rooms, furniture, robot specs) and, under the geometric
    /// rules, for the height labels.
    pub geometry: Option<crate::geometry::Layout>,
    pub source: Option<Source>,
}

/// The most steps a task's ground truth may claim. A ground truth is the length of a
/// plan someone wrote down (4 to 16 steps on the released benchmark and on the
/// project's own), and the step budget of an episode is twice it, each step a round of
/// model calls: 10,000 steps is far beyond any task a team of three robots is given, and
/// keeps twice it (and the steps counted for a failed episode, twice it plus one) far
/// inside 32 bits. `coherent validate` flags a larger one, and no budget is sized from
/// it ([`TaskMeta::twice_ground_truth`]).
pub const MAX_GROUND_TRUTH: u32 = 10_000;

impl TaskMeta {
    /// The paper's step budget, twice the ground truth, when the task has one; an error
    /// when the ground truth is above [`MAX_GROUND_TRUTH`].
    pub fn twice_ground_truth(&self) -> Option<Result<u32, String>> {
        self.gt_steps.map(|gt| {
            if gt > MAX_GROUND_TRUTH {
                Err(format!(
                    "the ground truth of {gt} steps is more than any task needs (at most \
                     {MAX_GROUND_TRUTH}), so no budget of 2 x GT is sized from it: pass a step budget"
                ))
            } else {
                Ok(2 * gt)
            }
        })
    }
}

/// A goal predicate before ids are resolved, with where each id was read.
#[derive(Clone, Debug)]
pub(crate) struct RawPredicate<'a> {
    pub relation: Relation,
    pub subject: (i64, Site<'a>),
    pub target: (i64, Site<'a>),
    pub count: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    pub meta: TaskMeta,
    pub nodes: Vec<Node>,
    pub vocab: Vocabulary,
    pub goal: Vec<GoalPredicate>,
    pub robots: Vec<Robot>,
    /// The state at the start.
    pub init: State,
    /// Initial edges in file order. The order matters to one rule: grabbing removes the
    /// object's *first* ON/INSIDE edge.
    pub init_edges: Vec<Edge>,
    /// What happens mid-task that the team does not do (docs/dynamic.md); none in the
    /// paper's tasks.
    pub events: Vec<Event>,
    index: FxHashMap<NodeId, Idx>,
    /// `(door, room)` for every `LEADING TO` edge of the initial graph.
    doors: Vec<(Idx, Idx)>,
    /// Each room's floor (a `Floor` node `INSIDE` it), if it has one.
    floors: FxHashMap<Idx, Idx>,
    /// Each quadrotor's basket (target of its `WITH` edge), if it has one.
    /// `(quadrotor, basket)`: a list, as a team has one or two quadrotors and the rules
    /// look a basket up for every robot in view.
    baskets: Vec<(Idx, Idx)>,
    rooms: Vec<Idx>,
    /// The rooms, as a set: every robot sees them all.
    room_set: NodeSet,
    /// The `LANDABLE` nodes.
    landable_set: NodeSet,
    /// The robots.
    robot_set: NodeSet,

    /// What a robot dog never walks up to whatever the state: rooms, robots, floors and
    /// `HIGH_HEIGHT` things (`unreached` of docs/semantics.md, "Actions").
    never_approached: NodeSet,
}

// Events (docs/dynamic.md): the types a task holds; reading them is `crate::events`, running
// them `crate::schedule`.

/// When an event happens.
#[derive(Clone, Debug, PartialEq)]
pub enum Trigger {
    /// Before step `n` (from 1) is taken.
    Step(u32),
    /// Before the first step at which some robot holds the thing.
    Held(Idx),
    /// Before the first step at which the predicate holds.
    Holds(GoalPredicate),
}

/// What an event does.
#[derive(Clone, Debug, PartialEq)]
pub enum Happening {
    /// The robot stops for good where it stands, holding what it holds.
    RobotDown { robot: Idx },
    /// The robot, out of the team until now, joins it: where the task placed it, or
    /// (a dog or a quadrotor) in `room`.
    RobotUp { robot: Idx, room: Option<Idx> },
    /// Someone outside the team puts `thing` on or into `target`.
    ObjectMoved {
        thing: Idx,
        relation: Relation,
        target: Idx,
    },
    /// Goal predicates removed and added, with the instruction's new wording.
    GoalChanged {
        add: Vec<GoalPredicate>,
        remove: Vec<GoalPredicate>,
        instruction: String,
    },
    /// A door (or every door of a room) is locked: no robot passes it, for `steps`
    /// steps or for good.
    Blocked {
        what: Idx,
        doors: Vec<Idx>,
        steps: Option<u32>,
    },
    /// Each action chosen (of `robot`, or of anyone) fails with `probability`, for
    /// `steps` steps or for good: nothing changes and the robot is told.
    ActionFails {
        probability: f64,
        robot: Option<Idx>,
        steps: Option<u32>,
    },
}

impl Happening {
    /// The kind's name, as task files write it.
    pub fn kind(&self) -> &'static str {
        match self {
            Happening::RobotDown { .. } => "robot_down",
            Happening::RobotUp { .. } => "robot_up",
            Happening::ObjectMoved { .. } => "object_moved",
            Happening::GoalChanged { .. } => "goal_changed",
            Happening::Blocked { .. } => "blocked",
            Happening::ActionFails { .. } => "action_fails",
        }
    }
}

/// One event of a task.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    pub trigger: Trigger,
    pub happening: Happening,
}

/// What the rules look up from the initial edges: the doors (`LEADING_TO`), each room's
/// floor (the first `Floor` `INSIDE` it) and each quadrotor's basket (its first `WITH`).
type Links = (Vec<(Idx, Idx)>, FxHashMap<Idx, Idx>, Vec<(Idx, Idx)>);

fn links(nodes: &[Node], edges: &[Edge]) -> Links {
    let (mut doors, mut floors, mut baskets) = (Vec::new(), FxHashMap::default(), Vec::new());
    let kind = |n: Idx| nodes[n.get()].kind;
    for e in edges {
        match e.rel() {
            Relation::LeadingTo => doors.push((e.from(), e.to())),
            Relation::Inside
                if kind(e.from()) == NodeKind::Floor && kind(e.to()) == NodeKind::Room =>
            {
                floors.entry(e.to()).or_insert(e.from());
            }
            Relation::With if !baskets.iter().any(|&(q, _)| q == e.from()) => {
                baskets.push((e.from(), e.to()));
            }
            _ => {}
        }
    }
    (doors, floors, baskets)
}

impl Task {
    /// Builds a task from a graph as written in a file; `site` is where the graph was read.
    pub(crate) fn build(
        meta: TaskMeta,
        graph: &RawGraph,
        goal: &[RawPredicate<'_>],
        site: &Site<'_>,
    ) -> Result<Task> {
        let nodes_site = site.key("nodes");
        ensure!(
            graph.nodes.len() <= MAX_NODES,
            nodes_site,
            "{} nodes: at most {MAX_NODES} are supported",
            graph.nodes.len()
        );
        let mut vocab = Vocabulary::default();
        let mut index = FxHashMap::default();
        let mut nodes = Vec::with_capacity(graph.nodes.len());
        let mut states = Vec::with_capacity(graph.nodes.len());
        let mut high = Vec::with_capacity(graph.nodes.len());
        for (i, raw) in graph.nodes.iter().enumerate() {
            let at = nodes_site.index(i);
            if let Some(first) = index.insert(NodeId(raw.id), Idx(i as u16)) {
                return Err(at.key("id").error(format!(
                    "duplicate node id {} (also the id of nodes[{}], {}; this one is {})",
                    raw.id,
                    first.0,
                    quoted(&graph.nodes[first.get()].class_name),
                    quoted(&raw.class_name)
                )));
            }
            let kind = node_kind(raw, &at)?;
            let properties = intern_names(
                &raw.properties,
                &at.key("properties"),
                "property",
                64 - PropSet::KNOWN.len(),
                |n| vocab.property(n).map(|p| p.0),
            )
            .map(PropSet)?;
            let set = intern_names(
                &raw.states,
                &at.key("states"),
                "state",
                32 - StateSet::KNOWN.len(),
                |n| vocab.state(n).map(|p| u64::from(p.0)),
            )
            .map(|bits| StateSet(bits as u32))?;
            states.push(set);
            high.push(properties.contains(PropSet::ON_HIGH_SURFACE));
            nodes.push(Node {
                id: NodeId(raw.id),
                category: raw.category.clone(),
                class_name: raw.class_name.clone(),
                prefab_name: raw.prefab_name.clone(),
                kind,
                properties,
            });
        }

        let edges_site = site.key("edges");
        let resolve = |id: i64, at: Site<'_>| {
            index
                .get(&NodeId(id))
                .copied()
                .ok_or_else(|| at.error(format!("unknown node id {id}")))
        };
        let mut init_edges = Vec::with_capacity(graph.edges.len());
        for (i, raw) in graph.edges.iter().enumerate() {
            let at = edges_site.index(i);
            let from = resolve(raw.from_id, at.key("from_id"))?;
            let to = resolve(raw.to_id, at.key("to_id"))?;
            let rel = Relation::from_name(&raw.relation_type).ok_or_else(|| {
                at.key("relation_type").error(format!(
                    "unknown relation {} (known: {})",
                    quoted(&raw.relation_type),
                    Relation::ALL.map(Relation::name).join(", ")
                ))
            })?;
            init_edges.push(Edge::new(from, rel, to));
        }
        if let Some(cycle) = location_cycle(nodes.len(), &init_edges) {
            return Err(cycle_error(&nodes, &init_edges, &cycle, &edges_site));
        }
        let init = State::new(states, high, init_edges.clone());

        let mut predicates = Vec::with_capacity(goal.len());
        let resolve_goal = |(id, at): &(i64, Site<'_>)| {
            index.get(&NodeId(*id)).copied().ok_or_else(|| {
                at.error(format!(
                    "the goal names node {id}, which is not in the graph"
                ))
            })
        };
        for p in goal {
            predicates.push(GoalPredicate {
                relation: p.relation,
                subject: resolve_goal(&p.subject)?,
                target: resolve_goal(&p.target)?,
                count: p.count,
            });
        }

        let robots = nodes
            .iter()
            .enumerate()
            .filter_map(|(i, n)| match n.kind {
                NodeKind::Robot(kind) => Some(Robot {
                    node: Idx(i as u16),
                    kind,
                }),
                _ => None,
            })
            .collect();
        let rooms: Vec<Idx> = (0..nodes.len())
            .map(|i| Idx(i as u16))
            .filter(|&i| nodes[i.get()].kind == NodeKind::Room)
            .collect();
        let (doors, floors, baskets) = links(&nodes, &init_edges);
        let mut task = Task {
            meta,
            nodes,
            vocab,
            goal: predicates,
            robots,
            init,
            init_edges,
            events: Vec::new(),
            index,
            doors,
            floors,
            baskets,
            rooms,
            room_set: NodeSet::new(0),
            landable_set: NodeSet::new(0),
            robot_set: NodeSet::new(0),
            never_approached: NodeSet::new(0),
        };
        task.find_node_sets();
        Ok(task)
    }

    /// Finds the node sets the rules use ([`Task::room_set`], [`Task::robot_set`],
    /// [`Task::landable_set`], [`Task::never_approached`]) from the nodes; again after
    /// their properties change (the geometric rules derive heights).
    pub(crate) fn find_node_sets(&mut self) {
        let n = self.nodes.len();
        let (mut rooms, mut landable, mut never) =
            (NodeSet::new(n), NodeSet::new(n), NodeSet::new(n));
        let mut robots = NodeSet::new(n);
        for (i, node) in self.nodes.iter().enumerate() {
            let i = Idx(i as u16);
            if matches!(node.kind, NodeKind::Robot(_)) {
                robots.insert(i);
            }
            if node.kind == NodeKind::Room {
                rooms.insert(i);
            }
            if node.properties.contains(PropSet::LANDABLE) {
                landable.insert(i);
            }
            if matches!(
                node.kind,
                NodeKind::Room | NodeKind::Robot(_) | NodeKind::Floor
            ) || node.properties.contains(PropSet::HIGH_HEIGHT)
            {
                never.insert(i);
            }
        }
        self.room_set = rooms;
        self.landable_set = landable;
        self.never_approached = never;
        self.robot_set = robots;
    }

    /// Every node's index, in file order.
    pub fn indices(&self) -> impl Iterator<Item = Idx> + use<> {
        (0..self.nodes.len() as u16).map(Idx)
    }

    pub fn node(&self, n: Idx) -> &Node {
        &self.nodes[n.get()]
    }

    /// The dense index of the node with file id `id`.
    pub fn idx(&self, id: NodeId) -> Option<Idx> {
        self.index.get(&id).copied()
    }

    pub fn id(&self, n: Idx) -> NodeId {
        self.nodes[n.get()].id
    }

    pub fn robot(&self, n: Idx) -> Option<&Robot> {
        self.robots.iter().find(|r| r.node == n)
    }

    /// The robot with file id `id`, or an error naming the robots there are.
    pub fn robot_by_id(&self, id: NodeId) -> Result<Robot> {
        self.idx(id)
            .and_then(|i| self.robot(i))
            .copied()
            .ok_or_else(|| {
                let known: Vec<String> = self
                    .robots
                    .iter()
                    .map(|r| format!("{} ({})", self.id(r.node), r.kind))
                    .collect();
                crate::Error::UnknownRobot(format!(
                    "{id} is not a robot of task {}/{}; its robots are {}",
                    self.meta.scene,
                    self.meta.task_id,
                    known.join(", ")
                ))
            })
    }

    /// The task as events have left it (docs/dynamic.md): `team` acts (the other robots
    /// stay where they are, as things), `goal` is the goal with `instruction` its wording,
    /// and the doors `locked` join nothing. A world that carries events out elsewhere
    /// (robots over ROS 2) makes the same variant of its own task with it.
    pub fn vary(
        &self,
        team: Vec<Robot>,
        goal: Vec<GoalPredicate>,
        instruction: &str,
        locked: &[Idx],
    ) -> Task {
        let mut task = self.clone();
        task.robots = team;
        task.goal = goal;
        instruction.clone_into(&mut task.meta.instruction);
        task.doors.retain(|(d, _)| !locked.contains(d));
        task
    }

    /// `(door, room)` pairs of the initial graph's `LEADING TO` edges (a door locked by
    /// an event has none).
    pub fn doors(&self) -> &[(Idx, Idx)] {
        &self.doors
    }

    pub fn rooms(&self) -> &[Idx] {
        &self.rooms
    }

    /// [`Task::rooms`] as a set.
    pub(crate) fn room_set(&self) -> &NodeSet {
        &self.room_set
    }

    /// The robots of the graph, as a set (in the team or not).
    pub(crate) fn robot_set(&self) -> &NodeSet {
        &self.robot_set
    }

    /// The `LANDABLE` nodes, as a set.
    pub(crate) fn landable_set(&self) -> &NodeSet {
        &self.landable_set
    }

    /// What a robot dog never walks up to: rooms, robots, floors, `HIGH_HEIGHT` things.
    pub(crate) fn never_approached(&self) -> &NodeSet {
        &self.never_approached
    }

    pub fn floor_of(&self, room: Idx) -> Option<Idx> {
        self.floors.get(&room).copied()
    }

    pub fn basket_of(&self, quadrotor: Idx) -> Option<Idx> {
        self.baskets
            .iter()
            .find(|(q, _)| *q == quadrotor)
            .map(|(_, b)| *b)
    }

    /// Whether `n` has property `p` in state `s` (`ON_HIGH_SURFACE` is dynamic).
    pub fn has(&self, s: &State, n: Idx, p: PropSet) -> bool {
        if p == PropSet::ON_HIGH_SURFACE {
            s.on_high_surface(n)
        } else {
            self.nodes[n.get()].properties.contains(p)
        }
    }

    /// The node's current properties, `ON_HIGH_SURFACE` included when it holds.
    pub fn properties(&self, s: &State, n: Idx) -> PropSet {
        let p = self.nodes[n.get()]
            .properties
            .without(PropSet::ON_HIGH_SURFACE);
        if s.on_high_surface(n) {
            p | PropSet::ON_HIGH_SURFACE
        } else {
            p
        }
    }

    /// The goal test of docs/semantics.md, "Goals": for every predicate, the number of
    /// matching edges equals its count (edges form a set, so that number is 0 or 1).
    pub fn goal_satisfied(&self, s: &State) -> bool {
        self.goal.iter().all(|p| predicate_holds(s, p))
    }

    /// A predicate in the original format's notation, `on_<apple>(3)_<table>(5)`.
    pub fn predicate_label(&self, p: &GoalPredicate) -> String {
        let rel = match p.relation {
            Relation::Inside => "inside",
            _ => "on",
        };
        format!(
            "{rel}_{}_{}",
            self.node(p.subject).label(),
            self.node(p.target).label()
        )
    }

    /// The graph of state `s` in the original format's field names.
    pub fn raw_graph(&self, s: &State) -> RawGraph {
        let all: Vec<Idx> = self.indices().collect();
        self.raw_subgraph(s, &all, s.edges())
    }

    /// Nodes `nodes` (with their properties and states in `s`) and `edges`, in the
    /// original format's field names: how observations and exports are written.
    pub fn raw_subgraph(&self, s: &State, nodes: &[Idx], edges: &[Edge]) -> RawGraph {
        let nodes = nodes
            .iter()
            .map(|&i| {
                let n = self.node(i);
                RawNode {
                    id: n.id.0,
                    category: n.category.clone(),
                    class_name: n.class_name.clone(),
                    prefab_name: n.prefab_name.clone(),
                    properties: self.vocab.property_names(self.properties(s, i)),
                    states: self.vocab.state_names(s.states(i)),
                }
            })
            .collect();
        let edges = edges
            .iter()
            .map(|e| RawEdge {
                from_id: self.id(e.from()).0,
                to_id: self.id(e.to()).0,
                relation_type: e.rel().name().to_owned(),
            })
            .collect();
        RawGraph { nodes, edges }
    }

    /// The initial graph as read, edges in file order: what both exporters write.
    pub fn initial_raw_graph(&self) -> RawGraph {
        let all: Vec<Idx> = self.indices().collect();
        self.raw_subgraph(&self.init, &all, &self.init_edges)
    }
}

/// The edges of a cycle of `ON` and `INSIDE` edges among `edges` (their indices, each
/// edge's target the next one's source, the last one's the first one's), if there is
/// one: a thing on or in itself, through others. Depth first, without recursion (a chain
/// may be as deep as the nodes are many).
fn location_cycle(nodes: usize, edges: &[Edge]) -> Option<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = vec![Vec::new(); nodes];
    for (i, e) in edges.iter().enumerate() {
        if e.rel().is_location() {
            out[e.from().get()].push(i);
        }
    }
    // Where each node on the current path was entered, in `path`'s edges; done ones.
    let mut entered: Vec<Option<usize>> = vec![None; nodes];
    let mut done = vec![false; nodes];
    for root in 0..nodes {
        if done[root] {
            continue;
        }
        // The nodes being walked, each with the next of its edges to follow, and the
        // edges that led to them.
        let mut stack: Vec<(usize, usize)> = vec![(root, 0)];
        let mut path: Vec<usize> = Vec::new();
        entered[root] = Some(0);
        while let Some(&mut (n, ref mut next)) = stack.last_mut() {
            let Some(&i) = out[n].get(*next) else {
                stack.pop();
                path.pop();
                entered[n] = None;
                done[n] = true;
                continue;
            };
            *next += 1;
            let to = edges[i].to().get();
            if let Some(at) = entered[to] {
                let mut cycle = path[at..].to_vec();
                cycle.push(i);
                return Some(cycle);
            }
            if !done[to] {
                path.push(i);
                entered[to] = Some(path.len());
                stack.push((to, 0));
            }
        }
    }
    None
}

/// The most edges of a cycle an error spells out.
const CYCLE_SHOWN: usize = 16;

/// The error for `cycle` ([`location_cycle`]), at the edge that closes it, with each of
/// its edges and where the file has it.
fn cycle_error(nodes: &[Node], edges: &[Edge], cycle: &[usize], at: &Site<'_>) -> Error {
    let shown: Vec<String> = cycle
        .iter()
        .take(CYCLE_SHOWN)
        .map(|&i| {
            let e = edges[i];
            format!(
                "{} {} {} ({})",
                nodes[e.from().get()].short_label(),
                e.rel().name(),
                nodes[e.to().get()].short_label(),
                at.index(i).path
            )
        })
        .collect();
    let more = match cycle.len().checked_sub(CYCLE_SHOWN) {
        Some(more) if more > 0 => format!(", and {more} more edges"),
        _ => String::new(),
    };
    let last = *cycle.last().expect("a cycle has an edge");
    at.index(last).error(format!(
        "a cycle of ON and INSIDE edges, each thing on or in the next and the last on or \
         in the first: {}{more}; nothing can be on or in itself (a robot would carry a \
         thing along inside what it holds, and no layout can place it)",
        shown.join(", ")
    ))
}

/// The bit set of `names`, each interned by `intern`; `None` from it means more than
/// `limit` unknown names.
fn intern_names(
    names: &[String],
    site: &Site<'_>,
    what: &str,
    limit: usize,
    mut intern: impl FnMut(&str) -> Option<u64>,
) -> Result<u64> {
    let mut bits = 0;
    for (j, name) in names.iter().enumerate() {
        bits |= intern(name).ok_or_else(|| {
            site.index(j).error(format!(
                "{what} {}: too many distinct unknown {what} names (at most {limit})",
                quoted(name)
            ))
        })?;
    }
    Ok(bits)
}

/// Whether `p` holds in `s`: its edge is there as many times as it asks (0 or 1).
pub fn predicate_holds(s: &State, p: &GoalPredicate) -> bool {
    u32::from(s.has(Edge::new(p.subject, p.relation, p.target))) == p.count
}

fn node_kind(raw: &RawNode, at: &Site<'_>) -> Result<NodeKind> {
    Ok(match raw.category.as_str() {
        "Rooms" => NodeKind::Room,
        "Floor" => NodeKind::Floor,
        "Doors" | "Door" => NodeKind::Door,
        "AgentTool" => NodeKind::Tool,
        "Agents" => {
            NodeKind::Robot(RobotKind::from_class_name(&raw.class_name).ok_or_else(|| {
                at.key("class_name").error(format!(
                    "unknown robot class {} (known: {})",
                    quoted(&raw.class_name),
                    RobotKind::ALL.map(RobotKind::class_name).join(", ")
                ))
            })?)
        }
        _ => NodeKind::Object,
    })
}
