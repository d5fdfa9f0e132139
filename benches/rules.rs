//! `rules/step/<scene>`: the action lists of every robot of a task plus one transition,
//! the work the rules do for one planning round.

use std::hint::black_box;

use coherent_core::rules;
use criterion::{Criterion, criterion_group, criterion_main};

mod common;

fn step(c: &mut Criterion) {
    let mut group = c.benchmark_group("rules/step");
    for n in 0..4 {
        // Task 0 of each scene, at its start.
        let task = common::task(n, 0);
        group.bench_function(format!("env{n}"), |b| {
            b.iter(|| {
                let s = black_box(&task.init);
                let lists = rules::team_actions(&task, s, &task.robots);
                let first = task
                    .robots
                    .iter()
                    .zip(&lists)
                    .find_map(|(&robot, actions)| actions.first().map(|a| (robot, *a)));
                black_box(&lists);
                let mut next = s.clone();
                if let Some((robot, action)) = first {
                    rules::apply(&task, &mut next, robot, action);
                }
                black_box(next)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
