//! A drawn task as a native task file (`docs/task-format.md`, version 1, the
//! `geometric` rules): the scene graph of the scene at the task's start, the robots,
//! the goal and instruction, and the geometry in metres. The value is read back with
//! the native reader, so that a generated task is exactly what its file says.

use coherent_core::geometry::{
    DoorGeom, ItemGeom, Layout, Lid, RobotGeom, RobotSpecs, RoomGeom, StairsGeom,
};
use coherent_core::native;
use serde_json::{Value, json};

use crate::goal::Pred;
use crate::scene::{DOOR_HEIGHT, DOOR_WIDTH, FLIGHT_WIDTH, Scene};
use crate::start::{Landing, Pose, Start, arm_spot, pad_spot};

/// The walls' height (m), as every scene of the project has it.
const WALL_HEIGHT: f32 = 2.6;

/// What a task file says besides its scene and start.
#[derive(Clone, Debug)]
pub struct Meta<'a> {
    pub task_id: i64,
    pub name: &'a str,
    pub instruction: &'a str,
    pub goal: &'a [Pred],
    pub ground_truth: Option<usize>,
}

/// The task as the JSON of a native task file.
pub fn task_value(scene: &Scene, start: &Start, meta: &Meta<'_>) -> Value {
    let (nodes, edges) = graph(scene, start);
    let goal: Vec<Value> = meta
        .goal
        .iter()
        .map(|p| json!({"relation": p.relation.name(), "subject": p.subject, "target": p.target, "count": 1}))
        .collect();
    let robots: Vec<Value> = start
        .robots
        .iter()
        .map(|r| json!({"id": r.id, "type": r.kind.class_name()}))
        .collect();
    json!({
        "format": native::FORMAT,
        "version": native::VERSION,
        "scene": scene.name,
        "task_id": meta.task_id,
        "name": meta.name,
        "rules": "geometric",
        "instruction": meta.instruction,
        "goal": goal,
        "ground_truth": meta.ground_truth.map(|steps| json!({"steps": steps})),
        "robots": robots,
        "graph": {"nodes": nodes, "edges": edges},
        "geometry": serde_json::to_value(layout(scene, start)).unwrap_or(Value::Null),
    })
}

fn node(id: i64, category: &str, name: &str, properties: &[&str], states: &[&str]) -> Value {
    json!({
        "id": id,
        "category": category,
        "class_name": name,
        "prefab_name": name.replace(' ', "_"),
        "properties": properties,
        "states": states,
    })
}

fn edge(from: i64, relation: &str, to: i64) -> Value {
    json!({"from_id": from, "to_id": to, "relation_type": relation})
}

