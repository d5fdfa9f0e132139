//! Property tests of the rules: random walks of offered actions over tasks of all four
//! scenes never break the world's invariants; `feasibility::check` accepts exactly the
//! offered actions and always says why it refuses; the action parser never panics and
//! round-trips what the rules render.

use std::sync::OnceLock;

use coherent_core::action::{self, Action, Verb};
use coherent_core::feasibility::{self, Reason};
use coherent_core::planner::{self, Limits};
use coherent_core::rules;
use coherent_core::{Idx, NodeKind, Relation, Robot, RobotKind, State, StateSet, Task, load};
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{FileFailurePersistence, TestCaseError};

mod common;

/// The well-formed tasks of env0..env3, by scene.
fn scenes() -> &'static [Vec<Task>] {
    static SCENES: OnceLock<Vec<Vec<Task>>> = OnceLock::new();
    SCENES.get_or_init(|| {
        (0..4)
            .map(|n| {
                let path = common::data_dir().join(format!("env{n}.json"));
                load::read_tasks(&path)
                    .expect("benchmark file loads")
                    .into_iter()
                    .filter_map(Result::ok)
                    .collect()
            })
            .collect()
    })
}

fn name(t: &Task) -> String {
    format!("{} task {}", t.meta.scene, t.meta.task_id)
}

fn is_location(rel: Relation) -> bool {
    matches!(rel, Relation::On | Relation::Inside)
}

fn locations(s: &State, n: Idx) -> usize {
    s.out(n).iter().filter(|e| is_location(e.rel())).count()
}

