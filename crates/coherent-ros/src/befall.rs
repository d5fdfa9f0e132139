//! Events over ROS 2 (docs/dynamic.md): what an event changes in the robots' world goes
//! from the bridge to the world's service, `/<namespace>/befall` of type
//! `coherent_msgs/srv/Befall`, before the step it comes before. The bridge sends the
//! world as the events left it, in the terms a world can carry out: the team as it now
//! is, the doors now locked, and each thing someone moved with where it now is
//! ([`asked`]). The reference servers carry it out in their world, the rules or Rapier
//! ([`carry_out`]), and answer where each thing moved now is, which the bridge judges
//! as it judges a robot's report. What changes only the task's words (its goal, its
//! instruction) or the chances of failing actions stays with the planner: the robots'
//! world has nothing to do for it.

use std::sync::Arc;

use coherent_core::schedule::move_thing;
use coherent_core::{Idx, NodeKind, Relation, State, Task};

use crate::relations;
use crate::wire::{self, BefallRequest};
use crate::world::World;

/// The doors of `base` that `world` (a variant of it, as events leave it) has locked.
fn locked_doors(base: &Task, world: &Task) -> Vec<Idx> {
    let mut locked: Vec<Idx> = base
        .doors()
        .iter()
        .map(|&(d, _)| d)
        .filter(|d| !world.doors().iter().any(|(open, _)| open == d))
        .collect();
    // A door leads to two rooms: it stands in two pairs, not always side by side.
    locked.sort_unstable();
    locked.dedup();
    locked
}

/// Where `thing` is in `s`: the place it stands on or is inside, if any.
fn place(s: &State, thing: Idx) -> Option<(Relation, Idx)> {
    s.out(thing)
        .iter()
        .find(|e| e.rel().is_location())
        .map(|e| (e.rel(), e.to()))
}

/// `thing` at `place` in the task's words: `<mug>(7) ON <sofa>(14)`.
fn placed(task: &Task, thing: Idx, (relation, target): (Relation, Idx)) -> wire::Relation {
    wire::Relation {
        subject: task.node(thing).label(),
        relation: relation.name().to_owned(),
        object: task.node(target).label(),
    }
}

fn is_robot(task: &Task, n: Idx) -> bool {
    matches!(task.node(n).kind, NodeKind::Robot(_))
}

/// The world as events left it, from the robots' world `told` (the team and the locked
/// doors it was last told of; `None`: never told) in state `from` to `world` in state
/// `to`, as the world's service takes it before the action numbered `step`; `None` when
/// nothing the robots' world holds has changed (a new goal, a failing-actions event).
/// `names` are the robots' ROS names in `base`'s order.
pub(crate) fn asked(
    base: &Task,
    names: &[String],
    told: Option<&(Vec<String>, Vec<String>)>,
    world: &Task,
    (from, to): (&State, &State),
    step: u32,
) -> Option<BefallRequest> {
    let team: Vec<String> = base
        .robots
        .iter()
        .zip(names)
        .filter(|(r, _)| world.robots.iter().any(|w| w.node == r.node))
        .map(|(_, name)| name.clone())
        .collect();
    let locked: Vec<String> = locked_doors(base, world)
        .into_iter()
        .map(|d| base.node(d).label())
        .collect();
    let moved: Vec<wire::Relation> = base
        .indices()
        .filter(|&n| !is_robot(base, n))
        .filter_map(|n| {
            let now = place(to, n)?;
            (place(from, n) != Some(now)).then(|| placed(base, n, now))
        })
        .collect();
    let unchanged = told.is_some_and(|(t, l)| *t == team && *l == locked) && moved.is_empty();
    (!unchanged).then_some(BefallRequest {
        step,
        team,
        locked,
        moved,
    })
}

