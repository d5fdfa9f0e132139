//! The top-down picture is well-formed, names every room and robot, and draws paths
//! only when given them.

use coherent_core::NodeKind;
use coherent_sim::{layout, render};

mod common;

/// Tag names in document order must nest: every opening tag is closed, in order.
fn balanced(svg: &str) -> Result<usize, String> {
    let mut stack: Vec<String> = Vec::new();
    let mut count = 0;
    let mut rest = svg;
    while let Some(i) = rest.find('<') {
        let after = &rest[i + 1..];
        let j = after.find('>').ok_or("an unclosed '<'")?;
        let tag = &after[..j];
        rest = &after[j + 1..];
        count += 1;
        if let Some(name) = tag.strip_prefix('/') {
            let open = stack.pop().ok_or(format!("</{name}> closes nothing"))?;
            if open != name.trim() {
                return Err(format!("<{open}> closed by </{name}>"));
            }
        } else if !tag.ends_with('/') && !tag.starts_with('?') && !tag.starts_with('!') {
            let name = tag.split_whitespace().next().ok_or("an empty tag")?;
            stack.push(name.to_string());
        }
    }
    if stack.is_empty() {
        Ok(count)
    } else {
        Err(format!("unclosed: {stack:?}"))
    }
}

#[test]
fn the_balance_check_catches_unbalanced_tags() {
    assert!(balanced("<svg><g></g></svg>").is_ok());
    assert!(balanced("<svg><g></svg>").is_err());
    assert!(balanced("<svg><g/></g></svg>").is_err());
}

#[test]
fn svg_is_balanced_names_rooms_and_robots_and_draws_paths_when_given() {
    for (scene, id) in [("env0", 1), ("env1", 0), ("env2", 4), ("env3", 1)] {
        let task = common::task(scene, id);
        let layout = layout::for_task(&task).expect("layout");
        let plain = render::svg(&task, &layout, &task.init, None);
        let tags = balanced(&plain).unwrap_or_else(|e| panic!("{scene} task {id}: {e}"));
        assert!(tags > 20, "{scene} task {id}: only {tags} tags");
        assert!(plain.starts_with("<svg") && plain.trim_end().ends_with("</svg>"));
        for n in task.indices() {
            let node = task.node(n);
            if matches!(node.kind, NodeKind::Room | NodeKind::Robot(_)) {
                let label = format!("{} {}", node.class_name, node.id.0);
                assert!(
                    plain.contains(&format!(">{label}<")) || plain.contains(&format!(">{label} (")),
                    "{scene} task {id}: no label {label}"
                );
            }
        }
        assert!(!plain.contains("class=\"path\""));

        let robot = task.robots[0].node;
        let track = vec![(
            task.id(robot),
            vec![[1.0, 0.0, 1.0], [2.0, 0.0, 1.5], [3.0, 0.0, 4.0]],
        )];
        let drawn = render::svg(&task, &layout, &task.init, Some(&track));
        balanced(&drawn).unwrap_or_else(|e| panic!("{scene} task {id} with a path: {e}"));
        assert_eq!(drawn.matches("class=\"path\"").count(), 1);
        assert!(drawn.contains(&format!("data-robot=\"{}\"", task.id(robot).0)));
    }
}
