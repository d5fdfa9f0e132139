//! The picture itself, layer by layer: the floor plan, the furniture, the objects, the
//! robots and their paths (or, for a viewer, their symbols to place), the labels and
//! the legend.

use std::fmt::Write as _;

use coherent_core::State;
use coherent_core::text::markup;

use super::frame::{Frame, MARGIN, Paths};
use super::labels::Labels;
use super::{items, legend, plan, robots};

/// How the robots and their paths get into the picture.
pub(super) enum Movers<'p> {
    /// At their start poses, with their paths when given.
    Drawn(Option<&'p Paths>),
    /// Not drawn: a viewer places them ([`Stage`](super::Stage)); `defs` (their symbols)
    /// goes into the picture, and the legend explains the paths.
    Placed { defs: &'p str },
}

pub(super) fn draw(frame: &Frame, state: &State, movers: Movers<'_>) -> String {
    let task = frame.task;
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
        markup(&task.meta.scene),
        task.meta.task_id
    );
    let mut labels = Labels {
        canvas: [2.0, 2.0, MARGIN + frame.total_w + 15.0, height - 2.0],
        placed: Vec::new(),
        out: String::new(),
    };

    plan::storeys(&mut out, &mut labels, frame);
    plan::rooms(&mut out, &mut labels, frame);
    plan::doors(&mut out, &mut labels, frame, state);
    plan::stairs(&mut out, &mut labels, frame);
    items::furniture(&mut out, &mut labels, frame, state);
    // Robots before the objects' labels are placed, so that those avoid them.
    if let Movers::Drawn(_) = movers {
        robots::robots(&mut out, &mut labels, frame);
    }
    items::objects(&mut out, &mut labels, frame);
    let with_paths = match movers {
        Movers::Drawn(Some(paths)) => {
            robots::paths(&mut out, frame, paths);
            true
        }
        Movers::Drawn(None) => false,
        Movers::Placed { defs } => {
            robots::arrow(&mut out);
            out.push_str(defs);
            true
        }
    };

    out.push_str(r#"<g class="labels">"#);
    out.push('\n');
    out.push_str(&labels.out);
    out.push_str("</g>\n");

    legend::legend(&mut out, frame, with_paths);
    out.push_str("</svg>\n");
    out
}
