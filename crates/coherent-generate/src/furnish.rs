//! Furnishing a laid-out scene: furniture in bands along each room's back and front
//! walls, clear of the doors' swing and approach and of the flight of stairs; the free
//! floor in the middle where robots start; the movable things that belong to the
//! scene.

use crate::catalogue::{self, FurnitureKind, LANDING, STAIR_HALL, THINGS, Wall};
use crate::rng::Rng;
use crate::scene::{Crowded, Piece, Scene, Thing, round};

/// Furniture keeps this far (m) off the wall it stands against.
const WALL_GAP: f32 = 0.15;
/// Pieces side by side keep this far apart: a front door swung open past square
/// (to 109 degrees) reaches this far to its left.
const PIECE_GAP: f32 = 0.4;
/// Along a wall, nothing stands within this of a door's middle (its opening, the
/// panel's swing and the robots' way through), nor this far from a side wall that has a
/// door (the door's swing into the room).
const DOOR_ZONE: f32 = 1.3;
const SIDE_DOOR_ZONE: f32 = 1.6;
/// Furniture stays this far from the west wall of the stair hall and of the landing:
/// the flight, the legged robot lining up before its foot and past its head, the
/// quadrotor's climb.
const FLIGHT_ZONE: f32 = 2.0;
/// Robots start on a grid this fine, this far from the walls and the furniture (a
/// legged robot working on a piece stands 0.42 m from it, with room for its body
/// beside a robot at a spot), and this far from a door along and across its wall.
const SPOT_GRID: f32 = 1.3;
const SPOT_WALL: f32 = 0.9;
const SPOT_FURNITURE: f32 = 1.3;
const SPOT_DOOR_ALONG: f32 = 2.2;
const SPOT_DOOR_ACROSS: f32 = 2.2;
/// ... and off the flight: its strip and its approaches.
const SPOT_FLIGHT_X: f32 = 1.9;
const SPOT_LANDING_Z: f32 = 2.4;
/// The chance a lidded container starts closed.
const CLOSED_LID: f64 = 0.7;
/// The most pieces besides counters in a room.
const MOST_PIECES: usize = 4;
/// Things per room, least and most.
const THINGS_PER_ROOM: (usize, usize) = (2, 3);
/// The tallest thing of every scene is at least this tall, so that a counter (1.25 m)
/// is out of the legged robot's reach (1.34 m) under the geometric rules.
const TALLEST: f32 = 0.12;

/// A stretch of wall furniture may stand along, `[from, to]` in x.
type Stretch = [f32; 2];

