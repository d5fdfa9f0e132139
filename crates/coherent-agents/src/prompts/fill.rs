//! What the methods' prompts share: filling a template of the prompt set
//! ([`crate::prompts::templates`]) with the situation, the team list, and robot labels.
//! Each role renders its own templates ([`crate::methods::assigner`],
//! [`crate::methods::executor`], [`crate::prompts::team_actions`], [`crate::methods::dmrs`]).
//! Observations are written as relation facts (`coherent_core::describe`), in the layout
//! the template asks for (`Sight`).

use coherent_core::{NodeId, Observation, State, Task, describe};

/// `template` with every `{{key}}` replaced by its value, in one pass: a value that
/// itself contains `{{...}}` (an instruction, say) is left as written.
pub fn fill(template: &str, values: &[(&str, &str)]) -> String {
    let mut out = String::with_capacity(template.len());
    let mut rest = template;
    while let Some(open) = rest.find("{{") {
        out.push_str(&rest[..open]);
        let after = &rest[open + 2..];
        let value = after.find("}}").and_then(|close| {
            let key = &after[..close];
            values
                .iter()
                .find(|(k, _)| *k == key)
                .map(|(_, v)| (*v, close))
        });
        match value {
            Some((v, close)) => {
                out.push_str(v);
                rest = &after[close + 2..];
            }
            None => {
                out.push_str("{{");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// What a role is shown of the world: the observations it gets, written for whichever
/// placeholders its template uses: `observation` (one block, the paper's layout:
/// [`describe::facts`]) or `scene` and `state` (the scene's fixed facts and what
/// changes: [`describe::layered`]). The same facts either way.
pub(crate) struct Sight<'a> {
    pub task: &'a Task,
    pub state: &'a State,
    pub observations: Vec<Observation>,
    /// What happened since the last round that the team did not do (the task's
    /// events), a sentence each; said first, before the facts that change.
    pub news: &'a [String],
}

impl Sight<'_> {
    /// The observation placeholders `text` uses, with their values (each layout written
    /// only when used). News comes first in the observation, or in the state: the part
    /// of a prompt that changes.
    pub(crate) fn values(&self, text: &str) -> Vec<(&'static str, String)> {
        let seen: Vec<&Observation> = self.observations.iter().collect();
        let mut out = Vec::new();
        if uses(text, "observation") {
            let facts = describe::facts(self.task, self.state, &seen);
            out.push(("observation", self.told(facts)));
        }
        if uses(text, "scene") || uses(text, "state") {
            let layers = describe::layered(self.task, self.state, &seen);
            out.push(("scene", layers.scene));
            out.push(("state", self.told(layers.state)));
        }
        out
    }

    /// `facts` after the news, if there is any.
    fn told(&self, facts: String) -> String {
        if self.news.is_empty() {
            return facts;
        }
        let mut out = String::from("What just happened, that the team did not do:\n");
        for line in self.news {
            out.push_str("- ");
            out.push_str(line);
            out.push('\n');
        }
        out.push('\n');
        out.push_str(&facts);
        out
    }
}

/// Whether `text` has the placeholder `{{key}}`.
fn uses(text: &str, key: &str) -> bool {
    text.contains(&format!("{{{{{key}}}}}"))
}

/// The team list of a system prompt: each robot's label and type, one per line.
pub(crate) fn team(task: &Task) -> String {
    task.robots
        .iter()
        .map(|r| format!("- {}: {}", task.node(r.node).label(), r.kind))
        .collect::<Vec<_>>()
        .join("\n")
}

/// `<label>(id)` of robot `robot`, or `robot <id>` when it is none of the task's.
pub fn robot_label(task: &Task, robot: NodeId) -> String {
    task.idx(robot)
        .map_or_else(|| format!("robot {robot}"), |i| task.node(i).label())
}

/// `<robot label>: <action>`: one robot's action as the central and dialogue prompts list
/// it, as their methods hear what ran and as their history recalls it.
pub fn action_line(task: &Task, robot: NodeId, action: &str) -> String {
    format!("{}: {action}", robot_label(task, robot))
}

/// Asserts that `template` has a placeholder for each of `keys` and that filling them
/// leaves none unfilled.
#[cfg(test)]
pub(crate) fn check_placeholders(template: &str, keys: &[&str]) {
    let values: Vec<(&str, &str)> = keys.iter().map(|&k| (k, "value")).collect();
    let filled = fill(template, &values);
    assert!(!filled.contains("{{"), "unfilled placeholder in:\n{filled}");
    for k in keys {
        assert!(template.contains(&format!("{{{{{k}}}}}")), "{k} unused");
    }
}

/// The built-in set with `template` replaced by every one of its placeholders, one a
/// line: rendering it must leave none unfilled.
#[cfg(test)]
pub(crate) fn every_placeholder(
    template: crate::prompts::templates::Template,
) -> crate::prompts::templates::Prompts {
    let text: Vec<String> = template
        .placeholders()
        .iter()
        .map(|p| format!("{p}: {{{{{p}}}}}"))
        .collect();
    crate::prompts::templates::Prompts::from_texts(
        std::path::Path::new("test"),
        vec![(template.file_name().to_owned(), text.join("\n"))],
    )
    .expect("its own placeholders check")
}

/// The demo task (`examples/tasks/demo.json`), for the unit tests.
#[cfg(test)]
pub(crate) fn demo_task() -> std::sync::Arc<Task> {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/tasks/demo.json");
    std::sync::Arc::new(
        coherent_core::load_tasks(&path)
            .expect("the demo")
            .remove(0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fill_replaces_every_known_key_once() {
        assert_eq!(
            fill(
                "{{a}} and {{a}}, {{b}} {{c}}",
                &[("a", "x"), ("b", "{{a}}")]
            ),
            "x and x, {{a}} {{c}}"
        );
    }
}
