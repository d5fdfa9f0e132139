//! A top-down SVG picture of a scene: rooms with their names, doors with their state,
//! furniture with its top height, objects, robots, a legend, and optionally each
//! robot's path. A scene of several storeys is drawn as one panel per storey, side by
//! side, with its flights of stairs. [`svg`] is a pure function of the task, its
//! layout, a symbolic state (door and lid states) and the paths.

mod frame;
mod items;
mod labels;
mod legend;
mod plan;
mod robots;

use std::fmt::Write as _;

use coherent_core::{State, Task};

pub use self::frame::Paths;
use self::frame::{Frame, MARGIN, esc};
use self::labels::Labels;
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
    let (width, height) = (frame.width, frame.height);
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="DejaVu Sans, Arial, sans-serif">"#
    );
    let _ = writeln!(
        out,
        r##"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="#ffffff"/>"##
    );
    let _ = writeln!(
        out,
        r#"<title>{} task {}</title>"#,
        esc(&task.meta.scene),
        task.meta.task_id
    );
    let mut labels = Labels {
        canvas: [2.0, 2.0, MARGIN + frame.total_w + 15.0, height - 2.0],
        placed: Vec::new(),
        out: String::new(),
    };

    plan::storeys(&mut out, &mut labels, &frame);
    plan::rooms(&mut out, &mut labels, &frame);
    plan::doors(&mut out, &mut labels, &frame, state);
    plan::stairs(&mut out, &mut labels, &frame);
    items::furniture(&mut out, &mut labels, &frame, state);
    // Robots before the objects' labels are placed, so that those avoid them.
    robots::robots(&mut out, &mut labels, &frame);
    items::objects(&mut out, &mut labels, &frame);
    if let Some(paths) = paths {
        robots::paths(&mut out, &frame, paths);
    }

    out.push_str(r#"<g class="labels">"#);
    out.push('\n');
    out.push_str(&labels.out);
    out.push_str("</g>\n");

    legend::legend(&mut out, &frame, paths.is_some());
    out.push_str("</svg>\n");
    out
}
