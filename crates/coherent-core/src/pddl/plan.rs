//! Plans in PDDL: the rules' actions written as the domain's actions, and a PDDL plan
//! (a planner's output: one `(action args...)` a line, `;` comments) read back and
//! played through the rules.

use std::path::Path;

use crate::action::{Action, Verb};
use crate::error::{Error, Result};
use crate::feasibility;
use crate::files::{self, Limit, MIB};
use crate::graph::{Idx, NodeKind, RobotKind, State};
use crate::pddl::domain::{MAX_VIA, arm_schema};
use crate::pddl::names::Names;
use crate::planner::Step;
use crate::rules;
use crate::task::{Robot, Task};

/// The schema of the domain that carries out `verb` for a robot of `kind`; a
/// `movetowards` to a room has its own.
fn schema(kind: RobotKind, verb: Verb, to_room: bool) -> String {
    let who = match kind {
        RobotKind::Quadrotor => "quadrotor",
        RobotKind::RobotDog => "dog",
        RobotKind::RobotArm => "arm",
    };
    let room = if to_room { "-room" } else { "" };
    format!("{who}-{}{room}", verb.name())
}

/// `robot`'s `action` in state `s` as a PDDL action: `(dog-grab robot-dog_23 apple_9)`.
/// A fixed arm's action also names the things between what it acts on and its surface
/// (`(arm-grab-via1 robot-arm_24 apple_9 plate_51)`).
pub fn action_text(task: &Task, names: &Names, s: &State, robot: Robot, action: Action) -> String {
    let to_room = task.node(action.object).kind == NodeKind::Room;
    let mut words = vec![names.of(robot.node), names.of(action.object)];
    if let Some(t) = action.target {
        words.push(names.of(t));
    }
    let name = if robot.kind == RobotKind::RobotArm {
        let reached = action.target.unwrap_or(action.object);
        let via = arm_chain(s, robot.node, reached);
        words.extend(via.iter().map(|&c| names.of(c)));
        arm_schema(action.verb.name(), via.len())
    } else {
        schema(robot.kind, action.verb, to_room)
    };
    format!("({name} {})", words.join(" "))
}

/// The things between `x` and the surface `arm` stands on, going down from `x`: none
/// when `x` stands on it (or is it).
fn arm_chain(s: &State, arm: Idx, x: Idx) -> Vec<Idx> {
    let base = s.targets(arm, crate::vocab::Relation::On).next();
    let mut via = Vec::new();
    let mut at = x;
    while Some(at) != base && via.len() <= MAX_VIA {
        let Some(p) = s
            .out(at)
            .iter()
            .find(|e| e.rel().is_location())
            .map(|e| e.to())
        else {
            break;
        };
        if Some(p) != base {
            via.push(p);
        }
        at = p;
    }
    via
}

/// A plan of the rules as a PDDL plan file: one action a line, and its cost. The plan
/// is played from the task's initial state, as an arm's action names what lies between
/// it and its surface then.
pub fn plan_text(task: &Task, steps: &[Step]) -> String {
    let names = Names::of_task(task);
    let mut state = task.init.clone();
    let mut text = String::new();
    for step in steps {
        if let Some(&robot) = task.robot(step.robot) {
            text.push_str(&action_text(task, &names, &state, robot, step.action));
            text.push('\n');
            rules::apply(task, &mut state, robot, step.action);
        }
    }
    text.push_str(&format!("; cost = {} (unit cost)\n", steps.len()));
    text
}

/// The most a PDDL plan file may hold: a plan of the released tasks takes under a
/// kilobyte, and a million actions fit.
pub const PLAN_FILE_LIMIT: Limit = Limit {
    bytes: 64 * MIB,
    what: "a plan file",
    raise: None,
};

/// The text of the PDDL plan file at `path`, read up to [`PLAN_FILE_LIMIT`].
pub fn read_plan_file(path: &Path) -> Result<String> {
    let bytes = files::read(path, &PLAN_FILE_LIMIT)?;
    String::from_utf8(bytes).map_err(|e| Error::Io {
        file: path.display().to_string(),
        message: format!("not UTF-8 text (at byte {})", e.utf8_error().valid_up_to()),
    })
}