/// Places each room's furniture (`counters[r]` counters a fixed arm can stand on, then
/// pieces of its kind) and finds its robots' spots. A counter that does not fit names
/// its column, to be widened.
pub(crate) fn furnish(
    scene: &mut Scene,
    rng: &mut Rng,
    counters: &[usize],
    id: &mut impl FnMut() -> i64,
) -> Result<(), Crowded> {
    for (r, &count) in counters.iter().enumerate() {
        let mut wanted: Vec<&'static FurnitureKind> = Vec::new();
        let kind = scene.rooms[r].kind;
        let counter = kind
            .furniture
            .iter()
            .filter_map(|f| catalogue::furniture(f))
            .find(|f| f.arm)
            .or_else(|| catalogue::furniture("kitchen counter"));
        for _ in 0..count {
            wanted.extend(counter);
        }
        let mut others: Vec<&'static FurnitureKind> = kind
            .furniture
            .iter()
            .filter_map(|f| catalogue::furniture(f))
            .filter(|f| !f.arm)
            .collect();
        // The first pieces of a kind's list are the likeliest (a kitchen's fridge).
        others.retain(|_| rng.chance(0.75));
        others.truncate(MOST_PIECES);
        let (mut back, mut front) = stretches(scene, r);
        let room = &scene.rooms[r];
        let mut placed = Vec::new();
        for f in wanted.iter().chain(&others) {
            let w = f.size[0];
            let slot = if f.wall == Wall::Either {
                take(&mut front, w)
                    .map(|x| (x, 1.0))
                    .or_else(|| take(&mut back, w).map(|x| (x, -1.0)))
            } else {
                take(&mut back, w).map(|x| (x, -1.0))
            };
            let Some((x, facing)) = slot else {
                if f.arm {
                    return Err(Crowded::Column(room.cell.0));
                }
                continue;
            };
            let d = f.size[2];
            let z = if facing < 0.0 {
                room.max[1] - WALL_GAP - d / 2.0
            } else {
                room.min[1] + WALL_GAP + d / 2.0
            };
            placed.push(Piece {
                id: 0,
                kind: f,
                room: r,
                pos: [round(x), room.level, round(z)],
                facing,
                closed: f.lid != coherent_core::geometry::Lid::None && rng.chance(CLOSED_LID),
            });
        }
        // Ids in the order the room lists them: counters first, then left to right.
        placed.sort_by(|a, b| {
            (!a.kind.arm, a.facing > 0.0, a.pos[0])
                .partial_cmp(&(!b.kind.arm, b.facing > 0.0, b.pos[0]))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        for mut p in placed {
            p.id = id();
            scene.pieces.push(p);
        }
        let spots = spots(scene, r);
        scene.rooms[r].spots = spots;
    }
    Ok(())
}

/// Where along the back and the front wall of room `r` furniture may stand: the wall
/// less its ends where a side wall has a door (or the flight runs), less each door's
/// zone in it.
fn stretches(scene: &Scene, r: usize) -> (Vec<Stretch>, Vec<Stretch>) {
    let room = &scene.rooms[r];
    let on_wall = |along_x: bool, at: f32| {
        scene
            .doors
            .iter()
            .filter(move |d| d.rooms.contains(&r) && d.along_x == along_x)
            .filter(move |d| (if along_x { d.center[1] } else { d.center[0] } - at).abs() < 1e-3)
    };
    let mut west = if on_wall(false, room.min[0]).next().is_some() {
        SIDE_DOOR_ZONE
    } else {
        WALL_GAP
    };
    let east = if on_wall(false, room.max[0]).next().is_some() {
        SIDE_DOOR_ZONE
    } else {
        WALL_GAP
    };
    if [STAIR_HALL.name, LANDING.name].contains(&room.kind.name) && scene.flight.is_some() {
        west = west.max(FLIGHT_ZONE);
    }
    let whole: Stretch = [room.min[0] + west, room.max[0] - east];
    let cut = |at: f32| -> Vec<Stretch> {
        let mut out = vec![whole];
        for d in on_wall(true, at) {
            let (a, b) = (d.center[0] - DOOR_ZONE, d.center[0] + DOOR_ZONE);
            out = out
                .into_iter()
                .flat_map(|[x0, x1]| [[x0, x1.min(a)], [x0.max(b), x1]])
                .filter(|[x0, x1]| x1 > x0)
                .collect();
        }
        out
    };
    (cut(room.max[1]), cut(room.min[1]))
}

/// The middle of the first stretch `w` fits in, taken from it with the gap after it.
fn take(stretches: &mut [Stretch], w: f32) -> Option<f32> {
    let s = stretches.iter_mut().find(|[a, b]| b - a >= w)?;
    let x = s[0] + w / 2.0;
    s[0] += w + PIECE_GAP;
    Some(x)
}

/// The robots' start spots in room `r`: a grid over its free middle, clear of the
/// furniture bands, the doors and the flight.
fn spots(scene: &Scene, r: usize) -> Vec<[f32; 2]> {
    let room = &scene.rooms[r];
    let band = |facing: f32| {
        scene
            .pieces
            .iter()
            .filter(|p| p.room == r && p.facing == facing)
            .map(|p| p.kind.size[2] + WALL_GAP)
            .fold(0.0f32, f32::max)
    };
    let (x0, x1) = (room.min[0] + SPOT_WALL, room.max[0] - SPOT_WALL);
    let z0 = room.min[1] + SPOT_WALL.max(band(1.0) + SPOT_FURNITURE);
    let z1 = room.max[1] - SPOT_WALL.max(band(-1.0) + SPOT_FURNITURE);
    if x1 < x0 || z1 < z0 {
        return Vec::new();
    }
    let (nx, nz) = (
        ((x1 - x0) / SPOT_GRID).floor() as usize + 1,
        ((z1 - z0) / SPOT_GRID).floor() as usize + 1,
    );
    // The grid centred in the free middle.
    let (ox, oz) = (
        x0 + (x1 - x0 - (nx - 1) as f32 * SPOT_GRID) / 2.0,
        z0 + (z1 - z0 - (nz - 1) as f32 * SPOT_GRID) / 2.0,
    );
    let flight = scene.flight.is_some();
    let mut out = Vec::new();
    for k in 0..nz {
        for i in 0..nx {
            let p = [
                round(ox + i as f32 * SPOT_GRID),
                round(oz + k as f32 * SPOT_GRID),
            ];
            let near_door = scene
                .doors
                .iter()
                .filter(|d| d.rooms.contains(&r))
                .any(|d| {
                    let (along, across) = if d.along_x {
                        ((p[0] - d.center[0]).abs(), (p[1] - d.center[1]).abs())
                    } else {
                        ((p[1] - d.center[1]).abs(), (p[0] - d.center[0]).abs())
                    };
                    along < SPOT_DOOR_ALONG && across < SPOT_DOOR_ACROSS
                });
            let near_flight = flight
                && p[0] < room.min[0] + SPOT_FLIGHT_X
                && (room.kind.name == STAIR_HALL.name
                    || (room.kind.name == LANDING.name && p[1] < room.min[1] + SPOT_LANDING_Z));
            if !near_door && !near_flight {
                out.push(p);
            }
        }
    }
    out
}

/// The movable things of the scene: two or three of each room's kinds (none twice in a
/// scene), and one tall enough that counters are high.
pub(crate) fn things(scene: &mut Scene, rng: &mut Rng, id: &mut impl FnMut() -> i64) {
    let mut used: Vec<&str> = Vec::new();
    for r in 0..scene.rooms.len() {
        let kind = scene.rooms[r].kind.name;
        let mut kinds: Vec<&'static catalogue::ThingKind> = THINGS
            .iter()
            .filter(|t| t.rooms.contains(&kind) && !used.contains(&t.name))
            .collect();
        rng.shuffle(&mut kinds);
        let n = rng.between(THINGS_PER_ROOM.0, THINGS_PER_ROOM.1);
        for t in kinds.into_iter().take(n) {
            used.push(t.name);
            scene.things.push(Thing {
                id: id(),
                kind: t,
                home: r,
            });
        }
    }
    let tallest = scene
        .things
        .iter()
        .map(|t| t.kind.size[1])
        .fold(0.0, f32::max);
    if tallest < TALLEST
        && let Some(t) = THINGS
            .iter()
            .find(|t| t.size[1] >= TALLEST && !used.contains(&t.name))
    {
        scene.things.push(Thing {
            id: id(),
            kind: t,
            home: 0,
        });
    }
}
