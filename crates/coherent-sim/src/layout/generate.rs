//! A layout generated from a task's graph, for a task without geometry (every imported
//! original task): the rooms on a grid joined where the doors say, one floor item per
//! cell, fixed arms on their furniture, and everything else packed on its surface or in
//! its container, things grown to fit what the graph puts on or in them. The result is
//! a deterministic function of the task.

use coherent_core::geometry::{
    DoorGeom, ItemGeom, Layout, Lid, RobotGeom, RobotSpecs, RoomGeom, landing_pad, wall_of,
};
use coherent_core::{Idx, NodeKind, PropSet, Relation, RobotKind, StateSet, Task};

use super::error::{LayoutError, err};

/// Side of a floor cell; the generated layout puts one floor item in each.
const CELL: f32 = 3.0;
/// Gap between things packed on a surface or in a container.
const GAP: f32 = 0.06;
/// Height of the generated layout's walls.
const WALL_HEIGHT: f32 = 2.6;
/// Where things that are in no room are set aside, `[x, z]`: in rows of `ASIDE_ROW`,
/// `ASIDE_SPACING` apart.
pub const ASIDE: [f32; 2] = [-30.0, -30.0];
const ASIDE_ROW: f32 = 10.0;
const ASIDE_SPACING: f32 = 0.5;
/// A generated door's opening: its width and height.
const DOOR_WIDTH: f32 = 1.1;
const DOOR_HEIGHT: f32 = 2.3;
/// Things are placed this far above what holds them and drop into place when the world
/// settles (not in it, where the solver would push them out).
const DROP: f32 = 0.002;
/// A quadrotor starting on furniture stands this far in from the +x end (beyond its half
/// width) and this far towards the front.
const QUAD_PAD_IN: f32 = 0.02;
const QUAD_PAD_FORWARD: f32 = 0.1;
/// A fixed arm stands left of its surface's middle (0.2 m on a 1.8 m table, in
/// proportion) and this far in from the back.
const ARM_LEFT: f32 = 0.2;
const ARM_LEFT_OF: f32 = 1.8;
const ARM_BACK_IN: f32 = 0.15;
/// A lidded container is at least this much taller inside than the tallest thing in it,
/// grown in steps of this much.
const LID_CLEARANCE: f32 = 0.02;
/// At most this many steps of growth for a holder to fit its things: furniture grows
/// along x up to `FURNITURE_MAX_LENGTH` (a walkway stays free in its cell), then along
/// z, `FURNITURE_GROWTH` a step; smaller things grow `THING_GROWTH` a step, about square.
const GROWTH_STEPS: usize = 80;
const FURNITURE_MAX_LENGTH: f32 = 2.2;
const FURNITURE_GROWTH: f32 = 0.1;
const THING_GROWTH: f32 = 0.04;
/// A basket's height as a holder (its floor is 2 cm thick, as the robot model builds it).
const BASKET_HEIGHT: f32 = 0.08;
/// A row of packed things may run over its region by this much (rounding).
const PACK_EPS: f32 = 1e-4;
/// Packing keeps this far inside a container's walls, and this far inside a surface's
/// edges; a fixed arm's strip at the back is this deep; things on a surface without an
/// arm start in a band this far behind its middle.
const INSIDE_MARGIN: f32 = 0.01;
const EDGE_MARGIN: f32 = 0.05;
const ARM_STRIP: f32 = 0.32;
const CENTRE_BAND: f32 = 0.15;

