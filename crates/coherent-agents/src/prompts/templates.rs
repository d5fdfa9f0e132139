//! The prompt set: the twelve templates the methods render their prompts from (four of
//! them for parallel episodes only), each the built-in one (`prompts/*.txt`, compiled in) or a file of the same name from a folder
//! given at run time. A set is one value, passed down to the methods with the episode's
//! settings; it is checked when it is made, so that a template naming a placeholder its
//! method does not fill is refused before any model call.
//!
//! The built-in templates put what never changes first and what changes each round
//! last (the rules, the team, the instruction, the scene's fixed facts; then where the
//! robots are, states, relations, the action list; the history at the end), so that a
//! server's prompt cache serves the unchanged beginning of each call. The paper's
//! layout, one block of facts after the instruction, stays at hand as the set named
//! [`PAPER_LAYOUT`] ([`Template::paper_layout`]): the same facts in the order the
//! templates had before.
//!
//! A transcript's header records the set ([`PromptRecord`]): a hash of the text of every
//! template its execution's methods render (a sequential episode's leaves the parallel
//! templates out, so that it is what it was before they existed) and the text of each
//! file that replaced a built-in template, so that two runs can be told apart and a
//! replay renders the very prompts that were recorded.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_core::files::{self, Limit, MIB};
use serde::{Deserialize, Serialize};

use crate::digest;
use coherent_core::Execution;

/// The most a template may hold: the built-in ones are a few KiB, and a prompt of a MiB
/// is already past any model's context.
pub const TEMPLATE_LIMIT: Limit = Limit {
    bytes: MIB,
    what: "a prompt template",
    raise: None,
};

/// The name of the built-in set in the paper's layout (`--prompts paper-layout`).
pub const PAPER_LAYOUT: &str = "paper-layout";

/// The line of a two-part template ([`Template::Central`], [`Template::DmrsSpeaker`])
/// that separates its system part from its user part.
pub const USER_MARK: &str = "@@user@@";

/// One template of the prompt set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Template {
    /// PEFA's task assigner, system prompt: the team and the world's rules.
    AssignerSystem,
    /// PEFA's task assigner, each round: the instruction, the robots, the history.
    AssignerUser,
    /// A quadrotor's executor, system prompt.
    ExecutorQuadrotor,
    /// A robot dog's executor, system prompt.
    ExecutorRobotDog,
    /// A robot arm's executor, system prompt.
    ExecutorRobotArm,
    /// Every executor, each round: the subtask, its observation, its action list.
    ExecutorUser,
    /// CMRS and LLM-MCTS: one central model choosing a line of the team action space.
    Central,
    /// DMRS: one robot's turn in the team's dialogue.
    DmrsSpeaker,
    /// PEFA in joint steps: the task assigner's system prompt.
    AssignerParallelSystem,
    /// PEFA in joint steps: each round, subtasks for any of the idle robots.
    AssignerParallelUser,
    /// CMRS in joint steps: one central model choosing at most one line per robot.
    CentralParallel,
    /// DMRS in joint steps: one robot's turn, proposing its own action.
    DmrsSpeakerParallel,
    /// LLM+P (`llm-pddl`): the model writes the task's goal as facts, once an episode.
    Goal,
}

impl Template {
    pub const ALL: [Template; 13] = [
        Template::AssignerSystem,
        Template::AssignerUser,
        Template::ExecutorQuadrotor,
        Template::ExecutorRobotDog,
        Template::ExecutorRobotArm,
        Template::ExecutorUser,
        Template::Central,
        Template::DmrsSpeaker,
        Template::AssignerParallelSystem,
        Template::AssignerParallelUser,
        Template::CentralParallel,
        Template::DmrsSpeakerParallel,
        Template::Goal,
    ];

    /// Whether only parallel episodes render it.
    pub fn parallel_only(self) -> bool {
        matches!(
            self,
            Template::AssignerParallelSystem
                | Template::AssignerParallelUser
                | Template::CentralParallel
                | Template::DmrsSpeakerParallel
        )
    }

