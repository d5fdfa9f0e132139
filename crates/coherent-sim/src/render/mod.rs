//! A top-down SVG picture of a scene: rooms with their names, doors with their state,
//! furniture with its top height, objects, robots, a legend, and optionally each
//! robot's path. A scene of several storeys is drawn as one panel per storey, side by
//! side, with its flights of stairs. [`svg`] is a pure function of the task, its
//! layout, a symbolic state (door and lid states) and the paths.

mod frame;
mod items;
mod labels;
mod legend;
mod picture;
mod plan;
mod robots;
mod stage;

use coherent_core::{State, Task};

use self::frame::Frame;
pub use self::frame::Paths;
use self::picture::{Movers, draw};
pub use self::stage::{Stage, robot_colour};
use crate::layout::Layout;

/// A top-down SVG picture of the scene (x to the right, z down): room outlines with
/// names, doors green when OPEN and red when CLOSED in `state`, furniture boxes with
/// their name and top height in metres, objects as small marks with names, robots as
/// a symbol per kind at their start pose, a legend, and each robot's path in `paths`
/// (as in `PlanReport::paths`) as a polyline from a dot to an arrow. With several
/// storeys each is a panel titled with its level, left to right from the lowest; a
/// flight of stairs is drawn in its lower storey's panel with its steps and an arrow
/// up, and as a dashed stairwell in the upper one; paths are split where they change
/// storey.
pub fn svg(task: &Task, layout: &Layout, state: &State, paths: Option<&Paths>) -> String {
    let frame = Frame::new(task, layout);
    draw(&frame, state, Movers::Drawn(paths))
}
