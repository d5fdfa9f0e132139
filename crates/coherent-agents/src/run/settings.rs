//! How an episode is run: the method (built in, or written outside the crate), each
//! built by its name into the [`Method`] an episode runs ([`MethodSpec::build`], the one
//! place that knows every method), and the settings a transcript records. The step
//! budget is apart ([`crate::episode::budget`]).

use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;
use std::time::Duration;

use coherent_core::planner::Limits;
use coherent_core::{Execution, Task};

use crate::episode::cancel::Cancel;
use crate::episode::method::Method;
use crate::episode::play::HISTORY_WINDOW;
use crate::episode::policy::{MakePolicy, MethodFailure, Policy};
use crate::error::Error;
use crate::methods::cmrs::Cmrs;
use crate::methods::dmrs::Dmrs;
use crate::methods::external::ExternalMethod;
use crate::methods::llm_pddl::LlmPddl;
use crate::methods::mcts::{Mcts, MctsConfig};
use crate::methods::optimal::Optimal;
use crate::methods::pefa::Pefa;
use crate::methods::random::Random;
use crate::prompts::templates::Prompts;
use crate::records::transcript::RobotsRecord;

/// A planning method built into the crate, by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builtin {
    /// COHERENT's loop with the assigner's history window.
    Pefa,
    /// The paper's "w/o history" ablation: the window is 0.
    PefaNoHistory,
    /// One central model choosing one robot's action per step.
    Cmrs,
    /// Decentralised dialogue, one round per step.
    Dmrs1d,
    /// Decentralised dialogue, two rounds per step.
    Dmrs2d,
    /// Primitive MCTS with the authors' settings; no model.
    Mcts,
    /// MCTS with a language-model prior at the root of each step's tree.
    LlmMcts,
    /// The optimal planner's plan: the ground-truth row; no model.
    Optimal,
    /// A random feasible action each round, seeded: the floor; no model.
    Random,
    /// LLM+P: the model writes the goal once, the optimal planner plans for it.
    LlmPddl,
}

