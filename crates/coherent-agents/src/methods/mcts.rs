//! The paper's two tree-search baselines: primitive MCTS and LLM-MCTS
//! (`docs/methods.md`, `mcts` and `llm-mcts`).
//!
//! Each real step builds a fresh tree from the environment's current state and searches
//! the team action space: every `(robot, action)` pair that [`rules::actions`] offers
//! any robot (one robot acts per step). The world model inside the search is the
//! symbolic rules on cloned [`State`]s, with the ground-truth reward, as in the paper.
//! The loop then carries the chosen action out through the environment, like any other
//! method's.
//!
//! # The search (the authors' settings are [`MctsConfig::default`])
//!
//! One simulation walks down from the root choosing, at node `s`, the action `a` that
//! maximises
//!
//! ```text
//! PUCT(s, a) = Q(s, a) + c * P(s, a) * sqrt(N(s)) / (1 + N(s, a))
//! ```
//!
//! with `c` = [`MctsConfig::exploration`] (24), `N(s)` the simulations that passed
//! through `s` before this one, and `N(s, a)` those that took `a` there. Ties (all
//! scores are 0 on a node's first visit) are broken uniformly at random with the seeded
//! generator. When the chosen action leads to a node not in the tree yet, that node is
//! added and a random rollout runs from it: uniform random team actions until the goal
//! holds or the depth (20, counted from the root, tree part included) is spent. A node
//! where the goal holds, where the depth is spent, or where no robot can act ends the
//! walk with nothing after it.
//!
//! Reward: `r` = [`MctsConfig::reward`] (10) for a step into a state where the goal
//! holds, else 0; the goal ends the episode, so at most one reward is ever collected.
//! A step's return is `G = r + gamma * G_next` with `gamma` = 0.95 (a rollout's own
//! return is discounted the same way, from its first step). Every node keeps the list of
//! returns `G_1..G_n` observed through the action that leads into it, and its value is
//! their softmax-weighted mean with temperature `T` = 10:
//!
//! ```text
//! Q(s, a) = sum_i w_i G_i,   w_i = exp(G_i / T) / sum_j exp(G_j / T)
//! ```
//!
//! which leans towards the best returns seen (a soft maximum) rather than their plain
//! mean. An action never taken has no returns: its `Q` is 0, the value of a failure, so
//! it is tried on the strength of its prior alone.
//!
//! After the simulations the root's most visited action is executed (greedy; ties go to
//! the higher `Q`, then to the earlier action in the list: robots in team order, each
//! robot's actions in [`rules::actions`] order). The tree is then thrown away.
//!
//! What these settings do: rewards are sparse, so most `Q`s are 0 and the search is
//! mostly breadth-first at the root; and a goal now (`G` = 10) is worth only 5% more
//! than a detour and the goal next step (9.5), while `c = 24` dwarfs that, so an early
//! lucky detour can keep most of the 50 visits. Both are the method's, not bugs; they
//! are why primitive MCTS solves so little (the paper: 0.000).
//!
//! # Priors
//!
//! Primitive MCTS uses the uniform prior `P = 1 / |A(s)|` at every node. LLM-MCTS asks a
//! language model at the root of each real step's tree: it is sampled
//! [`MctsConfig::samples`] (5) times with a CMRS-like prompt (the instruction, every
//! robot's observation as facts, the union of the action lists as `<robot>: <action>`
//! lines, the last executed actions: the history window), each answer is matched to the nearest valid
//! team action ([`match_line`]; an answer matching none is dropped), and
//! `P = 0.5 x (the empirical distribution of matched samples) + 0.5 x uniform`
//! ([`mix_prior`]). Below the root the prior is uniform. Asking the model only at the
//! root is this project's named simplification (LLM-MCTS as published asks its policy
//! at every node it expands): it bounds the model calls per real step at `n`
//! (a tree of 50 simulations would otherwise cost up to 250 calls a step) and keeps an
//! episode's cost comparable with the other LLM methods'.

