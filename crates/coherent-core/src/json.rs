//! Reading JSON input with errors that name the file, the JSON path and the value: the
//! typed fields of a parsed document, and short descriptions of values for messages.

use serde::de::DeserializeOwned;
use serde_json::Value;

use crate::error::{Error, Result, Site};

/// Deserializes `value`, reporting the exact path of a field that does not fit.
pub(crate) fn from_value<T: DeserializeOwned>(value: &Value, site: &Site<'_>) -> Result<T> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = site.path.join(&e.path().to_string());
        let found = lookup(value, e.path()).map(|v| format!(" (found {})", describe(v)));
        Error::Malformed {
            file: site.file.to_owned(),
            path,
            message: format!("{}{}", e.inner(), found.unwrap_or_default()),
        }
    })
}

fn lookup<'v>(value: &'v Value, path: &serde_path_to_error::Path) -> Option<&'v Value> {
    use serde_path_to_error::Segment;
    path.iter().try_fold(value, |v, seg| match seg {
        Segment::Seq { index } => v.get(index),
        Segment::Map { key } => v.get(key),
        Segment::Enum { .. } | Segment::Unknown => Some(v),
    })
}

/// A short description of a JSON value for error messages: its text when short.
pub(crate) fn describe(value: &Value) -> String {
    let text = value.to_string();
    if text.len() <= 60 {
        return text;
    }
    match value {
        Value::Array(a) => format!("a list of {} items", a.len()),
        Value::Object(o) => format!("an object with {} keys", o.len()),
        _ => format!("{}...", text.chars().take(57).collect::<String>()),
    }
}
