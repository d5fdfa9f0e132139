//! Furniture (fixed boxes with their name and top height) and objects (small marks with
//! their names).

use std::fmt::Write as _;

use coherent_core::{State, StateSet};

use super::frame::{FONT_ITEM, FONT_OBJECT, Frame, SCALE, name};
use super::labels::{Labels, around};

/// Furniture: fixed boxes, largest first so that what stands on a table is drawn
/// over it; a lidded container says whether it is open in `state`.
pub(super) fn furniture(out: &mut String, labels: &mut Labels, frame: &Frame, state: &State) {
    let (task, layout) = (frame.task, frame.layout);
    let mut fixed: Vec<&crate::layout::ItemGeom> = layout
        .items
        .iter()
        .filter(|it| !it.dynamic && frame.in_house(it.pos[0], it.pos[2]))
        .collect();
    fixed.sort_by(|a, b| {
        (b.size[0] * b.size[2])
            .total_cmp(&(a.size[0] * a.size[2]))
            .then(a.id.cmp(&b.id))
    });
    let _ = writeln!(out, r#"<g class="furniture">"#);
    for it in &fixed {
        let (w, d) = (it.size[0] * SCALE, it.size[2] * SCALE);
        let (x0, y0) = (
            frame.px(it.pos[0], frame.panel(it.pos)) - w / 2.0,
            frame.pz(it.pos[2]) - d / 2.0,
        );
        let fill = if it.container { "#dbe9f6" } else { "#ecdcc0" };
        let _ = writeln!(
            out,
            r##"<rect x="{x0:.1}" y="{y0:.1}" width="{w:.1}" height="{d:.1}" fill="{fill}" stroke="#7a5c2e" stroke-width="1.5"/>"##
        );
        let Some(n) = frame.node_of(it.id) else {
            continue;
        };
        // Above the floor it stands on, as the geometric rules measure it.
        let top = it.pos[1] + it.size[1] - frame.storeys[frame.panel(it.pos)];
        let mut text = format!("{}\ntop {:.2} m", name(task, n), top);
        if it.container && it.lid != crate::layout::Lid::None {
            let st = state.states(n);
            if st.contains(StateSet::CLOSED) {
                text.push_str(" closed");
            } else if st.contains(StateSet::OPEN) {
                text.push_str(" open");
            }
        }
        let len = text
            .split('\n')
            .map(|l| l.chars().count())
            .max()
            .unwrap_or(0);
        let tw = len as f32 * FONT_ITEM * 0.58;
        let mut cand = vec![
            (x0, y0 + d + FONT_ITEM + 3.0),
            (x0 + w - tw, y0 + d + FONT_ITEM + 3.0),
            (x0, y0 - 5.0 - FONT_ITEM * 1.15),
            (x0 + w + 5.0, y0 + FONT_ITEM),
        ];
        cand.extend(around(
            x0 + w / 2.0 - tw / 2.0,
            y0 + d / 2.0,
            len,
            FONT_ITEM,
        ));
        labels.place(
            &text,
            FONT_ITEM,
            &cand,
            Some((x0 + w / 2.0, y0 + d / 2.0)),
            r##"fill="#5a3d12""##,
        );
    }
    let _ = writeln!(out, "</g>");
}

/// Objects: small marks, and their names placed around them.
pub(super) fn objects(out: &mut String, labels: &mut Labels, frame: &Frame) {
    let (task, layout) = (frame.task, frame.layout);
    let mut marks = Vec::new();
    let _ = writeln!(out, r#"<g class="objects">"#);
    for it in layout.items.iter().filter(|it| it.dynamic) {
        if !frame.in_house(it.pos[0], it.pos[2]) {
            continue;
        }
        let (cx, cy) = (
            frame.px(it.pos[0], frame.panel(it.pos)),
            frame.pz(it.pos[2]),
        );
        let (w, d) = (it.size[0] * SCALE, it.size[2] * SCALE);
        let (fill, stroke) = if it.container {
            ("#bfe3c7", "#2b7a3d")
        } else {
            ("#fbe3a0", "#8a6d1f")
        };
        let _ = writeln!(
            out,
            r#"<rect x="{:.1}" y="{:.1}" width="{w:.1}" height="{d:.1}" rx="2" fill="{fill}" stroke="{stroke}" stroke-width="1.2"/>"#,
            cx - w / 2.0,
            cy - d / 2.0
        );
        if let Some(n) = frame.node_of(it.id) {
            marks.push((n, cx, cy, it.pos[1] + it.size[1]));
        }
    }
    let _ = writeln!(out, "</g>");
    for &(_, cx, cy, _) in &marks {
        labels.placed.push([cx - 3.0, cy - 3.0, cx + 3.0, cy + 3.0]);
    }
    for &(n, cx, cy, _) in &marks {
        let text = name(task, n);
        let cand = around(cx, cy, text.chars().count(), FONT_OBJECT);
        labels.place(
            &text,
            FONT_OBJECT,
            &cand,
            Some((cx, cy)),
            r##"fill="#222""##,
        );
    }
}