/// What playing a PDDL plan through the rules showed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlanCheck {
    /// The plan's actions, as the rules write them, up to the first that failed.
    pub actions: Vec<String>,
    /// The plan's length: how many actions it has.
    pub length: usize,
    /// The first action that cannot be read or is not allowed (1-based line of the
    /// file, and why), if any.
    pub failure: Option<(usize, String)>,
    /// Whether the goal holds after the whole plan (false when an action failed).
    pub goal_reached: bool,
}

impl PlanCheck {
    /// Every action allowed in turn and the goal reached at the end.
    pub fn valid(&self) -> bool {
        self.failure.is_none() && self.goal_reached
    }
}

/// Plays the PDDL plan `text` from `task`'s initial state through the rules: each
/// action must be in its robot's list when its turn comes.
pub fn check_plan(task: &Task, text: &str) -> PlanCheck {
    let names = Names::of_task(task);
    let mut state = task.init.clone();
    let mut check = PlanCheck {
        actions: Vec::new(),
        length: 0,
        failure: None,
        goal_reached: false,
    };
    for (i, line) in text.lines().enumerate() {
        let line = line.split(';').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        check.length += 1;
        if check.failure.is_some() {
            continue;
        }
        let step = read_action(task, &names, line).and_then(|(robot, action)| {
            let text = action.render(task);
            feasibility::check(task, &state, robot, &text)
                .map(|a| (robot, a, text))
                .map_err(|why| format!("{line}: {why}"))
        });
        match step {
            Ok((robot, action, text)) => {
                rules::apply(task, &mut state, robot, action);
                check
                    .actions
                    .push(format!("{} {text}", task.id(robot.node)));
            }
            Err(why) => check.failure = Some((i + 1, why)),
        }
    }
    check.goal_reached = check.failure.is_none() && task.goal_satisfied(&state);
    check
}

/// One PDDL action, `(schema robot object [target])`, as the robot and the rules' action.
fn read_action(task: &Task, names: &Names, line: &str) -> Result<(Robot, Action), String> {
    let inner = line
        .strip_prefix('(')
        .and_then(|l| l.strip_suffix(')'))
        .ok_or_else(|| format!("{line}: an action is written (name arguments...)"))?;
    let words: Vec<&str> = inner.split_whitespace().collect();
    let node = |w: &str| {
        names
            .node(w)
            .ok_or_else(|| format!("{line}: no object of the task is named {w}"))
    };
    let [name, args @ ..] = words.as_slice() else {
        return Err(format!("{line}: an empty action"));
    };
    let robot_node = node(args.first().ok_or_else(|| format!("{line}: no robot"))?)?;
    let robot = *task
        .robot(robot_node)
        .ok_or_else(|| format!("{line}: {} is not a robot", args[0]))?;
    let (verb, to_room, via) = Verb::ALL
        .iter()
        .flat_map(|&v| (0..=MAX_VIA).flat_map(move |via| [(v, false, via), (v, true, via)]))
        .find(|&(v, room, via)| {
            let schema = if robot.kind == RobotKind::RobotArm {
                arm_schema(v.name(), via)
            } else if via == 0 {
                schema(robot.kind, v, room)
            } else {
                return false;
            };
            schema.eq_ignore_ascii_case(name)
        })
        .ok_or_else(|| {
            format!(
                "{line}: {name} is not an action of the domain for {}",
                task.node(robot_node).label()
            )
        })?;
    let wanted = if verb.preposition().is_some() { 3 } else { 2 } + via;
    if args.len() != wanted {
        return Err(format!(
            "{line}: {name} takes {wanted} arguments, not {}",
            args.len()
        ));
    }
    let object = node(args[1])?;
    if (task.node(object).kind == NodeKind::Room) != to_room {
        return Err(format!(
            "{line}: {} is {}a room",
            args[1],
            if to_room { "not " } else { "" }
        ));
    }
    let action = match args.get(2) {
        Some(t) => Action::with_target(verb, object, node(t)?),
        None => Action::new(verb, object),
    };
    Ok((robot, action))
}