    /// Whether a set's hash covers it while it has its built-in text: every template but
    /// llm-pddl's goal, which came after transcripts had been recorded with the others,
    /// so that their hashes hold and they replay; a goal template that replaces the
    /// built-in one is covered (and recorded) like any other.
    fn hashed_as_builtin(self) -> bool {
        self != Template::Goal
    }

    /// Whether the methods of `execution` may render it.
    pub fn used_in(self, execution: Execution) -> bool {
        execution == Execution::Parallel || !self.parallel_only()
    }

    /// Its file's name, in `prompts/` and in a prompt folder.
    pub fn file_name(self) -> &'static str {
        match self {
            Template::AssignerSystem => "assigner_system.txt",
            Template::AssignerUser => "assigner_user.txt",
            Template::ExecutorQuadrotor => "executor_quadrotor.txt",
            Template::ExecutorRobotDog => "executor_robot_dog.txt",
            Template::ExecutorRobotArm => "executor_robot_arm.txt",
            Template::ExecutorUser => "executor_user.txt",
            Template::Central => "central.txt",
            Template::DmrsSpeaker => "dmrs_speaker.txt",
            Template::AssignerParallelSystem => "assigner_parallel_system.txt",
            Template::AssignerParallelUser => "assigner_parallel_user.txt",
            Template::CentralParallel => "central_parallel.txt",
            Template::DmrsSpeakerParallel => "dmrs_speaker_parallel.txt",
            Template::Goal => "goal.txt",
        }
    }

    /// The template of this name, if one has it.
    pub fn from_file_name(name: &str) -> Option<Template> {
        Template::ALL.into_iter().find(|t| t.file_name() == name)
    }

    /// The compiled-in text.
    pub fn builtin(self) -> &'static str {
        match self {
            Template::AssignerSystem => include_str!("../../prompts/assigner_system.txt"),
            Template::AssignerUser => include_str!("../../prompts/assigner_user.txt"),
            Template::ExecutorQuadrotor => include_str!("../../prompts/executor_quadrotor.txt"),
            Template::ExecutorRobotDog => include_str!("../../prompts/executor_robot_dog.txt"),
            Template::ExecutorRobotArm => include_str!("../../prompts/executor_robot_arm.txt"),
            Template::ExecutorUser => include_str!("../../prompts/executor_user.txt"),
            Template::Central => include_str!("../../prompts/central.txt"),
            Template::DmrsSpeaker => include_str!("../../prompts/dmrs_speaker.txt"),
            Template::AssignerParallelSystem => {
                include_str!("../../prompts/assigner_parallel_system.txt")
            }
            Template::AssignerParallelUser => {
                include_str!("../../prompts/assigner_parallel_user.txt")
            }
            Template::CentralParallel => include_str!("../../prompts/central_parallel.txt"),
            Template::DmrsSpeakerParallel => {
                include_str!("../../prompts/dmrs_speaker_parallel.txt")
            }
            Template::Goal => include_str!("../../prompts/goal.txt"),
        }
    }

    /// Its text in the paper's layout: the built-in text before the templates were laid
    /// out for prompt caching (the observation as one block, `{{observation}}`, after
    /// the instruction; the team in the middle of the system prompt).
    pub fn paper_layout(self) -> &'static str {
        match self {
            Template::AssignerSystem => {
                include_str!("../../prompts/paper-layout/assigner_system.txt")
            }
            Template::AssignerUser => include_str!("../../prompts/paper-layout/assigner_user.txt"),
            Template::ExecutorQuadrotor => {
                include_str!("../../prompts/paper-layout/executor_quadrotor.txt")
            }
            Template::ExecutorRobotDog => {
                include_str!("../../prompts/paper-layout/executor_robot_dog.txt")
            }
            Template::ExecutorRobotArm => {
                include_str!("../../prompts/paper-layout/executor_robot_arm.txt")
            }
            Template::ExecutorUser => include_str!("../../prompts/paper-layout/executor_user.txt"),
            Template::Central => include_str!("../../prompts/paper-layout/central.txt"),
            Template::DmrsSpeaker => include_str!("../../prompts/paper-layout/dmrs_speaker.txt"),
            // Its system prompt has nothing that changes: one text in both layouts.
            Template::AssignerParallelSystem => self.builtin(),
            Template::AssignerParallelUser => {
                include_str!("../../prompts/paper-layout/assigner_parallel_user.txt")
            }
            Template::CentralParallel => {
                include_str!("../../prompts/paper-layout/central_parallel.txt")
            }
            Template::DmrsSpeakerParallel => {
                include_str!("../../prompts/paper-layout/dmrs_speaker_parallel.txt")
            }
            // The paper has no LLM+P method: one text in both layouts.
            Template::Goal => self.builtin(),
        }
    }

    /// The placeholders its method fills (`{{name}}` in the text); any other is refused.
    /// Where a template shows an observation, `observation` is it in one block (the
    /// paper's layout), `scene` and `state` the same facts in two: what never changes,
    /// and what does.
    pub fn placeholders(self) -> &'static [&'static str] {
        match self {
            Template::AssignerSystem | Template::AssignerParallelSystem => &["team"],
            Template::AssignerUser => &[
                "instruction",
                "robots",
                "observation",
                "scene",
                "state",
                "history",
            ],
            Template::AssignerParallelUser => &[
                "instruction",
                "robots",
                "observation",
                "scene",
                "state",
                "history",
                "busy",
                "idle",
            ],
            Template::ExecutorQuadrotor
            | Template::ExecutorRobotDog
            | Template::ExecutorRobotArm => &["robot"],
            Template::ExecutorUser => &["subtask", "observation", "scene", "state", "actions"],
            Template::Central | Template::CentralParallel => &[
                "team",
                "instruction",
                "observation",
                "scene",
                "state",
                "history",
                "actions",
            ],
            Template::Goal => &["team", "instruction", "observation", "scene", "state"],
            Template::DmrsSpeaker | Template::DmrsSpeakerParallel => &[
                "robot",
                "kind",
                "team",
                "instruction",
                "observation",
                "scene",
                "state",
                "history",
                "dialogue",
                "actions",
            ],
        }
    }
}

