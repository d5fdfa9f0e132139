//! A task's start in its scene: the team (how many of each robot kind), where each robot
//! starts (fixed arms on counters, quadrotors landed on a table or the floor, legged
//! robots on the floor) and where each movable thing starts, packed on a surface or in
//! a container it fits, and the room a thing fits on a holder (`region`, `pack`),
//! which the goals use too.

use coherent_core::RobotKind;
use coherent_core::geometry::{Lid, RobotSpecs, WALL, wall_of};

use crate::catalogue::{COUNTER, MAX_FOOTPRINT};
use crate::request::KINDS;
use crate::rng::Rng;
use crate::scene::{Piece, Scene, round};

/// Things keep this far from each other and from a holder's edges (m).
const GAP: f32 = 0.06;
/// A landable top keeps this much of its +x end free: the quadrotor's landing pad.
pub const PAD: f32 = 1.0;
/// What a fixed arm reaches on its counter, relative to the counter's bottom centre:
/// the left metre less its edges, in front of the strip at the back where the arm
/// stands (`[x0, z0, x1, z1]`). Its far corner is 1.13 m from the shoulder; the arm
/// reaches 1.25 m.
const ARM_REGION: [f32; 4] = [-0.85, -0.45, -0.06, 0.19];
/// A fixed arm stands this far left of its counter's middle and in from its back.
const ARM_LEFT: f32 = 0.2;
const ARM_BACK_IN: f32 = 0.175;
/// Things are placed this far above what holds them and drop into place as the world
/// settles.
const DROP: f32 = 0.002;
/// The chance that a quadrotor starts on a landable top rather than a floor.
const ON_TOP: f64 = 0.5;
/// How much likelier a thing starts in its own room than elsewhere, and how much less
/// likely on a high shelf no robot reaches.
const HOME_WEIGHT: f64 = 4.0;
const OUT_OF_REACH_WEIGHT: f64 = 0.3;

/// Where a quadrotor starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Landing {
    /// On the landing pad of a piece (index into [`Scene::pieces`]).
    Top(usize),
    /// On the floor of a room, at a spot.
    Floor(usize, [f32; 2]),
}

/// Where a robot starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pose {
    /// A fixed arm on a counter (index into [`Scene::pieces`]).
    Arm(usize),
    /// A quadrotor, landed, with its basket's node id.
    Quad { basket: i64, on: Landing },
    /// A legged robot in a room, at a spot.
    Dog(usize, [f32; 2]),
}

/// A robot of the team where it starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed {
    pub id: i64,
    pub kind: RobotKind,
    pub pose: Pose,
}

/// Where a movable thing starts: the piece it is on or in, and its bottom centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThingAt {
    pub piece: usize,
    pub inside: bool,
    pub pos: [f32; 3],
}

/// A task's start.
#[derive(Clone, Debug)]
pub struct Start {
    /// Robots of each kind, in [`KINDS`] order.
    pub team: [usize; 3],
    /// In the graph's order: quadrotors, legged robots, arms.
    pub robots: Vec<Placed>,
    /// One per thing of the scene, in the scene's order.
    pub things: Vec<ThingAt>,
}

impl Start {
    /// A start for a team of `team` robots (per kind) in `scene`, or `None` when the
    /// scene has too few counters, spots or room on its holders for it.
    pub fn draw(scene: &Scene, team: [usize; 3], rng: &mut Rng) -> Option<Start> {
        let [nq, nd, na] = team;
        let mut counters = scene.counters();
        if counters.len() < na {
            return None;
        }
        rng.shuffle(&mut counters);
        counters.truncate(na);
        counters.sort_unstable();
        let mut spots: Vec<(usize, [f32; 2])> = scene
            .rooms
            .iter()
            .enumerate()
            .flat_map(|(r, room)| room.spots.iter().map(move |s| (r, *s)))
            .collect();
        rng.shuffle(&mut spots);
        // A quadrotor starts on the floor, or on the pad of a counter with an arm, which
        // loads and unloads it there.
        let mut tops: Vec<usize> = counters.clone();
        rng.shuffle(&mut tops);
        let mut next = scene.next_id;
        let mut robots = Vec::new();
        for _ in 0..nq {
            let on = match tops.pop().filter(|_| rng.chance(ON_TOP)) {
                Some(p) => Landing::Top(p),
                None => {
                    let (r, at) = spots.pop()?;
                    Landing::Floor(r, at)
                }
            };
            robots.push(Placed {
                id: next,
                kind: RobotKind::Quadrotor,
                pose: Pose::Quad {
                    basket: next + 1,
                    on,
                },
            });
            next += 2;
        }
        for _ in 0..nd {
            let (r, at) = spots.pop()?;
            robots.push(Placed {
                id: next,
                kind: RobotKind::RobotDog,
                pose: Pose::Dog(r, at),
            });
            next += 1;
        }
        for &p in &counters {
            robots.push(Placed {
                id: next,
                kind: RobotKind::RobotArm,
                pose: Pose::Arm(p),
            });
            next += 1;
        }
        let things = place_things(scene, &counters, rng)?;
        Some(Start {
            team,
            robots,
            things,
        })
    }

