//! The two layouts of an observation hold the same facts: `describe::facts` (one block,
//! the paper's layout) and `describe::layered` (the scene's fixed facts, then what
//! changes) give the same set of facts for every robot's view and the team's, in every
//! state along the shortest plans and along random walks of all released tasks; and the
//! scene layer of what all robots could see never changes, whatever the robots do.

use std::collections::BTreeSet;

use coherent_core::describe::{self, Layers};
use coherent_core::planner::{self, Limits};
use coherent_core::rules::{self, Observation};
use coherent_core::{Idx, State, Task};

mod common;

/// A fact as the model reads it, whichever layout wrote it.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Fact {
    Room(String),
    /// A door and the rooms it joins, as written.
    Joins(String, String),
    /// A thing seen.
    Seen(String),
    /// A property or state word of a thing or a door.
    Word(String, String),
    Relation(String),
}

/// The facts of the paper's layout: `Rooms: ...`, `Door D joins A and B (STATES)`,
/// `- THING: WORDS` under `Things seen:`, `- REL(A, B)` under `Relations:`.
fn old_facts(text: &str) -> BTreeSet<Fact> {
    let mut out = BTreeSet::new();
    for line in text.lines() {
        if let Some(rooms) = line.strip_prefix("Rooms: ") {
            out.extend(rooms.split(", ").map(|r| Fact::Room(r.to_owned())));
        } else if let Some(door) = line.strip_prefix("Door ") {
            let (joins, states) = door.rsplit_once(" (").expect("a door's states");
            door_facts(&mut out, joins, states.trim_end_matches(')'));
        } else if let Some(item) = line.strip_prefix("- ") {
            thing_facts(&mut out, item);
        } else {
            assert!(["Things seen:", "Relations:"].contains(&line), "{line:?}");
        }
    }
    out
}

/// The facts of the layered layout: `Rooms: ...`, `- D joins A and B` (with `(STATES)`
/// when they never change) under `Doors:`, `- THING: WORDS`, `- REL(A, B)`.
fn new_facts(layers: &Layers) -> BTreeSet<Fact> {
    let mut out = BTreeSet::new();
    for line in layers.scene.lines().chain(layers.state.lines()) {
        if let Some(rooms) = line.strip_prefix("Rooms: ") {
            out.extend(rooms.split(", ").map(|r| Fact::Room(r.to_owned())));
        } else if let Some(item) = line.strip_prefix("- ") {
            if item.contains(" joins ") {
                let (joins, states) = item.split_once(" (").unwrap_or((item, ""));
                door_facts(&mut out, joins, states.trim_end_matches(')'));
            } else {
                thing_facts(&mut out, item);
            }
        } else {
            assert!(
                [
                    "Doors:",
                    "Things that stay in place:",
                    "Where they stand:",
                    "Things that move, and states that change:",
                    "Their relations now:",
                    "The robots now:"
                ]
                .contains(&line),
                "{line:?}"
            );
        }
    }
    // A door's state line (`- <door>(8): CLOSED`) names the door, which is no thing seen.
    let doors: Vec<String> = out
        .iter()
        .filter_map(|f| match f {
            Fact::Joins(d, _) => Some(d.clone()),
            _ => None,
        })
        .collect();
    out.retain(|f| !matches!(f, Fact::Seen(d) if doors.contains(d)));
    out
}

fn door_facts(out: &mut BTreeSet<Fact>, joins: &str, states: &str) {
    let (door, rooms) = joins.split_once(" joins ").expect("joins");
    out.insert(Fact::Joins(door.to_owned(), rooms.to_owned()));
    for s in states.split(", ").filter(|s| !s.is_empty()) {
        out.insert(Fact::Word(door.to_owned(), s.to_owned()));
    }
}

fn thing_facts(out: &mut BTreeSet<Fact>, item: &str) {
    if item.starts_with('<') {
        let (thing, words) = item.split_once(": ").unwrap_or((item, ""));
        out.insert(Fact::Seen(thing.to_owned()));
        for w in words.split(", ").filter(|w| !w.is_empty()) {
            out.insert(Fact::Word(thing.to_owned(), w.to_owned()));
        }
    } else {
        out.insert(Fact::Relation(item.to_owned()));
    }
}