/// The invariants every reachable state keeps.
fn check_invariants(task: &Task, s: &State, context: &str) -> Result<(), TestCaseError> {
    let kind = |n: Idx| task.node(n).kind;
    let label = |n: Idx| task.node(n).label();
    let mut held_by: Vec<Option<Idx>> = vec![None; task.nodes.len()];
    for r in &task.robots {
        let holds: Vec<Idx> = s.targets(r.node, Relation::Hold).collect();
        prop_assert!(
            holds.len() <= 1,
            "{context}: {} holds {} things",
            label(r.node),
            holds.len()
        );
        prop_assert!(
            holds.is_empty() || r.kind != RobotKind::Quadrotor,
            "{context}: a quadrotor holds something"
        );
        for h in holds {
            prop_assert!(
                held_by[h.get()].is_none(),
                "{context}: {} is held by two robots",
                label(h)
            );
            held_by[h.get()] = Some(r.node);
        }
        // Exactly one room, and INSIDE nothing else.
        let inside: Vec<Idx> = s.targets(r.node, Relation::Inside).collect();
        prop_assert!(
            inside.len() == 1 && kind(inside[0]) == NodeKind::Room,
            "{context}: {} is INSIDE {:?}, not exactly one room",
            label(r.node),
            inside.iter().map(|&n| label(n)).collect::<Vec<_>>()
        );
        let on: Vec<Idx> = s.targets(r.node, Relation::On).collect();
        let above: Vec<Idx> = s.targets(r.node, Relation::Above).collect();
        match r.kind {
            RobotKind::RobotArm => {
                // A fixed arm never moves.
                prop_assert_eq!(
                    s.out(r.node)
                        .iter()
                        .filter(|e| is_location(e.rel()))
                        .count(),
                    2
                );
                let init_on: Vec<Idx> = task.init.targets(r.node, Relation::On).collect();
                prop_assert_eq!(&on, &init_on, "{}: {} moved", context, label(r.node));
                prop_assert!(above.is_empty());
            }
            RobotKind::RobotDog => {
                // The dog stands on the floor of its room.
                prop_assert!(
                    on.len() == 1 && Some(on[0]) == task.floor_of(inside[0]),
                    "{context}: {} is ON {:?} in {}",
                    label(r.node),
                    on.iter().map(|&n| label(n)).collect::<Vec<_>>(),
                    label(inside[0])
                );
                prop_assert!(above.is_empty());
            }
            RobotKind::Quadrotor => {
                let st = s.states(r.node);
                let landed = st.contains(StateSet::LAND);
                let flying = st.contains(StateSet::FLYING);
                prop_assert!(
                    landed != flying,
                    "{context}: {} is {st:?}, not exactly one of LAND and FLYING",
                    label(r.node)
                );
                if landed {
                    prop_assert!(
                        on.len() == 1 && above.is_empty(),
                        "{context}: a landed quadrotor is ON {} and ABOVE {} things",
                        on.len(),
                        above.len()
                    );
                } else {
                    prop_assert!(
                        on.is_empty() && above.len() <= 1,
                        "{context}: a flying quadrotor is ON {} and ABOVE {} things",
                        on.len(),
                        above.len()
                    );
                }
                // The basket rests where the quadrotor rests, and nowhere when it flies.
                if let Some(b) = task.basket_of(r.node) {
                    let basket_on: Vec<Idx> = s.targets(b, Relation::On).collect();
                    prop_assert_eq!(&basket_on, &on, "{}: basket and quadrotor apart", context);
                    prop_assert_eq!(s.targets(b, Relation::Inside).count(), 0);
                }
            }
        }
    }
    for e in s.edges() {
        let from = kind(e.from());
        let ok = match e.rel() {
            Relation::Close => from == NodeKind::Robot(RobotKind::RobotDog),
            Relation::Hold => matches!(
                from,
                NodeKind::Robot(RobotKind::RobotDog | RobotKind::RobotArm)
            ),
            Relation::Above => from == NodeKind::Robot(RobotKind::Quadrotor),
            _ => true,
        };
        prop_assert!(ok, "{context}: edge {e:?} from {}", label(e.from()));
    }
    for (i, holder) in held_by.iter().enumerate() {
        let n = Idx(i as u16);
        if matches!(kind(n), NodeKind::Robot(_)) {
            continue;
        }
        let now = locations(s, n);
        let at_start = locations(&task.init, n);
        prop_assert!(
            now <= at_start.max(1),
            "{context}: {} has {now} ON/INSIDE edges",
            label(n)
        );
        if holder.is_some() {
            prop_assert_eq!(now, 0, "{}: held {} still has a place", context, label(n));
        } else if at_start == 1 && kind(n) != NodeKind::Tool {
            // Nothing that had a place loses it without being held.
            prop_assert_eq!(now, 1, "{}: {} lost its place", context, label(n));
        }
    }
    Ok(())
}

/// No more actions are offered than `action::most_actions` allows, and each renders to
/// a string that parses back to it and that `feasibility::check` accepts as that very
/// action.
fn check_offered(
    task: &Task,
    s: &State,
    robot: Robot,
    offered: &[Action],
    context: &str,
) -> Result<(), TestCaseError> {
    prop_assert!(
        offered.len() <= action::most_actions(task, robot.kind),
        "{context}: {} offered {} actions, more than most_actions",
        robot.kind,
        offered.len()
    );
    for a in offered {
        prop_assert!(
            action::Verb::of(robot.kind).contains(&a.verb),
            "{context}: {} offered {:?}, not one of its verbs",
            robot.kind,
            a.verb
        );
        let text = a.render(task);
        let parsed = action::parse(&text).map_err(|e| {
            TestCaseError::fail(format!("{context}: offered {text:?} does not parse: {e}"))
        })?;
        prop_assert_eq!(parsed.verb, a.verb);
        prop_assert_eq!(parsed.object.id, task.id(a.object));
        prop_assert_eq!(&parsed.object.name, &task.node(a.object).class_name);
        prop_assert_eq!(
            parsed.target.as_ref().map(|m| m.id),
            a.target.map(|t| task.id(t))
        );
        prop_assert_eq!(
            parsed.target.as_ref().map(|m| m.name.clone()),
            a.target.map(|t| task.node(t).class_name.clone())
        );
        prop_assert_eq!(parsed.to_string(), text.clone());
        match feasibility::check(task, s, robot, &text) {
            Ok(b) => prop_assert_eq!(b, *a, "{}: {} resolves to another action", context, text),
            Err(e) => {
                return Err(TestCaseError::fail(format!(
                    "{context}: offered {text:?} refused ({:?}): {}",
                    e.reason, e.message
                )));
            }
        }
    }
    Ok(())
}