/// The nodes and edges of the scene at the start: rooms and their floors, doors, the
/// stairs, furniture on its floor, things on or in their holders, then the robots (a
/// quadrotor with its basket, the legged robots, the fixed arms on their counters).
fn graph(scene: &Scene, start: &Start) -> (Vec<Value>, Vec<Value>) {
    let mut nodes = Vec::new();
    let mut edges = Vec::new();
    for r in &scene.rooms {
        nodes.push(node(r.id, "Rooms", &r.name, &[], &[]));
        nodes.push(node(
            r.floor,
            "Floor",
            &format!("{} floor", r.name),
            &["SURFACES", "LANDABLE"],
            &[],
        ));
        edges.push(edge(r.floor, "INSIDE", r.id));
    }
    for d in &scene.doors {
        let state = if d.closed { "CLOSED" } else { "OPEN" };
        nodes.push(node(d.id, "Doors", "door", &["CAN_OPEN"], &[state]));
        for &r in &d.rooms {
            edges.push(edge(d.id, "LEADING TO", scene.rooms[r].id));
        }
    }
    if let Some(f) = &scene.flight {
        // A flight is a door that is always open (docs/physics.md, "Storeys and stairs").
        nodes.push(node(f.id, "Doors", "stairs", &[], &["OPEN"]));
        for &r in &f.rooms {
            edges.push(edge(f.id, "LEADING TO", scene.rooms[r].id));
        }
    }
    for p in &scene.pieces {
        let k = p.kind;
        let mut props = Vec::new();
        if k.surface {
            props.push("SURFACES");
        }
        if k.landable {
            props.push("LANDABLE");
        }
        if k.container {
            props.push("CONTAINERS");
        }
        let states: &[&str] = match (k.container, k.lid) {
            (false, _) => &[],
            // No door or lid: always open, as the quadrotor's basket is.
            (true, Lid::None) => &["OPEN_FOREVER"],
            (true, _) if p.closed => &["CLOSED"],
            (true, _) => &["OPEN"],
        };
        if k.container && k.lid != Lid::None {
            props.push("CAN_OPEN");
        }
        nodes.push(node(p.id, k.category, k.name, &props, states));
        edges.push(edge(p.id, "ON", scene.rooms[p.room].floor));
    }
    for (t, at) in scene.things.iter().zip(&start.things) {
        let (props, states): (&[&str], &[&str]) = if t.kind.container {
            (&["GRABABLE", "MOVABLE", "CONTAINERS"], &["OPEN_FOREVER"])
        } else {
            (&["GRABABLE", "MOVABLE"], &[])
        };
        nodes.push(node(t.id, t.kind.category, t.kind.name, props, states));
        let relation = if at.inside { "INSIDE" } else { "ON" };
        edges.push(edge(t.id, relation, scene.pieces[at.piece].id));
    }
    for r in &start.robots {
        match r.pose {
            Pose::Quad { basket, on } => {
                nodes.push(node(
                    r.id,
                    "Agents",
                    "quadrotor",
                    &["MOVABLE", "FLYABLE", "HAVE_A_BASKET"],
                    &["LAND"],
                ));
                nodes.push(node(
                    basket,
                    "AgentTool",
                    "basket",
                    &["MOVABLE", "CONTAINERS", "WITH_QUADROTOR"],
                    &["OPEN_FOREVER"],
                ));
                let (surface, room) = match on {
                    Landing::Top(p) => (scene.pieces[p].id, scene.pieces[p].room),
                    Landing::Floor(room, _) => (scene.rooms[room].floor, room),
                };
                edges.push(edge(r.id, "ON", surface));
                edges.push(edge(r.id, "INSIDE", scene.rooms[room].id));
                edges.push(edge(r.id, "WITH", basket));
                edges.push(edge(basket, "ON", surface));
            }
            Pose::Dog(room, _) => {
                nodes.push(node(r.id, "Agents", "robot dog", &["MOVABLE"], &[]));
                edges.push(edge(r.id, "ON", scene.rooms[room].floor));
                edges.push(edge(r.id, "INSIDE", scene.rooms[room].id));
            }
            Pose::Arm(p) => {
                nodes.push(node(r.id, "Agents", "robot arm", &[], &[]));
                edges.push(edge(r.id, "ON", scene.pieces[p].id));
                edges.push(edge(r.id, "INSIDE", scene.rooms[scene.pieces[p].room].id));
            }
        }
    }
    (nodes, edges)
}

/// The geometry: rooms, doors, the flight, furniture and things (in id order), and
/// where each robot starts, with the default robot specs written out.
fn layout(scene: &Scene, start: &Start) -> Layout {
    let rooms = scene
        .rooms
        .iter()
        .map(|r| RoomGeom {
            id: r.id,
            min: r.min,
            max: r.max,
            level: r.level,
        })
        .collect();
    let doors = scene
        .doors
        .iter()
        .map(|d| DoorGeom {
            id: d.id,
            rooms: [scene.rooms[d.rooms[0]].id, scene.rooms[d.rooms[1]].id],
            center: d.center,
            along_x: d.along_x,
            width: DOOR_WIDTH,
            height: DOOR_HEIGHT,
        })
        .collect();
    let stairs = scene
        .flight
        .iter()
        .map(|f| StairsGeom {
            id: f.id,
            rooms: [scene.rooms[f.rooms[0]].id, scene.rooms[f.rooms[1]].id],
            foot: f.foot,
            head: f.head,
            width: FLIGHT_WIDTH,
        })
        .collect();
    let mut items: Vec<ItemGeom> = scene
        .pieces
        .iter()
        .map(|p| ItemGeom {
            id: p.id,
            pos: p.pos,
            size: p.kind.size,
            container: p.kind.container,
            lid: if p.kind.container {
                p.kind.lid
            } else {
                Lid::None
            },
            dynamic: false,
        })
        .collect();
    items.extend(
        scene
            .things
            .iter()
            .zip(&start.things)
            .map(|(t, at)| ItemGeom {
                id: t.id,
                pos: at.pos,
                size: t.kind.size,
                container: t.kind.container,
                lid: Lid::None,
                dynamic: true,
            }),
    );
    items.sort_by_key(|i| i.id);
    let robots = start
        .robots
        .iter()
        .map(|r| {
            let pos = match r.pose {
                Pose::Arm(p) => arm_spot(&scene.pieces[p]),
                Pose::Quad {
                    on: Landing::Top(p),
                    ..
                } => pad_spot(&scene.pieces[p]),
                Pose::Quad {
                    on: Landing::Floor(room, at),
                    ..
                }
                | Pose::Dog(room, at) => [at[0], scene.rooms[room].level, at[1]],
            };
            RobotGeom {
                id: r.id,
                pos,
                yaw: 0.0,
            }
        })
        .collect();
    Layout {
        specs: RobotSpecs::default(),
        rooms,
        doors,
        stairs,
        items,
        robots,
        wall_height: WALL_HEIGHT,
    }
}
