//! The geometry of a scene: rooms, doors, stairs, furniture, objects, robot start poses
//! and robot specs, in metres. As JSON it is the `geometry` object of a native task file
//! (`docs/task-format.md`); `coherent-sim` builds its physical world from it.
//!
//! Frame: `y` up, each room's floor at its `level`; positions are the bottom centre of a
//! box.
//!
//! Under the `geometric` rule set (the project's own benchmark) the heights the rules
//! need are derived here from the geometry and the robot specs instead of being hand-set
//! labels: see [`derive_heights`].

use serde::{Deserialize, Serialize};

use crate::error::{Result, Site};
use crate::graph::{Idx, NodeId, NodeKind, RobotKind};
use crate::rules;
use crate::task::Task;
use crate::vocab::{PropSet, Relation};

/// Sizes and limits of the robots, shared by the layout and the robot models.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotSpecs {
    /// Half extents of the legged robot's body box (x, y, z); it walks with its bottom
    /// 2 cm above the floor.
    pub dog_half: [f32; 3],
    /// Shoulder of the arm on the dog's back, in the body frame (forward is +z).
    pub dog_shoulder: [f32; 3],
    /// Upper arm and forearm of the dog's arm (reach = their sum).
    pub dog_links: [f32; 2],
    pub dog_speed: f32,
    /// Shoulder height of a fixed arm above its surface.
    pub arm_shoulder: f32,
    pub arm_links: [f32; 2],
    pub quad_mass: f32,
    /// Half width of the quadrotor's frame (rotors inside it) and of its basket.
    pub quad_half: f32,
    pub basket_half: f32,
    pub cruise_altitude: f32,
    pub flight_speed: f32,
    /// Top heights of LOW_HEIGHT and HIGH_HEIGHT furniture.
    pub low_top: f32,
    pub high_top: f32,
}

impl Default for RobotSpecs {
    fn default() -> RobotSpecs {
        RobotSpecs {
            dog_half: [0.3, 0.2, 0.3],
            dog_shoulder: [0.0, 0.47, 0.15],
            dog_links: [0.45, 0.40],
            dog_speed: 1.0,
            arm_shoulder: 0.3,
            arm_links: [0.65, 0.6],
            quad_mass: 1.5,
            quad_half: 0.3,
            basket_half: 0.22,
            cruise_altitude: 1.9,
            flight_speed: 1.0,
            low_top: 0.45,
            high_top: 1.4,
        }
    }
}

impl RobotSpecs {
    pub fn dog_reach(&self) -> f32 {
        self.dog_links[0] + self.dog_links[1]
    }
    pub fn arm_reach(&self) -> f32 {
        self.arm_links[0] + self.arm_links[1]
    }
    /// Highest point the legged robot's hand gets to.
    pub fn dog_max_height(&self) -> f32 {
        self.dog_shoulder[1] + 0.02 + self.dog_reach()
    }
}

/// A room: an axis-aligned footprint on a level.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomGeom {
    pub id: i64,
    /// Corners of the footprint, `[x, z]`.
    pub min: [f32; 2],
    pub max: [f32; 2],
    /// Floor height of the level (0 for single-storey scenes).
    #[serde(default)]
    pub level: f32,
}

/// A door: an opening in the wall between two rooms with a hinged panel.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DoorGeom {
    pub id: i64,
    pub rooms: [i64; 2],
    /// Centre of the opening on the wall line, `[x, z]`.
    pub center: [f32; 2],
    /// Whether the wall runs along x (the opening spans x); otherwise along z.
    pub along_x: bool,
    pub width: f32,
    pub height: f32,
}

/// How a container opens.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Lid {
    /// Always open (no panel).
    None,
    /// A lid hinged at the back of the top.
    Top,
    /// A door hinged on the left of the front (-z) face; the top stays a surface.
    Front,
}

/// A piece of furniture or an object: a box (furniture, fixed) or a small body (GRABABLE
/// things are dynamic). Containers are open boxes with walls of `wall` thickness.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ItemGeom {
    pub id: i64,
    /// Bottom centre.
    pub pos: [f32; 3],
    /// Width (x), height (y), depth (z).
    pub size: [f32; 3],
    pub container: bool,
    pub lid: Lid,
    pub dynamic: bool,
}

/// A robot's start pose: base position (bottom centre) and heading about y.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotGeom {
    pub id: i64,
    pub pos: [f32; 3],
    #[serde(default)]
    pub yaw: f32,
}

/// A flight of stairs between two rooms on different levels. In the graph it is a door
/// node that cannot be closed (no `CAN_OPEN`), `LEADING TO` both rooms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StairsGeom {
    pub id: i64,
    /// The lower room, then the upper one.
    pub rooms: [i64; 2],
    /// Middle of the bottom step's front edge on the lower level, `[x, z]`.
    pub foot: [f32; 2],
    /// Middle of the top step's back edge on the upper level, `[x, z]`; the flight runs
    /// straight from `foot` to `head`, along x or along z.
    pub head: [f32; 2],
    pub width: f32,
}