/// A candidate action string over the task's nodes and what check must say of it.
#[derive(Clone, Copy, Debug)]
enum Naming {
    /// The node's own class name.
    Right,
    /// Another name with the node's id.
    WrongName,
    /// An id that no node has.
    UnknownId,
}

fn mention(task: &Task, n: Idx, naming: Naming) -> String {
    let node = task.node(n);
    match naming {
        Naming::Right => node.label(),
        Naming::WrongName => format!("<{} x>({})", node.class_name, node.id),
        Naming::UnknownId => {
            let max = task.nodes.iter().map(|n| n.id.0).max().unwrap_or(0);
            format!("<{}>({})", node.class_name, max + 1000)
        }
    }
}

/// An action text to try, `[verb] object` or `[verb] object prep target`, with the
/// target (or the sole object) named as `naming` says.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    verb: Verb,
    object: Idx,
    target: Idx,
    naming: Naming,
}

/// Where candidates are checked: a state of a task, a robot, what the rules offer it
/// there, and the walk that led there for messages.
struct Checked<'a> {
    task: &'a Task,
    s: &'a State,
    robot: Robot,
    offered: &'a [Action],
    context: &'a str,
}

/// Checks one candidate for the robot: Ok iff offered, and when refused, a reason that
/// explains it.
fn check_candidate(at: &Checked, candidate: Candidate) -> Result<(), TestCaseError> {
    let Checked {
        task,
        s,
        robot,
        offered,
        context,
    } = *at;
    let Candidate {
        verb,
        object,
        target,
        naming,
    } = candidate;
    let text = match verb.preposition() {
        Some(prep) => format!(
            "[{verb}] {} {prep} {}",
            mention(task, object, Naming::Right),
            mention(task, target, naming)
        ),
        None => format!("[{verb}] {}", mention(task, object, naming)),
    };
    let wanted = Action {
        verb,
        object,
        target: verb.preposition().map(|_| target),
    };
    let result = feasibility::check(task, s, robot, &text);
    let own_verb = Verb::of(robot.kind).contains(&verb);
    match &result {
        Ok(a) => {
            prop_assert!(
                own_verb && matches!(naming, Naming::Right),
                "{context}: {text:?} accepted for {}",
                robot.kind
            );
            prop_assert_eq!(
                *a,
                wanted,
                "{}: {} resolved to another action",
                context,
                text
            );
            prop_assert!(
                offered.contains(a),
                "{context}: {text:?} accepted but not offered"
            );
        }
        Err(e) => {
            prop_assert!(
                e.reason != Reason::NotOffered,
                "{context}: {text:?} refused without a reason: {}",
                e.message
            );
            prop_assert!(!e.message.is_empty());
            let expected = if !own_verb {
                Some(Reason::WrongRobotType)
            } else if !matches!(naming, Naming::Right) {
                Some(Reason::NoSuchNode)
            } else {
                None
            };
            match expected {
                Some(r) => prop_assert_eq!(e.reason, r, "{}: {}: {}", context, text, e.message),
                None => {
                    prop_assert!(
                        !offered.contains(&wanted),
                        "{context}: {text:?} is offered but refused ({:?}): {}",
                        e.reason,
                        e.message
                    );
                    prop_assert!(
                        !matches!(
                            e.reason,
                            Reason::Unparsable | Reason::NoSuchNode | Reason::WrongRobotType
                        ),
                        "{context}: {text:?}: {:?}: {}",
                        e.reason,
                        e.message
                    );
                }
            }
        }
    }
    Ok(())
}

