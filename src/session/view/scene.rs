//! The scene of a recorded episode, step by step: the pictures `coherent render` draws
//! (one per distinct state of the doors and lids), and after each round where every
//! robot is, the path it has come so far, and by the rules which room it is in, what
//! it is next to and what it holds or carries.
//!
//! Positions come from carrying the executed actions out in Rapier, as
//! `coherent render --transcript` does; what a robot is in, next to or holding comes
//! from the rules. When physics cannot follow the episode (a layout that cannot be
//! built, an action that fails physically), the robots stay drawn where physics left
//! them and the page says why; the rules still say where they are.

use std::collections::HashMap;
use std::sync::Arc;

use coherent_agents::transcript::Transcript;
use coherent_core::rules;
use coherent_core::text::shown;
use coherent_core::{
    Environment, Idx, NodeId, NodeKind, Relation, State, StateSet, SymbolicEnv, Task,
};
use coherent_sim::render::{Stage, robot_colour};
use coherent_sim::{PhysicalEnv, layout};
use serde::Serialize;

/// A robot as the page names and draws it.
#[derive(Debug, Serialize)]
pub struct RobotMark {
    pub id: i64,
    /// `<quadrotor>(11)`, as in the step lines.
    pub name: String,
    /// `quadrotor`, `robot dog` or `robot arm`.
    pub kind: &'static str,
    pub colour: &'static str,
}

/// A robot's whole path in picture coordinates; each frame says how much of it is
/// walked by then.
#[derive(Debug, Serialize)]
pub struct Track {
    pub id: i64,
    pub points: Vec<[f32; 2]>,
}

/// A robot at one moment.
#[derive(Debug, Serialize)]
pub struct RobotAt {
    pub id: i64,
    /// Where it is drawn, in picture coordinates (none without a picture).
    pub at: Option<[f32; 2]>,
    /// How many points of its track it has walked.
    pub walked: usize,
    /// The room it is in by the rules.
    pub room: Option<i64>,
    /// Where it is by the rules, in words: its room, what it stands on, hovers above
    /// or is next to.
    pub place: String,
    /// What it holds (a robot dog, an arm) or carries in its basket (a quadrotor).
    pub holds: Vec<String>,
}

/// The scene after a round (or at the start).
#[derive(Debug, Serialize)]
pub struct Moment {
    /// Which picture shows the doors and lids as they are.
    pub picture: usize,
    pub robots: Vec<RobotAt>,
    /// Simulated seconds the round's action took in physics.
    pub sim_seconds: Option<f64>,
}

/// The scene of an episode, start first, then one moment per round.
#[derive(Debug, Serialize)]
pub struct Scene {
    /// The pictures, as SVG; written into the page as markup, not as data.
    #[serde(skip)]
    pub pictures: Vec<String>,
    pub robots: Vec<RobotMark>,
    pub tracks: Vec<Track>,
    pub moments: Vec<Moment>,
    /// Why the robots stop moving in the picture from some round on, or why there is no
    /// picture.
    pub warning: Option<String>,
}

