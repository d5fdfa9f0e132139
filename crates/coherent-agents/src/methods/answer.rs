//! Reading the models' answers: the JSON object the prompt asks for, wherever it sits in
//! the text (code fences, chatter around it), and its fields, leniently typed. What each
//! method makes of them is the method's ([`crate::methods::assigner`],
//! [`crate::methods::executor`], [`crate::methods::joint`]); anything unreadable is an
//! error with the reason, never a panic.

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