/// The geometry of a scene. As JSON it is the `geometry` object of a native task file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layout {
    #[serde(default)]
    pub specs: RobotSpecs,
    pub rooms: Vec<RoomGeom>,
    pub doors: Vec<DoorGeom>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stairs: Vec<StairsGeom>,
    pub items: Vec<ItemGeom>,
    pub robots: Vec<RobotGeom>,
    #[serde(default = "default_wall_height")]
    pub wall_height: f32,
}

fn default_wall_height() -> f32 {
    2.6
}

impl Layout {
    pub fn room(&self, id: NodeId) -> Option<&RoomGeom> {
        self.rooms.iter().find(|r| r.id == id.0)
    }
    pub fn item(&self, id: NodeId) -> Option<&ItemGeom> {
        self.items.iter().find(|r| r.id == id.0)
    }
    pub fn door(&self, id: NodeId) -> Option<&DoorGeom> {
        self.doors.iter().find(|r| r.id == id.0)
    }
    pub fn stairs(&self, id: NodeId) -> Option<&StairsGeom> {
        self.stairs.iter().find(|r| r.id == id.0)
    }
    pub fn robot(&self, id: NodeId) -> Option<&RobotGeom> {
        self.robots.iter().find(|r| r.id == id.0)
    }

    /// The first room, door, robot or object of the task without an entry, described.
    pub fn missing_entry(&self, task: &Task) -> Option<String> {
        task.indices().find_map(|n| {
            let node = task.node(n);
            let id = node.id;
            let (ok, list) = match node.kind {
                NodeKind::Room => (self.room(id).is_some(), "rooms"),
                NodeKind::Door => (
                    self.door(id).is_some() || self.stairs(id).is_some(),
                    "doors or stairs",
                ),
                NodeKind::Robot(_) => (self.robot(id).is_some(), "robots"),
                NodeKind::Floor | NodeKind::Tool => (true, ""),
                NodeKind::Object => (self.item(id).is_some(), "items"),
            };
            (!ok).then(|| format!("no entry in {list} for {}", node.label()))
        })
    }
}

/// Thickness of a container's walls and floor (and of a box's lid) for a box of height
/// `h`.
pub fn wall_of(h: f32) -> f32 {
    WALL.min(h / 4.0)
}

/// The thickest a container's walls get.
pub const WALL: f32 = 0.04;

/// Width of the square a landing quadrotor needs on a top: its frame plus the landing
/// search's clearance on each side.
pub fn landing_pad(specs: &RobotSpecs) -> f32 {
    2.0 * specs.quad_half + 0.4
}

/// The labels the `geometric` rule set derives rather than reads.
pub const DERIVED: PropSet =
    PropSet(PropSet::HIGH_HEIGHT.0 | PropSet::LOW_HEIGHT.0 | PropSet::ON_HIGH_SURFACE.0);

