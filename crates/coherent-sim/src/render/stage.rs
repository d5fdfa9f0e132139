//! The scene for a viewer that moves the robots itself (`coherent view`): the picture
//! [`super::svg`] draws, without the robots and their paths, with each robot's symbol
//! defined once to be placed anywhere, and the picture's coordinates of any point.

use std::fmt::Write as _;

use coherent_core::text::markup;
use coherent_core::{NodeId, RobotKind, State, Task};

use super::frame::{Frame, robot_style};
use super::picture::{Movers, draw};
use super::robots;
use crate::layout::Layout;

/// A scene drawn once per state, its robots placed by whoever shows it.
pub struct Stage<'a> {
    frame: Frame<'a>,
}

impl std::fmt::Debug for Stage<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stage")
            .field("task", &self.frame.task.meta.name)
            .finish_non_exhaustive()
    }
}

/// The colour a robot kind is drawn in (its symbol and its path).
pub fn robot_colour(kind: RobotKind) -> &'static str {
    robot_style(kind).0
}

impl<'a> Stage<'a> {
    pub fn new(task: &'a Task, layout: &'a Layout) -> Stage<'a> {
        Stage {
            frame: Frame::new(task, layout),
        }
    }

    pub fn task(&self) -> &'a Task {
        self.frame.task
    }

    /// The scene in `state` as [`super::svg`] draws it, without robots or paths; in its
    /// `<defs>`, each robot's symbol centred on the origin as `<g id="{ids}robot-{id}">`
    /// (`ids` keeps the ids of several pictures in one page apart), and the arrowhead
    /// `url(#arrow)` that ends a path.
    pub fn svg(&self, state: &State, ids: &str) -> String {
        let (task, layout) = (self.frame.task, self.frame.layout);
        let mut defs = String::from("<defs>\n");
        for r in &task.robots {
            let _ = write!(
                defs,
                r#"<g id="{}robot-{}">"#,
                markup(ids),
                task.id(r.node).0
            );
            robots::symbol(&mut defs, layout, r.kind, 0.0, 0.0);
            defs.push_str("</g>\n");
        }
        defs.push_str("</defs>\n");
        draw(&self.frame, state, Movers::Placed { defs: &defs })
    }

    /// Where the point `[x, y, z]` of the scene is drawn: `[x, y]` in the picture (on
    /// the panel of its storey).
    pub fn point(&self, p: [f32; 3]) -> [f32; 2] {
        let k = self.frame.panel(p);
        [self.frame.px(p[0], k), self.frame.pz(p[2])]
    }

    /// Where `robot` starts in the scene's layout, `[x, y, z]`.
    pub fn start(&self, robot: NodeId) -> Option<[f32; 3]> {
        self.frame
            .layout
            .robots
            .iter()
            .find(|g| g.id == robot.0)
            .map(|g| g.pos)
    }
}