/// Every verb over every node for `robot` in `s`; two-argument verbs over every target
/// with, as object, what the robot holds and each of `objects`.
fn check_all_candidates(
    task: &Task,
    s: &State,
    robot: Robot,
    objects: &[Idx],
    context: &str,
) -> Result<(), TestCaseError> {
    let offered = rules::actions(task, s, robot);
    let holding = s.target(robot.node, Relation::Hold);
    let nodes: Vec<Idx> = (0..task.nodes.len()).map(|i| Idx(i as u16)).collect();
    let mut objects = objects.to_vec();
    objects.extend(holding.filter(|h| !objects.contains(h)));
    let at = Checked {
        task,
        s,
        robot,
        offered: &offered,
        context,
    };
    for verb in Verb::ALL {
        for &n in &nodes {
            let candidate = |object| Candidate {
                verb,
                object,
                target: n,
                naming: Naming::Right,
            };
            if verb.preposition().is_some() {
                for &object in &objects {
                    check_candidate(&at, candidate(object))?;
                }
            } else {
                check_candidate(&at, candidate(n))?;
            }
        }
    }
    Ok(())
}

/// One random walk: which scene and task, the steps `(robot, action)` as indices, the
/// candidates to check at every state `(verb, object, target, naming)`, and one node
/// used as a second object for the exhaustive check at the end.
type Walk = (
    usize,
    Index,
    Vec<(Index, Index)>,
    Vec<(Index, Index, Index, u8)>,
    Index,
);

fn walks() -> impl Strategy<Value = Walk> {
    (
        0..4usize,
        any::<Index>(),
        prop::collection::vec((any::<Index>(), any::<Index>()), 0..=40),
        prop::collection::vec(
            (any::<Index>(), any::<Index>(), any::<Index>(), 0..10u8),
            1..=12,
        ),
        any::<Index>(),
    )
}

fn run_walk(walk: Walk) -> Result<(), TestCaseError> {
    let (scene, task_ix, steps, candidates, other) = walk;
    let task = task_ix.get(&scenes()[scene]);
    let nodes: Vec<Idx> = (0..task.nodes.len()).map(|i| Idx(i as u16)).collect();
    let mut s = task.init.clone();
    let mut trace: Vec<String> = Vec::new();
    let ctx = |trace: &[String]| format!("{} after [{}]", name(task), trace.join("; "));
    check_invariants(task, &s, &ctx(&trace))?;
    for (robot_ix, action_ix) in steps {
        // The chosen robot, or the next one that has something to do.
        let first = robot_ix.index(task.robots.len());
        let mut chosen = None;
        for k in 0..task.robots.len() {
            let robot = task.robots[(first + k) % task.robots.len()];
            let offered = rules::actions(task, &s, robot);
            if !offered.is_empty() {
                chosen = Some((robot, offered));
                break;
            }
        }
        let Some((robot, offered)) = chosen else {
            return Err(TestCaseError::fail(format!(
                "{}: no robot can act",
                ctx(&trace)
            )));
        };
        let a = *action_ix.get(&offered);
        trace.push(format!("{} {}", task.id(robot.node), a.render(task)));
        rules::apply(task, &mut s, robot, a);
        let context = ctx(&trace);
        check_invariants(task, &s, &context)?;
        for &r in &task.robots {
            let offered = rules::actions(task, &s, r);
            check_offered(task, &s, r, &offered, &context)?;
            let at = Checked {
                task,
                s: &s,
                robot: r,
                offered: &offered,
                context: &context,
            };
            for &(verb, object, target, naming) in &candidates {
                let naming = match naming {
                    0 => Naming::WrongName,
                    1 => Naming::UnknownId,
                    _ => Naming::Right,
                };
                let candidate = Candidate {
                    verb: *verb.get(&Verb::ALL),
                    object: *object.get(&nodes),
                    target: *target.get(&nodes),
                    naming,
                };
                check_candidate(&at, candidate)?;
            }
        }
    }
    // At the end of the walk, every verb over every node.
    let context = ctx(&trace);
    for &r in &task.robots {
        check_all_candidates(task, &s, r, &[*other.get(&nodes)], &context)?;
    }
    Ok(())
}