/// The `geometric` rule set's heights, derived from the layout and the robot specs:
///
/// - a surface is `HIGH_HEIGHT` when its top, above its room's floor, plus the tallest
///   movable thing of the scene is above the legged robot's highest hand point
///   ([`RobotSpecs::dog_max_height`]): something placed on it might be out of the
///   legged robot's grasp. A container that is not also a surface is judged by its
///   inner floor instead of its top. Every other surface and container, and every
///   floor, is `LOW_HEIGHT`;
/// - a thing starts `ON_HIGH_SURFACE` when its top is above that hand point or when
///   what it stands on or in (followed down to the floor) is `HIGH_HEIGHT`.
///
/// The file may not carry these three labels itself: a hand-set label is refused with
/// its JSON path. The same derivation also checks the rest of what the rules take from
/// geometry: every fixed arm reaches the top of everything that starts on its surface,
/// and every `LANDABLE` top is large enough for the quadrotor.
pub(crate) fn derive_heights(task: &mut Task, layout: &Layout, site: &Site<'_>) -> Result<()> {
    let nodes_site = site.key("graph").key("nodes");
    for n in task.indices() {
        let node = task.node(n);
        let hand_set = PropSet(node.properties.0 & DERIVED.0);
        if hand_set.0 != 0 {
            return Err(nodes_site.index(n.get()).key("properties").error(format!(
                "{}: {} comes from the geometry under the geometric rule set and may not be set by hand",
                node.label(),
                task.vocab.property_names(hand_set).join(", ")
            )));
        }
    }
    let geometry = site.key("geometry");
    let specs = &layout.specs;
    let hand = specs.dog_max_height();
    let tallest = task
        .indices()
        .filter(|&n| task.node(n).properties.contains(PropSet::GRABABLE))
        .filter_map(|n| layout.item(task.id(n)))
        .map(|g| g.size[1])
        .fold(0.0_f32, f32::max);
    // Each node's top above its room's floor, when it has a box.
    let tops: Vec<Option<f32>> = task
        .indices()
        .map(|n| {
            let level = room_of(task, n)
                .and_then(|r| layout.room(task.id(r)))
                .map_or(0.0, |r| r.level);
            layout
                .item(task.id(n))
                .map(|g| g.pos[1] + g.size[1] - level)
        })
        .collect();
    // A container's inner floor above its room's floor: where what it holds stands.
    let floors: Vec<Option<f32>> = task
        .indices()
        .map(|n| {
            let g = layout.item(task.id(n))?;
            tops[n.get()].map(|t| t - g.size[1] + wall_of(g.size[1]))
        })
        .collect();
    let holds = PropSet(PropSet::SURFACES.0 | PropSet::CONTAINERS.0);
    let labels: Vec<Option<PropSet>> = task
        .indices()
        .map(|n| {
            let node = task.node(n);
            if node.kind == NodeKind::Floor {
                Some(PropSet::LOW_HEIGHT)
            } else if node.properties.0 & holds.0 != 0 {
                let place = if node.properties.contains(PropSet::SURFACES) {
                    tops[n.get()]
                } else {
                    floors[n.get()]
                };
                place.map(|t| {
                    if t + tallest > hand {
                        PropSet::HIGH_HEIGHT
                    } else {
                        PropSet::LOW_HEIGHT
                    }
                })
            } else {
                None
            }
        })
        .collect();
    for (node, label) in task.nodes.iter_mut().zip(labels) {
        if let Some(label) = label {
            node.properties = node.properties.with(label);
        }
    }
    let high: Vec<Idx> = task
        .indices()
        .filter(|&n| {
            let tall = layout
                .item(task.id(n))
                .is_some_and(|g| g.dynamic && tops[n.get()].is_some_and(|t| t > hand));
            tall || below(task, n).any(|x| task.node(x).properties.contains(PropSet::HIGH_HEIGHT))
        })
        .collect();
    for n in high {
        task.init.set_on_high_surface(n, true);
    }
    for robot in task.robots.iter().filter(|r| r.kind == RobotKind::RobotArm) {
        let (Some(surface), Some(base)) = (
            task.init.targets(robot.node, Relation::On).next(),
            layout.robot(task.id(robot.node)),
        ) else {
            continue;
        };
        let shoulder = [base.pos[0], base.pos[1] + specs.arm_shoulder, base.pos[2]];
        for x in task.init.sources(Relation::On, surface) {
            let Some((i, g)) = layout
                .items
                .iter()
                .enumerate()
                .find(|(_, g)| g.id == task.id(x).0)
            else {
                continue;
            };
            let d = ((g.pos[0] - shoulder[0]).powi(2)
                + (g.pos[1] + g.size[1] - shoulder[1]).powi(2)
                + (g.pos[2] - shoulder[2]).powi(2))
            .sqrt();
            if d > specs.arm_reach() {
                return Err(geometry.key("items").index(i).key("pos").error(format!(
                    "{} on {} is {d:.2} m from the shoulder of {}; its reach is {:.2} m",
                    task.node(x).label(),
                    task.node(surface).label(),
                    task.node(robot.node).label(),
                    specs.arm_reach()
                )));
            }
        }
    }
    let pad = landing_pad(specs);
    for (i, g) in layout.items.iter().enumerate() {
        let Some(n) = task.idx(NodeId(g.id)) else {
            continue;
        };
        if task.node(n).properties.contains(PropSet::LANDABLE) && g.size[0].min(g.size[2]) < pad {
            return Err(geometry.key("items").index(i).key("size").error(format!(
                "{} is LANDABLE but its top, {:.2} x {:.2} m, is smaller than the quadrotor's landing pad of {pad:.2} m",
                task.node(n).label(),
                g.size[0],
                g.size[2]
            )));
        }
    }
    Ok(())
}

/// What `n` stands on or in, then what that stands on or in, and so on down (rooms
/// excepted) at the start.
fn below(task: &Task, n: Idx) -> impl Iterator<Item = Idx> + '_ {
    std::iter::successors(Some(n), move |&at| {
        task.init
            .out(at)
            .iter()
            .filter(|e| e.rel().is_location())
            .map(|e| e.to())
            .find(|&t| task.node(t).kind != NodeKind::Room)
    })
    .skip(1)
    .take(task.nodes.len())
}

/// The room `n` is in at the start: its own, or that of what it stands on or in.
fn room_of(task: &Task, n: Idx) -> Option<Idx> {
    std::iter::once(n)
        .chain(below(task, n))
        .find_map(|x| rules::room_of(task, &task.init, x))
}
