//! A task's goal: predicates `ON`/`INSIDE` over the scene, drawn so that the task type a
//! request asks for is likely. A random goal over all things and places is mostly an
//! errand of one robot or impossible (nothing reaches a high shelf without an arm on
//! it), so each candidate predicate is classed by the robot kinds it plausibly needs
//! (a route: a low place to a low place needs a legged robot; a counter to another an
//! arm on each and a quadrotor between; a low place to a counter all three kinds), and a
//! goal is drawn from the routes of the kinds wanted, covering them all. The planner,
//! not the route, decides the type (`truth.rs`).

use coherent_core::Relation;

use crate::rng::Rng;
use crate::scene::Scene;
use crate::start::{
    BASKET_HOLDS, Landing, Pose, Start, fits_in_thing, fits_inside, high_pieces, pack_on,
};

/// The kinds a route needs, as bits: quadrotor, legged robot, arm (the order of
/// [`crate::request::KINDS`]).
pub const QUAD: u8 = 1;
pub const DOG: u8 = 2;
pub const ARM: u8 = 4;

/// One goal predicate, by node ids.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Pred {
    pub relation: Relation,
    pub subject: i64,
    pub target: i64,
}

/// Who can get at a place at the start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Reach {
    /// A legged robot (low, not on a counter).
    Low,
    /// The fixed arm on this counter (index into the pieces).
    Arm(usize),
    /// Nobody: a high shelf, a counter without an arm.
    Nobody,
}

/// A destination: a piece's top or inside, a movable container, a quadrotor's basket.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Dest {
    Piece(usize, bool),
    Thing(usize),
    Basket(usize),
}

/// A candidate predicate with the kinds its route needs.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    pred: Pred,
    mask: u8,
    /// The thing moved (index into the scene's things), or none for a landing.
    thing: Option<usize>,
    dest: Option<Dest>,
    /// The quadrotor that lands (index into the start's robots).
    quad: Option<usize>,
    /// Doors between where the subject starts and where it goes.
    hops: usize,
}

/// The reach of each piece at this start.
fn reaches(scene: &Scene, start: &Start, high: &[bool]) -> Vec<Reach> {
    (0..scene.pieces.len())
        .map(|p| {
            if start.arm_on(p).is_some() {
                Reach::Arm(p)
            } else if high[p] || scene.pieces[p].kind.arm {
                Reach::Nobody
            } else {
                Reach::Low
            }
        })
        .collect()
}

/// The kinds a move from `from` to `to` needs.
fn route(from: Reach, to: Reach) -> Option<u8> {
    Some(match (from, to) {
        (Reach::Nobody, _) | (_, Reach::Nobody) => return None,
        (Reach::Low, Reach::Low) => DOG,
        (Reach::Arm(a), Reach::Arm(b)) if a == b => ARM,
        (Reach::Arm(_), Reach::Arm(_)) => ARM | QUAD,
        _ => DOG | QUAD | ARM,
    })
}

/// Every predicate worth drawing at this start, with the kinds of its route.
fn candidates(scene: &Scene, start: &Start) -> Vec<Candidate> {
    let high = high_pieces(scene);
    let reach = reaches(scene, start, &high);
    let hops = scene.hops();
    let quad_room = |q: usize| match start.robots[q].pose {
        Pose::Quad {
            on: Landing::Top(p),
            ..
        } => scene.pieces[p].room,
        Pose::Quad {
            on: Landing::Floor(r, _),
            ..
        } => r,
        _ => 0,
    };
    let mut out = Vec::new();
    for (i, t) in scene.things.iter().enumerate() {
        let at = start.things[i];
        let from = reach[at.piece];
        if from == Reach::Nobody {
            continue;
        }
        let mut dests: Vec<(Dest, Reach)> = Vec::new();
        for (p, piece) in scene.pieces.iter().enumerate() {
            if piece.kind.surface && (p != at.piece || at.inside) {
                dests.push((Dest::Piece(p, false), reach[p]));
            }
            if piece.kind.container
                && !(p == at.piece && at.inside)
                && fits_inside(piece, t.kind.size)
            {
                dests.push((Dest::Piece(p, true), reach[p]));
            }
        }
        for (j, c) in scene.things.iter().enumerate() {
            if j != i && c.kind.container && fits_in_thing(c.kind.size, t.kind.size) {
                dests.push((Dest::Thing(j), reach[start.things[j].piece]));
            }
        }
        for (q, r) in start.robots.iter().enumerate() {
            if let Pose::Quad { .. } = r.pose {
                dests.push((Dest::Basket(q), Reach::Low));
            }
        }
        for (dest, to) in dests {
            let mask = match dest {
                // Loading a basket: from a low place by a legged robot, from a counter by
                // its arm; the quadrotor comes to them.
                Dest::Basket(_) => match from {
                    Reach::Low => DOG | QUAD,
                    Reach::Arm(_) => ARM | QUAD,
                    Reach::Nobody => continue,
                },
                _ => match route(from, to) {
                    Some(m) => m,
                    None => continue,
                },
            };
            let room = match dest {
                Dest::Piece(p, _) => scene.pieces[p].room,
                Dest::Thing(j) => scene.pieces[start.things[j].piece].room,
                Dest::Basket(q) => quad_room(q),
            };
            let (relation, target) = match dest {
                Dest::Piece(p, inside) => (
                    if inside {
                        Relation::Inside
                    } else {
                        Relation::On
                    },
                    scene.pieces[p].id,
                ),
                Dest::Thing(j) => (Relation::Inside, scene.things[j].id),
                Dest::Basket(q) => match start.robots[q].pose {
                    Pose::Quad { basket, .. } => (Relation::Inside, basket),
                    _ => continue,
                },
            };
            out.push(Candidate {
                pred: Pred {
                    relation,
                    subject: t.id,
                    target,
                },
                mask,
                thing: Some(i),
                dest: Some(dest),
                quad: None,
                hops: hops[scene.pieces[at.piece].room][room],
            });
        }
    }
    landings(scene, start, &hops, &mut out);
    out
}

