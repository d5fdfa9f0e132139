//! The legend to the right of the panels: the task, a symbol per robot kind, the
//! furniture, objects and doors, the paths when drawn, and a 1 m scale bar.

use std::fmt::Write as _;

use coherent_core::RobotKind;
use coherent_core::text::markup;

use super::frame::{Frame, LEGEND_W, MARGIN, SCALE, robot_style};

/// The legend: a box with the task's name, a row per robot kind and per kind of thing,
/// what the lines are when `with_paths`, and the scale bar.
pub(super) fn legend(out: &mut String, frame: &Frame, with_paths: bool) {
    let task = frame.task;
    let lx = MARGIN + frame.total_w + 30.0;
    let mut ly = MARGIN;
    let _ = writeln!(
        out,
        r##"<g class="legend"><rect x="{:.1}" y="{:.1}" width="{:.1}" height="330" fill="#fafafa" stroke="#999"/>"##,
        lx - 10.0,
        ly - 10.0,
        LEGEND_W - 40.0
    );
    let _ = writeln!(
        out,
        r#"<text x="{lx:.1}" y="{:.1}" font-size="15" font-weight="bold">{} task {}</text>"#,
        ly + 12.0,
        markup(&task.meta.scene),
        task.meta.task_id
    );
    ly += 36.0;
    let entry = |out: &mut String, y: f32, symbol: String, text: &str| {
        let _ = writeln!(
            out,
            r#"{symbol}<text x="{:.1}" y="{:.1}" font-size="13">{}</text>"#,
            lx + 34.0,
            y + 5.0,
            markup(text)
        );
    };
    for kind in RobotKind::ALL {
        let (colour, what) = robot_style(kind);
        let symbol = kind_symbol(kind, colour, lx, ly);
        let text = if kind == RobotKind::RobotArm {
            format!("{what} (dashed: reach)")
        } else {
            what.to_string()
        };
        entry(out, ly, symbol, &text);
        ly += 26.0;
    }
    let rows = thing_rows(lx, ly);
    for (symbol, text) in rows {
        entry(out, ly, symbol, text);
        ly += 26.0;
    }
    if with_paths {
        let _ = writeln!(
            out,
            r#"<text x="{lx:.1}" y="{:.1}" font-size="13">lines: each robot's path,</text><text x="{lx:.1}" y="{:.1}" font-size="13">dot = start, arrow = end</text>"#,
            ly + 4.0,
            ly + 20.0
        );
    }
    let _ = writeln!(
        out,
        r##"<line x1="{lx:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#333" stroke-width="3"/><text x="{:.1}" y="{:.1}" font-size="12" fill="#333">1 m</text>"##,
        ly + 44.0,
        lx + SCALE,
        ly + 44.0,
        lx + SCALE + 8.0,
        ly + 48.0
    );
    out.push_str("</g>\n");
}

/// A robot kind's symbol in the legend's row at `ly`, in `colour`.
fn kind_symbol(kind: RobotKind, colour: &str, lx: f32, ly: f32) -> String {
    match kind {
        RobotKind::Quadrotor => format!(
            r#"<g stroke="{colour}" stroke-width="3"><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/></g>"#,
            lx + 4.0,
            ly - 7.0,
            lx + 18.0,
            ly + 7.0,
            lx + 4.0,
            ly + 7.0,
            lx + 18.0,
            ly - 7.0
        ),
        RobotKind::RobotDog => format!(
            r#"<polygon points="{:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" fill="{colour}"/>"#,
            lx + 11.0,
            ly - 8.0,
            lx + 19.0,
            ly + 8.0,
            lx + 3.0,
            ly + 8.0
        ),
        RobotKind::RobotArm => format!(
            r#"<rect x="{:.1}" y="{:.1}" width="14" height="14" fill="{colour}"/>"#,
            lx + 4.0,
            ly - 7.0
        ),
    }
}

/// The rows of the kinds of things, from the row at `ly` down: each one's symbol and
/// its text.
fn thing_rows(lx: f32, ly: f32) -> [(String, &'static str); 6] {
    [
        (
            format!(
                r##"<rect x="{:.1}" y="{:.1}" width="22" height="14" fill="#ecdcc0" stroke="#7a5c2e"/>"##,
                lx,
                ly - 7.0
            ),
            "furniture, top height",
        ),
        (
            format!(
                r##"<rect x="{:.1}" y="{:.1}" width="22" height="14" fill="#dbe9f6" stroke="#7a5c2e"/>"##,
                lx,
                ly + 19.0
            ),
            "fixed container",
        ),
        (
            format!(
                r##"<rect x="{:.1}" y="{:.1}" width="12" height="12" fill="#fbe3a0" stroke="#8a6d1f"/>"##,
                lx + 5.0,
                ly + 46.0
            ),
            "object",
        ),
        (
            format!(
                r##"<rect x="{:.1}" y="{:.1}" width="12" height="12" fill="#bfe3c7" stroke="#2b7a3d"/>"##,
                lx + 5.0,
                ly + 72.0
            ),
            "movable container",
        ),
        (
            format!(
                r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#2e9e44" stroke-width="7" stroke-dasharray="6 4"/>"##,
                lx,
                ly + 104.0,
                lx + 22.0,
                ly + 104.0
            ),
            "door open",
        ),
        (
            format!(
                r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#d12f2f" stroke-width="7"/>"##,
                lx,
                ly + 130.0,
                lx + 22.0,
                ly + 130.0
            ),
            "door closed",
        ),
    ]
}
