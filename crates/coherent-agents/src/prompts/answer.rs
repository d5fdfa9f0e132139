//! Reading the models' answers: the JSON object the prompt asks for, wherever it sits in
//! the text (code fences, chatter around it), and its fields, leniently typed; the team
//! action line an answer names ([`read_line`]) and, for LLM-MCTS, the line it comes
//! nearest to ([`match_line`]). What each method makes of them is the method's
//! ([`crate::methods::assigner`], [`crate::methods::executor`],
//! [`crate::methods::central`]); anything unreadable is an error with the reason, never
//! a panic.

use coherent_core::text::cut;
use serde_json::{Map, Value};

/// The most bytes a field read from an answer keeps (a subtask, an action, a note, a
/// reasoning). What a round stores and what the history feeds back into the next prompt
/// are built from these fields, so a runaway answer cannot grow them.
pub(crate) const MAX_FIELD_BYTES: usize = 2_000;

/// `text` trimmed and cut to [`MAX_FIELD_BYTES`].
pub(crate) fn field_text(text: &str) -> String {
    cut(text.trim(), MAX_FIELD_BYTES).into_owned()
}

/// The first JSON object in `text`.
pub(crate) fn json_object(text: &str) -> Option<Map<String, Value>> {
    text.match_indices('{').take(16).find_map(|(i, _)| {
        let mut values = serde_json::Deserializer::from_str(&text[i..]).into_iter::<Value>();
        match values.next() {
            Some(Ok(Value::Object(map))) => Some(map),
            _ => None,
        }
    })
}

/// A string field, trimmed and cut to [`MAX_FIELD_BYTES`]; a number is taken as written.
pub(crate) fn string_field(map: &Map<String, Value>, key: &str) -> Option<String> {
    match map.get(key)? {
        Value::String(s) => Some(field_text(s)),
        Value::Number(n) => Some(field_text(&n.to_string())),
        _ => None,
    }
}

/// A boolean field; `"true"`, `"yes"`, `"false"` and `"no"` count too.
pub(crate) fn bool_field(map: &Map<String, Value>, key: &str) -> Option<bool> {
    match map.get(key)? {
        Value::Bool(b) => Some(*b),
        Value::String(s) => match s.trim().to_ascii_lowercase().as_str() {
            "true" | "yes" => Some(true),
            "false" | "no" => Some(false),
            _ => None,
        },
        _ => None,
    }
}

/// Lower case with single spaces, for matching an action however it was spaced.
pub(crate) fn normal(s: &str) -> String {
    s.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_ascii_lowercase()
}

/// Words and numbers: `[grab] <apple>(3)` gives `grab`, `apple`, `3`.
fn tokens(s: &str) -> Vec<String> {
    let mut out: Vec<String> = s
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|t| !t.is_empty())
        .map(str::to_ascii_lowercase)
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// |a ∩ b| / |a ∪ b| of two sorted token sets.
fn overlap(a: &[String], b: &[String]) -> f64 {
    let common = a.iter().filter(|t| b.binary_search(t).is_ok()).count();
    let union = a.len() + b.len() - common;
    if union == 0 {
        0.0
    } else {
        common as f64 / union as f64
    }
}

/// The least token overlap at which an answer counts as meaning an action.
const MIN_OVERLAP: f64 = 0.5;

/// The team action line of `lines` that `answer` means, or `None`. First an exact match
/// (ignoring case and spacing); then, when the answer names a robot by its label (the
/// first label in the text), the action of that robot whose words and ids overlap most
/// with the rest of the answer, at least half of them; when it names no robot, the best
/// such action of any robot (ties go to the earlier line).
pub fn match_line(lines: &[String], answer: &str) -> Option<usize> {
    let wanted = normal(answer);
    if wanted.is_empty() {
        return None;
    }
    if let Some(i) = lines.iter().position(|l| normal(l) == wanted) {
        return Some(i);
    }
    let split: Vec<(String, String)> = lines
        .iter()
        .map(|l| match l.split_once(": ") {
            Some((robot, action)) => (normal(robot), action.to_owned()),
            None => (String::new(), l.clone()),
        })
        .collect();
    let named = split
        .iter()
        .filter(|(robot, _)| !robot.is_empty())
        .filter_map(|(robot, _)| wanted.find(robot.as_str()).map(|at| (at, robot)))
        .min();
    let (robot, rest) = match named {
        Some((at, robot)) => {
            let rest = wanted[at + robot.len()..].trim_start_matches([':', '-', ',', ' ']);
            (Some(robot.clone()), rest.to_owned())
        }
        None => (None, wanted.clone()),
    };
    let want = tokens(&rest);
    let mut best: Option<(usize, f64)> = None;
    for (i, (r, action)) in split.iter().enumerate() {
        if robot.as_ref().is_some_and(|named| named != r) {
            continue;
        }
        let score = overlap(&want, &tokens(action));
        if score >= MIN_OVERLAP && best.is_none_or(|(_, s)| score > s) {
            best = Some((i, score));
        }
    }
    best.map(|(i, _)| i)
}

/// The action an answer names: the `action` field of its first JSON object (with its
/// `robot` field in front when the action does not name one; a `subtask` field stands in
/// for a missing `action`), else the whole text.
pub fn read_line(text: &str) -> String {
    let object = json_object(text);
    let Some(map) = object else {
        return field_text(text);
    };
    let field = |k: &str| map.get(k).and_then(Value::as_str).map(field_text);
    let action = field("action")
        .or_else(|| field("subtask"))
        .unwrap_or_default();
    match field("robot") {
        Some(robot) if !robot.is_empty() && !action.contains(&robot) => {
            format!("{robot}: {action}")
        }
        _ => action,
    }
}
