//! Relations between what a robot observes and the rules' state: the servers report what
//! their robot sees after acting ([`observed`]), the bridge lists what of a report the
//! rules' state does not hold ([`disagreements`]), as physics lists its disagreements.

use coherent_core::{Edge, Idx, NodeId, Relation, State, Task, rules};

use crate::wire::{self, IS};

/// The relations that change as robots act; `LEADING TO` and `WITH` never do.
const CHANGING: [Relation; 5] = [
    Relation::On,
    Relation::Inside,
    Relation::Close,
    Relation::Hold,
    Relation::Above,
];

/// What `robot` observes in `s`: the changing relations among the nodes it sees, then
/// each seen node's states as `IS`.
pub fn observed(task: &Task, s: &State, robot: Idx) -> Vec<wire::Relation> {
    let seen = rules::observe(task, s, robot);
    let label = |n: Idx| task.node(n).label();
    let mut out: Vec<wire::Relation> = seen
        .edges
        .iter()
        .filter(|e| CHANGING.contains(&e.rel()))
        .map(|e| wire::Relation {
            subject: label(e.from()),
            relation: e.rel().name().to_owned(),
            object: label(e.to()),
        })
        .collect();
    for &n in &seen.nodes {
        for state in task.vocab.state_names(s.states(n)) {
            out.push(wire::Relation {
                subject: label(n),
                relation: IS.to_owned(),
                object: state,
            });
        }
    }
    out
}

/// Every relation of `reported` that none of `states` holds, in words, with what the
/// first of them has.
///
/// A robot reports what it observes when its own action is over. Alone, that is the
/// state after its action. In a joint step the other robots act meanwhile, so it
/// observes a state between that one and the state after the whole step; since no two
/// actions of a valid step write the same relation differently (docs/semantics.md,
/// "Parallel steps"), each relation it can observe holds in one of those two, which the
/// bridge passes, in that order.
pub fn disagreements(task: &Task, states: &[&State], reported: &[wire::Relation]) -> Vec<String> {
    reported
        .iter()
        .filter_map(|r| {
            let (first, rest) = states.split_first()?;
            let why = disagreement(task, first, r)?;
            rest.iter()
                .all(|s| disagreement(task, s, r).is_some())
                .then_some(why)
        })
        .collect()
}

fn disagreement(task: &Task, s: &State, r: &wire::Relation) -> Option<String> {
    let said = format!("{} {} {}", r.subject, r.relation, r.object);
    let Some(subject) = node(task, &r.subject) else {
        return Some(format!("{said}: the task has no node {}", r.subject));
    };
    let label = |n: Idx| task.node(n).label();
    if r.relation == IS {
        let states = task.vocab.state_names(s.states(subject));
        return (!states.contains(&r.object)).then(|| {
            format!(
                "{said}: the rules have {} {}",
                r.subject,
                if states.is_empty() {
                    "in no state".to_owned()
                } else {
                    states.join(", ")
                }
            )
        });
    }
    let Some(relation) = Relation::from_name(&r.relation) else {
        return Some(format!("{said}: no relation {:?}", r.relation));
    };
    let Some(object) = node(task, &r.object) else {
        return Some(format!("{said}: the task has no node {}", r.object));
    };
    if s.has(Edge::new(subject, relation, object)) {
        return None;
    }
    let held: Vec<String> = s.targets(subject, relation).map(label).collect();
    Some(if held.is_empty() {
        format!(
            "{said}: the rules have {} {} nothing",
            r.subject, r.relation
        )
    } else {
        format!(
            "{said}: the rules have {} {} {}",
            r.subject,
            r.relation,
            held.join(", ")
        )
    })
}

/// The node a label such as `<apple>(9)` names: the id in parentheses, whose node must
/// have the class name in angle brackets.
pub(crate) fn node(task: &Task, label: &str) -> Option<Idx> {
    let inner = label.trim().strip_prefix('<')?;
    let (name, rest) = inner.split_once(">(")?;
    let id: i64 = rest.strip_suffix(')')?.parse().ok()?;
    let n = task.idx(NodeId(id))?;
    (task.node(n).class_name == name).then_some(n)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use coherent_core::native;

    /// The demo task of `examples/tasks`.
    pub(crate) fn demo() -> Task {
        let text = include_str!("../../../examples/tasks/demo.json");
        let value: serde_json::Value = serde_json::from_str(text).expect("demo.json is JSON");
        native::read("demo.json", &value).expect("demo.json is a task")
    }

    #[test]
    fn what_a_robot_observes_agrees_with_the_state_it_came_from() {
        let task = demo();
        for r in &task.robots {
            let seen = observed(&task, &task.init, r.node);
            assert!(!seen.is_empty());
            assert_eq!(
                disagreements(&task, &[&task.init], &seen),
                Vec::<String>::new()
            );
        }
    }

    #[test]
    fn a_relation_the_rules_do_not_hold_is_listed_with_what_they_have() {
        let task = demo();
        let rel = |subject: &str, relation: &str, object: &str| wire::Relation {
            subject: subject.into(),
            relation: relation.into(),
            object: object.into(),
        };
        let found = disagreements(
            &task,
            &[&task.init],
            &[
                rel("<apple>(9)", "ON", "<coffee table>(10)"),
                rel("<apple>(9)", "IS", "FLYING"),
                rel("<pear>(9)", "ON", "<coffee table>(10)"),
                rel("<apple>(9)", "NEAR", "<coffee table>(10)"),
            ],
        );
        assert_eq!(found.len(), 4, "{found:#?}");
        assert!(
            found[0].starts_with("<apple>(9) ON <coffee table>(10): the rules have <apple>(9) ON "),
            "{}",
            found[0]
        );
        assert!(
            found[1].contains("the rules have <apple>(9)"),
            "{}",
            found[1]
        );
        assert!(
            found[2].contains("the task has no node <pear>(9)"),
            "{}",
            found[2]
        );
        assert!(found[3].contains("no relation \"NEAR\""), "{}", found[3]);
    }
}
