//! A scene: rooms on one or two storeys joined by doors (some closed) and a flight of
//! stairs, furniture against the walls, and the movable things that belong to it. A
//! scene is the same for every task drawn in it; each task draws where its robots and
//! things start (`start.rs`).
//!
//! Rooms lie on a grid (columns of one width, rows of one depth), so that neighbours
//! share a whole wall; the doors join them along a random spanning tree of the grid and
//! a few more. A second storey sits behind the stair hall: the flight runs along the
//! hall's west wall up to its back wall, where the landing begins, and the upper rooms
//! lie over the rows behind (`docs/physics.md`, "Storeys and stairs": the flight inside
//! the lower room, open to the sky, its head on the landing's wall, 3.0 m up a 4.5 m
//! run). Furniture stands in bands along the back and front walls (`furnish`),
//! clear of the doors' swing and approach, so that the middle of every room is free
//! floor for the robots to walk, start and land on.

use crate::catalogue::{
    self, FurnitureKind, LANDING, RoomKind, STAIR_HALL, THINGS, ThingKind, Wall,
};
use crate::request::{KnobError, Span, knob};
use crate::rng::{Rng, seed_of};

/// A door's opening (m): wider than the quadrotor's frame with room to spare.
pub const DOOR_WIDTH: f32 = 1.3;
pub const DOOR_HEIGHT: f32 = 2.3;
/// The upper storey's floor (m above the lower one): above the lower walls (2.6 m) and
/// their slab.
pub const UPPER_LEVEL: f32 = 3.0;
/// The flight of stairs: its run along the stair hall's west wall, its width, and how
/// far its middle line is from that wall.
pub const FLIGHT_RUN: f32 = 4.5;
pub const FLIGHT_WIDTH: f32 = 1.0;
pub const FLIGHT_IN: f32 = 0.55;
/// The chance of a door beyond the spanning tree between two neighbouring rooms.
const EXTRA_DOOR: f64 = 0.3;

/// A room.
#[derive(Clone, Debug)]
pub struct Room {
    pub id: i64,
    /// Its floor node.
    pub floor: i64,
    pub kind: &'static RoomKind,
    /// Its class name: the kind's name, numbered when the scene has two of a kind.
    pub name: String,
    pub min: [f32; 2],
    pub max: [f32; 2],
    pub level: f32,
    /// Its place on the grid: column, row (rows of the upper storey counted on from the
    /// stair hall's).
    pub cell: (usize, usize),
    /// Where robots may start on its floor: free floor, clear of doors, furniture and
    /// stairs, 1.3 m apart.
    pub spots: Vec<[f32; 2]>,
}

/// A door between two rooms of one storey.
#[derive(Clone, Debug)]
pub struct Door {
    pub id: i64,
    /// Indices into [`Scene::rooms`].
    pub rooms: [usize; 2],
    pub center: [f32; 2],
    /// The wall runs along x (the rooms are one behind the other).
    pub along_x: bool,
    pub closed: bool,
}

/// The flight of stairs between the stair hall and the landing.
#[derive(Clone, Debug)]
pub struct Flight {
    pub id: i64,
    /// The stair hall, then the landing (indices into [`Scene::rooms`]).
    pub rooms: [usize; 2],
    pub foot: [f32; 2],
    pub head: [f32; 2],
}

/// A piece of furniture where it stands.
#[derive(Clone, Debug)]
pub struct Piece {
    pub id: i64,
    pub kind: &'static FurnitureKind,
    pub room: usize,
    /// Bottom centre.
    pub pos: [f32; 3],
    /// Which way the side the robots work from faces: -1 towards -z (it stands against
    /// the back wall), +1 towards +z (against the front wall).
    pub facing: f32,
    /// A container with a lid or a door: whether it starts closed.
    pub closed: bool,
}

impl Piece {
    /// Its top above its room's floor... and above the ground.
    pub fn top(&self) -> f32 {
        self.pos[1] + self.kind.size[1]
    }
}

/// A movable thing of the scene (where it starts is the task's).
#[derive(Clone, Debug)]
pub struct Thing {
    pub id: i64,
    pub kind: &'static ThingKind,
    /// The room it belongs to, where a start puts it most often.
    pub home: usize,
}

