//! What the `geometric` rule set takes from a task's [`Layout`]: the height labels,
//! derived instead of hand-set (`derive_heights`), and the checks that tie a layout to
//! its graph (every room, door, robot and object has an entry; every fixed arm reaches
//! what starts on its surface; every `LANDABLE` top is large enough).

use crate::error::{Result, Site};
use crate::geometry::{DERIVED, Layout, landing_pad, wall_of};
use crate::graph::{Idx, NodeId, NodeKind, RobotKind};
use crate::rules;
use crate::task::Task;
use crate::vocab::{PropSet, Relation};

impl Layout {
    /// The first room, door, robot or object of the task without an entry, described.
    pub fn missing_entry(&self, task: &Task) -> Option<String> {
        task.indices().find_map(|n| {
            let node = task.node(n);
            let id = node.id;
            let (ok, list) = match node.kind {
                NodeKind::Room => (self.room(id).is_some(), "rooms"),
                NodeKind::Door => (
                    self.door(id).is_some() || self.stairs(id).is_some(),
                    "doors or stairs",
                ),
                NodeKind::Robot(_) => (self.robot(id).is_some(), "robots"),
                NodeKind::Floor | NodeKind::Tool => (true, ""),
                NodeKind::Object => (self.item(id).is_some(), "items"),
            };
            (!ok).then(|| format!("no entry in {list} for {}", node.short_label()))
        })
    }
}

