//! CMRS, the paper's centralised baseline (docs/methods.md, `cmrs`): each step one model
//! sees every robot's observation, the union of all robots' action lists and the last
//! executed actions, and answers one `<robot>: <action>` line, which the loop checks and
//! runs. In a parallel episode it answers a list of lines, at most one per robot, carried
//! out together as the step's joint step. One model call per step.

use coherent_core::Execution;

use crate::episode::ask::{Side, ask};
use crate::episode::environment::team_sight;
use crate::episode::method::{Closing, Decided, Deciding, Method, Turn};
use crate::llm::{Query, Role, Situation};
use crate::methods::{central, decision};
use crate::prompts::team_actions;
use crate::prompts::templates::Prompts;
use crate::records::transcript::Round;

/// Most tokens of one answer (a line and a little reasoning).
const MAX_TOKENS: u32 = 200;

/// CMRS for one episode.
#[derive(Debug)]
pub struct Cmrs {
    /// The central template (`central.txt`; `central_parallel.txt` in joint steps) comes
    /// from here.
    prompts: Prompts,
    /// What of this round's answer was not used (a parallel answer's extra lines).
    unused: Option<String>,
}

impl Cmrs {
    pub fn new(prompts: Prompts) -> Cmrs {
        Cmrs {
            prompts,
            unused: None,
        }
    }
}

impl Method for Cmrs {
    fn decide<'a>(&'a mut self, turn: Turn<'a>, round: &'a mut Round) -> Deciding<'a> {
        Box::pin(async move {
            let Turn { task, env, .. } = turn;
            self.unused = None;
            let lines: Vec<String> = team_actions::offered(task, env.state())
                .iter()
                .map(|a| a.line(task))
                .collect();
            round.actions = lines.clone();
            let sight = team_sight(env, task, turn.news);
            let parallel = turn.execution == Execution::Parallel;
            let query = Query {
                role: Role::Assigner,
                robot: None,
                messages: if parallel {
                    central::messages_parallel(&self.prompts, &sight, &lines, turn.history)
                } else {
                    central::messages(&self.prompts, &sight, &lines, turn.history)
                },
                schema_name: if parallel {
                    "joint_step"
                } else {
                    "joint_action"
                },
                schema: if parallel {
                    central::schema_parallel(&lines)
                } else {
                    central::schema(&lines)
                },
                max_tokens: MAX_TOKENS,
                situation: Situation::now(task, env, None),
            };
            let Some(reply) = ask(turn.backend, query, turn.cancel, &mut round.calls).await else {
                return Ok(None);
            };
            if !parallel {
                return Ok(Some(
                    match reply.and_then(|r| r.read(|text| central::choose(task, &lines, text))) {
                        Ok((robot, action)) => {
                            decision::choose(round, robot, &action, String::new());
                            Decided::CarryOut
                        }
                        Err(e) => Decided::Ends(e.outcome(Side::Executor)),
                    },
                ));
            }
            Ok(Some(
                match reply.and_then(|r| r.read(|text| central::choose_several(task, &lines, text)))
                {
                    Ok((chosen, unused)) => {
                        round.parts = chosen
                            .iter()
                            .map(|(robot, action)| {
                                decision::part(env, *robot, action, String::new())
                            })
                            .collect();
                        self.unused = (!unused.is_empty()).then(|| {
                            format!("Part of the answer was not used: {}.", unused.join("; "))
                        });
                        Decided::CarryOut
                    }
                    Err(e) => Decided::Ends(e.outcome(Side::Executor)),
                },
            ))
        })
    }

    fn conclude(&mut self, closing: Closing<'_>, round: &mut Round) {
        decision::team_feedback(closing.task, round, self.unused.take());
    }

    fn recall(&self, task: &coherent_core::Task, round: &Round) -> Option<String> {
        decision::executed_line(task, round)
    }
}
