//! A top-down SVG picture of a scene: rooms with their names, doors with their state,
//! furniture with its top height, objects, robots, a legend, and optionally each
//! robot's path. A scene of several storeys is drawn as one panel per storey, side by
//! side, with its flights of stairs. [`svg`] is a pure function of the task, its
//! layout, a symbolic state (door and lid states) and the paths.

use std::fmt::Write as _;

use coherent_core::{Idx, NodeId, RobotKind, State, StateSet, Task};

use crate::layout::{self, Layout};

/// Each robot's track, `[x, y, z]` points (as in `PlanReport::paths`).
pub type Paths = [(NodeId, Vec<[f32; 3]>)];

/// Pixels per metre.
const SCALE: f32 = 56.0;
/// Margin around the house, in pixels; the legend goes to the right of it.
const MARGIN: f32 = 70.0;
const LEGEND_W: f32 = 250.0;
const FONT_ROOM: f32 = 24.0;
const FONT_ITEM: f32 = 15.0;
const FONT_OBJECT: f32 = 14.0;
/// Space between the panels of two storeys, in pixels.
const PANEL_GAP: f32 = 90.0;
/// Height of one step of a drawn flight, in metres.
const STEP_RISE: f32 = 0.18;

/// Colour and name of each robot kind's symbol.
fn robot_style(kind: RobotKind) -> (&'static str, &'static str) {
    match kind {
        RobotKind::Quadrotor => ("#1f6fd1", "quadrotor"),
        RobotKind::RobotDog => ("#e07b00", "legged robot"),
        RobotKind::RobotArm => ("#8a2be2", "fixed arm"),
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// `class id`, without the angle brackets of the action notation.
fn name(task: &Task, n: Idx) -> String {
    let node = task.node(n);
    format!("{} {}", node.class_name, node.id.0)
}

/// Estimated box of a text of `len` characters at `font` px, anchored at its left
/// baseline: `[x0, y0, x1, y1]`.
fn text_box(x: f32, y: f32, len: usize, font: f32) -> [f32; 4] {
    [
        x,
        y - font * 0.85,
        x + len as f32 * font * 0.58,
        y + font * 0.25,
    ]
}

fn overlaps(a: &[f32; 4], b: &[f32; 4]) -> bool {
    a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]
}

/// Labels placed so far: each new one takes the first candidate spot that overlaps
/// none of them.
struct Labels {
    /// The canvas, `[x0, y0, x1, y1]`: labels stay on it.
    canvas: [f32; 4],
    placed: Vec<[f32; 4]>,
    out: String,
}

impl Labels {
    /// Places `text` at the first free candidate left-baseline position (or the first
    /// one when all are taken); draws a leader line from `anchor` when it is far.
    fn place(
        &mut self,
        text: &str,
        font: f32,
        candidates: &[(f32, f32)],
        anchor: Option<(f32, f32)>,
        style: &str,
    ) {
        let lines: Vec<&str> = text.split('\n').collect();
        let len = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0);
        let extra = (lines.len() - 1) as f32 * font * 1.15;
        let text_box = |x: f32, y: f32, len: usize, font: f32| {
            let mut b = text_box(x, y, len, font);
            b[3] += extra;
            b
        };
        let pick = candidates
            .iter()
            .copied()
            .find(|&(x, y)| {
                let b = text_box(x, y, len, font);
                let c = self.canvas;
                b[0] >= c[0]
                    && b[1] >= c[1]
                    && b[2] <= c[2]
                    && b[3] <= c[3]
                    && self.placed.iter().all(|p| !overlaps(p, &b))
            })
            .or_else(|| candidates.first().copied());
        let Some((x, y)) = pick else {
            return;
        };
        let b = text_box(x, y, len, font);
        if let Some((ax, ay)) = anchor {
            let (cx, cy) = ((b[0] + b[2]) / 2.0, (b[1] + b[3]) / 2.0);
            let near_x = ax.clamp(b[0], b[2]);
            let near_y = ay.clamp(b[1], b[3]);
            if (near_x - ax).hypot(near_y - ay) > 10.0 {
                let _ = writeln!(
                    self.out,
                    r##"<line class="leader" x1="{ax:.1}" y1="{ay:.1}" x2="{:.1}" y2="{:.1}" stroke="#999" stroke-width="0.8"/>"##,
                    if ax < b[0] {
                        b[0]
                    } else if ax > b[2] {
                        b[2]
                    } else {
                        cx
                    },
                    if ay < b[1] {
                        b[1]
                    } else if ay > b[3] {
                        b[3]
                    } else {
                        cy
                    },
                );
            }
        }
        // A white halo keeps labels readable over lines and boxes.
        let body: String = lines
            .iter()
            .enumerate()
            .map(|(i, l)| {
                if i == 0 {
                    esc(l)
                } else {
                    format!(
                        r#"<tspan x="{x:.1}" dy="{:.1}">{}</tspan>"#,
                        font * 1.15,
                        esc(l)
                    )
                }
            })
            .collect();
        let _ = writeln!(
            self.out,
            r#"<text x="{x:.1}" y="{y:.1}" font-size="{font}" {style} stroke="white" stroke-width="3" paint-order="stroke">{body}</text>"#
        );
        self.placed.push(b);
    }
}

