//! The robots: a symbol per kind at the start pose with its name, and each robot's
//! path.

use std::fmt::Write as _;

use coherent_core::RobotKind;

use super::frame::{FONT_ITEM, Frame, Paths, SCALE, name, robot_style};
use super::labels::{Labels, around};
use crate::layout::Layout;

/// Each robot's symbol at its start pose, then their names (the marks are placed
/// first, so that no name covers another robot).
pub(super) fn robots(out: &mut String, labels: &mut Labels, frame: &Frame) {
    let (task, layout) = (frame.task, frame.layout);
    let robot_at = |id: i64| -> Option<(f32, f32, usize)> {
        let g = layout.robots.iter().find(|g| g.id == id)?;
        Some((g.pos[0], g.pos[2], frame.panel(g.pos)))
    };
    let _ = writeln!(out, r#"<g class="robots">"#);
    let mut robot_marks = Vec::new();
    for r in &task.robots {
        let id = task.id(r.node).0;
        let Some((x, z, k)) = robot_at(id) else {
            continue;
        };
        let (cx, cy) = (frame.px(x, k), frame.pz(z));
        symbol(out, layout, r.kind, cx, cy);
        robot_marks.push((r.node, r.kind, cx, cy));
    }
    let _ = writeln!(out, "</g>");
    let mark_radius = |kind: RobotKind| match kind {
        RobotKind::Quadrotor => layout.specs.quad_half * SCALE * 1.4,
        RobotKind::RobotDog => layout.specs.dog_half[0] * SCALE,
        RobotKind::RobotArm => 9.0,
    };
    for &(_, kind, cx, cy) in &robot_marks {
        let r = mark_radius(kind);
        labels.placed.push([cx - r, cy - r, cx + r, cy + r]);
    }
    for &(n, kind, cx, cy) in &robot_marks {
        let text = name(task, n);
        let (colour, _) = robot_style(kind);
        let r = mark_radius(kind);
        let cand = around(cx, cy, text.chars().count(), FONT_ITEM)
            .into_iter()
            .map(|(x, y)| {
                (
                    x + (x - cx).signum() * r * 0.8,
                    y + (y - cy).signum() * r * 0.5,
                )
            })
            .collect::<Vec<_>>();
        labels.place(
            &text,
            FONT_ITEM,
            &cand,
            Some((cx, cy)),
            &format!(r#"font-weight="bold" fill="{colour}""#),
        );
    }
}

/// A robot kind's symbol centred on `(cx, cy)`: a quadrotor's cross of rotors, a legged
/// robot's triangle, a fixed arm's square with its reach dashed around it.
pub(super) fn symbol(out: &mut String, layout: &Layout, kind: RobotKind, cx: f32, cy: f32) {
    let (colour, _) = robot_style(kind);
    match kind {
        RobotKind::Quadrotor => {
            let s = layout.specs.quad_half * SCALE;
            let _ = writeln!(
                out,
                r#"<g stroke="{colour}" stroke-width="3" fill="none"><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/><circle cx="{:.1}" cy="{:.1}" r="{:.1}"/><circle cx="{:.1}" cy="{:.1}" r="{:.1}"/><circle cx="{:.1}" cy="{:.1}" r="{:.1}"/><circle cx="{:.1}" cy="{:.1}" r="{:.1}"/></g>"#,
                cx - s,
                cy - s,
                cx + s,
                cy + s,
                cx - s,
                cy + s,
                cx + s,
                cy - s,
                cx - s,
                cy - s,
                s * 0.45,
                cx + s,
                cy - s,
                s * 0.45,
                cx - s,
                cy + s,
                s * 0.45,
                cx + s,
                cy + s,
                s * 0.45
            );
        }
        RobotKind::RobotDog => {
            let s = layout.specs.dog_half[0].max(layout.specs.dog_half[2]) * SCALE;
            let _ = writeln!(
                out,
                r##"<polygon points="{:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" fill="{colour}" stroke="#333" stroke-width="1.5"/>"##,
                cx,
                cy - s,
                cx + s,
                cy + s,
                cx - s,
                cy + s
            );
        }
        RobotKind::RobotArm => {
            let s = 9.0;
            let reach = layout.specs.arm_reach() * SCALE;
            let _ = writeln!(
                out,
                r##"<circle cx="{cx:.1}" cy="{cy:.1}" r="{reach:.1}" fill="none" stroke="{colour}" stroke-width="1" stroke-dasharray="3 4" opacity="0.6"/><rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{colour}" stroke="#333" stroke-width="1.5"/>"##,
                cx - s,
                cy - s,
                2.0 * s,
                2.0 * s
            );
        }
    }
}

/// The arrowhead that ends a path (`url(#arrow)`).
pub(super) fn arrow(out: &mut String) {
    let _ = writeln!(
        out,
        r#"<defs><marker id="arrow" viewBox="0 0 10 10" refX="8" refY="5" markerWidth="7" markerHeight="7" orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" fill="context-stroke"/></marker></defs>"#
    );
}

/// Each robot's path: one polyline per stretch on a storey, from a dot at the start to
/// an arrow at the end.
pub(super) fn paths(out: &mut String, frame: &Frame, paths: &Paths) {
    let task = frame.task;
    arrow(out);
    let _ = writeln!(out, r#"<g class="paths">"#);
    for (id, pts) in paths {
        if pts.len() < 2 {
            continue;
        }
        let kind = task
            .idx(*id)
            .and_then(|n| task.robot(n))
            .map_or(RobotKind::RobotDog, |r| r.kind);
        let (colour, _) = robot_style(kind);
        // One polyline per stretch on a storey; the arrow ends the last.
        let mut stretches: Vec<(usize, Vec<String>)> = Vec::new();
        for p in pts {
            let k = frame.panel(*p);
            let point = format!("{:.1},{:.1}", frame.px(p[0], k), frame.pz(p[2]));
            match stretches.last_mut() {
                Some((at, list)) if *at == k => list.push(point),
                _ => stretches.push((k, vec![point])),
            }
        }
        let last = stretches.len() - 1;
        for (i, (_, list)) in stretches.iter().enumerate() {
            if list.len() < 2 && i != last {
                continue;
            }
            let end = if i == last {
                r#" marker-end="url(#arrow)""#
            } else {
                ""
            };
            let _ = writeln!(
                out,
                r#"<polyline class="path" data-robot="{}" points="{}" fill="none" stroke="{colour}" stroke-width="3" stroke-opacity="0.85" stroke-linejoin="round"{end}/>"#,
                id.0,
                list.join(" ")
            );
        }
        let k = frame.panel(pts[0]);
        let _ = writeln!(
            out,
            r#"<circle cx="{:.1}" cy="{:.1}" r="5" fill="{colour}"/>"#,
            frame.px(pts[0][0], k),
            frame.pz(pts[0][2])
        );
    }
    let _ = writeln!(out, "</g>");
}