/// A scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub index: usize,
    pub rooms: Vec<Room>,
    pub doors: Vec<Door>,
    pub flight: Option<Flight>,
    pub pieces: Vec<Piece>,
    pub things: Vec<Thing>,
    /// The first id no node of the scene has: robots and baskets are numbered from it.
    pub next_id: i64,
}

/// What a scene must hold.
#[derive(Clone, Copy, Debug)]
pub struct SceneRequest {
    pub rooms: Span,
    pub upstairs: f64,
    pub closed: f64,
    /// Counters a fixed arm can stand on: at least the most arms a team has.
    pub counters: usize,
    /// Floor spots for the most quadrotors and legged robots a team has.
    pub spots: usize,
}

/// The grid the rooms lie on: column edges along x and row edges along z.
#[derive(Clone, Debug)]
struct Grid {
    xs: Vec<f32>,
    zs: Vec<f32>,
}

impl Grid {
    fn rect(&self, (i, j): (usize, usize)) -> ([f32; 2], [f32; 2]) {
        ([self.xs[i], self.zs[j]], [self.xs[i + 1], self.zs[j + 1]])
    }
}

/// Draws of a scene's rooms before it gives up.
const SCENE_DRAWS: usize = 16;

/// Tries to lay a scene out this many times (each with a wider room where a counter
/// did not fit) before it gives up.
const LAYOUT_TRIES: usize = 6;

impl Scene {
    /// Scene `index` of a set seeded `seed`. A draw of rooms too few (or too small) for
    /// the largest team is drawn again, up to 16 times (`SCENE_DRAWS`), from the scene's
    /// own stream, so a scene that fits at the first draw is the one it always was.
    pub fn generate(index: usize, seed: u64, req: &SceneRequest) -> Result<Scene, KnobError> {
        let mut rng = Rng::new(seed_of(seed, "scene", index as u64));
        for _ in 0..SCENE_DRAWS {
            let n = rng.between(req.rooms.lo, req.rooms.hi);
            let upper = if n >= 4 && rng.chance(req.upstairs) {
                rng.between(2, n / 2)
            } else {
                0
            };
            let lower = n - upper;
            if req.counters > 2 * lower {
                continue;
            }
            let plan = Plan::draw(&mut rng, lower, upper, req);
            let mut widen = vec![0.0f32; plan.columns];
            for _ in 0..LAYOUT_TRIES {
                let mut r = rng.clone();
                match plan.lay_out(&mut r, index, &widen, req) {
                    Ok(scene) => return Ok(scene),
                    Err(Crowded::Column(c)) => widen[c] += crate::catalogue::COUNTER[0] + 0.5,
                    Err(Crowded::Spots) => {
                        for w in &mut widen {
                            *w += 1.5;
                        }
                    }
                }
            }
        }
        knob(
            "--rooms",
            format!(
                "scene {index}: no layout in {SCENE_DRAWS} draws of {}-{} rooms holds {} counters with an arm (at most two a room downstairs) and floor for {} robots",
                req.rooms.lo, req.rooms.hi, req.counters, req.spots
            ),
        )
    }

    /// Index of the room whose node id is `id`.
    pub fn room_of_id(&self, id: i64) -> Option<usize> {
        self.rooms.iter().position(|r| r.id == id)
    }

    /// The doors (and the flight) between each two rooms on the shortest way.
    pub fn hops(&self) -> Vec<Vec<usize>> {
        let n = self.rooms.len();
        let mut links: Vec<[usize; 2]> = self.doors.iter().map(|d| d.rooms).collect();
        links.extend(self.flight.iter().map(|f| f.rooms));
        (0..n)
            .map(|from| {
                let mut dist = vec![usize::MAX; n];
                dist[from] = 0;
                let mut queue = std::collections::VecDeque::from([from]);
                while let Some(r) = queue.pop_front() {
                    for [a, b] in &links {
                        let other = if *a == r {
                            *b
                        } else if *b == r {
                            *a
                        } else {
                            continue;
                        };
                        if dist[other] == usize::MAX {
                            dist[other] = dist[r] + 1;
                            queue.push_back(other);
                        }
                    }
                }
                dist
            })
            .collect()
    }

