//! The scene of a recorded episode, step by step: the pictures `coherent render` draws
//! (one per distinct state of the doors and lids), and after each round where every
//! robot is, the path it has come so far, and by the rules which room it is in, what
//! it is next to and what it holds or carries.
//!
//! The rules go first, through every round (and the task's events before the rounds
//! they came before): they give each round's state, and so what the page says of rooms,
//! holds and doors. Positions come from carrying the executed actions (and the events)
//! out in Rapier, as `coherent render --transcript` does, but a round is carried out only
//! once: a round that does again what an earlier one did (the same actions from the same
//! state, as an episode going round in circles does) is drawn as physics drew it the
//! first time, so that a long episode costs the rounds that are new, not all of them
//! (since the last event: the world is another after it). When physics
//! cannot follow the episode (a layout that cannot be built, an action that fails
//! physically), the robots stay drawn where physics left them and the page says why;
//! the rules still say where they are.

use std::collections::{HashMap, VecDeque};
use std::sync::Arc;

use coherent_agents::transcript::Transcript;
use coherent_core::rules;
use coherent_core::text::shown;
use coherent_core::{
    Environment, Idx, NodeId, NodeKind, Relation, Schedule, State, StateSet, SymbolicEnv, Task,
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

/// What a round carried out: each robot's action, in team order.
type Actions<'t> = Vec<(NodeId, &'t str)>;

/// The same, kept beyond the transcript.
type OwnedActions = Vec<(NodeId, String)>;

/// The episode by the rules: each distinct state once, and for the start and after each
/// round the number of its state, with what each round carried out.
struct ByRules<'t> {
    states: Vec<State>,
    /// The start's state, then each round's: indices into `states`.
    at: Vec<usize>,
    rounds: Vec<(Actions<'t>, bool)>,
    /// For each round, when events changed the world before it: the task as they left
    /// it and the number of the state they left.
    events: Vec<Option<(Arc<Task>, usize)>>,
}

