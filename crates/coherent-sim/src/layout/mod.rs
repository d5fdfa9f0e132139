//! Where everything is. A task's `geometry` (native files, [`coherent_core::geometry`])
//! is used as it is; without one (every imported original task) [`generate()`] derives
//! a deterministic layout from the graph (`generate.rs`). [`flights`] works out and
//! checks a layout's stairs, and [`room_at`], [`levels`] and [`door_level`] answer
//! where things are on its storeys (`storeys.rs`).
//!
//! Frame: metres, `y` up, the floor at `y = 0`; positions are the bottom centre of a box.

mod error;
mod generate;
mod storeys;

use coherent_core::Task;
pub use coherent_core::geometry::{
    DoorGeom, ItemGeom, Layout, Lid, RobotGeom, RobotSpecs, RoomGeom, StairsGeom, WALL,
    landing_pad, wall_of,
};

pub use self::error::LayoutError;
pub use self::generate::{ASIDE, arm_spot, generate};
pub use self::storeys::{
    Flight, MAX_FLIGHT_SLOPE, MIN_FLIGHT_WIDTH, door_level, flights, levels, room_at,
};

/// The task's own geometry when it has one (checked when the task was read), otherwise
/// a generated layout.
pub fn for_task(task: &Task) -> Result<Layout, LayoutError> {
    match &task.meta.geometry {
        Some(layout) => Ok(layout.clone()),
        None => generate(task),
    }
}
