//! A task's events along an episode (docs/dynamic.md), as the loop runs them: before each
//! round, the events due are carried out on the world ([`Schedule`]) and the team is
//! told; at each, the optimum from the state they left is proven again (a [`Proof`]);
//! actions fail by their seeded chance; and the team's recovery is measured, round by
//! round, until it first brings the goal nearer. What the episode is measured against
//! comes out as its [`Reference`].

use std::io;
use std::sync::Arc;

use coherent_core::makespan;
use coherent_core::planner::{self, Limits};
use coherent_core::schedule::{Change, Schedule};
use coherent_core::task::predicate_holds;
use coherent_core::{Environment, Execution, Happening, Relation, State, Task};

use crate::records::transcript::{Happened, Proof, Recovery, Reference, Round};
use crate::rng::{Rng, seed_of};

/// The events of one episode, and what they are measured by.
pub(crate) struct Dynamics {
    schedule: Schedule,
    execution: Execution,
    limits: Limits,
    seed: u64,
    start: Proof,
    /// The step before which the world last changed, and the optimum from there.
    last: (u32, Proof),
    /// The steps (joint steps) that failed actions have cost since then.
    failed: u32,
    /// In a parallel episode, the state before the round under way (after its events):
    /// what a joint step's failed actions cost is measured from it.
    pre: Option<State>,
    recoveries: Vec<Recovery>,
    /// The recoveries still measured, and the sequential optimum before the next round.
    open: (Vec<usize>, Option<u32>),
}

impl Dynamics {
    /// The events of `task` along one episode, or `None` when it has none.
    pub(crate) fn new(
        task: &Arc<Task>,
        execution: Execution,
        max_states: usize,
        seed: u64,
    ) -> Option<Dynamics> {
        (!task.events.is_empty()).then(|| Dynamics {
            schedule: Schedule::new(Arc::clone(task)),
            execution,
            limits: Limits::max_states(max_states),
            seed,
            start: Proof::default(),
            last: (1, Proof::default()),
            failed: 0,
            pre: None,
            recoveries: Vec::new(),
            open: (Vec::new(), None),
        })
    }

    /// The world at the start (robots that join later out of the team), put into `env`,
    /// and the optimum from it. Returns the task as it starts.
    pub(crate) async fn start(
        &mut self,
        env: &mut (dyn Environment + Send + Sync),
    ) -> io::Result<Arc<Task>> {
        let world = self.schedule.world();
        env.befall(Arc::clone(&world), env.state().clone())
            .map_err(io::Error::other)?;
        self.start = self.prove(&world, env.state()).await?;
        self.last = (1, self.start.clone());
        Ok(world)
    }

    /// Carries out the events due before `step` on `env`, with the task as they leave
    /// it in `world`; what happened, each with the optimum from there.
    pub(crate) async fn before(
        &mut self,
        step: u32,
        env: &mut (dyn Environment + Send + Sync),
        world: &mut Arc<Task>,
    ) -> io::Result<Vec<Happened>> {
        let mut state = env.state().clone();
        let changes = self.schedule.before_step(step, &mut state);
        if changes.is_empty() {
            self.keep_pre(state);
            return Ok(Vec::new());
        }
        *world = self.schedule.world();
        env.befall(Arc::clone(world), state)
            .map_err(io::Error::other)?;
        self.keep_pre(env.state().clone());
        let proof = self.prove(world, env.state()).await?;
        self.last = (step, proof.clone());
        self.failed = 0;
        let base = Arc::clone(self.schedule.task());
        // A recovery not over by now never was.
        self.open.0.clear();
        for change in &changes {
            if changes_world(&base, change) {
                self.open.0.push(self.recoveries.len());
                self.recoveries.push(Recovery {
                    event: change.event,
                    step,
                    rounds: None,
                    wasted: 0,
                    calls: 0,
                });
            }
        }
        self.open.1 = proof.steps;
        if proof.steps.is_none() {
            self.open.0.clear();
        }
        Ok(changes
            .into_iter()
            .map(|c| Happened {
                kind: base.events[c.event].happening.kind().to_owned(),
                event: c.event,
                ended: c.ended,
                told: c.told,
                void: c.void,
                optimum: proof.clone(),
            })
            .collect())
    }