/// The scene of `t`, an episode of `task`, its pictures' ids prefixed with `ids`.
pub fn follow(task: &Arc<Task>, t: &Transcript, ids: &str) -> Scene {
    let robots = task
        .robots
        .iter()
        .map(|r| RobotMark {
            id: task.id(r.node).0,
            name: shown(&task.node(r.node).label()).into_owned(),
            kind: r.kind.class_name(),
            colour: robot_colour(r.kind),
        })
        .collect();
    let mut rules = SymbolicEnv::new(Arc::clone(task));
    let layout = match layout::for_task(task) {
        Ok(layout) => layout,
        Err(e) => {
            let mut moments = vec![moment(task, rules.state(), 0, None, None)];
            for round in &t.rounds {
                for (robot, action) in round.carried_out() {
                    let _ = rules.step(robot, action);
                }
                moments.push(moment(task, rules.state(), 0, None, None));
            }
            return Scene {
                pictures: Vec::new(),
                robots,
                tracks: Vec::new(),
                moments,
                warning: Some(format!("no picture: layout: {}", shown(&e.0))),
            };
        }
    };
    let stage = Stage::new(task, &layout);
    let mut drawn = Drawn::start(&stage, task);
    let mut physics = match PhysicalEnv::with_layout(Arc::clone(task), layout.clone()) {
        Ok(env) => Ok(env),
        Err(e) => Err(format!(
            "the robots are drawn at their start: physics: {}",
            shown(&e.message)
        )),
    };
    let mut pictures = Pictures::default();
    let first = pictures.of(&stage, rules.state(), ids);
    let mut moments = vec![moment(task, rules.state(), first, Some(&drawn), None)];
    for round in &t.rounds {
        let actions = round.carried_out();
        for &(robot, action) in &actions {
            let _ = rules.step(robot, action);
        }
        let mut sim_seconds = None;
        if let Ok(env) = &mut physics {
            match in_physics(env, &actions, !round.parts.is_empty()) {
                Ok(seconds) => {
                    sim_seconds = seconds;
                    drawn.update(&stage, env);
                }
                Err(why) => {
                    drawn.finish(&stage, env);
                    physics = Err(format!(
                        "from round {} on, the robots are drawn where physics left them: {}",
                        round.step,
                        shown(&why)
                    ));
                }
            }
        }
        let picture = pictures.of(&stage, rules.state(), ids);
        moments.push(moment(
            task,
            rules.state(),
            picture,
            Some(&drawn),
            sim_seconds,
        ));
    }
    if let Ok(env) = &physics {
        drawn.finish(&stage, env);
    }
    Scene {
        pictures: pictures.svgs,
        robots,
        tracks: drawn.tracks,
        moments,
        warning: physics.err(),
    }
}

/// Carries a round's executed actions out in physics: a joint step's together (its
/// robots moving at once, as long as the slowest), a sequential round's one action
/// alone; its simulated seconds (none when nothing was carried out), or why physics
/// could not.
fn in_physics(
    env: &mut PhysicalEnv,
    actions: &[(NodeId, &str)],
    joint: bool,
) -> Result<Option<f64>, String> {
    match actions {
        [] => Ok(None),
        [(robot, action)] if !joint => match env.step_physical(*robot, action) {
            Ok(Ok(report)) => Ok(Some(report.sim_seconds)),
            Ok(Err(why)) => Err(format!(
                "the rules refuse {} in physics: {why}",
                shown(action)
            )),
            Err(e) => Err(e.message),
        },
        _ => match env.step_joint_physical(actions) {
            Ok(Ok(report)) => Ok(Some(report.sim_seconds)),
            Ok(Err(why)) => Err(format!("the rules refuse the joint step in physics: {why}")),
            Err(e) => Err(e.message),
        },
    }
}

/// The pictures drawn so far, one per distinct state of the things that are drawn.
#[derive(Default)]
struct Pictures {
    svgs: Vec<String>,
    /// The states of every node but the robots (which the picture leaves to the page;
    /// the doors' and lids' are drawn), and their picture.
    seen: HashMap<Vec<StateSet>, usize>,
}

impl Pictures {
    fn of(&mut self, stage: &Stage<'_>, state: &State, ids: &str) -> usize {
        let task = stage.task();
        let key: Vec<StateSet> = task
            .indices()
            .filter(|&n| task.robot(n).is_none())
            .map(|n| state.states(n))
            .collect();
        let next = self.svgs.len();
        *self.seen.entry(key).or_insert_with(|| {
            self.svgs.push(stage.svg(state, ids));
            next
        })
    }
}

/// Where physics has the robots, in picture coordinates: each one's position, how much
/// of its track it has walked, and at the end the tracks.
struct Drawn {
    at: Vec<(NodeId, [f32; 2])>,
    walked: Vec<(NodeId, usize)>,
    tracks: Vec<Track>,
}