/// A deterministic layout from the graph: rooms on a grid joined where doors say,
/// one floor item per cell, things packed on their surface or in their container.
pub fn generate(task: &Task) -> Result<Layout, LayoutError> {
    let specs = RobotSpecs::default();
    let rooms = task.rooms().to_vec();
    if rooms.is_empty() {
        return err("layout: the task has no room".into());
    }
    let doors = door_rooms(task);
    let cell = grid_places(task, &rooms, &doors)?;
    let mut k = 2usize;
    for &r in &rooms {
        let n = floor_items(task, r).len() + 1;
        let mut kr = (n as f32).sqrt().ceil() as usize;
        kr += kr % 2; // even, so that no item stands in front of a door
        k = k.max(kr);
    }
    let side = k as f32 * CELL;
    let room_geom: Vec<RoomGeom> = cell
        .iter()
        .map(|&(r, (i, j))| RoomGeom {
            id: task.id(r).0,
            min: [i as f32 * side, j as f32 * side],
            max: [(i + 1) as f32 * side, (j + 1) as f32 * side],
            level: 0.0,
        })
        .collect();
    let door_geom = door_geoms(task, &doors, &cell, side)?;
    let loc = locations(task);
    let fitted = fitted_sizes(task, &specs, &loc);
    let (mut items, mut robots) = floor_things(task, &specs, &cell, k, &fitted);
    quadrotor_on_furniture(task, &specs, &items, &mut robots);
    fixed_arms(task, &items, &mut robots)?;
    held_things(task, &specs, &loc, &fitted, &mut items, &robots)?;
    let layout = Layout {
        specs,
        rooms: room_geom,
        doors: door_geom,
        stairs: Vec::new(),
        items,
        robots,
        wall_height: WALL_HEIGHT,
    };
    match layout.missing_entry(task) {
        Some(missing) => err(format!("layout: {missing}")),
        None => Ok(layout),
    }
}

/// Each door with its rooms, in file order.
fn door_rooms(task: &Task) -> Vec<(Idx, Vec<Idx>)> {
    let mut doors: Vec<(Idx, Vec<Idx>)> = Vec::new();
    for &(d, r) in task.doors() {
        match doors.iter_mut().find(|(x, _)| *x == d) {
            Some((_, rs)) => rs.push(r),
            None => doors.push((d, vec![r])),
        }
    }
    doors
}

/// Each room with its place on the grid of rooms, `(i, j)`: its footprint is the
/// square `i` sides along x and `j` along z.
type RoomPlaces = Vec<(Idx, (i32, i32))>;

/// Where `r` is on the grid of rooms.
fn place_of(cell: &[(Idx, (i32, i32))], r: Idx) -> Option<(i32, i32)> {
    cell.iter().find(|(x, _)| *x == r).map(|(_, p)| *p)
}

/// Each room's place on the grid: breadth first from the room with the most doors, a
/// room through a door on a free side of the one it joins; a room no door reaches at
/// the next free place along x.
fn grid_places(
    task: &Task,
    rooms: &[Idx],
    doors: &[(Idx, Vec<Idx>)],
) -> Result<RoomPlaces, LayoutError> {
    let degree = |r: Idx| doors.iter().filter(|(_, rs)| rs.contains(&r)).count();
    let hub = rooms
        .iter()
        .copied()
        .max_by_key(|&r| (degree(r), std::cmp::Reverse(r)))
        .unwrap_or(rooms[0]);
    let mut cell: RoomPlaces = vec![(hub, (0, 0))];
    let mut queue = vec![hub];
    let mut qi = 0;
    while qi < queue.len() || cell.len() < rooms.len() {
        if qi == queue.len() {
            // A room no door reaches: next free cell along x.
            let r = rooms
                .iter()
                .copied()
                .find(|&r| place_of(&cell, r).is_none())
                .unwrap_or(hub);
            let x = cell.iter().map(|(_, p)| p.0).max().unwrap_or(0) + 1;
            cell.push((r, (x, 0)));
            queue.push(r);
        }
        let r = queue[qi];
        qi += 1;
        let p = place_of(&cell, r).unwrap_or((0, 0));
        for (_, rs) in doors {
            if !rs.contains(&r) {
                continue;
            }
            for &o in rs {
                if o == r || place_of(&cell, o).is_some() {
                    continue;
                }
                let free = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                    .into_iter()
                    .map(|(dx, dz)| (p.0 + dx, p.1 + dz))
                    .find(|q| cell.iter().all(|(_, c)| c != q));
                let Some(q) = free else {
                    return err(format!(
                        "layout: no free side of {} for {}",
                        task.node(r).label(),
                        task.node(o).label()
                    ));
                };
                cell.push((o, q));
                queue.push(o);
            }
        }
    }
    Ok(cell)
}

