//! The geometry of a scene: rooms, doors, stairs, furniture, objects, robot start poses
//! and robot specs, in metres. As JSON it is the `geometry` object of a native task file
//! (`docs/task-format.md`); `coherent-sim` builds its physical world from it.
//!
//! Frame: `y` up, each room's floor at its `level`; positions are the bottom centre of a
//! box.
//!
//! Under the `geometric` rule set (the project's own benchmark) the heights the rules
//! need are derived from the geometry and the robot specs instead of being hand-set
//! labels: see the `heights` module.

use serde::{Deserialize, Serialize};

use crate::graph::NodeId;
use crate::vocab::PropSet;

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
