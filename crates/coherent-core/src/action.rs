//! The action grammar: `[verb] <name>(id)`, `[putinto] <name>(id) into <name>(id)` and
//! `[puton] <name>(id) on <name>(id)`. Parsing never panics; anything else is rejected
//! with the reason.

use std::fmt;

use crate::error::{Error, Result};
use crate::graph::{Idx, NodeId, RobotKind};
use crate::task::Task;

/// The verbs of the three robot types.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Verb {
    LandOn,
    MoveTowards,
    TakeoffFrom,
    Open,
    Close,
    Grab,
    PutInto,
    PutOn,
}

impl Verb {
    pub const ALL: [Verb; 8] = [
        Verb::LandOn,
        Verb::MoveTowards,
        Verb::TakeoffFrom,
        Verb::Open,
        Verb::Close,
        Verb::Grab,
        Verb::PutInto,
        Verb::PutOn,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Verb::LandOn => "land_on",
            Verb::MoveTowards => "movetowards",
            Verb::TakeoffFrom => "takeoff_from",
            Verb::Open => "open",
            Verb::Close => "close",
            Verb::Grab => "grab",
            Verb::PutInto => "putinto",
            Verb::PutOn => "puton",
        }
    }

    pub fn from_name(name: &str) -> Option<Verb> {
        Verb::ALL.into_iter().find(|v| v.name() == name)
    }

    /// The word between object and target (`into`, `on`) for two-argument verbs.
    pub fn preposition(self) -> Option<&'static str> {
        match self {
            Verb::PutInto => Some("into"),
            Verb::PutOn => Some("on"),
            _ => None,
        }
    }

    /// Verbs a robot type has (docs/semantics.md, "The robots").
    pub fn of(kind: RobotKind) -> &'static [Verb] {
        match kind {
            RobotKind::Quadrotor => &[Verb::LandOn, Verb::MoveTowards, Verb::TakeoffFrom],
            RobotKind::RobotDog => &[
                Verb::Open,
                Verb::Close,
                Verb::Grab,
                Verb::PutInto,
                Verb::PutOn,
                Verb::MoveTowards,
            ],
            RobotKind::RobotArm => &[
                Verb::Open,
                Verb::Close,
                Verb::Grab,
                Verb::PutInto,
                Verb::PutOn,
            ],
        }
    }
}

/// The most actions a robot of type `kind` is ever offered at once in `task`: each of
/// its verbs once per node. An action list has no duplicates, and an action differs from
/// another of its verb by its object or, for a put, by where it puts the one thing the
/// robot holds. A fixed-size action space (`coherent.marl`) is this long.
pub fn most_actions(task: &Task, kind: RobotKind) -> usize {
    Verb::of(kind).len() * task.nodes.len()
}

impl fmt::Display for Verb {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An action on resolved nodes: `object` is what the verb acts on, `target` the
/// container or surface of `putinto` / `puton`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Action {
    pub verb: Verb,
    pub object: Idx,
    pub target: Option<Idx>,
}

impl Action {
    pub fn new(verb: Verb, object: Idx) -> Action {
        Action {
            verb,
            object,
            target: None,
        }
    }
    pub fn with_target(verb: Verb, object: Idx, target: Idx) -> Action {
        Action {
            verb,
            object,
            target: Some(target),
        }
    }

    /// The action string, e.g. `[puton] <apple>(3) on <table>(5)`.
    pub fn render(&self, task: &Task) -> String {
        let mut s = format!("[{}] {}", self.verb, task.node(self.object).label());
        if let (Some(t), Some(prep)) = (self.target, self.verb.preposition()) {
            s.push_str(&format!(" {prep} {}", task.node(t).label()));
        }
        s
    }
}

/// `<name>(id)` as written in an action string.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mention {
    pub name: String,
    pub id: NodeId,
}

impl fmt::Display for Mention {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "<{}>({})", self.name, self.id)
    }
}

/// An action string parsed but not yet resolved against a task.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParsedAction {
    pub verb: Verb,
    pub object: Mention,
    pub target: Option<Mention>,
}

impl fmt::Display for ParsedAction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "[{}] {}", self.verb, self.object)?;
        if let (Some(t), Some(prep)) = (&self.target, self.verb.preposition()) {
            write!(f, " {prep} {t}")?;
        }
        Ok(())
    }
}

/// Parses an action string. Surrounding white space is ignored; nothing else is.
pub fn parse(text: &str) -> Result<ParsedAction> {
    parse_inner(text.trim()).map_err(|reason| Error::BadAction {
        action: text.to_owned(),
        reason,
    })
}

fn parse_inner(s: &str) -> std::result::Result<ParsedAction, String> {
    if s.is_empty() {
        return Err("empty action".to_owned());
    }
    let rest = s
        .strip_prefix('[')
        .ok_or("an action starts with [verb], e.g. [grab] <apple>(3)")?;
    let close = rest.find(']').ok_or("missing ']' after the verb")?;
    let word = &rest[..close];
    let verb = Verb::from_name(word).ok_or_else(|| {
        format!(
            "unknown verb {word:?} (verbs: {})",
            Verb::ALL.map(Verb::name).join(", ")
        )
    })?;
    let rest = rest[close + 1..]
        .strip_prefix(' ')
        .ok_or_else(|| format!("expected a space and <name>(id) after [{verb}]"))?;
    let (object, rest) = mention(rest).map_err(|why| format!("object of [{verb}]: {why}"))?;
    let target = match verb.preposition() {
        None if rest.is_empty() => None,
        None => return Err(format!("unexpected text after {object}: {rest:?}")),
        Some(prep) => {
            let after = rest
                .strip_prefix(' ')
                .and_then(|r| r.strip_prefix(prep))
                .and_then(|r| r.strip_prefix(' '))
                .ok_or_else(|| format!("[{verb}] needs \" {prep} <name>(id)\" after {object}"))?;
            let (target, rest) =
                mention(after).map_err(|why| format!("target of [{verb}]: {why}"))?;
            if !rest.is_empty() {
                return Err(format!("unexpected text after {target}: {rest:?}"));
            }
            Some(target)
        }
    };
    Ok(ParsedAction {
        verb,
        object,
        target,
    })
}

/// Every `<name>(id)` in free text (a subtask, a note), in the order written, each once.
pub fn mentions(text: &str) -> Vec<Mention> {
    let mut found: Vec<Mention> = Vec::new();
    let mut rest = text;
    while let Some(open) = rest.find('<') {
        rest = &rest[open..];
        match mention(rest) {
            Ok((m, after)) => {
                if !found.contains(&m) {
                    found.push(m);
                }
                rest = after;
            }
            Err(_) => rest = &rest[1..],
        }
    }
    found
}

/// `<name>(id)` at the start of `s`, and the rest of `s`.
fn mention(s: &str) -> std::result::Result<(Mention, &str), String> {
    let s = s.strip_prefix('<').ok_or("expected <name>(id)")?;
    let close = s.find('>').ok_or("missing '>' after the name")?;
    let name = &s[..close];
    if name.is_empty() {
        return Err("empty name in <>".to_owned());
    }
    let rest = s[close + 1..]
        .strip_prefix('(')
        .ok_or("expected (id) after the name")?;
    let end = rest.find(')').ok_or("missing ')' after the id")?;
    let digits = &rest[..end];
    let id = digits
        .parse::<i64>()
        .map_err(|_| format!("id {digits:?} is not an integer"))?;
    Ok((
        Mention {
            name: name.to_owned(),
            id: NodeId(id),
        },
        &rest[end + 1..],
    ))
}
