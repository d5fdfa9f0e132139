//! Helpers shared by the integration tests: the released benchmark files, and a
//! [`Scene`] that drives the hand-written rule tests (`rules_env*.rs`).
//!
//! Every expectation in the rule tests was derived by hand from the task's JSON and
//! `docs/semantics.md`; these helpers only drive a [`SymbolicEnv`] and compare, reporting
//! what is missing and what is unexpected when a list differs.
//!
//! A rule test starts from an opening: a task's initial state, or the state some moves
//! lead to ([`Scene::after`]). Each opening is a `static LazyLock<Scene>` of its test
//! file, built once per test binary and cloned by every test that starts there, so that
//! the moves that lead to it are written and played once.

#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::Arc;

use coherent_core::{Environment, NodeId, Outcome, PropSet, Reason, SymbolicEnv, read_tasks};

/// The original benchmark files, from `COHERENT_ORIGINAL_ENV` (`.cargo/config.toml`:
/// beside the checkout).
pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("COHERENT_ORIGINAL_ENV"))
}

/// The JSON list of `env<n>.json`, as released.
pub fn original_list(n: usize) -> Vec<serde_json::Value> {
    let path = data_dir().join(format!("env{n}.json"));
    let text = std::fs::read_to_string(&path).expect("benchmark file is readable");
    match serde_json::from_str(&text).expect("benchmark file is JSON") {
        serde_json::Value::Array(items) => items,
        other => panic!("{} is not a list: {other}", path.display()),
    }
}

/// Every well-formed task of the four files (env3 index 18 is malformed by design).
pub fn released_tasks() -> Vec<coherent_core::Task> {
    let mut out = Vec::new();
    for n in 0..4 {
        let path = data_dir().join(format!("env{n}.json"));
        for (i, t) in read_tasks(&path)
            .expect("benchmark file loads")
            .into_iter()
            .enumerate()
        {
            match t {
                Ok(t) => out.push(t),
                Err(e) => assert!(n == 3 && i == 18, "env{n}[{i}] is malformed: {e}"),
            }
        }
    }
    assert_eq!(out.len(), 81);
    out
}

/// `<scene> task <id>`, for messages.
pub fn name(t: &coherent_core::Task) -> String {
    format!("{} task {}", t.meta.scene, t.meta.task_id)
}

/// A move of a rule test: the robot, and the action it must be allowed.
pub type Move = (i64, &'static str);

/// `base` with `more` added and `less` taken out: an action list that differs from a
/// familiar one in a few entries.
pub fn with(base: &[&'static str], more: &[&'static str], less: &[&str]) -> Vec<&'static str> {
    let mut list: Vec<&'static str> = base.iter().copied().filter(|a| !less.contains(a)).collect();
    list.extend_from_slice(more);
    list
}

/// A task being played, step by step.
#[derive(Clone, Debug)]
pub struct Scene {
    pub env: SymbolicEnv,
    name: String,
}

impl Scene {
    /// Task `task_id` of `scene` (`env0`..`env3`), in its initial state.
    #[track_caller]
    pub fn load(scene: &str, task_id: i64) -> Scene {
        let file = data_dir().join(format!("{scene}.json"));
        // One malformed task elsewhere in the file (env3 task 18 repeats node id 24)
        // must not hide the others: take this task's own result.
        let tasks =
            read_tasks(&file).unwrap_or_else(|e| panic!("cannot read {}: {e}", file.display()));
        let task = tasks
            .into_iter()
            .filter_map(Result::ok)
            .find(|t| t.meta.task_id == task_id)
            .unwrap_or_else(|| panic!("{scene} has no loadable task {task_id}"));
        Scene {
            env: SymbolicEnv::new(Arc::new(task)),
            name: format!("{scene}/{task_id}"),
        }
    }