/// The floor items of `room` (robots included), in file order.
fn floor_items(task: &Task, room: Idx) -> Vec<Idx> {
    let floor = task.floor_of(room);
    task.indices()
        .filter(|&n| {
            let k = task.node(n).kind;
            (k == NodeKind::Object
                || k == NodeKind::Robot(RobotKind::RobotDog)
                || k == NodeKind::Robot(RobotKind::Quadrotor))
                && if k == NodeKind::Object {
                    floor.is_some_and(|f| {
                        task.init.has(coherent_core::Edge::new(n, Relation::On, f))
                            || task
                                .init
                                .has(coherent_core::Edge::new(n, Relation::Inside, f))
                    })
                } else {
                    // A robot is in the room its INSIDE edge names.
                    task.init
                        .has(coherent_core::Edge::new(n, Relation::Inside, room))
                }
        })
        .collect()
}

/// The doors between the rooms at their places on the grid, `side` metres apart: each
/// in the middle of the wall the two rooms share.
fn door_geoms(
    task: &Task,
    doors: &[(Idx, Vec<Idx>)],
    cell: &[(Idx, (i32, i32))],
    side: f32,
) -> Result<Vec<DoorGeom>, LayoutError> {
    let mut door_geom = Vec::new();
    for (d, rs) in doors {
        let label = task.node(*d).label();
        let [a, b] = rs[..] else {
            return err(format!(
                "layout: {label} leads to {} rooms, not 2",
                rs.len()
            ));
        };
        let (Some(pa), Some(pb)) = (place_of(cell, a), place_of(cell, b)) else {
            return err(format!("layout: {label} leads to an unplaced room"));
        };
        let (dx, dz) = (pb.0 - pa.0, pb.1 - pa.1);
        if dx.abs() + dz.abs() != 1 {
            return err(format!(
                "layout: {label} joins {} and {}, which are not side by side on the grid",
                task.node(a).label(),
                task.node(b).label()
            ));
        }
        let ca = [(pa.0 as f32 + 0.5) * side, (pa.1 as f32 + 0.5) * side];
        door_geom.push(DoorGeom {
            id: task.id(*d).0,
            rooms: [task.id(a).0, task.id(b).0],
            center: [
                ca[0] + dx as f32 * side / 2.0,
                ca[1] + dz as f32 * side / 2.0,
            ],
            along_x: dz != 0,
            width: DOOR_WIDTH,
            height: DOOR_HEIGHT,
        });
    }
    Ok(door_geom)
}

/// The floor items of each room in its `k` by `k` cells, one each: the robots that
/// stand on a floor, and the furniture and floor objects at their `fitted` sizes.
fn floor_things(
    task: &Task,
    specs: &RobotSpecs,
    cell: &[(Idx, (i32, i32))],
    k: usize,
    fitted: &[[f32; 3]],
) -> (Vec<ItemGeom>, Vec<RobotGeom>) {
    let side = k as f32 * CELL;
    let mut items: Vec<ItemGeom> = Vec::new();
    let mut robots: Vec<RobotGeom> = Vec::new();
    for &(r, (i, j)) in cell {
        for (slot, n) in floor_items(task, r).into_iter().enumerate() {
            let (a, b) = (slot % k, slot / k);
            let x = i as f32 * side + (a as f32 + 0.5) * CELL;
            let z = j as f32 * side + (b as f32 + 0.5) * CELL;
            match task.node(n).kind {
                NodeKind::Robot(_) => robots.push(RobotGeom {
                    id: task.id(n).0,
                    pos: [x, 0.0, z],
                    yaw: 0.0,
                }),
                _ => {
                    let (_, container, lid, dynamic) = shape_of(task, n, specs);
                    let size = fitted[n.get()];
                    items.push(ItemGeom {
                        id: task.id(n).0,
                        pos: [x, 0.0, z],
                        size,
                        container,
                        lid,
                        dynamic,
                    });
                }
            }
        }
    }
    (items, robots)
}