use std::io;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use coherent_core::{State, Task, rules};

use crate::episode::ask::place_call;
use crate::episode::environment::team_sight;
use crate::episode::method::{Closing, Decided, Deciding, Method, Turn};
use crate::llm::{Finish, Query, Role, Situation};
use crate::methods::{central, decision, feedback};
use crate::prompts::answer::{match_line, read_line};
use crate::prompts::fill::robot_label;
use crate::prompts::team_actions::{self, TeamAction};
use crate::prompts::templates::Prompts;
use crate::records::transcript::{Decision, Round, RoundOutcome};
use crate::rng::{Rng, seed_of};

/// Settings of one MCTS episode; the default is the authors' (docs/methods.md).
#[derive(Clone, Debug, PartialEq)]
pub struct MctsConfig {
    /// `c` of PUCT.
    pub exploration: f64,
    /// Simulations per real step.
    pub simulations: u32,
    /// Steps a simulation may look ahead, tree and rollout together.
    pub depth: u32,
    pub discount: f64,
    /// The reward of reaching the goal (0 otherwise).
    pub reward: f64,
    /// `T` of the softmax-weighted `Q`.
    pub temperature: f64,
    /// Seeds the search's random generator; the same seed gives the same episode.
    pub seed: u64,
    /// LLM-MCTS: model samples per real step.
    pub samples: u32,
    /// LLM-MCTS: the model's share of the root prior (the rest is uniform).
    pub llm_weight: f64,
    /// LLM-MCTS: the answer is one short line.
    pub max_tokens: u32,
    /// LLM-MCTS: the prompt's template (`central.txt`) comes from here.
    pub prompts: Prompts,
}

impl Default for MctsConfig {
    fn default() -> MctsConfig {
        MctsConfig {
            exploration: 24.0,
            simulations: 50,
            depth: 20,
            discount: 0.95,
            reward: 10.0,
            temperature: 10.0,
            seed: 0,
            samples: 5,
            llm_weight: 0.5,
            max_tokens: 120,
            prompts: Prompts::builtin(),
        }
    }
}

/// The softmax(`temperature`)-weighted mean of `returns`; 0 when there are none.
pub fn softmax_q(returns: &[f64], temperature: f64) -> f64 {
    let Some(max) = returns.iter().copied().reduce(f64::max) else {
        return 0.0;
    };
    // Shifting by the largest return changes no weight and keeps exp() finite.
    let (mut weights, mut weighted) = (0.0, 0.0);
    for &g in returns {
        let w = ((g - max) / temperature).exp();
        weights += w;
        weighted += w * g;
    }
    weighted / weights
}

/// `q + exploration * prior * sqrt(parent_visits) / (1 + child_visits)`.
pub fn puct(q: f64, prior: f64, parent_visits: u32, child_visits: u32, exploration: f64) -> f64 {
    q + exploration * prior * f64::from(parent_visits).sqrt() / (1.0 + f64::from(child_visits))
}

/// `llm_weight` x the empirical distribution of `counts` + the rest x uniform. With no
/// sample counted (every answer dropped) the prior is uniform.
pub fn mix_prior(counts: &[u32], llm_weight: f64) -> Vec<f64> {
    let n = counts.len() as f64;
    let total: u32 = counts.iter().sum();
    if total == 0 {
        return vec![1.0 / n; counts.len()];
    }
    counts
        .iter()
        .map(|&c| llm_weight * f64::from(c) / f64::from(total) + (1.0 - llm_weight) / n)
        .collect()
}

/// What the search saw at the root.
#[derive(Clone, Debug, PartialEq)]
pub struct RootStats {
    /// The root's team actions, in [`team_actions::offered`] order.
    pub actions: Vec<TeamAction>,
    pub prior: Vec<f64>,
    /// Simulations that took each action.
    pub visits: Vec<u32>,
    /// Each action's `Q` (0 for one never taken).
    pub q: Vec<f64>,
    /// The action to execute; `None` when no robot can act.
    pub choice: Option<usize>,
    /// Simulations run (fewer than asked when cancelled).
    pub simulations: u32,
}

