//! Labels placed where they overlap no other label or mark, with a leader line back to
//! what they name when they land far from it.

use std::fmt::Write as _;

use coherent_core::text::markup;

/// Estimated box of a text of `len` characters at `font` px, anchored at its left
/// baseline: `[x0, y0, x1, y1]`.
pub(super) fn text_box(x: f32, y: f32, len: usize, font: f32) -> [f32; 4] {
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
pub(super) struct Labels {
    /// The canvas, `[x0, y0, x1, y1]`: labels stay on it.
    pub(super) canvas: [f32; 4],
    pub(super) placed: Vec<[f32; 4]>,
    pub(super) out: String,
}

impl Labels {
    /// Places `text` at the first free candidate left-baseline position (or the first
    /// one when all are taken); draws a leader line from `anchor` when it is far.
    pub(super) fn place(
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
                    markup(l).into_owned()
                } else {
                    format!(
                        r#"<tspan x="{x:.1}" dy="{:.1}">{}</tspan>"#,
                        font * 1.15,
                        markup(l)
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
pub(super) fn around(x: f32, y: f32, len: usize, font: f32) -> Vec<(f32, f32)> {
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