/// A quadrotor that starts on a piece of furniture: on the right end of its top.
fn quadrotor_on_furniture(
    task: &Task,
    specs: &RobotSpecs,
    items: &[ItemGeom],
    robots: &mut [RobotGeom],
) {
    for r in &task.robots {
        if r.kind != RobotKind::Quadrotor {
            continue;
        }
        let Some(s) = task.init.target(r.node, Relation::On) else {
            continue;
        };
        if task.node(s).kind == NodeKind::Floor {
            continue;
        }
        let (Some(sg), Some(rg)) = (
            items.iter().find(|it| it.id == task.id(s).0),
            robots.iter_mut().find(|g| g.id == task.id(r.node).0),
        ) else {
            continue;
        };
        rg.pos = [
            sg.pos[0] + sg.size[0] / 2.0 - specs.quad_half - QUAD_PAD_IN,
            sg.pos[1] + sg.size[1],
            sg.pos[2] - QUAD_PAD_FORWARD,
        ];
    }
}

/// Each fixed arm on the surface it stands on ([`arm_spot`]).
fn fixed_arms(
    task: &Task,
    items: &[ItemGeom],
    robots: &mut Vec<RobotGeom>,
) -> Result<(), LayoutError> {
    for r in &task.robots {
        if r.kind != RobotKind::RobotArm {
            continue;
        }
        let Some(s) = task.init.target(r.node, Relation::On) else {
            return err(format!(
                "layout: {} stands on nothing",
                task.node(r.node).label()
            ));
        };
        let Some(sg) = items.iter().find(|it| it.id == task.id(s).0) else {
            return err(format!(
                "layout: {} stands on {}, which is not on a floor",
                task.node(r.node).label(),
                task.node(s).label()
            ));
        };
        let (x0, z0) = arm_spot(sg);
        robots.push(RobotGeom {
            id: task.id(r.node).0,
            pos: [x0, sg.pos[1] + sg.size[1], z0],
            yaw: 0.0,
        });
    }
    Ok(())
}

/// Everything not yet placed, level by level: on a surface or in a container already
/// placed (a quadrotor's basket included), packed in file order; a thing in no room is
/// set aside outside the house.
fn held_things(
    task: &Task,
    specs: &RobotSpecs,
    loc: &[Option<(Idx, bool)>],
    fitted: &[[f32; 3]],
    items: &mut Vec<ItemGeom>,
    robots: &[RobotGeom],
) -> Result<(), LayoutError> {
    let mut pending: Vec<Idx> = task
        .indices()
        .filter(|&n| task.node(n).kind == NodeKind::Object)
        .filter(|&n| items.iter().all(|it| it.id != task.id(n).0))
        .collect();
    // Where each holder's things go: packed in its region, in file order.
    let mut spots: Vec<(i64, bool, Vec<[f32; 2]>)> = Vec::new();
    while !pending.is_empty() {
        let before = pending.len();
        let mut rest = Vec::new();
        for n in pending {
            let Some((holder, inside)) = loc[n.get()] else {
                // In no room at all (some released tasks have such things): set
                // aside on an unnamed pad outside the house, where nothing sees it.
                let (size, container, lid, dynamic) = shape_of(task, n, specs);
                let k = items.len() as f32;
                items.push(ItemGeom {
                    id: task.id(n).0,
                    pos: [
                        ASIDE[0] - (k % ASIDE_ROW) * ASIDE_SPACING,
                        DROP,
                        ASIDE[1] - (k / ASIDE_ROW).floor() * ASIDE_SPACING,
                    ],
                    size,
                    container,
                    lid,
                    dynamic,
                });
                continue;
            };
            let hg = match items.iter().find(|it| it.id == task.id(holder).0) {
                Some(h) => h.clone(),
                // A quadrotor's basket: the open box on the craft.
                None => match basket_geom(task, holder, robots, specs) {
                    Some(h) => h,
                    None => {
                        rest.push(n);
                        continue;
                    }
                },
            };
            let (_, container, lid, dynamic) = shape_of(task, n, specs);
            let size = fitted[n.get()];
            let group: Vec<Idx> = contents(loc, holder, inside);
            let slot = group.iter().position(|&x| x == n).unwrap_or(0);
            let packed = match spots.iter().find(|c| c.0 == hg.id && c.1 == inside) {
                Some(c) => Some(c.2.clone()),
                None => {
                    let sizes: Vec<[f32; 3]> = group.iter().map(|x| fitted[x.get()]).collect();
                    let flags = holder_flags(task, specs, loc, holder);
                    let got = pack(pack_region(&hg, inside, flags.0, flags.1), &sizes);
                    if let Some(g) = &got {
                        spots.push((hg.id, inside, g.clone()));
                    }
                    got
                }
            };
            let Some(at) = packed.and_then(|p| p.get(slot).copied()) else {
                return err(format!(
                    "layout: no room left for {} {} {}",
                    task.node(n).label(),
                    if inside { "in" } else { "on" },
                    task.node(holder).label()
                ));
            };
            let y = if inside {
                hg.pos[1] + wall_of(hg.size[1])
            } else {
                hg.pos[1] + hg.size[1]
            };
            items.push(ItemGeom {
                id: task.id(n).0,
                pos: [hg.pos[0] + at[0], y + DROP, hg.pos[2] + at[1]],
                size,
                container,
                lid,
                dynamic,
            });
        }
        if rest.len() == before {
            let names: Vec<String> = rest.iter().map(|&n| task.node(n).label()).collect();
            return err(format!("layout: cannot place {}", names.join(", ")));
        }
        pending = rest;
    }
    Ok(())
}