struct Node {
    state: State,
    depth: u32,
    /// The reward of the step into this node.
    reward: f64,
    /// The goal holds: the episode would end here.
    goal: bool,
    /// Filled on the first visit that goes on from this node.
    branches: Option<Vec<Branch>>,
    visits: u32,
    /// Returns observed through the action that leads here.
    returns: Vec<f64>,
}

struct Branch {
    action: TeamAction,
    prior: f64,
    child: Option<usize>,
}

fn branches(actions: Vec<TeamAction>, prior: Option<&[f64]>) -> Vec<Branch> {
    let uniform = 1.0 / actions.len() as f64;
    actions
        .into_iter()
        .enumerate()
        .map(|(i, action)| Branch {
            action,
            prior: prior.map_or(uniform, |p| p[i]),
            child: None,
        })
        .collect()
}

/// Searches from `state` and picks the action to execute. `root_prior` is the prior
/// over [`team_actions::offered`]`(task, state)`, in that order; `None`, or a list of another
/// length, means uniform. `cancel` stops the search between simulations.
pub fn search(
    task: &Task,
    state: &State,
    root_prior: Option<&[f64]>,
    config: &MctsConfig,
    rng: &mut Rng,
    cancel: Option<&AtomicBool>,
) -> RootStats {
    let actions = team_actions::offered(task, state);
    let root_prior = root_prior.filter(|p| p.len() == actions.len());
    let mut tree = vec![Node {
        state: state.clone(),
        depth: 0,
        reward: 0.0,
        goal: task.goal_satisfied(state),
        branches: Some(branches(actions, root_prior)),
        visits: 0,
        returns: Vec::new(),
    }];
    let mut simulations = 0;
    while simulations < config.simulations {
        if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            break;
        }
        simulate(task, &mut tree, config, rng);
        simulations += 1;
    }
    root_stats(tree, config, simulations)
}

/// One simulation: selection, expansion of one node, a rollout, and backing up.
fn simulate(task: &Task, tree: &mut Vec<Node>, config: &MctsConfig, rng: &mut Rng) {
    let mut path = vec![0];
    let mut at = 0;
    let after_leaf = loop {
        if tree[at].goal || tree[at].depth >= config.depth {
            break 0.0;
        }
        if tree[at].branches.is_none() {
            let actions = team_actions::offered(task, &tree[at].state);
            tree[at].branches = Some(branches(actions, None));
        }
        let Some(b) = select(tree, at, config, rng) else {
            break 0.0; // nobody can act here
        };
        let Some((next, TeamAction { robot, action })) = tree[at]
            .branches
            .as_ref()
            .map(|bs| (bs[b].child, bs[b].action))
        else {
            break 0.0;
        };
        if let Some(child) = next {
            at = child;
            path.push(child);
            continue;
        }
        let mut state = tree[at].state.clone();
        rules::apply(task, &mut state, robot, action);
        let goal = task.goal_satisfied(&state);
        let depth = tree[at].depth + 1;
        let after = if goal {
            0.0
        } else {
            rollout(task, state.clone(), config.depth - depth, config, rng)
        };
        let child = tree.len();
        tree.push(Node {
            state,
            depth,
            reward: if goal { config.reward } else { 0.0 },
            goal,
            branches: None,
            visits: 0,
            returns: Vec::new(),
        });
        if let Some(bs) = tree[at].branches.as_mut() {
            bs[b].child = Some(child);
        }
        path.push(child);
        break after;
    };
    let mut g = after_leaf;
    for &i in path.iter().rev() {
        let node = &mut tree[i];
        node.visits += 1;
        if i != 0 {
            g = node.reward + config.discount * g;
            node.returns.push(g);
        }
    }
}