/// A quadrotor landing somewhere else: on a landable top, or the floor of a room.
fn landings(scene: &Scene, start: &Start, hops: &[Vec<usize>], out: &mut Vec<Candidate>) {
    for (q, r) in start.robots.iter().enumerate() {
        let Pose::Quad { on, .. } = r.pose else {
            continue;
        };
        let from = match on {
            Landing::Top(p) => scene.pieces[p].room,
            Landing::Floor(room, _) => room,
        };
        let tops = scene
            .pieces
            .iter()
            .enumerate()
            .filter(|(p, piece)| piece.kind.landable && on != Landing::Top(*p))
            .map(|(_, piece)| (piece.id, piece.room));
        let floors = scene
            .rooms
            .iter()
            .enumerate()
            .filter(|(room, _)| !matches!(on, Landing::Floor(r, _) if r == *room))
            .map(|(i, room)| (room.floor, i));
        for (target, room) in tops.chain(floors) {
            out.push(Candidate {
                pred: Pred {
                    relation: Relation::On,
                    subject: r.id,
                    target,
                },
                mask: QUAD,
                thing: None,
                dest: None,
                quad: Some(q),
                hops: hops[from][room],
            });
        }
    }
}

/// A goal of `k` predicates whose routes need exactly the kinds of `mask`, or `None`
/// when the draw finds none (the scene's things and places do not offer it, or what it
/// drew does not fit where it goes).
pub fn draw(scene: &Scene, start: &Start, k: usize, mask: u8, rng: &mut Rng) -> Option<Vec<Pred>> {
    let all: Vec<Candidate> = candidates(scene, start)
        .into_iter()
        .filter(|c| c.mask & !mask == 0)
        .collect();
    let mut classes: Vec<u8> = all.iter().map(|c| c.mask).collect();
    classes.sort_unstable();
    classes.dedup();
    if classes.iter().fold(0, |a, m| a | m) != mask {
        return None;
    }
    for _ in 0..GOAL_TRIES {
        let mut chosen: Vec<Candidate> = Vec::new();
        let mut covered = 0u8;
        for _ in 0..k * 4 {
            if chosen.len() == k {
                break;
            }
            // The kinds not covered yet come first: a class that adds one of them.
            let left = k - chosen.len();
            let uncovered = (mask & !covered).count_ones() as usize;
            let pool: Vec<u8> = classes
                .iter()
                .copied()
                .filter(|m| left > uncovered || m & !covered != 0)
                .collect();
            if pool.is_empty() {
                break;
            }
            let class = *rng.pick(&pool);
            let members: Vec<&Candidate> = all.iter().filter(|c| c.mask == class).collect();
            let weights: Vec<f64> = members
                .iter()
                .map(|c| NEAR[c.hops.min(NEAR.len() - 1)])
                .collect();
            let c = *members[rng.weighted(&weights)];
            if chosen.iter().any(|o| clashes(o, &c)) {
                continue;
            }
            chosen.push(c);
            covered |= c.mask;
        }
        if chosen.len() == k && covered == mask && fits(scene, start, &chosen) {
            let mut goal: Vec<Pred> = chosen.iter().map(|c| c.pred).collect();
            goal.sort_unstable();
            return Some(goal);
        }
    }
    None
}

/// How likely a predicate is drawn by the doors between where its subject starts and
/// where it goes: errands within a room or to the next one are the common ones (a mug
/// from the table to the cabinet), across the house the rarer.
const NEAR: [f64; 4] = [4.0, 2.0, 1.0, 0.5];

/// Draws of one goal before giving up on it.
const GOAL_TRIES: usize = 12;

/// Whether two predicates cannot be in one goal: one subject twice, one quadrotor
/// landing twice, a thing that is the other's container.
fn clashes(a: &Candidate, b: &Candidate) -> bool {
    a.pred.subject == b.pred.subject
        || a.pred.subject == b.pred.target
        || b.pred.subject == a.pred.target
        || (a.quad.is_some() && a.quad == b.quad)
}

/// Whether everything the goal puts somewhere fits there beside what starts there: in
/// rows on a top or in a container, two in a basket, one in a movable container.
fn fits(scene: &Scene, start: &Start, chosen: &[Candidate]) -> bool {
    let mut targets: Vec<Dest> = chosen.iter().filter_map(|c| c.dest).collect();
    targets.sort_unstable();
    targets.dedup();
    for dest in targets {
        let adding: Vec<[f32; 3]> = chosen
            .iter()
            .filter(|c| c.dest == Some(dest))
            .filter_map(|c| c.thing)
            .map(|i| scene.things[i].kind.size)
            .collect();
        let ok = match dest {
            Dest::Basket(_) => adding.len() <= BASKET_HOLDS,
            Dest::Thing(_) => adding.len() <= 1,
            Dest::Piece(p, inside) => {
                let piece = &scene.pieces[p];
                let mut load = start.contents(scene, p, inside);
                load.extend(adding);
                pack_on(piece, inside, start.arm_on(p).is_some(), &load).is_some()
            }
        };
        if !ok {
            return false;
        }
    }
    true
}

/// The kinds masks of `size` kinds the team has (its kinds as bits).
pub fn masks_of(team_bits: u8, size: usize) -> Vec<u8> {
    (1u8..8)
        .filter(|m| m & !team_bits == 0 && m.count_ones() as usize == size)
        .collect()
}