    /// The fixed arm on piece `p`, if this start has one there.
    pub fn arm_on(&self, p: usize) -> Option<i64> {
        self.robots
            .iter()
            .find(|r| r.pose == Pose::Arm(p))
            .map(|r| r.id)
    }

    /// The things that start on (`inside` false) or in piece `p`, with their sizes.
    pub fn contents(&self, scene: &Scene, p: usize, inside: bool) -> Vec<[f32; 3]> {
        self.things
            .iter()
            .zip(&scene.things)
            .filter(|(at, _)| at.piece == p && at.inside == inside)
            .map(|(_, t)| t.kind.size)
            .collect()
    }

    /// The team's size.
    pub fn size(&self) -> usize {
        self.team.iter().sum()
    }
}

/// Where each thing starts: a holder drawn by weight (its own room likelier, a high
/// shelf no robot reaches less likely, a counter only when an arm stands on it), the
/// first drawn it still fits on or in.
fn place_things(scene: &Scene, counters: &[usize], rng: &mut Rng) -> Option<Vec<ThingAt>> {
    // A closed cupboard starts empty: the physics turns a front door into its
    // cupboard as it opens (coherent-sim's `LID_OPEN_ANGLE`), and the door would push
    // what stands inside out through the front; once open it stands aside.
    let holders: Vec<(usize, bool)> = (0..scene.pieces.len())
        .flat_map(|p| {
            let piece = &scene.pieces[p];
            let k = piece.kind;
            let on = (k.surface && (!k.arm || counters.contains(&p))).then_some((p, false));
            let swept = k.lid == Lid::Front && piece.closed;
            let inside = (k.container && !swept).then_some((p, true));
            on.into_iter().chain(inside)
        })
        .collect();
    let high = high_pieces(scene);
    let mut loads: Vec<Vec<[f32; 3]>> = vec![Vec::new(); holders.len()];
    let mut out = Vec::with_capacity(scene.things.len());
    for t in &scene.things {
        let mut weights: Vec<f64> = holders
            .iter()
            .map(|&(p, _)| {
                let piece = &scene.pieces[p];
                let mut w = if piece.room == t.home {
                    HOME_WEIGHT
                } else {
                    1.0
                };
                if high[p] && !piece.kind.arm {
                    w *= OUT_OF_REACH_WEIGHT;
                }
                w
            })
            .collect();
        let mut at = None;
        while weights.iter().any(|w| *w > 0.0) {
            let h = rng.weighted(&weights);
            weights[h] = 0.0;
            let (p, inside) = holders[h];
            let piece = &scene.pieces[p];
            let mut load = loads[h].clone();
            load.push(t.kind.size);
            if let Some(spots) = pack_on(piece, inside, counters.contains(&p), &load) {
                let rel = spots[load.len() - 1];
                let y = if inside {
                    piece.pos[1] + wall_of(piece.kind.size[1])
                } else {
                    piece.top()
                } + DROP;
                at = Some(ThingAt {
                    piece: p,
                    inside,
                    pos: [
                        round(piece.pos[0] + rel[0]),
                        round(y),
                        round(piece.pos[2] + rel[1]),
                    ],
                });
                loads[h] = load;
                break;
            }
        }
        out.push(at?);
    }
    Some(out)
}

/// Where things go on (or, `inside`, in) piece `p`, relative to its bottom centre, as
/// `[x0, z0, x1, z1]`: inside its walls; on a counter with an arm, what the arm reaches;
/// on a landable top, all but the landing pad; elsewhere the top less its edges.
pub fn region(p: &Piece, inside: bool, arm_here: bool) -> [f32; 4] {
    let [w, h, d] = p.kind.size;
    let (hx, hz) = (w / 2.0, d / 2.0);
    if inside {
        let m = wall_of(h) + GAP / 2.0;
        return [-hx + m, -hz + m, hx - m, hz - m];
    }
    if arm_here {
        return ARM_REGION;
    }
    let pad = if p.kind.landable { PAD } else { 0.0 };
    [-hx + GAP, -hz + GAP, hx - GAP - pad, hz - GAP]
}