impl Drawn {
    fn start(stage: &Stage<'_>, task: &Task) -> Drawn {
        Drawn {
            at: task
                .robots
                .iter()
                .filter_map(|r| {
                    let id = task.id(r.node);
                    stage.start(id).map(|p| (id, rounded(stage.point(p))))
                })
                .collect(),
            walked: Vec::new(),
            tracks: Vec::new(),
        }
    }

    /// After a step carried out in `env`.
    fn update(&mut self, stage: &Stage<'_>, env: &PhysicalEnv) {
        let poses = env.world().poses();
        for (id, p) in &mut self.at {
            if let Some((_, pose)) = poses.iter().find(|(i, _)| i == id) {
                *p = rounded(stage.point([pose[0], pose[1], pose[2]]));
            }
        }
        self.walked = env
            .world()
            .paths
            .iter()
            .map(|(id, points)| (*id, points.len()))
            .collect();
    }

    /// The tracks as `env` has them when physics stops following the episode.
    fn finish(&mut self, stage: &Stage<'_>, env: &PhysicalEnv) {
        self.tracks = env
            .world()
            .paths
            .iter()
            .map(|(id, points)| Track {
                id: id.0,
                points: points.iter().map(|&p| rounded(stage.point(p))).collect(),
            })
            .collect();
    }

    fn at(&self, id: NodeId) -> Option<[f32; 2]> {
        self.at.iter().find(|(i, _)| *i == id).map(|(_, p)| *p)
    }

    /// Points of `id`'s track walked; its start is always drawn.
    fn walked(&self, id: NodeId) -> usize {
        self.walked
            .iter()
            .find(|(i, _)| *i == id)
            .map_or(1, |(_, n)| *n)
    }
}

/// A point to a tenth of a pixel: what the picture can show, and a smaller page.
fn rounded(p: [f32; 2]) -> [f32; 2] {
    p.map(|v| (v * 10.0).round() / 10.0)
}

/// The scene in state `s`, drawn in `picture`, the robots where `drawn` has them.
fn moment(
    task: &Task,
    s: &State,
    picture: usize,
    drawn: Option<&Drawn>,
    sim_seconds: Option<f64>,
) -> Moment {
    let robots = task
        .robots
        .iter()
        .map(|r| {
            let id = task.id(r.node);
            let room = rules::room_of(task, s, r.node);
            RobotAt {
                id: id.0,
                at: drawn.and_then(|d| d.at(id)),
                walked: drawn.map_or(1, |d| d.walked(id)),
                room: room.map(|n| task.id(n).0),
                place: place(task, s, r.node, room),
                holds: holds(task, s, r.node),
            }
        })
        .collect();
    Moment {
        picture,
        robots,
        sim_seconds,
    }
}

/// Where robot `n` is by the rules, in words.
fn place(task: &Task, s: &State, n: Idx, room: Option<Idx>) -> String {
    let label = |m: Idx| shown(&task.node(m).label()).into_owned();
    let mut parts = Vec::new();
    if let Some(room) = room {
        parts.push(format!("in {}", label(room)));
    }
    let not_room = |m: &Idx| task.node(*m).kind != NodeKind::Room;
    let on: Vec<String> = s
        .targets(n, Relation::On)
        .filter(not_room)
        .map(label)
        .collect();
    let above: Vec<String> = s.targets(n, Relation::Above).map(label).collect();
    let close: Vec<String> = s.targets(n, Relation::Close).map(label).collect();
    for (what, list) in [("on", on), ("above", above), ("next to", close)] {
        if !list.is_empty() {
            parts.push(format!("{what} {}", list.join(", ")));
        }
    }
    parts.join(", ")
}

/// What robot `n` holds, and what its basket carries.
fn holds(task: &Task, s: &State, n: Idx) -> Vec<String> {
    let label = |m: Idx| shown(&task.node(m).label()).into_owned();
    let mut out: Vec<String> = s.targets(n, Relation::Hold).map(label).collect();
    if let Some(basket) = task.basket_of(n) {
        let inside: Vec<String> = s.sources(Relation::Inside, basket).map(label).collect();
        if !inside.is_empty() {
            out.push(format!("{} with {}", label(basket), inside.join(", ")));
        }
    }
    out
}