/// Where a fixed arm stands on its surface: towards the back, left of centre, leaving
/// the right end free for the quadrotor to land.
pub fn arm_spot(surface: &ItemGeom) -> (f32, f32) {
    (
        surface.pos[0] - ARM_LEFT * surface.size[0] / ARM_LEFT_OF,
        surface.pos[2] + surface.size[2] / 2.0 - ARM_BACK_IN,
    )
}

/// Where each object is at the start: the holder its location edge names and whether
/// it is inside (rather than on) it.
fn locations(task: &Task) -> Vec<Option<(Idx, bool)>> {
    let mut loc = vec![None; task.nodes.len()];
    for n in task.indices() {
        if task.node(n).kind != NodeKind::Object {
            continue;
        }
        loc[n.get()] = task
            .init_edges
            .iter()
            .find(|e| e.from() == n && e.rel().is_location())
            .map(|e| (e.to(), e.rel() == Relation::Inside));
    }
    loc
}

/// The things on (or in) `holder`, in file order.
fn contents(loc: &[Option<(Idx, bool)>], holder: Idx, inside: bool) -> Vec<Idx> {
    loc.iter()
        .enumerate()
        .filter(|(_, l)| **l == Some((holder, inside)))
        .map(|(i, _)| Idx(i as u16))
        .collect()
}

/// Whether a fixed arm stands on `holder`, and whether the quadrotor may land on it
/// (a top standing on a floor, in a task with a quadrotor).
fn holder_flags(
    task: &Task,
    specs: &RobotSpecs,
    loc: &[Option<(Idx, bool)>],
    holder: Idx,
) -> (bool, Option<f32>) {
    let arm_here = task.robots.iter().any(|r| {
        r.kind == RobotKind::RobotArm
            && task
                .init
                .has(coherent_core::Edge::new(r.node, Relation::On, holder))
    });
    let has_quad = task.robots.iter().any(|r| r.kind == RobotKind::Quadrotor);
    let p = task.node(holder).properties;
    let on_floor = loc
        .get(holder.get())
        .copied()
        .flatten()
        .is_some_and(|(h, _)| task.node(h).kind == NodeKind::Floor);
    let pad =
        (has_quad && on_floor && p.contains(PropSet::SURFACES) && !p.contains(PropSet::GRABABLE))
            .then(|| landing_pad(specs));
    (arm_here, pad)
}