/// `cases` cases; failures are saved next to this file (`invariants.proptest-regressions`),
/// as integration tests have no `lib.rs` for proptest's default to find.
fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource(
            "proptest-regressions",
        ))),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn random_walks_keep_invariants_and_check_agrees_with_actions(walk in walks()) {
        run_walk(walk)?;
    }
}

/// The initial state of every task, every robot, every verb over every node (with a
/// few objects for the two-argument verbs: nothing is held at the start, so those are
/// all refused for an empty hand).
#[test]
fn check_agrees_with_actions_at_every_initial_state() {
    for tasks in scenes() {
        for task in tasks {
            let context = format!("{} at the start", name(task));
            check_invariants(task, &task.init, &context).unwrap_or_else(|e| panic!("{e}"));
            let some: Vec<Idx> = (0..task.nodes.len())
                .step_by(9)
                .map(|i| Idx(i as u16))
                .collect();
            for &r in &task.robots {
                let offered = rules::actions(task, &task.init, r);
                check_offered(task, &task.init, r, &offered, &context)
                    .unwrap_or_else(|e| panic!("{e}"));
                check_all_candidates(task, &task.init, r, &some, &context)
                    .unwrap_or_else(|e| panic!("{e}"));
            }
        }
    }
}

/// Along shortest plans, which reach the states that matter (things held, containers
/// opened, the quadrotor elsewhere): the invariants, and every verb over every node for
/// every robot, with the goal's subjects as objects of the two-argument verbs.
#[test]
fn check_agrees_with_actions_along_shortest_plans() {
    let mut planned = 0;
    let mut states = 0;
    for tasks in scenes() {
        for task in tasks {
            let search =
                planner::search(task, &task.robots, &task.goal, &Limits::max_states(20_000));
            let Some(plan) = search.plan else { continue };
            planned += 1;
            let mut objects: Vec<Idx> = task.goal.iter().map(|p| p.subject).collect();
            objects.dedup();
            let mut s = task.init.clone();
            for (i, step) in plan.iter().enumerate() {
                let robot = *task.robot(step.robot).expect("a robot of the task");
                rules::apply(task, &mut s, robot, step.action);
                states += 1;
                let context = format!("{} after {} plan steps", name(task), i + 1);
                check_invariants(task, &s, &context).unwrap_or_else(|e| panic!("{e}"));
                for &r in &task.robots {
                    let offered = rules::actions(task, &s, r);
                    check_offered(task, &s, r, &offered, &context)
                        .unwrap_or_else(|e| panic!("{e}"));
                    check_all_candidates(task, &s, r, &objects, &context)
                        .unwrap_or_else(|e| panic!("{e}"));
                }
            }
        }
    }
    eprintln!("{planned} tasks planned within 20000 states, {states} states checked");
    assert!(planned >= 20, "only {planned} tasks planned");
}

/// Strings made of the grammar's own pieces, which reach deeper into the parser than
/// arbitrary text.
fn fragments() -> impl Strategy<Value = String> {
    let piece = prop_oneof![
        Just("["),
        Just("]"),
        Just("<"),
        Just(">"),
        Just(">("),
        Just("("),
        Just(")"),
        Just(" "),
        Just("grab"),
        Just("putinto"),
        Just("puton"),
        Just("land_on"),
        Just("movetowards"),
        Just(" into "),
        Just(" on "),
        Just("into"),
        Just("apple"),
        Just("high table"),
        Just("0"),
        Just("7"),
        Just("42"),
        Just("-3"),
        Just("+5"),
        Just("99999999999999999999"),
        Just("é"),
        Just("日本"),
        Just("🤖"),
        Just("\u{0}"),
        Just("\t"),
        Just("\n"),
        Just("\u{200b}"),
    ];
    prop::collection::vec(piece, 0..16).prop_map(|v| v.concat())
}