/// Where things go on or in piece `p` at a start: [`region`], packed by [`pack`] from
/// the side the robots work from.
pub fn pack_on(
    p: &Piece,
    inside: bool,
    arm_here: bool,
    sizes: &[[f32; 3]],
) -> Option<Vec<[f32; 2]>> {
    pack(region(p, inside, arm_here), p.facing, sizes)
}

/// Packs things of `sizes` in rows across `region`, the first row along the side that
/// faces the room (`facing` -1: the -z side), each row further in, left to right; the
/// middle of each relative to the holder, or `None` when they do not all fit.
pub fn pack(region: [f32; 4], facing: f32, sizes: &[[f32; 3]]) -> Option<Vec<[f32; 2]>> {
    let [x0, z0, x1, z1] = region;
    let (mut x, mut depth, mut row) = (x0, 0.0f32, 0.0f32);
    let mut out = Vec::with_capacity(sizes.len());
    for s in sizes {
        if x + s[0] > x1 + 1e-4 {
            x = x0;
            depth += row + GAP;
            row = 0.0;
        }
        if x + s[0] > x1 + 1e-4 || depth + s[2] > (z1 - z0) + 1e-4 {
            return None;
        }
        let z = if facing < 0.0 {
            z0 + depth + s[2] / 2.0
        } else {
            z1 - depth - s[2] / 2.0
        };
        out.push([x + s[0] / 2.0, z]);
        x += s[0] + GAP;
        row = row.max(s[2]);
    }
    Some(out)
}

/// Where a fixed arm stands on counter `p`: left of its middle, at the back.
pub fn arm_spot(p: &Piece) -> [f32; 3] {
    [
        round(p.pos[0] - ARM_LEFT),
        round(p.top()),
        round(p.pos[2] + p.kind.size[2] / 2.0 - ARM_BACK_IN),
    ]
}

/// Where a quadrotor starts on the landing pad of piece `p`: the middle of the pad.
pub fn pad_spot(p: &Piece) -> [f32; 3] {
    [
        round(p.pos[0] + p.kind.size[0] / 2.0 - PAD / 2.0),
        round(p.top()),
        round(p.pos[2]),
    ]
}

/// Whether a thing of `size` fits inside the container piece at all, under its rim
/// and its lid.
pub fn fits_inside(p: &Piece, size: [f32; 3]) -> bool {
    let [w, h, d] = p.kind.size;
    let t = wall_of(h);
    let lids = match p.kind.lid {
        Lid::Front => 2.0,
        Lid::Top => 1.0,
        Lid::None => 0.0,
    };
    size[0] <= w - 2.0 * t - GAP && size[2] <= d - 2.0 * t - GAP && size[1] <= h - t - lids * t
}

/// The inside of a movable container of `size` fits a thing of `thing`: its footprint
/// within the walls (a thing taller than the rim pokes out, and is still in it).
pub fn fits_in_thing(size: [f32; 3], thing: [f32; 3]) -> bool {
    let t = wall_of(size[1]);
    thing[0] <= size[0] - 2.0 * t - 0.03 && thing[2] <= size[2] - 2.0 * t - 0.03
}

/// The counter a fixed arm stands on is as wide as [`COUNTER`]; things the basket takes
/// are at most [`MAX_FOOTPRINT`]: two side by side inside its walls.
pub const BASKET_HOLDS: usize = 2;
const _: () = assert!(2.0 * MAX_FOOTPRINT + GAP <= 0.40 && COUNTER[0] >= 2.0 && WALL > 0.0);

/// The kinds of a team, in [`KINDS`] order, that it has at least one robot of.
pub fn kinds_of(team: [usize; 3]) -> Vec<RobotKind> {
    KINDS
        .iter()
        .zip(team)
        .filter(|(_, n)| *n > 0)
        .map(|(k, _)| *k)
        .collect()
}

/// Which pieces are high for the legged robot under the geometric rules: a surface
/// whose top plus the scene's tallest thing is above its hand, a container that is no
/// surface judged by its inner floor (`docs/task-format.md`, "Geometric rules").
pub fn high_pieces(scene: &Scene) -> Vec<bool> {
    let hand = RobotSpecs::default().dog_max_height();
    let tallest = scene
        .things
        .iter()
        .map(|t| t.kind.size[1])
        .fold(0.0f32, f32::max);
    scene
        .pieces
        .iter()
        .map(|p| {
            let h = p.kind.size[1];
            let place = if p.kind.surface { h } else { wall_of(h) };
            place + tallest > hand
        })
        .collect()
}