impl<'t> ByRules<'t> {
    fn follow(task: &Arc<Task>, t: &'t Transcript) -> ByRules<'t> {
        let mut rules = SymbolicEnv::new(Arc::clone(task));
        let mut numbers: HashMap<State, usize> = HashMap::new();
        let mut by = ByRules {
            states: Vec::new(),
            at: Vec::with_capacity(t.rounds.len() + 1),
            rounds: Vec::with_capacity(t.rounds.len()),
            events: Vec::with_capacity(t.rounds.len()),
        };
        // The task's events, carried out before the rounds they came before, as the
        // episode did: a thing moved, a robot joined in a room, is where the rules say.
        let mut schedule = (!task.events.is_empty()).then(|| Schedule::new(Arc::clone(task)));
        if let Some(schedule) = &schedule {
            let _ = rules.befall(schedule.world(), rules.state().clone());
        }
        by.note(&mut numbers, rules.state());
        for round in &t.rounds {
            let mut changed = None;
            if let Some(schedule) = schedule.as_mut() {
                let mut state = rules.state().clone();
                if !schedule.before_step(round.step, &mut state).is_empty() {
                    let world = schedule.world();
                    let _ = rules.befall(Arc::clone(&world), state);
                    changed = Some((world, by.number(&mut numbers, rules.state())));
                }
            }
            by.events.push(changed);
            let actions = round.carried_out();
            for &(robot, action) in &actions {
                let _ = rules.step(robot, action);
            }
            by.rounds.push((actions, !round.parts.is_empty()));
            by.note(&mut numbers, rules.state());
        }
        by
    }

    fn note(&mut self, numbers: &mut HashMap<State, usize>, state: &State) {
        let k = self.number(numbers, state);
        self.at.push(k);
    }

    /// The number of `state`, a new one when it is new.
    fn number(&mut self, numbers: &mut HashMap<State, usize>, state: &State) -> usize {
        let next = self.states.len();
        let k = *numbers.entry(state.clone()).or_insert(next);
        if k == next {
            self.states.push(state.clone());
        }
        k
    }
}

/// The scene of `t`, an episode of `task`, its pictures' ids prefixed with `ids`;
/// `progress` is told how many rounds of how many are followed.
pub fn follow(
    task: &Arc<Task>,
    t: &Transcript,
    ids: &str,
    progress: &mut dyn FnMut(usize, usize),
) -> Scene {
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
    let by = ByRules::follow(task, t);
    let layout = match layout::for_task(task) {
        Ok(layout) => layout,
        Err(e) => {
            let moments = by
                .at
                .iter()
                .map(|&k| moment(task, &by.states[k], 0, None, None))
                .collect();
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
    let mut physics = Physics::start(task, &layout, &stage);
    let mut pictures = Pictures::default();
    let first = pictures.of(&stage, &by.states[by.at[0]], ids);
    let mut moments = vec![moment(
        task,
        &by.states[by.at[0]],
        first,
        Some(&physics.drawn),
        None,
    )];
    let total = by.rounds.len();
    for (k, ((actions, joint), round)) in by.rounds.iter().zip(&t.rounds).enumerate() {
        let (mut from, to) = (by.at[k], by.at[k + 1]);
        if let Some((world, after)) = &by.events[k] {
            physics.befall(&by, from, world, *after, round.step);
            from = *after;
        }
        let sim_seconds = physics.round(&by, from, to, actions, *joint, round.step);
        let state = &by.states[to];
        let picture = pictures.of(&stage, state, ids);
        moments.push(moment(
            task,
            state,
            picture,
            Some(&physics.drawn),
            sim_seconds,
        ));
        progress(k + 1, total);
    }
    Scene {
        pictures: pictures.svgs,
        robots,
        tracks: physics.drawn.tracks(),
        moments,
        warning: physics.stopped,
    }
}

/// How far apart, in pixels of the picture (56 to the metre), two positions of a robot
/// may be and still be the same place: a round done again from there is drawn as it
/// was done the first time.
const SAME_PLACE: f32 = 1.0;

/// What carrying a round out in physics did, kept to draw a round that does it again.
#[derive(Clone)]
struct Done {
    /// Where the robots were drawn when it started.
    from: Vec<(NodeId, [f32; 2])>,
    /// Where each robot that acted or walked is drawn after it, and the points its
    /// track gained.
    moved: Vec<(NodeId, [f32; 2], Vec<[f32; 2]>)>,
    sim_seconds: Option<f64>,
}

/// The episode in Rapier, each distinct round once.
struct Physics<'s> {
    stage: &'s Stage<'s>,
    env: Option<PhysicalEnv>,
    /// The state, by number, the physical world is in.
    world_at: usize,
    /// The rounds carried out so far: from a state, these actions, each time from
    /// another place (robots more than [`SAME_PLACE`] apart).
    done: HashMap<(usize, OwnedActions), Vec<Done>>,
    /// The same, as the ways out of each state: the actions and the state they lead to.
    ways: HashMap<usize, Vec<(OwnedActions, usize, bool)>>,
    drawn: Drawn,
    /// Why physics stopped following the episode.
    stopped: Option<String>,
}

impl<'s> Physics<'s> {
    fn start(task: &Arc<Task>, layout: &layout::Layout, stage: &'s Stage<'s>) -> Physics<'s> {
        let mut drawn = Drawn::start(stage, task);
        let (env, stopped) = match PhysicalEnv::with_layout(Arc::clone(task), layout.clone()) {
            Ok(env) => {
                drawn.tracks_from(stage, &env);
                (Some(env), None)
            }
            Err(e) => (
                None,
                Some(format!(
                    "the robots are drawn at their start: physics: {}",
                    shown(&e.message)
                )),
            ),
        };
        Physics {
            stage,
            env,
            world_at: 0,
            done: HashMap::new(),
            ways: HashMap::new(),
            drawn,
            stopped,
        }
    }

    /// Draws round `step`, which carried `actions` out from state `from` to state `to`:
    /// as an earlier round that did the same from the same place, or carried out in
    /// Rapier (the world first brought to `from` by rounds done before, if it is
    /// elsewhere). Its simulated seconds.
    fn round(
        &mut self,
        by: &ByRules<'_>,
        from: usize,
        to: usize,
        actions: &Actions<'_>,
        joint: bool,
        step: u32,
    ) -> Option<f64> {
        if actions.is_empty() || self.env.is_none() {
            return None;
        }
        let key = (from, owned(actions));
        let before = self.done.get(&key).into_iter().flatten();
        if let Some(done) = before
            .into_iter()
            .find(|d| self.drawn.near(&d.from))
            .cloned()
        {
            self.drawn.again(&done);
            return done.sim_seconds;
        }
        if self.world_at != from
            && let Err(why) = self.bring_to(by, from)
        {
            self.stop(step, &why);
            return None;
        }
        match self.carry_out(actions, joint) {
            Ok(done) => {
                self.world_at = to;
                let seconds = done.sim_seconds;
                let (from, actions) = key;
                let times = self.done.entry((from, actions.clone())).or_default();
                if times.is_empty() {
                    self.ways
                        .entry(from)
                        .or_default()
                        .push((actions, to, joint));
                }
                times.push(done);
                seconds
            }
            Err(why) => {
                self.stop(step, &why);
                None
            }
        }
    }

    /// Carries out in the world the events that came before round `step`: brought first
    /// to state `at`, where the episode was, then put where they left it, state `after`
    /// of the task as they left it (`world`). The rounds done before are not ways through
    /// the world from then on.
    fn befall(&mut self, by: &ByRules<'_>, at: usize, world: &Arc<Task>, after: usize, step: u32) {
        if self.env.is_none() {
            return;
        }
        if self.world_at != at
            && let Err(why) = self.bring_to(by, at)
        {
            self.stop(step, &why);
            return;
        }
        let Some(env) = self.env.as_mut() else {
            return;
        };
        match env.befall(Arc::clone(world), by.states[after].clone()) {
            Ok(()) => {
                self.world_at = after;
                self.done.clear();
                self.ways.clear();
            }
            Err(e) => self.stop(step, &Unfollowed(e.to_string())),
        }
    }

    /// Carries `actions` out in the world and draws every robot where it then is.
    fn carry_out(&mut self, actions: &[(NodeId, &str)], joint: bool) -> Result<Done, Unfollowed> {
        let env = self.env.as_mut().ok_or_else(Unfollowed::no_world)?;
        let before = self.drawn.lengths(env);
        let from = self.drawn.placed(self.stage, env);
        let sim_seconds = in_physics(env, actions, joint)?;
        let actors: Vec<NodeId> = actions.iter().map(|&(robot, _)| robot).collect();
        let moved = self.drawn.update(self.stage, env, &before, &actors);
        Ok(Done {
            from,
            moved,
            sim_seconds,
        })
    }

    /// Brings the world from where it is to state `to` by rounds carried out before (the
    /// fewest): the rules went there through rounds that were all done before, so there
    /// is such a way.
    fn bring_to(&mut self, by: &ByRules<'_>, to: usize) -> Result<(), Unfollowed> {
        let mut came: HashMap<usize, (usize, usize)> = HashMap::new();
        let mut queue = VecDeque::from([self.world_at]);
        while let Some(s) = queue.pop_front() {
            if s == to {
                break;
            }
            for (i, (_, next, _)) in self.ways.get(&s).into_iter().flatten().enumerate() {
                if *next != self.world_at && !came.contains_key(next) {
                    came.insert(*next, (s, i));
                    queue.push_back(*next);
                }
            }
        }
        let mut path = Vec::new();
        let mut at = to;
        while at != self.world_at {
            let &(s, i) = came.get(&at).ok_or_else(|| {
                Unfollowed(format!(
                    "no way back to a state of the episode ({} states known)",
                    by.states.len()
                ))
            })?;
            path.push((s, i));
            at = s;
        }
        for (s, i) in path.into_iter().rev() {
            let way = self.ways.get(&s).and_then(|ways| ways.get(i)).cloned();
            let (actions, next, joint) =
                way.ok_or_else(|| Unfollowed("a way back that is not there".into()))?;
            let borrowed: Vec<(NodeId, &str)> =
                actions.iter().map(|(r, a)| (*r, a.as_str())).collect();
            let env = self.env.as_mut().ok_or_else(Unfollowed::no_world)?;
            in_physics(env, &borrowed, joint)?;
            self.world_at = next;
        }
        Ok(())
    }

    fn stop(&mut self, step: u32, why: &Unfollowed) {
        self.env = None;
        self.stopped = Some(format!(
            "from round {step} on, the robots are drawn where physics left them: {}",
            shown(&why.0)
        ));
    }
}

/// Why physics cannot follow the episode any further, in words the page shows.
struct Unfollowed(String);

impl Unfollowed {
    /// Physics stopped following before.
    fn no_world() -> Unfollowed {
        Unfollowed("no physical world".into())
    }
}

fn owned(actions: &[(NodeId, &str)]) -> OwnedActions {
    actions.iter().map(|&(r, a)| (r, a.to_owned())).collect()
}

/// Carries a round's executed actions out in physics: a joint step's together (its
/// robots moving at once, as long as the slowest), a sequential round's one action
/// alone; its simulated seconds (none when nothing was carried out), or why physics
/// could not.
fn in_physics(
    env: &mut PhysicalEnv,
    actions: &[(NodeId, &str)],
    joint: bool,
) -> Result<Option<f64>, Unfollowed> {
    match actions {
        [] => Ok(None),
        [(robot, action)] if !joint => match env.step_physical(*robot, action) {
            Ok(Ok(report)) => Ok(Some(report.sim_seconds)),
            Ok(Err(why)) => Err(Unfollowed(format!(
                "the rules refuse {} in physics: {why}",
                shown(action)
            ))),
            Err(e) => Err(Unfollowed(e.message)),
        },
        _ => match env.step_joint_physical(actions) {
            Ok(Ok(report)) => Ok(Some(report.sim_seconds)),
            Ok(Err(why)) => Err(Unfollowed(format!(
                "the rules refuse the joint step in physics: {why}"
            ))),
            Err(e) => Err(Unfollowed(e.message)),
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

/// Where the robots are drawn, in picture coordinates: each one's position, and the
/// track of each mobile one so far.
struct Drawn {
    at: Vec<(NodeId, [f32; 2])>,
    tracks: Vec<(NodeId, Vec<[f32; 2]>)>,
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
            tracks: Vec::new(),
        }
    }

    /// The tracks as they start in `env`.
    fn tracks_from(&mut self, stage: &Stage<'_>, env: &PhysicalEnv) {
        self.tracks = env
            .world()
            .paths
            .iter()
            .map(|(id, points)| {
                (
                    *id,
                    points.iter().map(|&p| rounded(stage.point(p))).collect(),
                )
            })
            .collect();
    }

    /// How many points each robot's path in `env` has.
    fn lengths(&self, env: &PhysicalEnv) -> Vec<(NodeId, usize)> {
        env.world()
            .paths
            .iter()
            .map(|(id, points)| (*id, points.len()))
            .collect()
    }

    /// Where `env` has the robots, in picture coordinates.
    fn placed(&self, stage: &Stage<'_>, env: &PhysicalEnv) -> Vec<(NodeId, [f32; 2])> {
        let poses = env.world().poses();
        self.at
            .iter()
            .map(|&(id, at)| match poses.iter().find(|(i, _)| *i == id) {
                Some((_, pose)) => (id, rounded(stage.point([pose[0], pose[1], pose[2]]))),
                None => (id, at),
            })
            .collect()
    }

    /// Whether every robot is drawn within [`SAME_PLACE`] of where `then` had it.
    fn near(&self, then: &[(NodeId, [f32; 2])]) -> bool {
        self.at.iter().all(|(id, [x, y])| {
            then.iter()
                .find(|(i, _)| i == id)
                .is_some_and(|(_, [tx, ty])| (x - tx).hypot(y - ty) <= SAME_PLACE)
        })
    }

    /// After a step of `actors` carried out in `env` (its paths `before` it that long):
    /// every robot where it is, each track with the points walked; where the robots
    /// that acted or walked went, and the points their tracks gained.
    fn update(
        &mut self,
        stage: &Stage<'_>,
        env: &PhysicalEnv,
        before: &[(NodeId, usize)],
        actors: &[NodeId],
    ) -> Vec<(NodeId, [f32; 2], Vec<[f32; 2]>)> {
        self.at = self.placed(stage, env);
        let paths = &env.world().paths;
        let mut moved = Vec::new();
        for &(id, at) in &self.at {
            let added: Vec<[f32; 2]> = paths
                .iter()
                .find(|(i, _)| *i == id)
                .map(|(_, points)| {
                    let from = before.iter().find(|(i, _)| *i == id).map_or(0, |(_, n)| *n);
                    let new = points.get(from..).unwrap_or_default();
                    new.iter().map(|&p| rounded(stage.point(p))).collect()
                })
                .unwrap_or_default();
            if let Some((_, track)) = self.tracks.iter_mut().find(|(i, _)| *i == id) {
                track.extend_from_slice(&added);
            }
            if actors.contains(&id) || !added.is_empty() {
                moved.push((id, at, added));
            }
        }
        moved
    }

    /// A step done before, again: its robots where it left them, their tracks longer
    /// by the same walk.
    fn again(&mut self, done: &Done) {
        for (id, at, added) in &done.moved {
            if let Some((_, p)) = self.at.iter_mut().find(|(i, _)| i == id) {
                *p = *at;
            }
            if let Some((_, track)) = self.tracks.iter_mut().find(|(i, _)| i == id) {
                track.extend_from_slice(added);
            }
        }
    }

    fn tracks(self) -> Vec<Track> {
        self.tracks
            .into_iter()
            .map(|(id, points)| Track { id: id.0, points })
            .collect()
    }

    fn at(&self, id: NodeId) -> Option<[f32; 2]> {
        self.at.iter().find(|(i, _)| *i == id).map(|(_, p)| *p)
    }

    /// Points of `id`'s track walked; its start is always drawn.
    fn walked(&self, id: NodeId) -> usize {
        self.tracks
            .iter()
            .find(|(i, _)| *i == id)
            .map_or(1, |(_, points)| points.len())
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
