//! A task as a PDDL problem of its rule set's domain: the objects by type, the initial
//! facts (the rules' state and what the domain derives from it), the goal; and the
//! checks that refuse a task the domain cannot express exactly.

use std::fmt::Write;

use crate::graph::{Idx, NodeKind, NodeSet, RobotKind};
use crate::pddl::domain::{domain_name, rules_name};
use crate::pddl::names::Names;
use crate::task::Task;
use crate::vocab::{PropSet, Relation, StateSet};

/// What each node is to the domain.
pub(crate) struct Classes {
    /// Grabable things, baskets, and whatever starts on or in one of them.
    pub movable: NodeSet,
    /// Movable things that can carry others: baskets, surfaces, containers, and
    /// whatever starts with something on or in it.
    pub carrier: NodeSet,
}

/// Why the domain cannot express `task` exactly, or its classes.
pub(crate) fn classify(task: &Task) -> Result<Classes, String> {
    let n = task.nodes.len();
    let s = &task.init;
    let label = |x: Idx| task.node(x).label();
    let locations = |x: Idx| s.out(x).iter().filter(|e| e.rel().is_location()).count();
    let has = |x: Idx, p: PropSet| task.node(x).properties.contains(p);
    let acted_on = PropSet::GRABABLE.0 | PropSet::SURFACES.0 | PropSet::CONTAINERS.0;
    let acted_on = PropSet(acted_on | PropSet::LANDABLE.0);
    for x in task.indices() {
        let node = task.node(x);
        let props = node.properties;
        match node.kind {
            NodeKind::Robot(kind) => {
                if props.0 & acted_on.0 != 0 {
                    return Err(format!(
                        "the robot {} is GRABABLE, a surface, a container or LANDABLE: the domain has no robot to act on",
                        label(x)
                    ));
                }
                let inside: Vec<Idx> = s.targets(x, Relation::Inside).collect();
                if inside.len() > 1 || inside.iter().any(|&t| task.node(t).kind != NodeKind::Room) {
                    return Err(format!(
                        "the robot {} is INSIDE something other than one room",
                        label(x)
                    ));
                }
                let most = |rel| s.targets(x, rel).count() > 1;
                if most(Relation::On) || most(Relation::Hold) || most(Relation::Above) {
                    return Err(format!(
                        "the robot {} has more than one ON, HOLD or ABOVE edge",
                        label(x)
                    ));
                }
                match kind {
                    RobotKind::Quadrotor => basket_follows(task, x)?,
                    RobotKind::RobotArm => base_stays(task, x)?,
                    RobotKind::RobotDog => {}
                }
            }
            NodeKind::Room if locations(x) > 0 || props.0 & acted_on.0 != 0 => {
                return Err(format!(
                    "the room {} stands on or in something, or is a surface, container, GRABABLE or LANDABLE",
                    label(x)
                ));
            }
            NodeKind::Door if locations(x) > 0 => {
                return Err(format!(
                    "the door {} stands on or in something: doors are seen from the rooms they lead to",
                    label(x)
                ));
            }
            _ if locations(x) > 1 => {
                return Err(format!(
                    "{} stands in {} places at once: the domain keeps one location per thing",
                    label(x),
                    locations(x)
                ));
            }
            _ => {}
        }
        if task.robot(x).is_some()
            && s.sources(Relation::On, x)
                .chain(s.sources(Relation::Inside, x))
                .next()
                .is_some()
        {
            return Err(format!("something stands on or in the robot {}", label(x)));
        }
    }
    // Movable: grabable things and baskets, then whatever stands on or in them.
    let mut movable = NodeSet::new(n);
    for x in task.indices() {
        if has(x, PropSet::GRABABLE) || task.node(x).kind == NodeKind::Tool {
            movable.insert(x);
        }
    }
    loop {
        let before = movable.iter().count();
        for e in s.edges().iter().filter(|e| e.rel().is_location()) {
            if movable.contains(e.to()) && task.robot(e.from()).is_none() {
                movable.insert(e.from());
            }
        }
        if movable.iter().count() == before {
            break;
        }
    }
    let mut carrier = NodeSet::new(n);
    for x in movable.iter() {
        let node = task.node(x);
        if matches!(node.kind, NodeKind::Robot(_) | NodeKind::Room) {
            return Err(format!(
                "{} is GRABABLE or stands on something that is: the domain moves things, not robots or rooms",
                label(x)
            ));
        }
        if has(x, PropSet::LANDABLE) {
            return Err(format!(
                "{} is LANDABLE and can move: the domain lands quadrotors on things that stay put",
                label(x)
            ));
        }
        let holds_things = s.sources(Relation::On, x).next().is_some()
            || s.sources(Relation::Inside, x).next().is_some();
        if has(x, PropSet::SURFACES)
            || has(x, PropSet::CONTAINERS)
            || node.kind == NodeKind::Tool
            || holds_things
        {
            carrier.insert(x);
        }
    }
    no_cycle(task)?;
    Ok(Classes { movable, carrier })
}