/// `text`'s system part and user part, split at the [`USER_MARK`] line; without one, all
/// of it is the user part.
pub fn split(text: &str) -> (&str, &str) {
    text.split_once(USER_MARK).unwrap_or(("", text))
}

/// Why a prompt set could not be made.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PromptError {
    /// A folder or a file that cannot be read.
    Io { file: String, message: String },
    /// A `.txt` file whose name is no template's (a typo would otherwise be ignored).
    UnknownFile { file: String },
    /// `{{placeholder}}` on line `line` of `file`, which its template does not fill.
    UnknownPlaceholder {
        file: String,
        line: usize,
        placeholder: String,
        known: &'static [&'static str],
    },
    /// A recorded set that this version cannot render again.
    Recorded(String),
}

impl PromptError {
    /// A reading error of `coherent_core` (a file that cannot be read, or holds too much).
    fn from_core(e: coherent_core::Error) -> PromptError {
        match e {
            coherent_core::Error::Io { file, message } => PromptError::Io { file, message },
            other => PromptError::Io {
                file: String::new(),
                message: other.to_string(),
            },
        }
    }

    /// The file the error is about, when it is about one.
    pub fn file(&self) -> Option<&str> {
        match self {
            PromptError::Io { file, .. }
            | PromptError::UnknownFile { file }
            | PromptError::UnknownPlaceholder { file, .. } => Some(file),
            PromptError::Recorded(_) => None,
        }
    }
}