    /// A copy of this scene after `moves`, each of which must be executed; `label` names
    /// the state reached in failure messages.
    #[track_caller]
    pub fn after(&self, label: &str, moves: &[Move]) -> Scene {
        let mut next = self.clone();
        next.name = format!("{} after {label}", self.name);
        for &(robot, action) in moves {
            next.act(robot, action);
        }
        next
    }

    /// This scene is in the state `opening` starts from: a story that ends where another
    /// test's opening begins has played the same moves.
    #[track_caller]
    pub fn expect_state_of(&self, opening: &Scene) {
        assert!(
            self.env.state() == opening.env.state(),
            "{}: the state differs from that of {}",
            self.name,
            opening.name
        );
    }

    /// Robot `robot` does `action`, which must be executed.
    #[track_caller]
    pub fn act(&mut self, robot: i64, action: &str) -> Outcome {
        let outcome = self
            .env
            .step(NodeId(robot), action)
            .unwrap_or_else(|e| panic!("{}: robot {robot}: {e}", self.name));
        if let Some(why) = &outcome.infeasible {
            panic!(
                "{}: robot {robot} could not do {action:?}: {:?}: {}\n  its actions: {:#?}",
                self.name,
                why.reason,
                why.message,
                self.actions(robot)
            );
        }
        outcome
    }

    /// Robot `robot` is refused `action` for `reason`, and nothing changes.
    #[track_caller]
    pub fn refused(&mut self, robot: i64, action: &str, reason: Reason) {
        let before = self.env.state().clone();
        let outcome = self
            .env
            .step(NodeId(robot), action)
            .unwrap_or_else(|e| panic!("{}: robot {robot}: {e}", self.name));
        match &outcome.infeasible {
            None => panic!("{}: robot {robot} was allowed {action:?}", self.name),
            Some(why) => assert_eq!(
                why.reason, reason,
                "{}: robot {robot} refused {action:?} for another reason: {}",
                self.name, why.message
            ),
        }
        assert_eq!(
            self.env.state(),
            &before,
            "{}: a refused action changed the state",
            self.name
        );
    }

    /// The robot's action list, sorted.
    #[track_caller]
    pub fn actions(&self, robot: i64) -> Vec<String> {
        let mut list = self
            .env
            .actions(NodeId(robot))
            .unwrap_or_else(|e| panic!("{}: robot {robot}: {e}", self.name));
        list.sort();
        list
    }

    /// The robot's action list is exactly `expected` (in any order, without repeats).
    #[track_caller]
    pub fn expect_actions(&self, robot: i64, expected: &[&str]) {
        let actual = self.actions(robot);
        let mut want: Vec<String> = expected.iter().map(|s| (*s).to_owned()).collect();
        want.sort();
        if actual != want {
            let missing: Vec<&String> = want.iter().filter(|a| !actual.contains(a)).collect();
            let extra: Vec<&String> = actual.iter().filter(|a| !want.contains(a)).collect();
            panic!(
                "{}: actions of robot {robot} differ\n  missing: {missing:#?}\n  unexpected: {extra:#?}\n  all actual: {actual:#?}",
                self.name
            );
        }
    }

    /// Ids of the nodes the robot observes, sorted.
    #[track_caller]
    pub fn view(&self, robot: i64) -> Vec<i64> {
        let obs = self
            .env
            .observe(NodeId(robot))
            .unwrap_or_else(|e| panic!("{}: robot {robot}: {e}", self.name));
        let task = self.env.task();
        let mut ids: Vec<i64> = obs.nodes.iter().map(|&n| task.id(n).0).collect();
        ids.sort();
        ids
    }

    /// The robot observes exactly the nodes `expected`.
    #[track_caller]
    pub fn expect_view(&self, robot: i64, expected: &[i64]) {
        let actual = self.view(robot);
        let mut want = expected.to_vec();
        want.sort();
        if actual != want {
            let missing: Vec<i64> = want
                .iter()
                .copied()
                .filter(|n| !actual.contains(n))
                .collect();
            let extra: Vec<i64> = actual
                .iter()
                .copied()
                .filter(|n| !want.contains(n))
                .collect();
            panic!(
                "{}: nodes observed by robot {robot} differ\n  missing: {missing:?}\n  unexpected: {extra:?}\n  all actual: {actual:?}",
                self.name
            );
        }
    }

