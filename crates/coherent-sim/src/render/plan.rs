//! The floor plan: each storey's title, the rooms with their names, the doors with
//! their state, and the flights of stairs.

use std::fmt::Write as _;

use coherent_core::{NodeId, State, StateSet};

use super::frame::{FONT_ITEM, FONT_ROOM, Frame, MARGIN, SCALE, STEP_RISE, name};
use super::labels::{Labels, around, text_box};
use crate::layout;

/// Each storey's title over its panel, when there are several.
pub(super) fn storeys(out: &mut String, labels: &mut Labels, frame: &Frame) {
    if frame.storeys.len() > 1 {
        let _ = writeln!(out, r#"<g class="storeys">"#);
        for (k, level) in frame.storeys.iter().enumerate() {
            let (x, y) = (frame.px(frame.lo[0], k), MARGIN - 28.0);
            let text = format!("level {level:.2} m");
            let _ = writeln!(
                out,
                r##"<text x="{x:.1}" y="{y:.1}" font-size="{FONT_ROOM}" font-weight="bold" fill="#555">{text}</text>"##
            );
            labels
                .placed
                .push(text_box(x, y, text.chars().count(), FONT_ROOM));
        }
        let _ = writeln!(out, "</g>");
    }
}

/// The rooms: outlines with their names.
pub(super) fn rooms(out: &mut String, labels: &mut Labels, frame: &Frame) {
    let (task, layout) = (frame.task, frame.layout);
    let _ = writeln!(out, r#"<g class="rooms">"#);
    for r in &layout.rooms {
        let (x0, y0) = (
            frame.px(r.min[0], frame.panel_of_level(r.level)),
            frame.pz(r.min[1]),
        );
        let (w, h) = ((r.max[0] - r.min[0]) * SCALE, (r.max[1] - r.min[1]) * SCALE);
        let _ = writeln!(
            out,
            r##"<rect x="{x0:.1}" y="{y0:.1}" width="{w:.1}" height="{h:.1}" fill="#f7f7f2" stroke="#333" stroke-width="3"/>"##
        );
        let text = match frame.node_of(r.id) {
            Some(n) if r.level != 0.0 => format!("{} (level {:.1} m)", name(task, n), r.level),
            Some(n) => name(task, n),
            None => format!("room {}", r.id),
        };
        labels.place(
            &text,
            FONT_ROOM,
            &[
                (x0 + 10.0, y0 + FONT_ROOM + 6.0),
                (x0 + 10.0, y0 + h - 10.0),
            ],
            None,
            r##"font-weight="bold" fill="#333""##,
        );
    }
    let _ = writeln!(out, "</g>");
}

/// The doors: a thick bar across the opening, green and dashed when open in `state`,
/// red when closed.
pub(super) fn doors(out: &mut String, labels: &mut Labels, frame: &Frame, state: &State) {
    let (task, layout) = (frame.task, frame.layout);
    let _ = writeln!(out, r#"<g class="doors">"#);
    for d in &layout.doors {
        let open = frame
            .node_of(d.id)
            .is_none_or(|n| !state.states(n).contains(StateSet::CLOSED));
        let colour = if open { "#2e9e44" } else { "#d12f2f" };
        let k = frame.panel_of_level(layout::door_level(layout, d));
        let (cx, cy) = (frame.px(d.center[0], k), frame.pz(d.center[1]));
        let half = d.width / 2.0 * SCALE;
        let (x1, y1, x2, y2) = if d.along_x {
            (cx - half, cy, cx + half, cy)
        } else {
            (cx, cy - half, cx, cy + half)
        };
        let dash = if open {
            r#" stroke-dasharray="6 4""#
        } else {
            ""
        };
        let _ = writeln!(
            out,
            r#"<line x1="{x1:.1}" y1="{y1:.1}" x2="{x2:.1}" y2="{y2:.1}" stroke="{colour}" stroke-width="7"{dash}/>"#
        );
        let text = format!(
            "{} {}",
            frame
                .node_of(d.id)
                .map_or_else(|| format!("door {}", d.id), |n| name(task, n)),
            if open { "open" } else { "closed" }
        );
        let len = text.chars().count();
        let cand = if d.along_x {
            vec![
                (cx + half + 6.0, cy + FONT_ITEM * 1.2),
                (cx + half + 6.0, cy - 6.0),
                (cx - half - 6.0 - len as f32 * FONT_ITEM * 0.58, cy - 6.0),
            ]
        } else {
            vec![
                (cx + 8.0, cy + half + FONT_ITEM),
                (cx + 8.0, cy - half - 6.0),
                (
                    cx - 8.0 - len as f32 * FONT_ITEM * 0.58,
                    cy + half + FONT_ITEM,
                ),
            ]
        };
        labels.place(
            &text,
            FONT_ITEM,
            &cand,
            None,
            &format!(r#"fill="{colour}""#),
        );
    }
    let _ = writeln!(out, "</g>");
}

/// The flights of stairs: steps and an arrow up in the lower storey's panel, the open
/// stairwell dashed in the upper one.
pub(super) fn stairs(out: &mut String, labels: &mut Labels, frame: &Frame) {
    let (task, layout) = (frame.task, frame.layout);
    let flights = layout::flights(layout).unwrap_or_default();
    if !flights.is_empty() {
        let _ = writeln!(
            out,
            r##"<defs><marker id="up" viewBox="0 0 10 10" refX="8" refY="5" markerWidth="6" markerHeight="6" orient="auto"><path d="M 0 0 L 10 5 L 0 10 z" fill="#444"/></marker></defs>"##
        );
        let _ = writeln!(out, r#"<g class="stairs">"#);
    }
    for f in &flights {
        let rect = f.rect();
        let (lower, upper) = (frame.panel_of_level(f.lower), frame.panel_of_level(f.upper));
        let (w, h) = ((rect[2] - rect[0]) * SCALE, (rect[3] - rect[1]) * SCALE);
        let (x0, y0) = (frame.px(rect[0], lower), frame.pz(rect[1]));
        let _ = writeln!(
            out,
            r##"<rect x="{x0:.1}" y="{y0:.1}" width="{w:.1}" height="{h:.1}" fill="#e6e6e6" stroke="#444" stroke-width="1.5"/>"##
        );
        let steps = ((f.upper - f.lower) / STEP_RISE).ceil().max(1.0) as usize;
        let side = [
            f.dir[1].abs() * f.width / 2.0,
            f.dir[0].abs() * f.width / 2.0,
        ];
        for i in 1..steps {
            let c = f.at(f.run * i as f32 / steps as f32, 0.0);
            let _ = writeln!(
                out,
                r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#777" stroke-width="1"/>"##,
                frame.px(c[0] - side[0], lower),
                frame.pz(c[2] - side[1]),
                frame.px(c[0] + side[0], lower),
                frame.pz(c[2] + side[1])
            );
        }
        let (a, b) = (f.at(0.2, 0.0), f.at(f.run - 0.2, 0.0));
        let _ = writeln!(
            out,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#444" stroke-width="2.5" marker-end="url(#up)"/>"##,
            frame.px(a[0], lower),
            frame.pz(a[2]),
            frame.px(b[0], lower),
            frame.pz(b[2])
        );
        let name_of = |id: i64| {
            task.idx(NodeId(id))
                .map_or_else(|| format!("stairs {id}"), |n| name(task, n))
        };
        let text = format!("{} up to {:.2} m", name_of(f.id), f.upper);
        let cand = around(
            frame.px((rect[0] + rect[2]) / 2.0, lower),
            frame.pz((rect[1] + rect[3]) / 2.0),
            text.chars().count(),
            FONT_ITEM,
        );
        labels.place(&text, FONT_ITEM, &cand, None, r##"fill="#333""##);
        // The opening in the upper room's wall where the flight arrives.
        let (a, b) = (
            [f.head[0] - side[0], f.head[1] - side[1]],
            [f.head[0] + side[0], f.head[1] + side[1]],
        );
        let _ = writeln!(
            out,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#f7f7f2" stroke-width="5"/>"##,
            frame.px(a[0], upper),
            frame.pz(a[1]),
            frame.px(b[0], upper),
            frame.pz(b[1])
        );
        let x0 = frame.px(rect[0], upper);
        let _ = writeln!(
            out,
            r##"<rect x="{x0:.1}" y="{y0:.1}" width="{w:.1}" height="{h:.1}" fill="none" stroke="#444" stroke-width="1.5" stroke-dasharray="5 4"/>"##
        );
        let text = format!("{} down to {:.2} m", name_of(f.id), f.lower);
        let cand = around(
            frame.px((rect[0] + rect[2]) / 2.0, upper),
            frame.pz((rect[1] + rect[3]) / 2.0),
            text.chars().count(),
            FONT_ITEM,
        );
        labels.place(&text, FONT_ITEM, &cand, None, r##"fill="#333""##);
    }
    if !flights.is_empty() {
        let _ = writeln!(out, "</g>");
    }
}