impl fmt::Display for PromptError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PromptError::Io { file, message } => write!(f, "{file}: {message}"),
            PromptError::UnknownFile { file } => {
                let names: Vec<&str> = Template::ALL.iter().map(|t| t.file_name()).collect();
                write!(
                    f,
                    "{file}: not a template of the prompt set; the templates: {}",
                    names.join(", ")
                )
            }
            PromptError::UnknownPlaceholder {
                file,
                line,
                placeholder,
                known,
            } => write!(
                f,
                "{file}:{line}: unknown placeholder {{{{{placeholder}}}}}; the placeholders \
                 of this template: {}",
                known.join(", ")
            ),
            PromptError::Recorded(why) => f.write_str(why),
        }
    }
}

impl std::error::Error for PromptError {}

/// The first placeholder of `text` its template does not fill, as an error naming
/// `file`; a placeholder is `{{name}}` on one line, as the methods fill it.
pub fn check(template: Template, text: &str, file: &str) -> Result<(), PromptError> {
    for (i, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(open) = rest.find("{{") {
            let after = &rest[open + 2..];
            let Some(close) = after.find("}}") else { break };
            let name = &after[..close];
            if name.contains("{{") {
                // `{{` before the placeholder: literal braces, as `fill` leaves them.
                rest = after;
                continue;
            }
            if !template.placeholders().contains(&name) {
                return Err(PromptError::UnknownPlaceholder {
                    file: file.to_owned(),
                    line: i + 1,
                    placeholder: name.to_owned(),
                    known: template.placeholders(),
                });
            }
            rest = &after[close + 2..];
        }
    }
    Ok(())
}

/// The templates the methods render, checked. Cheap to clone (shared).
#[derive(Clone, PartialEq, Eq)]
pub struct Prompts(Arc<Set>);

#[derive(PartialEq, Eq)]
struct Set {
    /// The templates that replace built-in ones, with their text.
    replaced: BTreeMap<Template, String>,
    /// [`Prompts::hash`] of each execution: sequential, parallel.
    hashes: [String; 2],
}

impl Default for Prompts {
    fn default() -> Prompts {
        Prompts::builtin()
    }
}

impl fmt::Debug for Prompts {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Prompts")
            .field("hashes", &self.0.hashes)
            .field("replaced", &self.replaced_names())
            .finish()
    }
}

impl Prompts {
    /// The compiled-in templates.
    pub fn builtin() -> Prompts {
        Prompts::with(BTreeMap::new())
    }

    /// The compiled-in templates in the paper's layout ([`Template::paper_layout`]), as a
    /// set that replaces the built-in templates whose layout changed.
    pub fn paper_layout() -> Prompts {
        Prompts::with(
            Template::ALL
                .into_iter()
                .filter(|t| t.paper_layout() != t.builtin())
                .map(|t| (t, t.paper_layout().to_owned()))
                .collect(),
        )
    }

    fn with(replaced: BTreeMap<Template, String>) -> Prompts {
        let hashes = Execution::ALL.map(|execution| {
            digest::fnv128(
                Template::ALL
                    .into_iter()
                    .filter(|t| t.used_in(execution))
                    .filter(|t| t.hashed_as_builtin() || replaced.contains_key(t))
                    .map(|t| {
                        let text = replaced.get(&t).map_or(t.builtin(), String::as_str);
                        (t.file_name(), text)
                    }),
            )
        });
        Prompts(Arc::new(Set { replaced, hashes }))
    }