/// A quadrotor's basket goes where it goes: always open, never grabable, on the surface
/// the quadrotor has landed on, and nowhere while it flies.
fn basket_follows(task: &Task, q: Idx) -> Result<(), String> {
    let Some(b) = task.basket_of(q) else {
        return Ok(());
    };
    let s = &task.init;
    let node = task.node(b);
    let states = s.states(b);
    if node.kind != NodeKind::Tool
        || !states.contains(StateSet::OPEN_FOREVER)
        || states.intersects(StateSet::OPEN | StateSet::CLOSED)
        || node.properties.contains(PropSet::GRABABLE)
        || task
            .robots
            .iter()
            .filter(|r| task.basket_of(r.node) == Some(b))
            .count()
            > 1
    {
        return Err(format!(
            "the basket {} of {} is not an AgentTool that is always open (OPEN_FOREVER only), not GRABABLE and of one quadrotor",
            node.label(),
            task.node(q).label()
        ));
    }
    let on: Vec<Idx> = s.targets(q, Relation::On).collect();
    let basket_on: Vec<Idx> = s.targets(b, Relation::On).collect();
    if on != basket_on || s.targets(b, Relation::Inside).next().is_some() {
        return Err(format!(
            "the basket {} does not stand where {} has landed",
            node.label(),
            task.node(q).label()
        ));
    }
    Ok(())
}

/// A fixed arm's surface never moves and is never hidden: nothing it stands in can be
/// closed.
fn base_stays(task: &Task, arm: Idx) -> Result<(), String> {
    let s = &task.init;
    let Some(base) = s.targets(arm, Relation::On).next() else {
        return Ok(());
    };
    let node = task.node(base);
    let moves = node.properties.contains(PropSet::GRABABLE)
        || matches!(node.kind, NodeKind::Robot(_) | NodeKind::Tool);
    let shut = s.targets(base, Relation::Inside).any(|c| {
        let c = task.node(c);
        c.kind == NodeKind::Door || c.properties.contains(PropSet::CONTAINERS)
    });
    if moves || shut {
        return Err(format!(
            "the surface {} of the arm {} can move or be shut in: the domain keeps an arm's surface where it is and in view",
            node.label(),
            task.node(arm).label()
        ));
    }
    Ok(())
}

/// Location edges never loop: a thing is never, through others, on or in itself.
fn no_cycle(task: &Task) -> Result<(), String> {
    for x in task.indices() {
        let mut at = x;
        for _ in 0..=task.nodes.len() {
            match task
                .init
                .out(at)
                .iter()
                .find(|e| e.rel().is_location() && task.robot(at).is_none())
            {
                Some(e) if e.to() == x => {
                    return Err(format!(
                        "{} stands, through others, on or in itself",
                        task.node(x).label()
                    ));
                }
                Some(e) => at = e.to(),
                None => break,
            }
        }
    }
    Ok(())
}

/// The problem text of `task`, its classes found.
pub(crate) fn problem(task: &Task, classes: &Classes, names: &Names) -> String {
    let mut p = String::new();
    let _ = writeln!(
        p,
        ";; {}, written by coherent {} ({} rule set).",
        task_origin(task),
        env!("CARGO_PKG_VERSION"),
        rules_name(task.meta.rules)
    );
    let _ = writeln!(
        p,
        "(define (problem {})\n  (:domain {})",
        names.problem,
        domain_name(task.meta.rules)
    );
    objects(task, classes, names, &mut p);
    p.push_str("  (:init\n");
    for fact in init_facts(task, classes, names) {
        let _ = writeln!(p, "    {fact}");
    }
    p.push_str("  )\n");
    p.push_str(&goal(task, names));
    p.push_str(")\n");
    p
}

/// Where the task came from: its scene and id, the file of an imported one.
pub(crate) fn task_origin(task: &Task) -> String {
    let m = &task.meta;
    match &m.source {
        Some(src) => format!(
            "task {} of scene {} ({}, index {} of {})",
            m.task_id, m.scene, m.name, src.index, src.file
        ),
        None => format!("task {} of scene {} ({})", m.task_id, m.scene, m.name),
    }
}