/// The branch of node `at` with the highest PUCT score, ties at random; `None` when it
/// has no branches.
fn select(tree: &[Node], at: usize, config: &MctsConfig, rng: &mut Rng) -> Option<usize> {
    let node = &tree[at];
    let mut best = None;
    let mut best_score = f64::NEG_INFINITY;
    let mut ties = 0;
    for (i, b) in node
        .branches
        .as_deref()
        .unwrap_or_default()
        .iter()
        .enumerate()
    {
        let (q, visits) = match b.child {
            Some(c) => (
                softmax_q(&tree[c].returns, config.temperature),
                tree[c].visits,
            ),
            None => (0.0, 0),
        };
        let score = puct(q, b.prior, node.visits, visits, config.exploration);
        if score > best_score {
            (best, best_score, ties) = (Some(i), score, 1);
        } else if score == best_score {
            // Reservoir sampling: each of the tied branches is kept with equal chance.
            ties += 1;
            if rng.below(ties) == 0 {
                best = Some(i);
            }
        }
    }
    best
}

/// The discounted return of uniform random team actions from `s` for at most `steps`
/// steps, stopping at the goal.
fn rollout(task: &Task, mut s: State, steps: u32, config: &MctsConfig, rng: &mut Rng) -> f64 {
    let mut discount = 1.0;
    for _ in 0..steps {
        let actions = team_actions::offered(task, &s);
        if actions.is_empty() {
            break;
        }
        let a = actions[rng.below(actions.len())];
        rules::apply(task, &mut s, a.robot, a.action);
        if task.goal_satisfied(&s) {
            return discount * config.reward;
        }
        discount *= config.discount;
    }
    0.0
}

fn root_stats(mut tree: Vec<Node>, config: &MctsConfig, simulations: u32) -> RootStats {
    let root = tree[0].branches.take().unwrap_or_default();
    let mut stats = RootStats {
        actions: Vec::new(),
        prior: Vec::new(),
        visits: Vec::new(),
        q: Vec::new(),
        choice: None,
        simulations,
    };
    for b in root {
        let (visits, q) = b.child.map_or((0, 0.0), |c| {
            (
                tree[c].visits,
                softmax_q(&tree[c].returns, config.temperature),
            )
        });
        stats.actions.push(b.action);
        stats.prior.push(b.prior);
        stats.visits.push(visits);
        stats.q.push(q);
    }
    for i in 0..stats.actions.len() {
        let better = stats
            .choice
            .is_none_or(|c: usize| (stats.visits[i], stats.q[i]) > (stats.visits[c], stats.q[c]));
        if better {
            stats.choice = Some(i);
        }
    }
    stats
}

/// MCTS for one episode: primitive MCTS, or LLM-MCTS with the model's prior at the root
/// of each step's tree.
#[derive(Debug)]
pub struct Mcts {
    config: MctsConfig,
    /// Whether the episode's backend gives the prior (LLM-MCTS).
    llm: bool,
}

impl Mcts {
    /// Primitive MCTS: the uniform prior everywhere; no model.
    pub fn primitive(config: MctsConfig) -> Mcts {
        Mcts { config, llm: false }
    }

    /// LLM-MCTS: the model's samples shape the root's prior.
    pub fn llm(config: MctsConfig) -> Mcts {
        Mcts { config, llm: true }
    }