/// Every object's size, grown from its default (see [`shape_of`]) until what the graph
/// puts on or in it packs there, with the landing pad and arm strip kept free; lidded
/// containers also grow tall enough to close over their contents. Deepest things first.
fn fitted_sizes(task: &Task, specs: &RobotSpecs, loc: &[Option<(Idx, bool)>]) -> Vec<[f32; 3]> {
    let n = task.nodes.len();
    let mut size: Vec<[f32; 3]> = vec![[0.0; 3]; n];
    let depth = |x: Idx| {
        let mut d = 0;
        let mut cur = x;
        while let Some((h, _)) = loc[cur.get()] {
            d += 1;
            cur = h;
            if d > 16 {
                break;
            }
        }
        d
    };
    let mut order: Vec<Idx> = task
        .indices()
        .filter(|&x| task.node(x).kind == NodeKind::Object)
        .collect();
    order.sort_by_key(|&x| std::cmp::Reverse(depth(x)));
    // Again until nothing changes: a goal may put a thing that grew into a holder that
    // was sized before it (a plate into a sink).
    for _ in 0..4 {
        let before = size.clone();
        fit_pass(task, specs, loc, &order, &mut size);
        if size == before {
            break;
        }
    }
    size
}

/// One sizing pass over `order` (see [`fitted_sizes`]).
fn fit_pass(
    task: &Task,
    specs: &RobotSpecs,
    loc: &[Option<(Idx, bool)>],
    order: &[Idx],
    size: &mut [[f32; 3]],
) {
    for &x in order {
        let (base, container, lid, _) = shape_of(task, x, specs);
        let mut s = base;
        // What must fit inside: what starts there and what the goal puts there.
        let mut inner_things = contents(loc, x, true);
        for g in &task.goal {
            if g.relation == Relation::Inside
                && g.target == x
                && g.count > 0
                && !inner_things.contains(&g.subject)
            {
                inner_things.push(g.subject);
            }
        }
        let inner: Vec<[f32; 3]> = inner_things
            .iter()
            .map(|&c| {
                if size[c.get()][0] > 0.0 {
                    size[c.get()]
                } else {
                    shape_of(task, c, specs).0
                }
            })
            .collect();
        let on: Vec<[f32; 3]> = contents(loc, x, false)
            .iter()
            .map(|c| size[c.get()])
            .collect();
        if container && lid != Lid::None {
            let tallest = inner.iter().map(|c| c[1]).fold(0.0f32, f32::max);
            let lids = if lid == Lid::Front { 2.0 } else { 1.0 };
            while s[1] - lids * wall_of(s[1]) < tallest + LID_CLEARANCE {
                s[1] += LID_CLEARANCE;
            }
        }
        let flags = holder_flags(task, specs, loc, x);
        let floor_standing =
            loc[x.get()].is_some_and(|(h, _)| task.node(h).kind == NodeKind::Floor);
        for _ in 0..GROWTH_STEPS {
            let g = ItemGeom {
                id: 0,
                pos: [0.0; 3],
                size: s,
                container,
                lid,
                dynamic: false,
            };
            let fits = (inner.is_empty()
                || pack(pack_region(&g, true, false, None), &inner).is_some())
                && (on.is_empty() || pack(pack_region(&g, false, flags.0, flags.1), &on).is_some());
            if fits {
                break;
            }
            // Furniture grows along x up to what leaves a walkway in its 3 m cell;
            // smaller things stay about square.
            if floor_standing {
                if s[0] < FURNITURE_MAX_LENGTH {
                    s[0] += FURNITURE_GROWTH;
                } else {
                    s[2] += FURNITURE_GROWTH;
                }
            } else if s[0] <= s[2] {
                s[0] += THING_GROWTH;
            } else {
                s[2] += THING_GROWTH;
            }
        }
        size[x.get()] = s;
    }
}

