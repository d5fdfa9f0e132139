//! What makes the lines of a results file comparable: the settings every episode of a
//! run shares (who answered and with which model, the simulated error rates, the seeds,
//! the prompt set, the history window, the step budget, ...) and each method's own,
//! recorded in every line. Resuming a results file with other settings is refused
//! ([`crate::harness::ledger::mismatch`]), and the tables are made of lines of one set of
//! settings only ([`crate::harness::report::groups`]), so that two runs are never counted
//! as one.

use std::collections::BTreeMap;

use coherent_core::Execution;
use serde::{Deserialize, Serialize};

use crate::llm::BackendKind;
use crate::prompts::templates::Prompts;
use crate::setting::{Difference, Setting, field};

/// The settings one results line was run with.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSettings {
    /// Who answered the model-using methods.
    pub backend: BackendKind,
    /// The model, for an endpoint or a replay of one; none for the planner's backends.
    pub model: Option<String>,
    /// The simulated backend's error rates ([`crate::ErrorRates::label`]).
    pub sim_errors: Option<String>,
    /// The endpoint's sampling temperature.
    pub temperature: Option<f32>,
    /// The seed sent to the endpoint.
    pub model_seed: Option<u64>,
    /// Seed indices `0..seeds`.
    pub seeds: u32,
    /// The prompt set ([`Prompts::hash`]).
    pub prompts: String,
    /// Rounds of history the methods see.
    pub history: usize,
    /// Every episode's step budget; none for the paper's 2 x GT.
    pub max_steps: Option<u32>,
    /// The most states one planner search may visit.
    pub max_states: usize,
    /// Every action in Rapier too.
    pub physics: bool,
    /// Who carried the actions out: `local` or `ros2`.
    pub robots: String,
    /// The version of coherent that ran the episode.
    pub coherent: String,
    /// Every execution the run takes its episodes in (`bench --execution
    /// sequential,parallel` is one run of both: its lines share these settings and differ
    /// by their own `execution`, part of the episode key). Absent for the paper's
    /// sequential alone, so that a sequential run records what it did before parallel
    /// episodes.
    #[serde(
        default = "sequential_only",
        skip_serializing_if = "is_sequential_only"
    )]
    pub executions: Vec<Execution>,
    /// The method's own settings: what a method written in Python declares (its
    /// `settings`); none for a built-in method, whose settings are the ones above.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub method: BTreeMap<String, serde_json::Value>,
}

impl RunSettings {
    /// Each run-wide setting (the method's own apart) with its value as shown.
    pub fn shown(&self) -> Vec<(Setting, String)> {
        let or = |v: Option<String>, none: &str| v.unwrap_or_else(|| none.to_owned());
        vec![
            (Setting::Backend, self.backend.name().to_owned()),
            (Setting::Model, or(self.model.clone(), "none")),
            (Setting::SimErrors, or(self.sim_errors.clone(), "none")),
            (
                Setting::Temperature,
                or(self.temperature.map(|t| t.to_string()), "none"),
            ),
            (
                Setting::ModelSeed,
                or(self.model_seed.map(|s| s.to_string()), "none"),
            ),
            (Setting::Seeds, self.seeds.to_string()),
            (Setting::Prompts, prompt_set(&self.prompts)),
            (Setting::History, self.history.to_string()),
            (
                Setting::MaxSteps,
                or(self.max_steps.map(|n| n.to_string()), "2 x GT"),
            ),
            (Setting::MaxStates, self.max_states.to_string()),
            (
                Setting::Physics,
                if self.physics { "on" } else { "off" }.to_owned(),
            ),
            (Setting::Robots, self.robots.clone()),
            (Setting::Execution, executions_text(&self.executions)),
            (Setting::Version, self.coherent.clone()),
        ]
    }

    /// The run-wide settings that differ from `now`'s.
    pub fn differences(&self, now: &RunSettings) -> Vec<Difference> {
        self.shown()
            .into_iter()
            .zip(now.shown())
            .filter(|((_, a), (_, b))| a != b)
            .map(|((setting, file), (_, now))| Difference {
                setting,
                method: None,
                file,
                now,
            })
            .collect()
    }

    /// The same settings without the method's own: what every line of a run shares.
    pub fn run_wide(&self) -> RunSettings {
        RunSettings {
            method: BTreeMap::new(),
            ..self.clone()
        }
    }