fn parse_never_panics_and_display_round_trips(text: &str) -> Result<(), TestCaseError> {
    if let Ok(p) = action::parse(text) {
        let shown = p.to_string();
        let again = action::parse(&shown).map_err(|e| {
            TestCaseError::fail(format!(
                "{text:?} parsed, its display {shown:?} does not: {e}"
            ))
        })?;
        prop_assert_eq!(again, p);
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(2000))]

    #[test]
    fn parse_never_panics_on_any_string(text in any::<String>()) {
        parse_never_panics_and_display_round_trips(&text)?;
    }

    #[test]
    fn parse_never_panics_on_grammar_fragments(text in fragments()) {
        parse_never_panics_and_display_round_trips(&text)?;
    }

    #[test]
    fn parse_never_panics_on_near_actions(
        verb in prop::sample::select(Verb::ALL.to_vec()),
        name in "[a-z <>()]{0,8}",
        id in any::<i64>(),
        tail in fragments(),
    ) {
        let text = format!("[{verb}] <{name}>({id}){tail}");
        parse_never_panics_and_display_round_trips(&text)?;
    }

    /// Every string the grammar generates parses to its parts.
    #[test]
    fn parse_accepts_the_grammar(
        verb in prop::sample::select(Verb::ALL.to_vec()),
        a in "[a-z][a-z ]{0,12}[a-z]",
        i in any::<i64>(),
        b in "[a-z][a-z ]{0,12}[a-z]",
        j in any::<i64>(),
        pad in "[ \t]{0,2}",
    ) {
        let text = match verb.preposition() {
            Some(prep) => format!("{pad}[{verb}] <{a}>({i}) {prep} <{b}>({j}){pad}"),
            None => format!("{pad}[{verb}] <{a}>({i}){pad}"),
        };
        let p = action::parse(&text).map_err(|e| TestCaseError::fail(format!("{text:?}: {e}")))?;
        prop_assert_eq!(p.verb, verb);
        prop_assert_eq!(&p.object.name, &a);
        prop_assert_eq!(p.object.id.0, i);
        match verb.preposition() {
            Some(_) => {
                let t = p.target.as_ref().expect("a target");
                prop_assert_eq!(&t.name, &b);
                prop_assert_eq!(t.id.0, j);
            }
            None => prop_assert!(p.target.is_none()),
        }
        prop_assert_eq!(p.to_string(), text.trim());
    }
}

#[test]
fn parse_rejects_with_reasons() {
    for text in [
        "",
        "   ",
        "grab <apple>(3)",
        "[grab <apple>(3)",
        "[fly] <apple>(3)",
        "[grab]<apple>(3)",
        "[grab] apple(3)",
        "[grab] <>(3)",
        "[grab] <apple(3)",
        "[grab] <apple>3",
        "[grab] <apple>(3",
        "[grab] <apple>(x)",
        "[grab] <apple>(3) extra",
        "[putinto] <apple>(3)",
        "[putinto] <apple>(3) on <box>(4)",
        "[puton] <apple>(3) into <table>(4)",
        "[puton] <apple>(3) on <table>(4) now",
        "[puton] <apple>(3) on <table>(99999999999999999999)",
    ] {
        match action::parse(text) {
            Ok(p) => panic!("{text:?} parsed as {p:?}"),
            Err(coherent_core::Error::BadAction { action, reason }) => {
                assert_eq!(action, text);
                assert!(!reason.is_empty());
            }
            Err(other) => panic!("{text:?}: unexpected error {other:?}"),
        }
    }
}
