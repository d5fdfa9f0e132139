//! Every solvable released task executes its optimal plan in Rapier, and after every
//! step the relations read back from the bodies agree with the symbolic state; the same
//! for its makespan plan, each joint step's robots moving at once.

use std::time::Instant;

use coherent_core::makespan;
use coherent_core::planner::Limits;
use coherent_sim::{execute_joint_plan, execute_plan};

mod common;

#[test]
fn every_solvable_task_executes_its_optimal_plan_physically() {
    let start = Instant::now();
    let only = std::env::var("COHERENT_SIM_ONLY").ok();
    let mut solvable = 0;
    let mut failures = Vec::new();
    for task in common::released_tasks() {
        let name = common::name(&task);
        if only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        let Some(plan) = common::optimal_plan(&task) else {
            continue;
        };
        solvable += 1;
        let report = execute_plan(&task, &plan);
        eprintln!(
            "{name}: {} steps, ok {}, {:.1} s simulated in {:.0} ms",
            plan.len(),
            report.physics_ok,
            report.sim_seconds,
            report.wall_ms
        );
        if report.physics_ok {
            assert_eq!(report.steps_done, plan.len(), "{name}");
            assert!(
                report.sim_seconds > 1.0,
                "{name}: motions take simulated time"
            );
        } else {
            eprintln!("  {}", report.physics_error.clone().unwrap_or_default());
            failures.push(format!(
                "{name}: {}",
                report.physics_error.unwrap_or_default()
            ));
        }
    }
    eprintln!(
        "{solvable} solvable tasks in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
    if only.is_none() {
        assert_eq!(solvable, 80);
    }
}

/// The makespan plans are the plans that robots acting at once carry out: every one of
/// the 80 solvable released tasks runs in Rapier with no robot running into another and
/// the relations agreeing with the rules' state after every joint step.
#[test]
fn every_solvable_task_executes_its_makespan_plan_physically() {
    let start = Instant::now();
    let only = std::env::var("COHERENT_SIM_ONLY").ok();
    let (mut solvable, mut seconds) = (0, 0.0);
    let mut failures = Vec::new();
    for task in common::released_tasks() {
        let name = common::name(&task);
        if only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        let found = makespan::search(&task, &task.robots, &task.goal, &Limits::default());
        let Some(plan) = found.plan else {
            continue;
        };
        solvable += 1;
        let report = execute_joint_plan(&task, &plan);
        eprintln!(
            "{name}: {} joint steps, ok {}, {:.1} s simulated in {:.0} ms",
            plan.len(),
            report.physics_ok,
            report.sim_seconds,
            report.wall_ms
        );
        if report.physics_ok {
            assert_eq!(report.steps_done, plan.len(), "{name}");
            seconds += report.sim_seconds;
        } else {
            failures.push(format!(
                "{name}: {}",
                report.physics_error.unwrap_or_default()
            ));
        }
    }
    eprintln!(
        "{solvable} solvable tasks, {seconds:.1} s simulated, in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
    if only.is_none() {
        assert_eq!(solvable, 80);
    }
}

/// Two runs of the same plan end in bit-identical poses.
#[test]
fn two_runs_give_bit_identical_final_poses() {
    let task = common::task("env0", 1);
    let plan = common::optimal_plan(&task).expect("solvable");
    let a = execute_plan(&task, &plan);
    let b = execute_plan(&task, &plan);
    assert!(a.physics_ok && b.physics_ok);
    let bits = |r: &coherent_sim::PlanReport| -> Vec<(i64, [u32; 7])> {
        r.final_poses
            .iter()
            .map(|(id, p)| (id.0, p.map(f32::to_bits)))
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    assert!(!a.final_poses.is_empty());
}