fn objects(task: &Task, classes: &Classes, names: &Names, p: &mut String) {
    let type_of = |x: Idx| match task.node(x).kind {
        NodeKind::Room => "room",
        NodeKind::Robot(RobotKind::Quadrotor) => "quadrotor",
        NodeKind::Robot(RobotKind::RobotDog) => "dog",
        NodeKind::Robot(RobotKind::RobotArm) => "arm",
        _ if classes.carrier.contains(x) => "carrier",
        _ if classes.movable.contains(x) => "movable",
        _ => "fixed",
    };
    p.push_str("  (:objects");
    for ty in [
        "room",
        "quadrotor",
        "dog",
        "arm",
        "fixed",
        "movable",
        "carrier",
    ] {
        let of: Vec<&str> = task
            .indices()
            .filter(|&x| type_of(x) == ty)
            .map(|x| names.of(x))
            .collect();
        if of.is_empty() {
            continue;
        }
        p.push_str("\n   ");
        let mut width = 3;
        for name in of {
            if width + name.len() > 90 {
                p.push_str("\n   ");
                width = 3;
            }
            p.push(' ');
            p.push_str(name);
            width += name.len() + 1;
        }
        let _ = write!(p, " - {ty}");
    }
    p.push_str(")\n");
}

/// Every initial fact, the static ones first.
fn init_facts(task: &Task, classes: &Classes, names: &Names) -> Vec<String> {
    let s = &task.init;
    let nm = |x: Idx| names.of(x);
    let mut facts = Vec::new();
    let is_thing = |x: Idx| !matches!(task.node(x).kind, NodeKind::Room | NodeKind::Robot(_));
    let props = [
        (PropSet::GRABABLE, "grabable"),
        (PropSet::SURFACES, "surface"),
        (PropSet::CONTAINERS, "container"),
        (PropSet::LANDABLE, "landable"),
        (PropSet::HIGH_HEIGHT, "high-height"),
        (PropSet::LOW_HEIGHT, "low-height"),
    ];
    for x in task.indices().filter(|&x| is_thing(x)) {
        let node = task.node(x);
        for (p, name) in props {
            if node.properties.contains(p) {
                facts.push(format!("({name} {})", nm(x)));
            }
        }
        if node
            .properties
            .intersects(PropSet::SURFACES | PropSet::CONTAINERS)
        {
            facts.push(format!("(holder {})", nm(x)));
        }
        match node.kind {
            NodeKind::Floor => facts.push(format!("(floor {})", nm(x))),
            NodeKind::Door => facts.push(format!("(door {})", nm(x))),
            _ => {}
        }
        if classes.carrier.contains(x) {
            facts.push(format!("(is-carrier {})", nm(x)));
        }
    }
    for &(door, room) in task.doors() {
        facts.push(format!("(leads {} {})", nm(door), nm(room)));
    }
    for &room in task.rooms() {
        if let Some(f) = task.floor_of(room) {
            facts.push(format!("(floor-of {} {})", nm(f), nm(room)));
        }
    }
    for r in &task.robots {
        if let Some(b) = task.basket_of(r.node) {
            facts.push(format!("(basket-of {} {})", nm(r.node), nm(b)));
        }
        if r.kind == RobotKind::RobotArm
            && let Some(base) = arm_base(task, r.node)
        {
            facts.push(format!("(arm-base {} {})", nm(r.node), nm(base)));
        }
    }
    edge_facts(task, names, &mut facts);
    for x in task.indices() {
        let states = s.states(x);
        if is_thing(x) {
            for (st, name) in [(StateSet::OPEN, "is-open"), (StateSet::CLOSED, "is-closed")] {
                if states.contains(st) {
                    facts.push(format!("({name} {})", nm(x)));
                }
            }
            if states.is_open() {
                facts.push(format!("(opened {})", nm(x)));
            }
            if s.on_high_surface(x) {
                facts.push(format!("(marked {})", nm(x)));
            }
        }
        if let Some(r) = task.robot(x) {
            if r.kind == RobotKind::Quadrotor {
                for (st, name) in [(StateSet::FLYING, "flying"), (StateSet::LAND, "landed")] {
                    if states.contains(st) {
                        facts.push(format!("({name} {})", nm(x)));
                    }
                }
            }
            if r.kind != RobotKind::Quadrotor && s.targets(x, Relation::Hold).next().is_none() {
                facts.push(format!("(free {})", nm(x)));
            }
        }
    }
    derived_facts(task, classes, names, &mut facts);
    facts
}