    /// 8 hex digits that name the run-wide settings ([`crate::digest::fnv128`] of their
    /// JSON): equal settings, equal names.
    pub fn digest(&self) -> String {
        let json = serde_json::to_string(&self.run_wide()).unwrap_or_default();
        crate::digest::fnv128([("settings", json.as_str())])[..8].to_owned()
    }

    /// One line: `backend simulated, sim_errors all=0.1, seeds 3, ...` (the settings
    /// that have a value, by the names the results file uses).
    pub fn summary(&self) -> String {
        self.shown()
            .into_iter()
            .filter(|(setting, value)| {
                (value != "none" || matches!(setting, Setting::Backend | Setting::SimErrors))
                    && !(*setting == Setting::Execution && value == "sequential")
            })
            .map(|(setting, value)| format!("{} {value}", field(setting)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The executions as a flag writes them: `sequential,parallel`.
pub fn executions_text(executions: &[Execution]) -> String {
    executions
        .iter()
        .map(|e| e.name())
        .collect::<Vec<_>>()
        .join(",")
}

fn sequential_only() -> Vec<Execution> {
    vec![Execution::Sequential]
}

fn is_sequential_only(executions: &[Execution]) -> bool {
    executions == [Execution::Sequential]
}

/// A method's own settings as shown: JSON, or `none`.
pub fn method_text(own: &BTreeMap<String, serde_json::Value>) -> String {
    if own.is_empty() {
        "none".to_owned()
    } else {
        serde_json::to_string(own).unwrap_or_default()
    }
}

/// `built-in`, or the hash of a prompt set with other templates.
fn prompt_set(hash: &str) -> String {
    if Execution::ALL
        .iter()
        .any(|&e| hash == Prompts::builtin().hash(e))
    {
        "built-in".to_owned()
    } else {
        format!("set {hash}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> RunSettings {
        RunSettings {
            backend: BackendKind::Simulated,
            model: None,
            sim_errors: Some("all=0.1".into()),
            temperature: None,
            model_seed: None,
            seeds: 3,
            prompts: Prompts::builtin().hash(Execution::Sequential).to_owned(),
            history: 5,
            max_steps: None,
            max_states: 1000,
            physics: false,
            robots: "local".into(),
            coherent: "0.1.0".into(),
            executions: sequential_only(),
            method: BTreeMap::new(),
        }
    }

    #[test]
    fn a_sequential_run_records_no_executions_and_a_run_of_both_does() {
        let json = serde_json::to_value(settings()).expect("settings as JSON");
        assert!(json.get("executions").is_none(), "{json}");
        let both = RunSettings {
            executions: Execution::ALL.to_vec(),
            ..settings()
        };
        let json = serde_json::to_value(&both).expect("settings as JSON");
        assert_eq!(
            json["executions"],
            serde_json::json!(["sequential", "parallel"])
        );
        let back: RunSettings = serde_json::from_value(json).expect("read back");
        assert_eq!(back, both);
        let d = settings().differences(&both);
        assert_eq!(d.len(), 1);
        assert_eq!(
            d[0].to_string(),
            "sequential in the file, sequential,parallel now"
        );
        assert!(both.summary().contains("executions sequential,parallel"));
        assert!(!settings().summary().contains("executions"));
    }

    #[test]
    fn differences_name_each_setting_with_both_values() {
        let a = settings();
        let b = RunSettings {
            sim_errors: Some("all=0.3".into()),
            seeds: 1,
            ..settings()
        };
        let d = a.differences(&b);
        assert_eq!(
            d.iter().map(|d| d.setting).collect::<Vec<_>>(),
            [Setting::SimErrors, Setting::Seeds]
        );
        assert_eq!(d[0].to_string(), "all=0.1 in the file, all=0.3 now");
        assert!(a.differences(&a).is_empty());
    }

    #[test]
    fn the_summary_shows_the_built_in_prompt_set_and_the_budget_rule() {
        let s = settings().summary();
        assert!(
            s.starts_with("backend simulated, sim_errors all=0.1, seeds 3"),
            "{s}"
        );
        assert!(s.contains("prompts built-in"), "{s}");
        assert!(s.contains("max_steps 2 x GT"), "{s}");
        assert!(!s.contains("model "), "{s}");
    }
}