    /// The edges the robot observes, as `(from, RELATION, to)` with file ids, sorted.
    #[track_caller]
    pub fn edges(&self, robot: i64) -> Vec<(i64, String, i64)> {
        let obs = self
            .env
            .observe(NodeId(robot))
            .unwrap_or_else(|e| panic!("{}: robot {robot}: {e}", self.name));
        let task = self.env.task();
        let mut edges: Vec<(i64, String, i64)> = obs
            .edges
            .iter()
            .map(|e| {
                (
                    task.id(e.from()).0,
                    e.rel().name().to_owned(),
                    task.id(e.to()).0,
                )
            })
            .collect();
        edges.sort();
        edges
    }

    /// The robot observes exactly the edges `expected`.
    #[track_caller]
    pub fn expect_edges(&self, robot: i64, expected: &[(i64, &str, i64)]) {
        let actual = self.edges(robot);
        let mut want: Vec<(i64, String, i64)> = expected
            .iter()
            .map(|&(a, r, b)| (a, r.to_owned(), b))
            .collect();
        want.sort();
        if actual != want {
            let missing: Vec<_> = want.iter().filter(|e| !actual.contains(e)).collect();
            let extra: Vec<_> = actual.iter().filter(|e| !want.contains(e)).collect();
            panic!(
                "{}: edges observed by robot {robot} differ\n  missing: {missing:?}\n  unexpected: {extra:?}",
                self.name
            );
        }
    }

    /// The robot observes (at least) every edge of `expected`.
    #[track_caller]
    pub fn expect_seen_edges(&self, robot: i64, expected: &[(i64, &str, i64)]) {
        let actual = self.edges(robot);
        for &(a, r, b) in expected {
            assert!(
                actual.contains(&(a, r.to_owned(), b)),
                "{}: robot {robot} does not observe {a} {r} {b}; it observes {actual:?}",
                self.name
            );
        }
    }

    /// The robot observes none of the edges `unexpected`.
    #[track_caller]
    pub fn expect_unseen_edges(&self, robot: i64, unexpected: &[(i64, &str, i64)]) {
        let actual = self.edges(robot);
        for &(a, r, b) in unexpected {
            assert!(
                !actual.contains(&(a, r.to_owned(), b)),
                "{}: robot {robot} observes {a} {r} {b}, which should not exist or be visible",
                self.name
            );
        }
    }

    /// Whether node `id` has `ON_HIGH_SURFACE` now.
    #[track_caller]
    pub fn on_high_surface(&self, id: i64) -> bool {
        let task = self.env.task();
        let n = task
            .idx(NodeId(id))
            .unwrap_or_else(|| panic!("{}: no node {id}", self.name));
        task.has(self.env.state(), n, PropSet::ON_HIGH_SURFACE)
    }

    /// Each of `ids` has `ON_HIGH_SURFACE` exactly when `high` says so.
    #[track_caller]
    pub fn expect_high(&self, ids: &[i64], high: bool) {
        for &id in ids {
            assert_eq!(
                self.on_high_surface(id),
                high,
                "{}: ON_HIGH_SURFACE of node {id}",
                self.name
            );
        }
    }

    /// Names of node `id`'s states now, sorted.
    #[track_caller]
    pub fn states(&self, id: i64) -> Vec<String> {
        let task = self.env.task();
        let n = task
            .idx(NodeId(id))
            .unwrap_or_else(|| panic!("{}: no node {id}", self.name));
        let mut names = task.vocab.state_names(self.env.state().states(n));
        names.sort();
        names
    }

    pub fn done(&self) -> bool {
        self.env.goal_satisfied()
    }
}