    /// Why `robot`'s action at `step` fails, when a failing-actions event draws so
    /// ([`action_failure`]).
    pub(crate) fn fails(
        &self,
        task: &Task,
        step: u32,
        robot: coherent_core::NodeId,
    ) -> Option<String> {
        action_failure(&self.schedule, task, self.seed, step, robot)
    }

    /// After a round: counts what its failed actions cost, and measures the open
    /// recoveries.
    pub(crate) async fn after(
        &mut self,
        round: &Round,
        env: &(dyn Environment + Send + Sync),
        world: &Arc<Task>,
    ) -> io::Result<()> {
        if round.failed_actions() > 0 {
            self.failed += self.failure_cost(env, world).await?;
        }
        if self.open.0.is_empty() {
            return Ok(());
        }
        for &i in &self.open.0 {
            self.recoveries[i].calls += round.calls.len() as u32;
        }
        let acted = round.actions_executed();
        if acted == 0 {
            return Ok(());
        }
        let now = self.prove_steps(world, env.state()).await?;
        let nearer = matches!((now, self.open.1), (Some(d1), Some(d0)) if d1 < d0);
        for &i in &self.open.0 {
            let r = &mut self.recoveries[i];
            if nearer {
                r.rounds = Some(round.step + 1 - r.step);
            } else {
                r.wasted += acted;
            }
        }
        if nearer || now.is_none() {
            self.open.0.clear();
        }
        self.open.1 = now;
        Ok(())
    }

    fn keep_pre(&mut self, state: State) {
        if self.execution == Execution::Parallel {
            self.pre = Some(state);
        }
    }

    /// What the failed actions of the round just played cost: a step in a sequential
    /// episode; in a parallel one, the joint step they lost, if they lost it: the
    /// makespan from after the round against the makespan from before it, one fewer
    /// (failed actions off the critical path lose nothing), at most one (the same joint
    /// step again would make it up), one when either is not known.
    async fn failure_cost(
        &self,
        env: &(dyn Environment + Send + Sync),
        world: &Arc<Task>,
    ) -> io::Result<u32> {
        let Some(pre) = &self.pre else {
            return Ok(1);
        };
        let before = self.prove(world, pre).await?.makespan;
        let after = self.prove(world, env.state()).await?.makespan;
        Ok(match (before, after) {
            (Some(b), Some(a)) => (a + 1).saturating_sub(b).min(1),
            _ => 1,
        })
    }

    /// Why the goal cannot be reached anymore, when the last change made it so for good
    /// (nothing yet to come may bring it back within reach: [`Schedule::may_help_later`]).
    pub(crate) fn unreachable(&self) -> Option<&str> {
        if self.schedule.may_help_later() {
            return None;
        }
        self.last.1.unreachable.as_deref()
    }

    /// What the episode is measured against, and how the team recovered; `closing`, the
    /// events that left the goal holding before a step could be taken (none otherwise).
    pub(crate) fn reference(&self, closing: Vec<Happened>) -> Reference {
        let (step, proof) = &self.last;
        let optimum = match self.execution {
            Execution::Sequential => proof.steps,
            Execution::Parallel => proof.makespan,
        };
        Reference {
            kinds: self
                .schedule
                .task()
                .events
                .iter()
                .map(|e| e.happening.kind().to_owned())
                .collect(),
            steps: optimum.map(|d| step - 1 + d + self.failed),
            unreachable: self.unreachable().map(str::to_owned),
            start: self.start.clone(),
            recoveries: self.recoveries.clone(),
            closing,
        }
    }

    async fn prove(&self, task: &Arc<Task>, s: &State) -> io::Result<Proof> {
        let (t, s, l, ex) = (
            Arc::clone(task),
            s.clone(),
            self.limits.clone(),
            self.execution,
        );
        tokio::task::spawn_blocking(move || prove(&t, &s, &l, ex))
            .await
            .map_err(io::Error::other)
    }