/// The edges the rules read, as facts: locations (with `at` for things), the dogs'
/// `CLOSE`, the hands' `HOLD`, the quadrotors' `ABOVE`.
fn edge_facts(task: &Task, names: &Names, facts: &mut Vec<String>) {
    let nm = |x: Idx| names.of(x);
    for e in task.init.edges() {
        let (from, to) = (nm(e.from()), nm(e.to()));
        let robot = task.robot(e.from()).map(|r| r.kind);
        match e.rel() {
            Relation::On | Relation::Inside => {
                let rel = if e.rel() == Relation::On {
                    "on"
                } else {
                    "inside"
                };
                facts.push(format!("({rel} {from} {to})"));
                if robot.is_none() {
                    facts.push(format!("(at {from} {to})"));
                }
            }
            Relation::Close if robot == Some(RobotKind::RobotDog) => {
                facts.push(format!("(close {from} {to})"));
            }
            Relation::Hold if matches!(robot, Some(RobotKind::RobotDog | RobotKind::RobotArm)) => {
                facts.push(format!("(holds {from} {to})"));
            }
            Relation::Above if robot == Some(RobotKind::Quadrotor) => {
                facts.push(format!("(above {from} {to})"));
            }
            _ => {}
        }
    }
}

/// The surface a fixed arm stands on, when the arm sees it from its room and always
/// will (nothing it stands in can be closed); otherwise the arm has no action.
fn arm_base(task: &Task, arm: Idx) -> Option<Idx> {
    let s = &task.init;
    let room = crate::rules::room_of(task, s, arm)?;
    let base = s.targets(arm, Relation::On).next()?;
    let seen = crate::rules::visible(task, s, arm).contains(base);
    let in_room = closures(task)
        .iter()
        .find(|(r, _)| *r == room)
        .is_some_and(|(_, set)| set.contains(base));
    (seen && in_room).then_some(base)
}

/// Every room's closure at the start: what stands, at any depth, in it.
fn closures(task: &Task) -> Vec<(Idx, NodeSet)> {
    let s = &task.init;
    let n = task.nodes.len();
    task.rooms()
        .iter()
        .map(|&room| {
            let mut set = NodeSet::new(n);
            let mut stack: Vec<Idx> = s
                .sources(Relation::Inside, room)
                .filter(|&x| set.insert(x))
                .collect();
            while let Some(p) = stack.pop() {
                for x in s
                    .sources(Relation::On, p)
                    .chain(s.sources(Relation::Inside, p))
                {
                    if set.insert(x) {
                        stack.push(x);
                    }
                }
            }
            (room, set)
        })
        .collect()
}

/// What the domain derives and keeps: `hidden`, `inroom` (the rooms' closures, doors in
/// the rooms they lead to), `anc` (the carriers above each movable thing).
fn derived_facts(task: &Task, classes: &Classes, names: &Names, facts: &mut Vec<String>) {
    let s = &task.init;
    let nm = |x: Idx| names.of(x);
    for x in task.indices() {
        let hidden = s
            .targets(x, Relation::Inside)
            .any(|c| task.node(c).kind != NodeKind::Room && !s.states(c).is_open());
        if hidden && task.robot(x).is_none() {
            facts.push(format!("(hidden {})", nm(x)));
        }
    }
    for (room, set) in &closures(task) {
        for x in set.iter().filter(|&x| task.robot(x).is_none()) {
            facts.push(format!("(inroom {} {})", nm(x), nm(*room)));
        }
    }
    for &(door, room) in task.doors() {
        facts.push(format!("(inroom {} {})", nm(door), nm(room)));
    }
    for x in classes.movable.iter() {
        let mut at = x;
        while let Some(p) = s
            .out(at)
            .iter()
            .find(|e| e.rel().is_location())
            .map(|e| e.to())
        {
            if classes.carrier.contains(p) {
                facts.push(format!("(anc {} {})", nm(x), nm(p)));
            }
            at = p;
            if at == x {
                break;
            }
        }
    }
}

/// The goal: each predicate's edge for a count of 1, its absence for 0; a larger count
/// can never hold (edges form a set), written as a goal that contradicts itself.
fn goal(task: &Task, names: &Names) -> String {
    let mut parts = Vec::new();
    for p in &task.goal {
        let rel = if p.relation == Relation::On {
            "on"
        } else {
            "inside"
        };
        let atom = format!("({rel} {} {})", names.of(p.subject), names.of(p.target));
        match p.count {
            0 => parts.push(format!("(not {atom})")),
            1 => parts.push(atom),
            _ => {
                parts.push(format!("(not {atom})"));
                parts.push(atom);
            }
        }
    }
    format!("  (:goal (and\n    {}))\n", parts.join("\n    "))
}
