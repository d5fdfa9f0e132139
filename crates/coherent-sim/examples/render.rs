//! Writes a top-down picture of one task of each original scene, with the robots'
//! paths from executing its optimal plan physically, to `docs/render/envN.svg`.
//!
//! `cargo run --release -p coherent-sim --example render [OUT_DIR]`; with
//! `RENDER_TASKS=14,15,13,13` it draws those task ids of env0..env3 instead of choosing.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_core::planner::{self, Limits};
use coherent_core::read_tasks;
use coherent_sim::{execute_plan, layout, render};

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out_dir = std::env::args()
        .nth(1)
        .map_or_else(|| root.join("../../docs/render"), PathBuf::from);
    std::fs::create_dir_all(&out_dir).expect("output directory can be made");
    let data = PathBuf::from(env!("COHERENT_ORIGINAL_ENV"));
    let chosen: Option<Vec<i64>> = std::env::var("RENDER_TASKS")
        .ok()
        .map(|v| v.split(',').filter_map(|x| x.trim().parse().ok()).collect());
    for scene in 0..4 {
        let tasks = read_tasks(&data.join(format!("env{scene}.json"))).expect("scene file loads");
        // The solvable task whose plan moves the most robots, the longest plan on ties.
        let mut best: Option<(usize, usize, Arc<coherent_core::Task>, _)> = None;
        for task in tasks.into_iter().flatten() {
            if chosen
                .as_ref()
                .is_some_and(|c| c.get(scene) != Some(&task.meta.task_id))
            {
                continue;
            }
            let task = Arc::new(task);
            let Some(plan) = planner::analyse(&task, &Limits::default()).plan else {
                continue;
            };
            let report = execute_plan(&task, &plan);
            if !report.physics_ok {
                eprintln!(
                    "env{scene} task {}: {:?}",
                    task.meta.task_id, report.physics_error
                );
                continue;
            }
            let moving = report.paths.iter().filter(|(_, p)| p.len() > 1).count();
            if best
                .as_ref()
                .is_none_or(|b| (moving, plan.len()) > (b.0, b.1))
            {
                best = Some((moving, plan.len(), task, report.paths));
            }
        }
        let Some((_, steps, task, paths)) = best else {
            eprintln!("env{scene}: no task executes");
            continue;
        };
        let layout = layout::for_task(&task).expect("layout");
        let picture = render::svg(&task, &layout, &task.init, Some(&paths));
        let path = out_dir.join(format!("env{scene}.svg"));
        std::fs::write(&path, picture).expect("picture is written");
        println!(
            "{}: env{scene} task {} ({steps} steps)",
            path.display(),
            task.meta.task_id
        );
    }
}