    /// The counters a fixed arm can stand on (indices into [`Scene::pieces`]).
    pub fn counters(&self) -> Vec<usize> {
        (0..self.pieces.len())
            .filter(|&p| self.pieces[p].kind.arm)
            .collect()
    }
}

/// Why a layout failed: a column too narrow for its counters, or too little floor for
/// the robots.
pub(crate) enum Crowded {
    Column(usize),
    Spots,
}

/// The drawn plan of a scene before it has sizes: each room's kind and cell, the
/// counters each room gets, the doors.
struct Plan {
    columns: usize,
    /// Kind, cell, counters, storey (upper or not).
    rooms: Vec<(&'static RoomKind, (usize, usize), usize, bool)>,
    /// Pairs of room indices joined by a door, and whether it starts closed.
    doors: Vec<(usize, usize, bool)>,
    /// Widths of the columns and depths of the rows before widening.
    widths: Vec<f32>,
    depths: Vec<f32>,
    upstairs: bool,
}

impl Plan {
    fn draw(rng: &mut Rng, lower: usize, upper: usize, req: &SceneRequest) -> Plan {
        let columns = (lower as f32).sqrt().ceil() as usize;
        let mut cells: Vec<(usize, usize)> =
            (0..lower).map(|k| (k % columns, k / columns)).collect();
        let upstairs = upper > 0;
        let kinds = lower_kinds(rng, lower, req.counters, upstairs);
        let counters = spread_counters(&kinds, req.counters);
        let mut rooms: Vec<(&'static RoomKind, (usize, usize), usize, bool)> = kinds
            .iter()
            .zip(&cells)
            .zip(&counters)
            .map(|((k, c), n)| (*k, *c, *n, false))
            .collect();
        if upstairs {
            // Behind the stair hall (cell 0, 0): the landing, then the others breadth
            // first over the cells of the rows behind.
            let mut up = vec![(0usize, 1usize)];
            let mut i = 0;
            while up.len() < upper && i < up.len() {
                let (x, z) = up[i];
                let mut next = vec![(x + 1, z), (x, z + 1)];
                if x > 0 {
                    next.push((x - 1, z));
                }
                if z > 1 {
                    next.push((x, z - 1));
                }
                rng.shuffle(&mut next);
                for c in next {
                    if c.0 < columns.max(2) && !up.contains(&c) && up.len() < upper {
                        up.push(c);
                    }
                }
                i += 1;
            }
            let mut names: Vec<&'static RoomKind> =
                catalogue::ROOMS.iter().filter(|k| k.upstairs).collect();
            rng.shuffle(&mut names);
            for (k, c) in up.iter().enumerate() {
                let kind = if k == 0 {
                    &LANDING
                } else {
                    names[(k - 1) % names.len()]
                };
                rooms.push((kind, *c, 0, true));
            }
            cells.extend(up);
        }
        let ncols = rooms.iter().map(|r| r.1.0 + 1).max().unwrap_or(1);
        let nrows = rooms.iter().map(|r| r.1.1 + 1).max().unwrap_or(1);
        let mut widths = vec![0.0f32; ncols];
        let mut depths = vec![0.0f32; nrows];
        for (kind, (x, z), _, _) in &rooms {
            widths[*x] = widths[*x].max(rng.decimetres(kind.width.0, kind.width.1));
            depths[*z] = depths[*z].max(rng.decimetres(kind.depth.0, kind.depth.1));
        }
        let doors = draw_doors(rng, &rooms, req.closed);
        Plan {
            columns: ncols,
            rooms,
            doors,
            widths,
            depths,
            upstairs,
        }
    }

    /// The scene with sizes: the grid (columns widened by `widen`), the rooms, doors
    /// and flight, the furniture in its bands and the things.
    fn lay_out(
        &self,
        rng: &mut Rng,
        index: usize,
        widen: &[f32],
        req: &SceneRequest,
    ) -> Result<Scene, Crowded> {
        let edges = |sizes: &[f32]| {
            let mut e = vec![0.0f32];
            for s in sizes {
                e.push(round(e[e.len() - 1] + s));
            }
            e
        };
        let widths: Vec<f32> = self.widths.iter().zip(widen).map(|(w, x)| w + x).collect();
        let grid = Grid {
            xs: edges(&widths),
            zs: edges(&self.depths),
        };
        let mut next = 0i64;
        let mut id = || {
            next += 1;
            next - 1
        };
        let mut seen: Vec<&str> = Vec::new();
        let mut rooms = Vec::new();
        for (kind, cell, _, up) in &self.rooms {
            let (min, max) = grid.rect(*cell);
            let count = seen.iter().filter(|n| **n == kind.name).count();
            seen.push(kind.name);
            let name = if count == 0 {
                kind.name.to_owned()
            } else {
                format!("{} {}", kind.name, count + 1)
            };
            rooms.push(Room {
                id: id(),
                floor: id(),
                kind,
                name,
                min,
                max,
                level: if *up { UPPER_LEVEL } else { 0.0 },
                cell: *cell,
                spots: Vec::new(),
            });
        }
        let doors: Vec<Door> = self
            .doors
            .iter()
            .map(|&(a, b, closed)| door(id(), &rooms, a, b, closed))
            .collect();
        let flight = self.upstairs.then(|| {
            let (hall, landing) = (
                &rooms[0],
                &rooms[rooms.len() - (self.rooms.iter().filter(|r| r.3).count())],
            );
            let x = round(hall.min[0] + FLIGHT_IN);
            Flight {
                id: id(),
                rooms: [
                    0,
                    rooms.iter().position(|r| r.id == landing.id).unwrap_or(0),
                ],
                foot: [x, round(hall.max[1] - FLIGHT_RUN)],
                head: [x, hall.max[1]],
            }
        });
        let mut scene = Scene {
            name: format!("scene-{index:03}"),
            index,
            rooms,
            doors,
            flight,
            pieces: Vec::new(),
            things: Vec::new(),
            next_id: 0,
        };
        let counters: Vec<usize> = self.rooms.iter().map(|r| r.2).collect();
        furnish(&mut scene, rng, &counters, &mut id)?;
        let spots: usize = scene.rooms.iter().map(|r| r.spots.len()).sum();
        if spots < req.spots {
            return Err(Crowded::Spots);
        }
        things(&mut scene, rng, &mut id);
        scene.next_id = id();
        Ok(scene)
    }
}

/// Kinds for the rooms downstairs: enough that can hold a counter first (a counter with
/// an arm belongs in a kitchen or a workshop), then any, each kind once while there
/// are kinds left; the stair hall first when there is a second storey.
fn lower_kinds(
    rng: &mut Rng,
    lower: usize,
    counters: usize,
    upstairs: bool,
) -> Vec<&'static RoomKind> {
    let arm_kind = |k: &RoomKind| {
        k.furniture
            .iter()
            .any(|f| catalogue::furniture(f).is_some_and(|f| f.arm))
    };
    let mut with: Vec<&'static RoomKind> =
        catalogue::ROOMS.iter().filter(|k| arm_kind(k)).collect();
    let mut without: Vec<&'static RoomKind> =
        catalogue::ROOMS.iter().filter(|k| !arm_kind(k)).collect();
    rng.shuffle(&mut with);
    rng.shuffle(&mut without);
    let mut out: Vec<&'static RoomKind> = Vec::new();
    if upstairs {
        out.push(&STAIR_HALL);
    }
    let wanted = counters.div_ceil(2).min(lower - out.len());
    out.extend(with.iter().take(wanted));
    let mut rest: Vec<&'static RoomKind> =
        with.iter().skip(wanted).chain(&without).copied().collect();
    rng.shuffle(&mut rest);
    let mut k = 0;
    while out.len() < lower {
        out.push(rest[k % rest.len()]);
        k += 1;
    }
    // The stair hall keeps cell (0, 0); the others are shuffled over the grid.
    let start = usize::from(upstairs);
    rng.shuffle(&mut out[start..]);
    out
}

/// How many counters each room downstairs gets: one in each room whose kind has one,
/// then more, at most two a room, until the teams' arms have one each.
fn spread_counters(kinds: &[&'static RoomKind], wanted: usize) -> Vec<usize> {
    let natural = |k: &RoomKind| {
        usize::from(
            k.furniture
                .iter()
                .any(|f| catalogue::furniture(f).is_some_and(|f| f.arm)),
        )
    };
    let mut counts: Vec<usize> = kinds.iter().map(|k| natural(k)).collect();
    let mut total: usize = counts.iter().sum();
    // Rooms whose kind has a counter take a second one first, then the others; the
    // stair hall keeps its floor free for the flight.
    let mut order: Vec<usize> = (0..kinds.len()).filter(|&i| counts[i] == 1).collect();
    order.extend((0..kinds.len()).filter(|&i| counts[i] == 0 && kinds[i].name != STAIR_HALL.name));
    order.extend((0..kinds.len()).filter(|&i| counts[i] == 0 && kinds[i].name != STAIR_HALL.name));
    for i in order {
        if total >= wanted {
            break;
        }
        if counts[i] < 2 {
            counts[i] += 1;
            total += 1;
        }
    }
    counts
}

/// The doors: a random spanning tree of the grid's neighbours on each storey, and a
/// few more; each closed with chance `closed`. The stair hall has none on its west wall
/// (the flight is there), which the grid keeps outside anyway.
fn draw_doors(
    rng: &mut Rng,
    rooms: &[(&'static RoomKind, (usize, usize), usize, bool)],
    closed: f64,
) -> Vec<(usize, usize, bool)> {
    let mut pairs = Vec::new();
    for a in 0..rooms.len() {
        for b in a + 1..rooms.len() {
            let ((xa, za), (xb, zb)) = (rooms[a].1, rooms[b].1);
            let side = xa.abs_diff(xb) + za.abs_diff(zb) == 1;
            if side && rooms[a].3 == rooms[b].3 {
                pairs.push((a, b));
            }
        }
    }
    rng.shuffle(&mut pairs);
    // Kruskal's algorithm over shuffled pairs: a random spanning tree of each storey.
    let mut parent: Vec<usize> = (0..rooms.len()).collect();
    fn root(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let mut out = Vec::new();
    let mut extra = Vec::new();
    for (a, b) in pairs {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra != rb {
            parent[ra] = rb;
            out.push((a, b));
        } else {
            extra.push((a, b));
        }
    }
    for pair in extra {
        if rng.chance(EXTRA_DOOR) {
            out.push(pair);
        }
    }
    out.sort_unstable();
    out.into_iter()
        .map(|(a, b)| (a, b, rng.chance(closed)))
        .collect()
}

/// The door `id` between rooms `a` and `b`, in the middle of the wall they share.
fn door(id: i64, rooms: &[Room], a: usize, b: usize, closed: bool) -> Door {
    let (ra, rb) = (&rooms[a], &rooms[b]);
    let along_x = ra.cell.0 == rb.cell.0;
    let center = if along_x {
        let z = if ra.cell.1 < rb.cell.1 {
            ra.max[1]
        } else {
            ra.min[1]
        };
        [round((ra.min[0] + ra.max[0]) / 2.0), z]
    } else {
        let x = if ra.cell.0 < rb.cell.0 {
            ra.max[0]
        } else {
            ra.min[0]
        };
        [x, round((ra.min[1] + ra.max[1]) / 2.0)]
    };
    Door {
        id,
        rooms: [a, b],
        center,
        along_x,
        closed,
    }
}

/// A length rounded to the millimetre: the files say 2.35, not 2.3500001.
pub fn round(x: f32) -> f32 {
    (x * 1000.0).round() / 1000.0
}

// Furnishing a laid-out scene: furniture in bands along each room's back and front
// walls, clear of the doors' swing and approach and of the flight of stairs; the free
// floor in the middle where robots start; the movable things that belong to the scene.

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
fn furnish(
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
fn things(scene: &mut Scene, rng: &mut Rng, id: &mut impl FnMut() -> i64) {
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
