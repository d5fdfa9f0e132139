//! The picture's frame: its scale, margins and fonts, where a point of the floor plan
//! is drawn (one panel per storey, side by side), and the names and styles every part
//! of the picture shares.

use coherent_core::text::shown;
use coherent_core::{Idx, NodeId, RobotKind, Task};

use crate::layout::{self, Layout};

/// Each robot's track, `[x, y, z]` points (as in `PlanReport::paths`).
pub type Paths = [(NodeId, Vec<[f32; 3]>)];

/// Pixels per metre.
pub(super) const SCALE: f32 = 56.0;
/// Margin around the house, in pixels; the legend goes to the right of it.
pub(super) const MARGIN: f32 = 70.0;
pub(super) const LEGEND_W: f32 = 250.0;
pub(super) const FONT_ROOM: f32 = 24.0;
pub(super) const FONT_ITEM: f32 = 15.0;
pub(super) const FONT_OBJECT: f32 = 14.0;
/// Space between the panels of two storeys, in pixels.
pub(super) const PANEL_GAP: f32 = 90.0;
/// Height of one step of a drawn flight, in metres.
pub(super) const STEP_RISE: f32 = 0.18;

/// Colour and name of each robot kind's symbol.
pub(super) fn robot_style(kind: RobotKind) -> (&'static str, &'static str) {
    match kind {
        RobotKind::Quadrotor => ("#1f6fd1", "quadrotor"),
        RobotKind::RobotDog => ("#e07b00", "legged robot"),
        RobotKind::RobotArm => ("#8a2be2", "fixed arm"),
    }
}

/// `class id`, without the angle brackets of the action notation; a control character of
/// the name shown as an escape ([`shown`]), so that a line break in it does not start a
/// new line of the label that quotes it.
pub(super) fn name(task: &Task, n: Idx) -> String {
    let node = task.node(n);
    format!("{} {}", shown(&node.class_name), node.id.0)
}

/// Where things are drawn: the house's extent on the floor plan (things set aside
/// outside it are not drawn), one panel per storey, the lowest on the left, and the
/// picture's size.
pub(super) struct Frame<'a> {
    pub(super) task: &'a Task,
    pub(super) layout: &'a Layout,
    /// The house's lowest `[x, z]` corner.
    pub(super) lo: [f32; 2],
    hi: [f32; 2],
    /// One panel's width, in pixels.
    house_w: f32,
    /// Each storey's floor level, one panel each.
    pub(super) storeys: Vec<f32>,
    /// The panels' width together, in pixels.
    pub(super) total_w: f32,
    pub(super) width: f32,
    pub(super) height: f32,
}

impl<'a> Frame<'a> {
    pub(super) fn new(task: &'a Task, layout: &'a Layout) -> Frame<'a> {
        let mut lo = [f32::INFINITY; 2];
        let mut hi = [f32::NEG_INFINITY; 2];
        for r in &layout.rooms {
            for k in 0..2 {
                lo[k] = lo[k].min(r.min[k]);
                hi[k] = hi[k].max(r.max[k]);
            }
        }
        if layout.rooms.is_empty() {
            lo = [0.0; 2];
            hi = [1.0; 2];
        }
        let house_w = (hi[0] - lo[0]) * SCALE;
        let house_h = (hi[1] - lo[1]) * SCALE;
        let mut storeys = layout::levels(layout);
        if storeys.is_empty() {
            storeys.push(0.0);
        }
        let total_w = house_w * storeys.len() as f32 + PANEL_GAP * (storeys.len() - 1) as f32;
        Frame {
            task,
            layout,
            lo,
            hi,
            house_w,
            storeys,
            total_w,
            width: total_w + 2.0 * MARGIN + LEGEND_W,
            height: (house_h + 2.0 * MARGIN).max(420.0),
        }
    }

    pub(super) fn in_house(&self, x: f32, z: f32) -> bool {
        let (lo, hi) = (self.lo, self.hi);
        x >= lo[0] && x <= hi[0] && z >= lo[1] && z <= hi[1]
    }

    /// The panel of the storey at `level`.
    pub(super) fn panel_of_level(&self, level: f32) -> usize {
        self.storeys.iter().position(|&l| l == level).unwrap_or(0)
    }

    /// The panel of the storey a point `[x, y, z]` is on.
    pub(super) fn panel(&self, p: [f32; 3]) -> usize {
        layout::room_at(self.layout, p).map_or(0, |r| self.panel_of_level(r.level))
    }

    /// The picture's x of the floor plan's `x` in panel `k`.
    pub(super) fn px(&self, x: f32, k: usize) -> f32 {
        MARGIN + (x - self.lo[0]) * SCALE + k as f32 * (self.house_w + PANEL_GAP)
    }

    /// The picture's y of the floor plan's `z`.
    pub(super) fn pz(&self, z: f32) -> f32 {
        MARGIN + (z - self.lo[1]) * SCALE
    }

    pub(super) fn node_of(&self, id: i64) -> Option<Idx> {
        self.task.idx(NodeId(id))
    }
}