/// The `geometric` rule set's heights, derived from the layout and the robot specs:
///
/// - a surface is `HIGH_HEIGHT` when its top, above its room's floor, plus the tallest
///   movable thing of the scene is above the legged robot's highest hand point
///   ([`RobotSpecs::dog_max_height`]): something placed on it might be out of the
///   legged robot's grasp. A container that is not also a surface is judged by its
///   inner floor instead of its top. Every other surface and container, and every
///   floor, is `LOW_HEIGHT`;
/// - a thing starts `ON_HIGH_SURFACE` when its top is above that hand point or when
///   what it stands on or in (followed down to the floor) is `HIGH_HEIGHT`.
///
/// The file may not carry these three labels itself: a hand-set label is refused with
/// its JSON path. The same derivation also checks the rest of what the rules take from
/// geometry: every fixed arm reaches the top of everything that starts on its surface,
/// and every `LANDABLE` top is large enough for the quadrotor.
///
/// [`RobotSpecs::dog_max_height`]: crate::geometry::RobotSpecs::dog_max_height
pub(crate) fn derive_heights(task: &mut Task, layout: &Layout, site: &Site<'_>) -> Result<()> {
    let nodes_site = site.key("graph").key("nodes");
    for n in task.indices() {
        let node = task.node(n);
        let hand_set = PropSet(node.properties.0 & DERIVED.0);
        if hand_set.0 != 0 {
            return Err(nodes_site.index(n.get()).key("properties").error(format!(
                "{}: {} comes from the geometry under the geometric rule set and may not be set by hand",
                node.short_label(),
                task.vocab.property_names(hand_set).join(", ")
            )));
        }
    }
    let geometry = site.key("geometry");
    let specs = &layout.specs;
    let hand = specs.dog_max_height();
    let tallest = task
        .indices()
        .filter(|&n| task.node(n).properties.contains(PropSet::GRABABLE))
        .filter_map(|n| layout.item(task.id(n)))
        .map(|g| g.size[1])
        .fold(0.0_f32, f32::max);
    // Each node's top above its room's floor, when it has a box.
    let tops: Vec<Option<f32>> = task
        .indices()
        .map(|n| {
            let level = room_of(task, n)
                .and_then(|r| layout.room(task.id(r)))
                .map_or(0.0, |r| r.level);
            layout
                .item(task.id(n))
                .map(|g| g.pos[1] + g.size[1] - level)
        })
        .collect();
    // A container's inner floor above its room's floor: where what it holds stands.
    let floors: Vec<Option<f32>> = task
        .indices()
        .map(|n| {
            let g = layout.item(task.id(n))?;
            tops[n.get()].map(|t| t - g.size[1] + wall_of(g.size[1]))
        })
        .collect();
    let holds = PropSet(PropSet::SURFACES.0 | PropSet::CONTAINERS.0);
    let labels: Vec<Option<PropSet>> = task
        .indices()
        .map(|n| {
            let node = task.node(n);
            if node.kind == NodeKind::Floor {
                Some(PropSet::LOW_HEIGHT)
            } else if node.properties.0 & holds.0 != 0 {
                let place = if node.properties.contains(PropSet::SURFACES) {
                    tops[n.get()]
                } else {
                    floors[n.get()]
                };
                place.map(|t| {
                    if t + tallest > hand {
                        PropSet::HIGH_HEIGHT
                    } else {
                        PropSet::LOW_HEIGHT
                    }
                })
            } else {
                None
            }
        })
        .collect();
    for (node, label) in task.nodes.iter_mut().zip(labels) {
        if let Some(label) = label {
            node.properties = node.properties.with(label);
        }
    }
    task.find_node_sets();
    let high: Vec<Idx> = task
        .indices()
        .filter(|&n| {
            let tall = layout
                .item(task.id(n))
                .is_some_and(|g| g.dynamic && tops[n.get()].is_some_and(|t| t > hand));
            tall || below(task, n).any(|x| task.node(x).properties.contains(PropSet::HIGH_HEIGHT))
        })
        .collect();
    for n in high {
        task.init.set_on_high_surface(n, true);
    }
    for robot in task.robots.iter().filter(|r| r.kind == RobotKind::RobotArm) {
        let (Some(surface), Some(base)) = (
            task.init.targets(robot.node, Relation::On).next(),
            layout.robot(task.id(robot.node)),
        ) else {
            continue;
        };
        let shoulder = [base.pos[0], base.pos[1] + specs.arm_shoulder, base.pos[2]];
        for x in task.init.sources(Relation::On, surface) {
            let Some((i, g)) = layout
                .items
                .iter()
                .enumerate()
                .find(|(_, g)| g.id == task.id(x).0)
            else {
                continue;
            };
            let d = ((g.pos[0] - shoulder[0]).powi(2)
                + (g.pos[1] + g.size[1] - shoulder[1]).powi(2)
                + (g.pos[2] - shoulder[2]).powi(2))
            .sqrt();
            if d > specs.arm_reach() {
                return Err(geometry.key("items").index(i).key("pos").error(format!(
                    "{} on {} is {d:.2} m from the shoulder of {}; its reach is {:.2} m",
                    task.node(x).short_label(),
                    task.node(surface).short_label(),
                    task.node(robot.node).short_label(),
                    specs.arm_reach()
                )));
            }
        }
    }
    let pad = landing_pad(specs);
    for (i, g) in layout.items.iter().enumerate() {
        let Some(n) = task.idx(NodeId(g.id)) else {
            continue;
        };
        if task.node(n).properties.contains(PropSet::LANDABLE) && g.size[0].min(g.size[2]) < pad {
            return Err(geometry.key("items").index(i).key("size").error(format!(
                "{} is LANDABLE but its top, {:.2} x {:.2} m, is smaller than the quadrotor's landing pad of {pad:.2} m",
                task.node(n).short_label(),
                g.size[0],
                g.size[2]
            )));
        }
    }
    Ok(())
}

/// What `n` stands on or in, then what that stands on or in, and so on down (rooms
/// excepted) at the start.
fn below(task: &Task, n: Idx) -> impl Iterator<Item = Idx> + '_ {
    std::iter::successors(Some(n), move |&at| {
        task.init
            .out(at)
            .iter()
            .filter(|e| e.rel().is_location())
            .map(|e| e.to())
            .find(|&t| task.node(t).kind != NodeKind::Room)
    })
    .skip(1)
    .take(task.nodes.len())
}

/// The room `n` is in at the start: its own, or that of what it stands on or in.
fn room_of(task: &Task, n: Idx) -> Option<Idx> {
    std::iter::once(n)
        .chain(below(task, n))
        .find_map(|x| rules::room_of(task, &task.init, x))
}