    /// The root's prior from the model's samples, or the outcome that ends the round
    /// (the model could not be reached); `None` when cancelled.
    async fn prior(
        &self,
        turn: &Turn<'_>,
        round: &mut Round,
        lines: &[String],
    ) -> Option<Result<Vec<f64>, RoundOutcome>> {
        let Turn { task, env, .. } = *turn;
        let config = &self.config;
        let messages = central::messages(
            &config.prompts,
            &team_sight(env, task, turn.news),
            lines,
            turn.history,
        );
        let mut counts = vec![0u32; lines.len()];
        for _ in 0..config.samples {
            let query = Query {
                role: Role::Assigner,
                robot: None,
                messages: messages.clone(),
                schema_name: "team_action",
                schema: central::schema(lines),
                max_tokens: config.max_tokens,
                situation: Situation::now(task, env, None),
            };
            let call = place_call(turn.backend, query, turn.cancel).await?;
            // A refusal, a filtered or an empty answer names nothing.
            if let Some(answer) = &call.answer
                && matches!(answer.finish, Finish::Stop | Finish::Length)
                && !answer.text.trim().is_empty()
                && let Some(i) = match_line(lines, &read_line(&answer.text))
            {
                counts[i] += 1;
            }
            let ended = call.error.as_ref().filter(|e| e.ends_episode()).cloned();
            round.calls.push(call);
            if let Some(e) = ended {
                return Some(Err(RoundOutcome::BackendError {
                    message: e.to_string(),
                }));
            }
        }
        Some(Ok(mix_prior(&counts, config.llm_weight)))
    }
}

impl Method for Mcts {
    fn decide<'a>(&'a mut self, turn: Turn<'a>, round: &'a mut Round) -> Deciding<'a> {
        Box::pin(async move {
            let task = turn.task;
            let state = turn.env.state().clone();
            let actions = team_actions::offered(task, &state);
            let lines: Vec<String> = actions.iter().map(|a| a.line(task)).collect();
            round.actions = lines.clone();
            if actions.is_empty() {
                return Ok(Some(Decided::Ends(RoundOutcome::Declined)));
            }
            let prior = if self.llm {
                match self.prior(&turn, round, &lines).await {
                    None => return Ok(None),
                    Some(Err(ended)) => return Ok(Some(Decided::Ends(ended))),
                    Some(Ok(prior)) => Some(prior),
                }
            } else {
                None
            };

            // The search is CPU work: keep it off the async workers.
            let seed = seed_of(self.config.seed, u64::from(round.step));
            let (t, c, flag) = (Arc::clone(task), self.config.clone(), turn.cancel.flag());
            let stats = tokio::task::spawn_blocking(move || {
                search(
                    &t,
                    &state,
                    prior.as_deref(),
                    &c,
                    &mut Rng::new(seed),
                    Some(&flag),
                )
            })
            .await
            .map_err(io::Error::other)?;
            if turn.cancel.is_cancelled() {
                return Ok(None);
            }
            let Some(i) = stats.choice else {
                return Ok(Some(Decided::Ends(RoundOutcome::Declined)));
            };
            let chosen = stats.actions[i];
            round.decision = Some(Decision {
                robot: Some(task.id(chosen.robot.node)),
                can_do: true,
                action: Some(chosen.action.render(task)),
                subtask_complete: false,
                note: format!(
                    "{} of {} simulations, Q {:.3}, prior {:.3}",
                    stats.visits[i], stats.simulations, stats.q[i], stats.prior[i]
                ),
            });
            Ok(Some(Decided::CarryOut))
        })
    }

    /// What its chosen action did ([`feedback::mcts`]), or that no robot could act, or
    /// that the model could not be reached.
    fn conclude(&mut self, closing: Closing<'_>, round: &mut Round) {
        let task = closing.task;
        let chosen = round
            .decision
            .as_ref()
            .and_then(|d| Some((d.robot?, d.action.as_deref()?)));
        round.feedback = match (&round.outcome, chosen) {
            (RoundOutcome::BackendError { .. }, _) => feedback::team("", &round.outcome),
            (_, None) => feedback::mcts(None, &round.outcome),
            (outcome, Some((robot, action))) => {
                feedback::mcts(Some((&robot_label(task, robot), action)), outcome)
            }
        };
    }

    fn recall(&self, task: &Task, round: &Round) -> Option<String> {
        decision::executed_line(task, round)
    }
}
