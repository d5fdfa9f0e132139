//! Reading JSON input with errors that name the file, the place and the value: whole
//! documents ([`parse`]: UTF-8 text, JSON syntax, no key twice in one object), the typed
//! fields of a parsed document (`from_value`), and short descriptions of values for
//! messages (`describe`).
//!
//! JSON leaves repeated keys to the reader and serde_json keeps the last one, so that
//! `{"task_id": 0, "task_id": 7}` would silently be task 7. [`value`] deserializes a
//! document as serde_json's own [`Value`] does, in the same single pass, and refuses an
//! object that names a key twice, with the JSON path of the repeat.

use std::fmt;

use serde::de::{self, DeserializeOwned, DeserializeSeed, Deserializer, MapAccess, SeqAccess};
use serde_json::{Map, Number, Value};

use crate::error::{Error, JsonPath, Result, Site, clip, quoted};

/// The JSON document `bytes`, read from `file`. Text that is not UTF-8 is refused with
/// the byte offset, line and column of the first bad byte; bad syntax with its line and
/// column; a key repeated in one object with the JSON path of the repeat.
pub fn parse(file: &str, bytes: &[u8]) -> Result<Value> {
    let root = Site::new(file, JsonPath::root());
    let text = std::str::from_utf8(bytes).map_err(|e| root.error(not_utf8(bytes, &e)))?;
    let mut repeated = None;
    let mut de = serde_json::Deserializer::from_str(text);
    let parsed = ValueSeed {
        at: &At::Root,
        repeated: &mut repeated,
    }
    .deserialize(&mut de)
    .and_then(|v| de.end().map(|()| v));
    parsed.map_err(|e| match repeated {
        Some(Repeated { path, key }) => Error::Malformed {
            file: file.to_owned(),
            path,
            message: format!(
                "duplicate key {}: the object already has one (line {} column {})",
                quoted(&key),
                e.line(),
                e.column()
            ),
        },
        None => root.error(format!(
            "invalid JSON at line {} column {}: {e}",
            e.line(),
            e.column()
        )),
    })
}

/// One JSON value from `de`, as `serde_json::Value`'s own `Deserialize` reads it, except
/// that an object naming a key twice is an error (`duplicate key "k" at $.a.k`).
pub fn value<'de, D: Deserializer<'de>>(de: D) -> Result<Value, D::Error> {
    let mut repeated = None;
    ValueSeed {
        at: &At::Root,
        repeated: &mut repeated,
    }
    .deserialize(de)
}

/// Where a repeated key was found.
struct Repeated {
    /// The path of the second occurrence.
    path: JsonPath,
    key: String,
}

/// Where the value being read lies: a chain of keys and indices up to the root, kept on
/// the stack while the document is walked, turned into a [`JsonPath`] only for an error.
enum At<'a> {
    Root,
    Key(&'a At<'a>, &'a str),
    Index(&'a At<'a>, usize),
}

impl At<'_> {
    fn path(&self) -> JsonPath {
        match self {
            At::Root => JsonPath::root(),
            At::Key(up, key) => up.path().key(key),
            At::Index(up, i) => up.path().index(*i),
        }
    }
}

/// Reads the value at `at`; records the first repeated key in `repeated`.
struct ValueSeed<'a, 'r> {
    at: &'a At<'a>,
    repeated: &'r mut Option<Repeated>,
}

impl<'de> DeserializeSeed<'de> for ValueSeed<'_, '_> {
    type Value = Value;

    fn deserialize<D: Deserializer<'de>>(self, de: D) -> Result<Value, D::Error> {
        de.deserialize_any(self)
    }
}