    /// The built-in templates, with those of `files` (`(name, text)`, the name a
    /// template's file name) in their place; each is checked, and errors name the file
    /// as `origin/name`. A file with the built-in text replaces nothing; one of more than
    /// [`TEMPLATE_LIMIT`] is refused.
    pub fn from_texts(origin: &Path, files: Vec<(String, String)>) -> Result<Prompts, PromptError> {
        let mut replaced = BTreeMap::new();
        for (name, text) in files {
            let path = origin.join(&name);
            let file = path.display().to_string();
            let template = Template::from_file_name(&name)
                .ok_or(PromptError::UnknownFile { file: file.clone() })?;
            if text.len() as u64 > TEMPLATE_LIMIT.bytes {
                return Err(PromptError::from_core(TEMPLATE_LIMIT.exceeded(&path)));
            }
            check(template, &text, &file)?;
            if text != template.builtin() {
                replaced.insert(template, text);
            }
        }
        Ok(Prompts::with(replaced))
    }

    /// The built-in templates, with the files of folder `dir` that are named after one in
    /// their place. Other `.txt` files are refused (a misspelt name would silently leave
    /// the built-in template in use), and so is a `.txt` that is not a regular file (a
    /// folder, a pipe, a link to a device or to nothing) or holds more than
    /// [`TEMPLATE_LIMIT`]; anything else in the folder is ignored.
    pub fn read_dir(dir: &Path) -> Result<Prompts, PromptError> {
        let io = |file: &Path, e: std::io::Error| PromptError::Io {
            file: file.display().to_string(),
            message: e.to_string(),
        };
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| io(dir, e))?
            .map(|entry| entry.map(|e| e.path()).map_err(|e| io(dir, e)))
            .collect::<Result<_, _>>()?;
        paths.sort();
        let mut files = Vec::new();
        for path in paths {
            let is_txt = path.extension().is_some_and(|e| e == "txt");
            let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
                continue;
            };
            if !is_txt || name.starts_with('.') {
                continue;
            }
            let meta = std::fs::metadata(&path).map_err(|e| io(&path, e))?;
            if !meta.is_file() {
                return Err(PromptError::Io {
                    file: path.display().to_string(),
                    message: "not a regular file (a folder, a pipe, a device?): a template \
                              must be one"
                        .into(),
                });
            }
            let bytes = files::read(&path, &TEMPLATE_LIMIT).map_err(PromptError::from_core)?;
            let text = String::from_utf8(bytes).map_err(|e| PromptError::Io {
                file: path.display().to_string(),
                message: format!("not UTF-8: {e}"),
            })?;
            files.push((name.to_owned(), text));
        }
        Prompts::from_texts(dir, files)
    }

    /// The set a transcript recorded: the built-in templates with the recorded
    /// replacements, which must hash as recorded for `execution`. A transcript recorded
    /// while the paper's layout was built in hashes as the paper's layout with its
    /// replacements; any other hash means that the built-in templates changed since, and
    /// the recorded prompts cannot be rendered again.
    pub fn from_record(
        record: &PromptRecord,
        execution: Execution,
    ) -> Result<Prompts, PromptError> {
        let replaced = record
            .replaced
            .iter()
            .map(|(name, text)| (name.clone(), text.clone()));
        let prompts = Prompts::from_texts(Path::new("(recorded)"), replaced.clone().collect())?;
        if prompts.hash(execution) == record.hash {
            return Ok(prompts);
        }
        let mut files: BTreeMap<String, String> = Template::ALL
            .iter()
            .filter(|t| t.paper_layout() != t.builtin())
            .map(|t| (t.file_name().to_owned(), t.paper_layout().to_owned()))
            .collect();
        files.extend(replaced);
        let paper = Prompts::from_texts(Path::new("(recorded)"), files.into_iter().collect())?;
        if paper.hash(execution) == record.hash {
            return Ok(paper);
        }
        Err(PromptError::Recorded(format!(
            "the transcript was recorded with prompt set {}, but its replaced templates ({}) \
             with this version's built-in ones give {} (and with the paper's layout {}): the \
             built-in templates changed since, so its prompts cannot be rendered again",
            record.hash,
            if record.replaced.is_empty() {
                "none".to_owned()
            } else {
                record
                    .replaced
                    .keys()
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", ")
            },
            prompts.hash(execution),
            paper.hash(execution)
        )))
    }

    /// The text of `template` in this set.
    pub fn text(&self, template: Template) -> &str {
        self.0
            .replaced
            .get(&template)
            .map_or(template.builtin(), String::as_str)
    }

    /// 32 hex digits: FNV-1a (128 bits) of the file name and text of every template the
    /// methods of `execution` render, in [`Template::ALL`] order (llm-pddl's goal only when
    /// replaced).
    pub fn hash(&self, execution: Execution) -> &str {
        &self.0.hashes[execution as usize]
    }

    /// The file names of the templates that replace built-in ones.
    pub fn replaced_names(&self) -> Vec<&'static str> {
        self.0.replaced.keys().map(|t| t.file_name()).collect()
    }

    /// The templates that replace built-in ones, by file name, with their text.
    pub fn replaced_texts(&self) -> BTreeMap<String, String> {
        self.0
            .replaced
            .iter()
            .map(|(t, text)| (t.file_name().to_owned(), text.clone()))
            .collect()
    }

    /// The file names of the replacing templates that hold nothing but white space (a
    /// write cut short, say): worth a warning, since their prompts say nothing.
    pub fn blank_names(&self) -> Vec<&'static str> {
        self.0
            .replaced
            .iter()
            .filter(|(_, text)| text.trim().is_empty())
            .map(|(t, _)| t.file_name())
            .collect()
    }

    /// What the header of a transcript of `execution` records of the set.
    pub fn record(&self, execution: Execution) -> PromptRecord {
        PromptRecord {
            hash: self.hash(execution).to_owned(),
            replaced: self.replaced_texts(),
        }
    }
}