impl Builtin {
    pub const ALL: [Builtin; 10] = [
        Builtin::Pefa,
        Builtin::PefaNoHistory,
        Builtin::Cmrs,
        Builtin::Dmrs1d,
        Builtin::Dmrs2d,
        Builtin::Mcts,
        Builtin::LlmMcts,
        Builtin::Optimal,
        Builtin::Random,
        Builtin::LlmPddl,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Builtin::Pefa => "pefa",
            Builtin::PefaNoHistory => "pefa-no-history",
            Builtin::Cmrs => "cmrs",
            Builtin::Dmrs1d => "dmrs-1d",
            Builtin::Dmrs2d => "dmrs-2d",
            Builtin::Mcts => "mcts",
            Builtin::LlmMcts => "llm-mcts",
            Builtin::Optimal => "optimal",
            Builtin::Random => "random",
            Builtin::LlmPddl => "llm-pddl",
        }
    }

    /// Whether the method asks the episode's backend at all.
    pub fn asks_backend(self) -> bool {
        !matches!(self, Builtin::Mcts | Builtin::Optimal | Builtin::Random)
    }

    /// Whether the method can run `execution`: the tree searches, MCTS and LLM-MCTS,
    /// are sequential only (their tree's edges are one robot's action; a tree over
    /// joint steps is a method of its own, which the paper does not have).
    pub fn runs(self, execution: Execution) -> bool {
        execution == Execution::Sequential || !matches!(self, Builtin::Mcts | Builtin::LlmMcts)
    }

    pub fn from_name(name: &str) -> Option<Builtin> {
        Builtin::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// A method written outside the crate (a Python class, say), by name: each episode gets
/// its own [`Policy`] from the maker.
#[derive(Clone)]
pub struct External {
    name: String,
    make: Arc<MakePolicy>,
    /// The longest one step may take (the policy's `act`, and its making at the first
    /// step); `None` for no limit.
    step_timeout: Option<Duration>,
    /// What the method declares of its own settings, recorded in each results line.
    settings: BTreeMap<String, serde_json::Value>,
}

impl External {
    /// The method `name`, whose episodes get their policy from `make`. The name goes
    /// into results, tables and transcript file names: letters, digits, `-`, `_` and `.`
    /// (not first), and none of the built-in methods' names.
    pub fn new(name: &str, make: Arc<MakePolicy>) -> Result<External, Error> {
        let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.');
        if name.is_empty() || !name.chars().all(allowed) || name.starts_with('.') {
            return Err(Error::Invalid(format!(
                "method name {name:?}: use letters, digits, '-', '_' and '.' (not first)"
            )));
        }
        if Builtin::from_name(name).is_some() {
            return Err(Error::Invalid(format!(
                "method name {name:?} is a built-in method's: give yours another name"
            )));
        }
        Ok(External {
            name: name.to_owned(),
            make,
            step_timeout: None,
            settings: BTreeMap::new(),
        })
    }

    /// The method with each step limited to `limit` (`None`: no limit): a step that takes
    /// longer ends as the method's error.
    pub fn with_step_timeout(mut self, limit: Option<Duration>) -> External {
        self.step_timeout = limit;
        self
    }

    /// The method with its own settings declared (recorded in every results line, so
    /// that results of other settings are not taken for its own).
    pub fn with_settings(mut self, settings: BTreeMap<String, serde_json::Value>) -> External {
        self.settings = settings;
        self
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The longest one step may take.
    pub fn step_timeout(&self) -> Option<Duration> {
        self.step_timeout
    }

    /// Its own settings, as declared.
    pub fn settings(&self) -> &BTreeMap<String, serde_json::Value> {
        &self.settings
    }

    /// The policy of one episode of `task`, or why there is none.
    pub fn make(&self, task: &Arc<Task>) -> Result<Box<dyn Policy>, MethodFailure> {
        (self.make)(task)
    }
}

impl fmt::Debug for External {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("External")
            .field("name", &self.name)
            .field("step_timeout", &self.step_timeout)
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

/// Two are the same method when they have the same name, the same maker and the same
/// step limit and settings.
impl PartialEq for External {
    fn eq(&self, other: &External) -> bool {
        self.name == other.name
            && Arc::ptr_eq(&self.make, &other.make)
            && self.step_timeout == other.step_timeout
            && self.settings == other.settings
    }
}

/// The method of an episode: one of the built-in ones, or one written outside the crate.
#[derive(Clone, Debug, PartialEq)]
pub enum MethodSpec {
    Builtin(Builtin),
    External(External),
}

impl MethodSpec {
    /// The name in results, tables and transcripts.
    pub fn name(&self) -> &str {
        match self {
            MethodSpec::Builtin(m) => m.name(),
            MethodSpec::External(e) => e.name(),
        }
    }

    /// Whether the episode's backend answers the method's questions (a method written
    /// outside the crate asks its own models, if any). Whether an episode used a model
    /// is another question, answered by its calls ([`crate::harness::prices::ModelUse`]).
    pub fn asks_backend(&self) -> bool {
        match self {
            MethodSpec::Builtin(m) => m.asks_backend(),
            MethodSpec::External(_) => false,
        }
    }

    /// Whether the method can run `execution` (a method written outside the crate can:
    /// its `act` answers a decision per robot).
    pub fn runs(&self, execution: Execution) -> bool {
        self.builtin().is_none_or(|m| m.runs(execution))
    }

    /// `Ok` when the method can run `execution`, else the error that says it cannot.
    pub fn check_runs(&self, execution: Execution) -> Result<(), Error> {
        if self.runs(execution) {
            return Ok(());
        }
        Err(Error::Invalid(format!(
            "{} is sequential only: its search tree takes one robot's action a step; \
             run it with execution sequential",
            self.name()
        )))
    }

    /// The method's own settings: what a method written outside the crate declares;
    /// none for a built-in one (its settings are the run's).
    pub fn own_settings(&self) -> BTreeMap<String, serde_json::Value> {
        match self {
            MethodSpec::Builtin(_) => BTreeMap::new(),
            MethodSpec::External(e) => e.settings.clone(),
        }
    }

    /// The built-in method, when it is one.
    pub fn builtin(&self) -> Option<Builtin> {
        match self {
            MethodSpec::Builtin(m) => Some(*m),
            MethodSpec::External(_) => None,
        }
    }

    /// The method of one episode of `task` run with `settings` (its execution, prompt set
    /// and seed), or the error that says it cannot run that execution. Every method is
    /// built here and nowhere else. `cancel` stops the optimal method's search.
    pub fn build(
        &self,
        task: &Arc<Task>,
        settings: &Settings,
        cancel: &Cancel,
    ) -> Result<Box<dyn Method>, Error> {
        self.check_runs(settings.execution)?;
        let prompts = settings.prompts.clone();
        let seed = settings.seed.unwrap_or(0);
        let mcts = || MctsConfig {
            seed,
            prompts: prompts.clone(),
            ..MctsConfig::default()
        };
        Ok(match self {
            MethodSpec::Builtin(Builtin::Pefa | Builtin::PefaNoHistory) => {
                Box::new(Pefa::new(prompts))
            }
            MethodSpec::Builtin(Builtin::Cmrs) => Box::new(Cmrs::new(prompts)),
            MethodSpec::Builtin(Builtin::Dmrs1d) => Box::new(Dmrs::new(1, seed, prompts)),
            MethodSpec::Builtin(Builtin::Dmrs2d) => Box::new(Dmrs::new(2, seed, prompts)),
            MethodSpec::Builtin(Builtin::Mcts) => Box::new(Mcts::primitive(mcts())),
            MethodSpec::Builtin(Builtin::LlmMcts) => Box::new(Mcts::llm(mcts())),
            MethodSpec::Builtin(Builtin::Optimal) => Box::new(Optimal::new(Limits {
                cancel: Some(cancel.flag()),
                ..Limits::default()
            })),
            MethodSpec::Builtin(Builtin::Random) => Box::new(Random::new(seed)),
            MethodSpec::Builtin(Builtin::LlmPddl) => Box::new(LlmPddl::new(
                prompts,
                Limits {
                    cancel: Some(cancel.flag()),
                    ..Limits::default()
                },
            )),
            MethodSpec::External(e) => {
                Box::new(ExternalMethod::new(e.make(task), e.step_timeout()))
            }
        })
    }
}

impl From<Builtin> for MethodSpec {
    fn from(m: Builtin) -> MethodSpec {
        MethodSpec::Builtin(m)
    }
}

/// How an episode is run, as recorded in its transcript's header. The step budget is
/// apart ([`crate::episode::Budget`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub method: MethodSpec,
    /// One robot's action a step (the paper's), or joint steps.
    pub execution: Execution,
    /// Rounds of history the assigner sees (ignored by `pefa-no-history`); for the
    /// baselines, the executed actions in their prompts (the paper: 5 for both).
    pub history: usize,
    pub temperature: Option<f32>,
    /// The model's sampling seed; also the MCTS search's and the DMRS speaking order's
    /// (0 when unset).
    pub seed: Option<u64>,
    /// Whether the environment is physical (recorded; the caller builds the environment).
    pub physics: bool,
    /// Who carries the actions out (recorded; the caller builds the environment).
    pub robots: RobotsRecord,
    /// The templates the method's prompts are rendered from (checked when made).
    pub prompts: Prompts,
    /// The most states one search of the loop's own may visit (the optimum proven again
    /// at each event of the task).
    pub max_states: usize,
}

impl Settings {
    /// The rounds of history the episode's prompts recall: [`Settings::history`], but none
    /// for `pefa-no-history` (the paper's "w/o history").
    pub fn history_window(&self) -> usize {
        match self.method {
            MethodSpec::Builtin(Builtin::PefaNoHistory) => 0,
            _ => self.history,
        }
    }

    /// The method these settings name, built for one episode of `task`
    /// ([`MethodSpec::build`]).
    pub fn build(&self, task: &Arc<Task>, cancel: &Cancel) -> Result<Box<dyn Method>, Error> {
        self.method.build(task, self, cancel)
    }

    pub fn new(method: impl Into<MethodSpec>) -> Settings {
        Settings {
            method: method.into(),
            execution: Execution::Sequential,
            history: HISTORY_WINDOW,
            temperature: None,
            seed: None,
            physics: false,
            robots: RobotsRecord::Local,
            prompts: Prompts::builtin(),
            max_states: Limits::DEFAULT_MAX_STATES,
        }
    }
}