/// Candidate label positions around a point: right, left, above, below, then further
/// out in a spiral of steps.
fn around(x: f32, y: f32, len: usize, font: f32) -> Vec<(f32, f32)> {
    let w = len as f32 * font * 0.58;
    let mut c = Vec::new();
    for ring in 0..7 {
        let d = 6.0 + ring as f32 * font * 1.1;
        c.push((x + d, y + font * 0.35));
        c.push((x - d - w, y + font * 0.35));
        c.push((x - w / 2.0, y - d));
        c.push((x - w / 2.0, y + d + font * 0.7));
        c.push((x + d, y - d));
        c.push((x + d, y + d + font * 0.5));
        c.push((x - d - w, y - d));
        c.push((x - d - w, y + d + font * 0.5));
    }
    c
}

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
    // The house's extent (things set aside outside it are not drawn).
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
    let in_house = |x: f32, z: f32| x >= lo[0] && x <= hi[0] && z >= lo[1] && z <= hi[1];
    let house_w = (hi[0] - lo[0]) * SCALE;
    let house_h = (hi[1] - lo[1]) * SCALE;
    // One panel per storey, the lowest on the left.
    let mut storeys = layout::levels(layout);
    if storeys.is_empty() {
        storeys.push(0.0);
    }
    let panel_of_level = |level: f32| storeys.iter().position(|&l| l == level).unwrap_or(0);
    // The panel of the storey a point `[x, y, z]` is on.
    let panel = |p: [f32; 3]| layout::room_at(layout, p).map_or(0, |r| panel_of_level(r.level));
    let ox = |k: usize| k as f32 * (house_w + PANEL_GAP);
    let px = |x: f32, k: usize| MARGIN + (x - lo[0]) * SCALE + ox(k);
    let pz = |z: f32| MARGIN + (z - lo[1]) * SCALE;
    let total_w = house_w * storeys.len() as f32 + PANEL_GAP * (storeys.len() - 1) as f32;
    let width = total_w + 2.0 * MARGIN + LEGEND_W;
    let height = (house_h + 2.0 * MARGIN).max(420.0);
    let node_of = |id: i64| task.idx(NodeId(id));

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
        canvas: [2.0, 2.0, MARGIN + total_w + 15.0, height - 2.0],
        placed: Vec::new(),
        out: String::new(),
    };

    // Storeys' titles.
    if storeys.len() > 1 {
        let _ = writeln!(out, r#"<g class="storeys">"#);
        for (k, level) in storeys.iter().enumerate() {
            let (x, y) = (px(lo[0], k), MARGIN - 28.0);
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

    // Rooms.
    let _ = writeln!(out, r#"<g class="rooms">"#);
    for r in &layout.rooms {
        let (x0, y0) = (px(r.min[0], panel_of_level(r.level)), pz(r.min[1]));
        let (w, h) = ((r.max[0] - r.min[0]) * SCALE, (r.max[1] - r.min[1]) * SCALE);
        let _ = writeln!(
            out,
            r##"<rect x="{x0:.1}" y="{y0:.1}" width="{w:.1}" height="{h:.1}" fill="#f7f7f2" stroke="#333" stroke-width="3"/>"##
        );
        let text = match node_of(r.id) {
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

    // Doors: a thick bar across the opening.
    let _ = writeln!(out, r#"<g class="doors">"#);
    for d in &layout.doors {
        let open = node_of(d.id).is_none_or(|n| !state.states(n).contains(StateSet::CLOSED));
        let colour = if open { "#2e9e44" } else { "#d12f2f" };
        let k = panel_of_level(layout::door_level(layout, d));
        let (cx, cy) = (px(d.center[0], k), pz(d.center[1]));
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
            node_of(d.id).map_or_else(|| format!("door {}", d.id), |n| name(task, n)),
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

    // Flights of stairs: steps and an arrow up in the lower storey's panel, the open
    // stairwell dashed in the upper one.
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
        let (lower, upper) = (panel_of_level(f.lower), panel_of_level(f.upper));
        let (w, h) = ((rect[2] - rect[0]) * SCALE, (rect[3] - rect[1]) * SCALE);
        let (x0, y0) = (px(rect[0], lower), pz(rect[1]));
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
                px(c[0] - side[0], lower),
                pz(c[2] - side[1]),
                px(c[0] + side[0], lower),
                pz(c[2] + side[1])
            );
        }
        let (a, b) = (f.at(0.2, 0.0), f.at(f.run - 0.2, 0.0));
        let _ = writeln!(
            out,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#444" stroke-width="2.5" marker-end="url(#up)"/>"##,
            px(a[0], lower),
            pz(a[2]),
            px(b[0], lower),
            pz(b[2])
        );
        let name_of = |id: i64| {
            task.idx(NodeId(id))
                .map_or_else(|| format!("stairs {id}"), |n| name(task, n))
        };
        let text = format!("{} up to {:.2} m", name_of(f.id), f.upper);
        let cand = around(
            px((rect[0] + rect[2]) / 2.0, lower),
            pz((rect[1] + rect[3]) / 2.0),
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
            px(a[0], upper),
            pz(a[1]),
            px(b[0], upper),
            pz(b[1])
        );
        let x0 = px(rect[0], upper);
        let _ = writeln!(
            out,
            r##"<rect x="{x0:.1}" y="{y0:.1}" width="{w:.1}" height="{h:.1}" fill="none" stroke="#444" stroke-width="1.5" stroke-dasharray="5 4"/>"##
        );
        let text = format!("{} down to {:.2} m", name_of(f.id), f.lower);
        let cand = around(
            px((rect[0] + rect[2]) / 2.0, upper),
            pz((rect[1] + rect[3]) / 2.0),
            text.chars().count(),
            FONT_ITEM,
        );
        labels.place(&text, FONT_ITEM, &cand, None, r##"fill="#333""##);
    }
    if !flights.is_empty() {
        let _ = writeln!(out, "</g>");
    }

    // Furniture: fixed boxes, largest first so that what stands on a table is drawn
    // over it.
    let mut fixed: Vec<&crate::layout::ItemGeom> = layout
        .items
        .iter()
        .filter(|it| !it.dynamic && in_house(it.pos[0], it.pos[2]))
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
            px(it.pos[0], panel(it.pos)) - w / 2.0,
            pz(it.pos[2]) - d / 2.0,
        );
        let fill = if it.container { "#dbe9f6" } else { "#ecdcc0" };
        let _ = writeln!(
            out,
            r##"<rect x="{x0:.1}" y="{y0:.1}" width="{w:.1}" height="{d:.1}" fill="{fill}" stroke="#7a5c2e" stroke-width="1.5"/>"##
        );
        let Some(n) = node_of(it.id) else { continue };
        // Above the floor it stands on, as the geometric rules measure it.
        let top = it.pos[1] + it.size[1] - storeys[panel(it.pos)];
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

    // Robots (drawn before the objects' labels are placed, so that those avoid them).
    let robot_at = |id: i64| -> Option<(f32, f32, usize)> {
        let g = layout.robots.iter().find(|g| g.id == id)?;
        Some((g.pos[0], g.pos[2], panel(g.pos)))
    };
    let _ = writeln!(out, r#"<g class="robots">"#);
    let mut robot_marks = Vec::new();
    for r in &task.robots {
        let id = task.id(r.node).0;
        let Some((x, z, k)) = robot_at(id) else {
            continue;
        };
        let (cx, cy) = (px(x, k), pz(z));
        let (colour, _) = robot_style(r.kind);
        match r.kind {
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

    // Objects: small marks.
    let mut marks = Vec::new();
    let _ = writeln!(out, r#"<g class="objects">"#);
    for it in layout.items.iter().filter(|it| it.dynamic) {
        if !in_house(it.pos[0], it.pos[2]) {
            continue;
        }
        let (cx, cy) = (px(it.pos[0], panel(it.pos)), pz(it.pos[2]));
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
        if let Some(n) = node_of(it.id) {
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

    // Paths.
    if let Some(paths) = paths {
        let _ = writeln!(
            out,
            r#"<defs><marker id="arrow" viewBox="0 0 10 10" refX="8" refY="5" markerWidth="7" markerHeight="7" orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" fill="context-stroke"/></marker></defs>"#
        );
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
                let k = panel(*p);
                let point = format!("{:.1},{:.1}", px(p[0], k), pz(p[2]));
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
            let k = panel(pts[0]);
            let _ = writeln!(
                out,
                r#"<circle cx="{:.1}" cy="{:.1}" r="5" fill="{colour}"/>"#,
                px(pts[0][0], k),
                pz(pts[0][2])
            );
        }
        let _ = writeln!(out, "</g>");
    }

    out.push_str(r#"<g class="labels">"#);
    out.push('\n');
    out.push_str(&labels.out);
    out.push_str("</g>\n");

    // Legend.
    let lx = MARGIN + total_w + 30.0;
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
        esc(&task.meta.scene),
        task.meta.task_id
    );
    ly += 36.0;
    let entry = |out: &mut String, y: f32, symbol: String, text: &str| {
        let _ = writeln!(
            out,
            r#"{symbol}<text x="{:.1}" y="{:.1}" font-size="13">{}</text>"#,
            lx + 34.0,
            y + 5.0,
            esc(text)
        );
    };
    for kind in RobotKind::ALL {
        let (colour, what) = robot_style(kind);
        let symbol = match kind {
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
        };
        let text = if kind == RobotKind::RobotArm {
            format!("{what} (dashed: reach)")
        } else {
            what.to_string()
        };
        entry(&mut out, ly, symbol, &text);
        ly += 26.0;
    }
    let rows: [(String, &str); 6] = [
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
    ];
    for (symbol, text) in rows {
        entry(&mut out, ly, symbol, text);
        ly += 26.0;
    }
    if paths.is_some() {
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
    out.push_str("</g>\n</svg>\n");
    out
}