/// The prompt set as a transcript's header records it.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct PromptRecord {
    /// [`Prompts::hash`]: equal hashes, equal templates.
    pub hash: String,
    /// The files that replaced built-in templates, by name, with their text.
    pub replaced: BTreeMap<String, String>,
}

/// Writes every template of `set` into `dir` (made when missing), one file each; an
/// existing file is an error unless `overwrite`, and a symbolic link is one always (an
/// export writes regular files, never through a link to elsewhere). Each file is written
/// to a temporary file that is renamed once complete, so that a full disk leaves no
/// empty template behind. Returns the files written.
pub fn export(dir: &Path, overwrite: bool, set: &Prompts) -> Result<Vec<PathBuf>, PromptError> {
    let io = |file: &Path, e: std::io::Error| PromptError::Io {
        file: file.display().to_string(),
        message: e.to_string(),
    };
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let paths: Vec<PathBuf> = Template::ALL
        .iter()
        .map(|t| dir.join(t.file_name()))
        .collect();
    for path in &paths {
        // Not `exists()`, which follows a link and calls a dangling one absent.
        let Ok(meta) = std::fs::symlink_metadata(path) else {
            continue;
        };
        let refused = if meta.file_type().is_symlink() {
            "is a symbolic link: export writes regular files only; remove it first"
        } else if !overwrite {
            "exists already (pass --force to overwrite)"
        } else if !meta.is_file() {
            "exists and is not a regular file"
        } else {
            continue;
        };
        return Err(PromptError::Io {
            file: path.display().to_string(),
            message: refused.into(),
        });
    }
    for (t, path) in Template::ALL.iter().zip(&paths) {
        write_whole(path, set.text(*t)).map_err(|e| io(path, e))?;
    }
    Ok(paths)
}