/// Carries `request` out in `world`, whose task as given is `base` (its robots named
/// `names`): the team and the locked doors become the request's, each thing moved is
/// taken out of any hand and set where the request puts it (as the rules move it, and
/// in Rapier on a free spot there), and the world must then agree with the rules. What
/// was done in words, and where each thing moved now is; or why nothing was done (a
/// request that names what the task does not have, a move the world cannot make).
pub(crate) fn carry_out(
    base: &Arc<Task>,
    names: &[String],
    world: &mut World,
    request: &BefallRequest,
) -> Result<(String, Vec<wire::Relation>), String> {
    let mut team = Vec::with_capacity(request.team.len());
    for name in &request.team {
        let Some(n) = names.iter().position(|known| known == name) else {
            return Err(format!(
                "the team names {}, which is no robot of this task (its robots: {})",
                coherent_core::text::shown(name),
                names.join(", ")
            ));
        };
        team.push(base.robots[n]);
    }
    let mut locked = Vec::with_capacity(request.locked.len());
    for label in &request.locked {
        match relations::node(base, label) {
            Some(d) if base.doors().iter().any(|&(door, _)| door == d) => locked.push(d),
            _ => {
                return Err(format!(
                    "{} is no door of this task",
                    coherent_core::text::shown(label)
                ));
            }
        }
    }
    let varied = Arc::new(base.vary(team, base.goal.clone(), &base.meta.instruction, &locked));
    let mut state = world.state().clone();
    let mut things = Vec::with_capacity(request.moved.len());
    for m in &request.moved {
        let said = || {
            let words = format!("{} {} {}", m.subject, m.relation, m.object);
            coherent_core::text::shown(&words).into_owned()
        };
        let relation = Relation::from_name(&m.relation).filter(|r| r.is_location());
        let (Some(thing), Some(relation), Some(target)) = (
            relations::node(base, &m.subject),
            relation,
            relations::node(base, &m.object),
        ) else {
            return Err(format!(
                "{}: not a thing ON or INSIDE a node of this task",
                said()
            ));
        };
        if is_robot(base, thing) {
            return Err(format!("{}: a robot is not moved by an event", said()));
        }
        move_thing(&varied, &mut state, thing, relation, target)?;
        things.push(thing);
    }
    world.befall(Arc::clone(&varied), state)?;
    let now = world.state();
    let relations: Vec<wire::Relation> = things
        .iter()
        .filter_map(|&n| Some(placed(base, n, place(now, n)?)))
        .collect();
    let list = |words: &[String]| {
        if words.is_empty() {
            "none".to_owned()
        } else {
            words.join(", ")
        }
    };
    let moved: Vec<String> = relations
        .iter()
        .map(|r| format!("{} {} {}", r.subject, r.relation, r.object))
        .collect();
    let doors: Vec<String> = locked.iter().map(|&d| base.node(d).label()).collect();
    let message = format!(
        "the team: {}; doors locked: {}; moved: {}",
        list(&request.team),
        list(&doors),
        list(&moved)
    );
    Ok((message, relations))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::relations::tests::demo;
    use coherent_core::events;

    /// The demo with `events` (as a task file writes them), and its robots' ROS names.
    fn with_events(text: &str) -> (Arc<Task>, Vec<String>) {
        let mut task = demo();
        let value: serde_json::Value = serde_json::from_str(text).expect("JSON");
        task.events = events::read(
            &task,
            &value,
            "events.json",
            coherent_core::JsonPath::root(),
        )
        .expect("events of the demo");
        let names = wire::robot_names(&task);
        (Arc::new(task), names)
    }

    /// The requests the demo's events make, step by step, from the start, with `told`
    /// following what was sent; each carried out in a world of the rules, which then holds
    /// the rules' state.
    fn requests(text: &str, steps: u32) -> Vec<BefallRequest> {
        let (task, names) = with_events(text);
        let mut schedule = coherent_core::Schedule::new(Arc::clone(&task));
        let mut world = World::new(&task, false).expect("a world of the rules");
        let mut state = task.init.clone();
        let mut told = None;
        let mut sent = Vec::new();
        for step in 1..=steps {
            let mut next = state.clone();
            if step > 1 {
                schedule.before_step(step, &mut next);
            }
            let varied = schedule.world();
            if let Some(request) =
                asked(&task, &names, told.as_ref(), &varied, (&state, &next), step)
            {
                let (_, relations) =
                    carry_out(&task, &names, &mut world, &request).expect("carried out");
                assert!(relations::disagreements(&varied, &[&next], &relations).is_empty());
                assert_eq!(world.state(), &next, "step {step}");
                assert_eq!(world.task().robots, varied.robots);
                assert_eq!(world.task().doors(), varied.doors());
                told = Some((request.team.clone(), request.locked.clone()));
                sent.push(request);
            }
            state = next;
        }
        sent
    }

    #[test]
    fn each_event_asks_the_world_for_what_it_changed_and_nothing_more() {
        let all = ["robot_arm_6", "quadrotor_11", "robot_dog_13"]
            .map(String::from)
            .to_vec();
        // Told at the start, whatever the events: a world served before may hold anything.
        let sent = requests(
            r#"[{"step": 2, "kind": "goal_changed", "remove": [{"relation": "ON", "subject": 9, "target": 10}], "add": [{"relation": "ON", "subject": 9, "target": 14}], "instruction": "The apple to the sofa."}]"#,
            4,
        );
        assert_eq!(sent.len(), 1);
        assert_eq!((sent[0].step, &sent[0].team), (1, &all));
        // A robot joining later is out of the team until its step.
        let sent = requests(r#"[{"step": 3, "kind": "robot_up", "robot": 13}]"#, 4);
        let teams: Vec<(u32, usize)> = sent.iter().map(|r| (r.step, r.team.len())).collect();
        assert_eq!(teams, [(1, 2), (3, 3)]);
        // A door locked for two steps, then open again.
        let sent = requests(
            r#"[{"step": 2, "kind": "blocked", "door": 4, "steps": 2}]"#,
            5,
        );
        let locked: Vec<(u32, Vec<String>)> =
            sent.iter().map(|r| (r.step, r.locked.clone())).collect();
        assert_eq!(
            locked,
            [(1, vec![]), (2, vec!["<door>(4)".to_owned()]), (4, vec![])]
        );
        // A thing moved, once.
        let sent = requests(
            r#"[{"step": 2, "kind": "object_moved", "thing": 9, "relation": "ON", "target": 14}]"#,
            4,
        );
        assert_eq!(sent.len(), 2);
        let moved = &sent[1].moved;
        assert_eq!(moved.len(), 1);
        assert_eq!(
            (
                moved[0].subject.as_str(),
                moved[0].relation.as_str(),
                moved[0].object.as_str()
            ),
            ("<apple>(9)", "ON", "<sofa>(14)")
        );
    }

    #[test]
    fn a_request_naming_what_the_task_lacks_is_refused_changing_nothing() {
        let (task, names) = with_events("[]");
        let mut world = World::new(&task, false).expect("a world of the rules");
        let good = BefallRequest {
            step: 1,
            team: names.clone(),
            locked: Vec::new(),
            moved: Vec::new(),
        };
        let relation = |s: &str, r: &str, o: &str| wire::Relation {
            subject: s.into(),
            relation: r.into(),
            object: o.into(),
        };
        let refused = [
            (
                BefallRequest {
                    team: vec!["robot_cat_1".into()],
                    ..good.clone()
                },
                "the team names robot_cat_1, which is no robot of this task",
            ),
            (
                BefallRequest {
                    locked: vec!["<sofa>(14)".into()],
                    ..good.clone()
                },
                "<sofa>(14) is no door of this task",
            ),
            (
                BefallRequest {
                    moved: vec![relation("<apple>(9)", "HOLD", "<sofa>(14)")],
                    ..good.clone()
                },
                "<apple>(9) HOLD <sofa>(14): not a thing ON or INSIDE a node of this task",
            ),
            (
                BefallRequest {
                    moved: vec![relation("<robot dog>(13)", "ON", "<sofa>(14)")],
                    ..good.clone()
                },
                "<robot dog>(13) ON <sofa>(14): a robot is not moved by an event",
            ),
        ];
        for (request, why) in refused {
            let got = carry_out(&task, &names, &mut world, &request).expect_err("refused");
            assert!(got.starts_with(why), "{got}");
            assert_eq!(world.state(), &task.init);
        }
        let (message, relations) = carry_out(&task, &names, &mut world, &good).expect("done");
        assert_eq!(
            message,
            "the team: robot_arm_6, quadrotor_11, robot_dog_13; doors locked: none; moved: none"
        );
        assert!(relations.is_empty());
    }
}