impl<'de> de::Visitor<'de> for ValueSeed<'_, '_> {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("any JSON value")
    }

    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }

    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::Number(v.into()))
    }

    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::Number(v.into()))
    }

    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        Ok(Number::from_f64(v).map_or(Value::Null, Value::Number))
    }

    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.to_owned()))
    }

    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }

    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }

    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }

    fn visit_some<D: Deserializer<'de>>(self, de: D) -> Result<Value, D::Error> {
        self.deserialize(de)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut items = Vec::with_capacity(seq.size_hint().unwrap_or(0));
        loop {
            let at = At::Index(self.at, items.len());
            let seed = ValueSeed {
                at: &at,
                repeated: &mut *self.repeated,
            };
            match seq.next_element_seed(seed)? {
                Some(item) => items.push(item),
                None => return Ok(Value::Array(items)),
            }
        }
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut members = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            let at = At::Key(self.at, &key);
            if members.contains_key(&key) {
                let path = at.path();
                let message = format!("duplicate key {} at {path}", quoted(&key));
                *self.repeated = Some(Repeated {
                    path,
                    key: key.clone(),
                });
                return Err(de::Error::custom(message));
            }
            let seed = ValueSeed {
                at: &at,
                repeated: &mut *self.repeated,
            };
            let member = map.next_value_seed(seed)?;
            members.insert(key, member);
        }
        Ok(Value::Object(members))
    }
}

/// Where the first byte that is not UTF-8 lies, and what is wrong with it.
fn not_utf8(bytes: &[u8], e: &std::str::Utf8Error) -> String {
    let at = e.valid_up_to();
    // Everything before `at` is valid UTF-8.
    let before = String::from_utf8_lossy(&bytes[..at]);
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    let what = match e.error_len() {
        Some(_) => format!("byte 0x{:02x} does not start a UTF-8 character", bytes[at]),
        None => "the text ends inside a UTF-8 character".to_owned(),
    };
    format!("not UTF-8 text: at byte offset {at} (line {line} column {column}) {what}")
}

/// Deserializes `value`, reporting the exact path of a field that does not fit.
pub(crate) fn from_value<T: DeserializeOwned>(value: &Value, site: &Site<'_>) -> Result<T> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().iter().fold(site.path.clone(), |p, seg| {
            use serde_path_to_error::Segment;
            match seg {
                Segment::Seq { index } => p.index(*index),
                Segment::Map { key } => p.key(key),
                Segment::Enum { variant } => p.key(variant),
                Segment::Unknown => p.key("?"),
            }
        });
        let found = lookup(value, e.path()).map(|v| format!(" (found {})", describe(v)));
        Error::Malformed {
            file: site.file.to_owned(),
            path,
            message: format!(
                "{}{}",
                clip_quoted(&e.inner().to_string()),
                found.unwrap_or_default()
            ),
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

/// A short description of a JSON value for error messages: its text when short, a long
/// string cut by [`quoted`], a long list or object by its size.
pub(crate) fn describe(value: &Value) -> String {
    let text = value.to_string();
    if text.len() <= 60 {
        return text;
    }
    match value {
        Value::Array(a) => format!("a list of {} items", a.len()),
        Value::Object(o) => format!("an object with {} keys", o.len()),
        Value::String(s) => quoted(s),
        _ => clip(&text),
    }
}

/// serde's message with every quoted (`"..."`) or backquoted (`` `...` ``) part that is
/// longer than [`crate::error::ECHO_CHARS`] cut by [`clip`]: serde repeats a wrong
/// string or an unknown field name whole.
fn clip_quoted(message: &str) -> String {
    let mut out = String::with_capacity(message.len().min(1024));
    let mut rest = message;
    while let Some(open) = rest.find(['"', '`']) {
        let quote = rest.as_bytes()[open];
        out.push_str(&rest[..=open]);
        let body = &rest[open + 1..];
        // The closing quote: the next one not escaped by a backslash (serde writes
        // strings with Rust's escapes, field names as they are).
        let mut escaped = false;
        let close = body.char_indices().find_map(|(i, c)| {
            let end = !escaped && c == quote as char;
            escaped = !escaped && quote == b'"' && c == '\\';
            end.then_some(i)
        });
        let Some(close) = close else {
            out.push_str(body);
            return out;
        };
        out.push_str(&clip(&body[..close]));
        out.push(quote as char);
        rest = &body[close + 1..];
    }
    out.push_str(rest);
    out
}
