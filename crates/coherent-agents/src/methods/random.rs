//! The floor every table should show (`--method random`): no model and no search, a
//! feasible action drawn at random each round, seeded (the episode's seed and the step,
//! so that an episode is the same every time and replays exactly). In a sequential
//! episode one of the team's actions, every robot's offered actions alike; in a parallel
//! episode every robot that can, in a random order, draws one of its own actions that
//! does not interfere with those drawn before it (`coherent_core::joint::check`), so that
//! the joint step is valid.

use coherent_core::joint::{self, Part};
use coherent_core::{Execution, Task, rules};

use crate::episode::method::{Closing, Decided, Deciding, Method, Turn};
use crate::methods::decision;
use crate::prompts::team_actions;
use crate::records::transcript::{Round, RoundOutcome};
use crate::rng::{Rng, seed_of};

/// The random floor for one episode.
#[derive(Debug)]
pub struct Random {
    seed: u64,
}

impl Random {
    /// Draws from `seed`.
    pub fn new(seed: u64) -> Random {
        Random { seed }
    }
}

/// `0..n` in a random order.
fn shuffled(n: usize, rng: &mut Rng) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    rng.shuffle(&mut order);
    order
}

impl Method for Random {
    fn decide<'a>(&'a mut self, turn: Turn<'a>, round: &'a mut Round) -> Deciding<'a> {
        Box::pin(async move {
            let Turn { task, env, .. } = turn;
            let state = env.state();
            let mut rng = Rng::new(seed_of(self.seed, u64::from(round.step)));
            if turn.execution == Execution::Sequential {
                let offered = team_actions::offered(task, state);
                round.actions = offered.iter().map(|a| a.line(task)).collect();
                if offered.is_empty() {
                    return Ok(Some(Decided::Ends(RoundOutcome::Declined)));
                }
                let pick = offered[rng.below(offered.len())];
                let robot = task.id(pick.robot.node);
                decision::choose(round, robot, &pick.action.render(task), String::new());
                return Ok(Some(Decided::CarryOut));
            }
            let each = rules::team_actions(task, state, &task.robots);
            let mut step: Vec<Part> = Vec::new();
            for r in shuffled(task.robots.len(), &mut rng) {
                let robot = task.robots[r];
                let own = each.get(r);
                for a in shuffled(own.len(), &mut rng) {
                    step.push((robot, own[a]));
                    if joint::check(task, state, &step).is_ok() {
                        break;
                    }
                    step.pop();
                }
            }
            round.parts = step
                .iter()
                .map(|&(robot, action)| {
                    let (id, action) = (task.id(robot.node), action.render(task));
                    decision::part(env, id, &action, String::new())
                })
                .collect();
            Ok(Some(Decided::CarryOut))
        })
    }

    fn conclude(&mut self, closing: Closing<'_>, round: &mut Round) {
        decision::team_feedback(closing.task, round, None);
    }

    fn recall(&self, _: &Task, _: &Round) -> Option<String> {
        None
    }
}