/// A quadrotor's basket as a holder: the open box on the craft where the layout put it.
fn basket_geom(
    task: &Task,
    basket: Idx,
    robots: &[RobotGeom],
    specs: &RobotSpecs,
) -> Option<ItemGeom> {
    let q = task
        .robots
        .iter()
        .find(|r| task.basket_of(r.node) == Some(basket))?;
    let rg = robots.iter().find(|g| g.id == task.id(q.node).0)?;
    let b = 2.0 * specs.basket_half;
    Some(ItemGeom {
        id: task.id(basket).0,
        pos: rg.pos,
        size: [b, BASKET_HEIGHT, b],
        container: true,
        lid: Lid::None,
        dynamic: true,
    })
}

/// Packs boxes of `sizes` in rows from the region's near corner; their centres relative
/// to the holder's bottom centre, or `None` when they do not all fit.
fn pack(region: [f32; 4], sizes: &[[f32; 3]]) -> Option<Vec<[f32; 2]>> {
    let (mut x, mut z, mut row) = (region[0], region[1], 0.0f32);
    let mut out = Vec::with_capacity(sizes.len());
    for s in sizes {
        if x + s[0] > region[2] + PACK_EPS {
            x = region[0];
            z += row + GAP;
            row = 0.0;
        }
        if x + s[0] > region[2] + PACK_EPS || z + s[2] > region[3] + PACK_EPS {
            return None;
        }
        out.push([x + s[0] / 2.0, z + s[2] / 2.0]);
        x += s[0] + GAP;
        row = row.max(s[2]);
    }
    Some(out)
}

/// Part of a holder's top (or inside) to pack things in, relative to its bottom centre:
/// `[x0, z0, x1, z1]`. `pad`: width kept free at the +x end for landing.
fn pack_region(h: &ItemGeom, inside: bool, arm_here: bool, pad: Option<f32>) -> [f32; 4] {
    let (hx, hz) = (h.size[0] / 2.0, h.size[2] / 2.0);
    if inside {
        let m = wall_of(h.size[1]) + INSIDE_MARGIN;
        return [-hx + m, -hz + m, hx - m, hz - m];
    }
    let m = EDGE_MARGIN;
    let x1 = hx - pad.unwrap_or(m);
    if arm_here {
        // All but the back strip, where the arm stands.
        [-hx + m, -hz + m, x1, hz - ARM_STRIP]
    } else {
        // Centre band first, so that the legged robot reaches from either long side.
        [-hx + m, (-CENTRE_BAND).max(-hz + m), x1, hz - m]
    }
}

/// Size, whether a container, its lid, whether dynamic.
fn shape_of(task: &Task, n: Idx, specs: &RobotSpecs) -> ([f32; 3], bool, Lid, bool) {
    let p = task.node(n).properties;
    let states = task.init.states(n);
    let container = p.contains(PropSet::CONTAINERS);
    let surface = p.contains(PropSet::SURFACES);
    let grabable = p.contains(PropSet::GRABABLE);
    let openable = container
        && (p.contains(PropSet::CAN_OPEN) || states.intersects(StateSet::OPEN | StateSet::CLOSED))
        && !states.contains(StateSet::OPEN_FOREVER);
    let lid = match (openable, surface) {
        (false, _) => Lid::None,
        (true, true) => Lid::Front,
        (true, false) => Lid::Top,
    };
    let on_floor = task.init_edges.iter().any(|e| {
        e.from() == n && e.rel().is_location() && task.node(e.to()).kind == NodeKind::Floor
    });
    let size = if grabable {
        if container {
            // Room for two by two small things: more may be put in than it starts with.
            [0.3, 0.08, 0.3]
        } else if surface {
            [0.4, 0.03, 0.3]
        } else {
            [0.12, 0.12, 0.12]
        }
    } else if on_floor {
        if p.contains(PropSet::HIGH_HEIGHT) {
            [1.8, specs.high_top, 1.0]
        } else if container {
            [0.7, 0.6, 0.6]
        } else if surface {
            [1.2, specs.low_top, 0.6]
        } else {
            [0.6, 0.5, 0.6]
        }
    } else if container {
        [0.4, 0.22, 0.35]
    } else if surface {
        [0.35, 0.08, 0.35]
    } else {
        [0.3, 0.2, 0.3]
    };
    (size, container, lid, grabable)
}