/// Writes `text` to `path` through a temporary file beside it, synced and then renamed,
/// so that `path` holds either its old content or all of `text`.
fn write_whole(path: &Path, text: &str) -> std::io::Result<()> {
    use std::io::Write;
    let name = path
        .file_name()
        .map_or_else(Default::default, |n| n.to_string_lossy());
    let temporary = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let written = (|| {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temporary)?;
        file.write_all(text.as_bytes())?;
        file.sync_all()?;
        std::fs::rename(&temporary, path)
    })();
    if written.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    written
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_template_uses_exactly_its_placeholders() {
        let uses = |text: &str, p: &str| text.contains(&format!("{{{{{p}}}}}"));
        for t in Template::ALL {
            for text in [t.builtin(), t.paper_layout()] {
                check(t, text, t.file_name()).expect("the built-in templates check");
            }
            for p in t.placeholders() {
                // The observation in one block in the paper's layout, in two in ours.
                let (ours, paper) = match *p {
                    "observation" => (false, true),
                    "scene" | "state" => (true, false),
                    _ => (true, true),
                };
                assert_eq!(
                    uses(t.builtin(), p),
                    ours,
                    "{} and {{{{{p}}}}}",
                    t.file_name()
                );
                // llm-pddl's goal has one text in both layouts.
                if t.paper_layout() != t.builtin() {
                    assert_eq!(
                        uses(t.paper_layout(), p),
                        paper,
                        "{} (paper layout) and {{{{{p}}}}}",
                        t.file_name()
                    );
                }
            }
        }
    }

    #[test]
    fn the_paper_layout_is_a_set_of_its_own_that_records_and_replays() {
        let paper = Prompts::paper_layout();
        // Recorded before parallel episodes existed: a sequential episode's set.
        let seq = Execution::Sequential;
        assert_ne!(paper.hash(seq), Prompts::builtin().hash(seq));
        for t in Template::ALL {
            assert_eq!(paper.text(t), t.paper_layout());
        }
        assert_eq!(
            Prompts::from_record(&paper.record(seq), seq).expect("rebuilt"),
            paper
        );
        // A transcript recorded while the paper's layout was built in records no
        // replacement and that layout's hash, with or without files of its own.
        let then = PromptRecord {
            hash: paper.hash(seq).to_owned(),
            replaced: BTreeMap::new(),
        };
        assert_eq!(Prompts::from_record(&then, seq).expect("rebuilt"), paper);
        let edited = "Do {{instruction}} with {{observation}}.".to_owned();
        let mut files: Vec<(String, String)> = Template::ALL
            .iter()
            .map(|t| (t.file_name().to_owned(), t.paper_layout().to_owned()))
            .collect();
        files[1].1.clone_from(&edited);
        let old_set = Prompts::from_texts(Path::new("d"), files).expect("a set");
        let then = PromptRecord {
            hash: old_set.hash(seq).to_owned(),
            replaced: BTreeMap::from([("assigner_user.txt".to_owned(), edited)]),
        };
        assert_eq!(Prompts::from_record(&then, seq).expect("rebuilt"), old_set);
    }

    #[test]
    fn unknown_placeholders_are_named_with_file_and_line() {
        let text = "Task: {{instruction}}\n\nSee {{robots}} and {{no_such_thing}}.\n";
        let e = check(Template::AssignerUser, text, "d/assigner_user.txt").expect_err("refused");
        assert_eq!(
            e.to_string(),
            "d/assigner_user.txt:3: unknown placeholder {{no_such_thing}}; the placeholders of \
             this template: instruction, robots, observation, scene, state, history"
        );
        // A placeholder of another template is unknown here too.
        assert!(check(Template::AssignerSystem, "{{history}}", "f").is_err());
        // Braces that are no placeholder pass: a JSON example, an unclosed pair.
        check(Template::AssignerSystem, "{\"a\": 1} {{ and {{team}}", "f").expect("fine");
    }

    #[test]
    fn a_set_replaces_only_the_templates_given() {
        let set = Prompts::from_texts(
            Path::new("d"),
            vec![("assigner_user.txt".into(), "Do {{instruction}}.".into())],
        )
        .expect("a set");
        assert_eq!(set.text(Template::AssignerUser), "Do {{instruction}}.");
        assert_eq!(
            set.text(Template::AssignerSystem),
            Template::AssignerSystem.builtin()
        );
        assert_eq!(set.replaced_names(), ["assigner_user.txt"]);
        assert_ne!(
            set.hash(Execution::Sequential),
            Prompts::builtin().hash(Execution::Sequential)
        );
        assert_eq!(set.hash(Execution::Sequential).len(), 32);
        // The same texts, the same hash; a file that repeats the built-in text replaces
        // nothing.
        let same = Prompts::from_texts(
            Path::new("elsewhere"),
            vec![("assigner_user.txt".into(), "Do {{instruction}}.".into())],
        )
        .expect("a set");
        assert_eq!(same, set);
        let copy = Prompts::from_texts(
            Path::new("d"),
            vec![("central.txt".into(), Template::Central.builtin().to_owned())],
        )
        .expect("a set");
        assert_eq!(
            copy.hash(Execution::Sequential),
            Prompts::builtin().hash(Execution::Sequential)
        );
        assert!(copy.replaced_names().is_empty());
        let unknown =
            Prompts::from_texts(Path::new("d"), vec![("asigner.txt".into(), String::new())]);
        assert!(matches!(unknown, Err(PromptError::UnknownFile { .. })));
    }

    #[test]
    fn records_round_trip_and_refuse_a_changed_set() {
        let set = Prompts::from_texts(
            Path::new("d"),
            vec![("executor_user.txt".into(), "{{subtask}} {{actions}}".into())],
        )
        .expect("a set");
        let record = set.record(Execution::Sequential);
        assert_eq!(
            Prompts::from_record(&record, Execution::Sequential).expect("rebuilt"),
            set
        );
        let changed = PromptRecord {
            hash: "0".repeat(32),
            ..record
        };
        let e = Prompts::from_record(&changed, Execution::Sequential).expect_err("refused");
        assert!(e.to_string().contains("executor_user.txt"), "{e}");
    }

    #[test]
    fn a_parallel_template_changes_the_parallel_hash_alone() {
        let set = Prompts::from_texts(
            Path::new("d"),
            vec![("central_parallel.txt".into(), "{{actions}}".into())],
        )
        .expect("a set");
        let builtin = Prompts::builtin();
        assert_eq!(
            set.hash(Execution::Sequential),
            builtin.hash(Execution::Sequential)
        );
        assert_ne!(
            set.hash(Execution::Parallel),
            builtin.hash(Execution::Parallel)
        );
        // The hash of the eight templates a sequential episode renders, as recorded before
        // parallel templates existed: old transcripts replay.
        assert_eq!(
            builtin.hash(Execution::Sequential),
            digest::fnv128(
                Template::ALL[..8]
                    .iter()
                    .map(|t| (t.file_name(), t.builtin()))
            )
        );
    }

    #[test]
    fn split_at_the_user_mark() {
        assert_eq!(split("a\n@@user@@\nb"), ("a\n", "\nb"));
        assert_eq!(split("only user"), ("", "only user"));
    }

    #[test]
    fn export_writes_every_template_once() {
        let dir = std::env::temp_dir().join(format!("coherent-export-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let written = export(&dir, false, &Prompts::builtin()).expect("exported");
        assert_eq!(written.len(), Template::ALL.len());
        assert_eq!(
            Prompts::read_dir(&dir)
                .expect("reads back")
                .hash(Execution::Parallel),
            Prompts::builtin().hash(Execution::Parallel)
        );
        assert!(
            export(&dir, false, &Prompts::builtin()).is_err(),
            "no silent overwrite"
        );
        // A folder in the paper's layout (as `prompts export` wrote it before) reads back
        // as that layout.
        export(&dir, true, &Prompts::paper_layout()).expect("overwritten on request");
        assert_eq!(
            Prompts::read_dir(&dir).expect("reads back"),
            Prompts::paper_layout()
        );
        std::fs::remove_dir_all(&dir).expect("cleaned up");
    }
}
