//! A goal in English, from varied phrasings and no model: each predicate as one of
//! several verbs for its kind (putting on, putting in, loading a basket, landing), with
//! or without the room of its place, joined in one of several ways, after one of
//! several openings. Things are named as robots name them, `<mug>(12)`.

use coherent_core::Relation;

use crate::goal::Pred;
use crate::rng::Rng;
use crate::scene::Scene;
use crate::start::{Pose, Start};

const ON: &[&str] = &[
    "put {s} on {t}",
    "place {s} on {t}",
    "move {s} onto {t}",
    "set {s} down on {t}",
    "bring {s} to {t}",
    "get {s} onto {t}",
    "make sure {s} ends up on {t}",
];
const INSIDE: &[&str] = &[
    "put {s} in {t}",
    "place {s} inside {t}",
    "store {s} in {t}",
    "move {s} into {t}",
    "pack {s} into {t}",
    "make sure {s} ends up in {t}",
];
const BASKET: &[&str] = &[
    "load {s} into {t}",
    "put {s} in {t}",
    "have {s} carried in {t}",
];
const LAND: &[&str] = &[
    "land {s} on {t}",
    "fly {s} to {t} and land it there",
    "park {s} on {t}",
    "make sure {s} ends up landed on {t}",
];
/// Openings; the second element says whether the sentence is a question.
const OPENINGS: &[(&str, bool)] = &[
    ("", false),
    ("please ", false),
    ("could you ", true),
    ("I need you to ", false),
    ("your task: ", false),
    ("team, ", false),
];
/// The chance a place is named with its room.
const WITH_ROOM: f64 = 0.7;

/// The instruction for `goal` at `start`.
pub fn instruction(scene: &Scene, start: &Start, goal: &[Pred], rng: &mut Rng) -> String {
    let parts: Vec<String> = goal
        .iter()
        .map(|p| predicate(scene, start, p, rng))
        .collect();
    let (opening, question) = *rng.pick(OPENINGS);
    let body = match parts.len() {
        1 => parts[0].clone(),
        n => match rng.below(3) {
            0 => format!("{} and {}", parts[..n - 1].join(", "), parts[n - 1]),
            1 => parts.join("; "),
            _ => format!("{}; also {}", parts[..n - 1].join(", "), parts[n - 1]),
        },
    };
    let text = format!("{opening}{body}{}", if question { "?" } else { "." });
    let mut chars = text.chars();
    match chars.next() {
        Some(c) => c.to_uppercase().chain(chars).collect(),
        None => text,
    }
}

/// One predicate in words.
fn predicate(scene: &Scene, start: &Start, p: &Pred, rng: &mut Rng) -> String {
    let subject = format!("the {}", label(scene, start, p.subject));
    let basket_of = start
        .robots
        .iter()
        .find(|r| matches!(r.pose, Pose::Quad { basket, .. } if basket == p.target));
    let (forms, target) = if let Some(q) = basket_of {
        (
            BASKET,
            format!(
                "the {} of the {}",
                label(scene, start, p.target),
                label(scene, start, q.id)
            ),
        )
    } else {
        let room = room_of(scene, p.target)
            .filter(|_| rng.chance(WITH_ROOM))
            .map(|r| {
                let name = &scene.rooms[r].name;
                if name == "landing" {
                    " on the landing".to_owned()
                } else {
                    format!(" in the {name}")
                }
            })
            .unwrap_or_default();
        let is_robot = start.robots.iter().any(|r| r.id == p.subject);
        let forms = match (p.relation, is_robot) {
            (_, true) => LAND,
            (Relation::Inside, _) => INSIDE,
            _ => ON,
        };
        (
            forms,
            format!("the {}{room}", label(scene, start, p.target)),
        )
    };
    rng.pick(forms)
        .replace("{s}", &subject)
        .replace("{t}", &target)
}

/// The room a piece of furniture or a floor is in (a movable container moves, and is
/// named alone).
fn room_of(scene: &Scene, id: i64) -> Option<usize> {
    scene
        .pieces
        .iter()
        .find(|p| p.id == id)
        .map(|p| p.room)
        .or_else(|| scene.rooms.iter().position(|r| r.floor == id))
}

/// `<name>(id)` of any node of the task.
pub fn label(scene: &Scene, start: &Start, id: i64) -> String {
    let name = scene
        .rooms
        .iter()
        .find_map(|r| {
            if r.id == id {
                Some(r.name.clone())
            } else if r.floor == id {
                Some(format!("{} floor", r.name))
            } else {
                None
            }
        })
        .or_else(|| {
            scene
                .pieces
                .iter()
                .find(|p| p.id == id)
                .map(|p| p.kind.name.to_owned())
        })
        .or_else(|| {
            scene
                .things
                .iter()
                .find(|t| t.id == id)
                .map(|t| t.kind.name.to_owned())
        })
        .or_else(|| {
            start.robots.iter().find_map(|r| match r.pose {
                _ if r.id == id => Some(r.kind.class_name().to_owned()),
                Pose::Quad { basket, .. } if basket == id => Some("basket".to_owned()),
                _ => None,
            })
        })
        .unwrap_or_default();
    format!("<{name}>({id})")
}