    async fn prove_steps(&self, task: &Arc<Task>, s: &State) -> io::Result<Option<u32>> {
        let (t, s, l) = (Arc::clone(task), s.clone(), self.limits.clone());
        tokio::task::spawn_blocking(move || {
            planner::search_from(&t, &s, &t.robots, &t.goal, &l)
                .plan
                .map(|p| p.len() as u32)
        })
        .await
        .map_err(io::Error::other)
    }
}

/// Why `robot`'s action at `step` fails, when a failing-actions event of `schedule`
/// draws so; `None` when it does not, or when no failure runs. The draw is seeded by the
/// episode's `seed`, the step and the robot: the same draws whatever the method does,
/// and whoever steps the world (the loop, and Python's `Env` stepped by hand). `task` is
/// the task as the events have left it.
pub fn action_failure(
    schedule: &Schedule,
    task: &Task,
    seed: u64,
    step: u32,
    robot: coherent_core::NodeId,
) -> Option<String> {
    let r = task.idx(robot)?;
    let (p, event) = schedule.failure_chance(r)?;
    let stream = u64::from(step) << 32 | (robot.0 as u64 & 0xFFFF_FFFF);
    let draw = Rng::new(seed_of(seed, stream)).unit();
    (draw < p).then(|| {
        format!(
            "the action failed (events[{event}]: each action fails with probability {p}); nothing changed"
        )
    })
}

/// What the team is told of `happened`: a sentence each, of those that tell something.
pub(crate) fn news(happened: &[Happened]) -> Vec<String> {
    happened
        .iter()
        .filter(|h| !h.told.is_empty())
        .map(|h| h.told.clone())
        .collect()
}

/// Whether `change` changed the world (failing actions, their end, and an event that
/// could not happen do not).
fn changes_world(task: &Task, change: &Change) -> bool {
    let fails = matches!(
        task.events[change.event].happening,
        Happening::ActionFails { .. }
    );
    !fails && change.void.is_none()
}

/// The optimum from `s` in `task` (its team and goal as events left them): the fewest
/// steps, the fewest joint steps in a parallel episode, or why there is none.
pub fn prove(task: &Task, s: &State, limits: &Limits, execution: Execution) -> Proof {
    let search = planner::search_from(task, s, &task.robots, &task.goal, limits);
    let Some(plan) = search.plan else {
        return if search.truncated {
            Proof {
                unknown: Some(format!(
                    "the search stopped before it could decide ({} states)",
                    search.states_seen
                )),
                ..Proof::default()
            }
        } else {
            Proof {
                unreachable: Some(why_unreachable(task, s)),
                ..Proof::default()
            }
        };
    };
    let mut proof = Proof {
        steps: Some(plan.len() as u32),
        ..Proof::default()
    };
    if execution == Execution::Parallel {
        let joint = makespan::search_with(task, s, &task.robots, &task.goal, Some(&plan), limits);
        match (joint.proven, joint.makespan()) {
            (true, Some(m)) => proof.makespan = Some(m as u32),
            _ => {
                proof.unknown = Some(format!(
                    "the makespan search stopped before it could prove the fewest joint steps \
                     (at least {})",
                    joint.lower
                ));
            }
        }
    }
    proof
}

/// Why no plan of the team reaches the goal from `s`: a reason seen without search
/// when there is one, else that the search covered every state.
fn why_unreachable(task: &Task, s: &State) -> String {
    if task.robots.is_empty() {
        return "no robot is left in the team".to_owned();
    }
    for p in task.goal.iter().filter(|p| !predicate_holds(s, p)) {
        if let Some(why) = planner::static_obstacle(task, p) {
            return format!("{}: {why}", task.predicate_label(p));
        }
        if let Some(holder) = s.sources(Relation::Hold, p.subject).next()
            && task.robot(holder).is_none()
        {
            return format!(
                "{} is held by {}, which is out of the team",
                task.node(p.subject).label(),
                task.node(holder).label()
            );
        }
    }
    "no sequence of the team's actions reaches the goal from here (the search went \
     through every state it can reach)"
        .to_owned()
}