/// Every robot's observation alone, and the team's.
fn views(task: &Task, s: &State) -> Vec<Vec<Observation>> {
    let each: Vec<Observation> = task
        .robots
        .iter()
        .map(|r| rules::observe(task, s, r.node))
        .collect();
    let mut views: Vec<Vec<Observation>> = each.iter().map(|o| vec![o.clone()]).collect();
    views.push(each);
    views
}

/// Asserts that both layouts of every view of `s` hold the same facts, and that the
/// layered one has each fact once.
fn same_facts(task: &Task, s: &State, context: &str) {
    for view in views(task, s) {
        let refs: Vec<&Observation> = view.iter().collect();
        let old = describe::facts(task, s, &refs);
        let layers = describe::layered(task, s, &refs);
        let (a, b) = (old_facts(&old), new_facts(&layers));
        assert_eq!(
            a,
            b,
            "{context}: the layouts differ\nonly in the paper's: {:?}\nonly in the layered: {:?}",
            a.difference(&b).collect::<Vec<_>>(),
            b.difference(&a).collect::<Vec<_>>()
        );
        let lines: Vec<&str> = layers
            .scene
            .lines()
            .chain(layers.state.lines())
            .filter(|l| l.contains("(<"))
            .collect();
        let unique: BTreeSet<&&str> = lines.iter().collect();
        assert_eq!(unique.len(), lines.len(), "{context}: a line twice");
    }
}

/// What every robot could see at once: all nodes, all relations.
fn everything(task: &Task, s: &State) -> Layers {
    let all = Observation {
        room: None,
        nodes: (0..task.nodes.len()).map(|i| Idx(i as u16)).collect(),
        edges: s.edges().to_vec(),
    };
    describe::layered(task, s, &[&all])
}

/// A small deterministic generator for the random walks (xorshift64*).
struct Walker(u64);

impl Walker {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 33) as usize % n
    }
}

/// Every state along each solvable task's shortest plan, then along random walks of
/// offered actions from the start (a robot with an empty list passes its turn).
fn states(task: &Task, walks: usize, steps: usize) -> Vec<State> {
    let mut out = vec![task.init.clone()];
    let search = planner::search(task, &task.robots, &task.goal, &Limits::max_states(20_000));
    if let Some(plan) = search.plan {
        let mut s = task.init.clone();
        for step in plan {
            let robot = *task.robot(step.robot).expect("a robot of the task");
            rules::apply(task, &mut s, robot, step.action);
            out.push(s.clone());
        }
    }
    let mut rng = Walker(0x9e37_79b9_7f4a_7c15 ^ task.meta.task_id as u64);
    for _ in 0..walks {
        let mut s = task.init.clone();
        for _ in 0..steps {
            let robot = task.robots[rng.below(task.robots.len())];
            let offered = rules::actions(task, &s, robot);
            if offered.is_empty() {
                continue;
            }
            rules::apply(task, &mut s, robot, offered[rng.below(offered.len())]);
            out.push(s.clone());
        }
    }
    out
}

#[test]
fn both_layouts_hold_the_same_facts_in_every_view() {
    let mut checked = 0;
    for task in common::released_tasks() {
        for (i, s) in states(&task, 4, 30).iter().enumerate() {
            same_facts(&task, s, &format!("{} state {i}", common::name(&task)));
            checked += 1;
        }
    }
    eprintln!("{checked} states checked");
    assert!(checked > 8_000, "{checked}");
}

#[test]
fn the_scene_layer_of_everything_never_changes() {
    for task in common::released_tasks() {
        let scene = everything(&task, &task.init).scene;
        for (i, s) in states(&task, 4, 30).iter().enumerate() {
            assert_eq!(
                everything(&task, s).scene,
                scene,
                "{} state {i}: the scene changed",
                common::name(&task)
            );
        }
    }
}
