//! Seeded mutations of JSON task files for the fuzz tests (`fuzz_inputs.rs` here, and
//! the command line's `tests/cli_fuzz.rs`, which includes this file): bytes flipped,
//! inserted, deleted or cut off; numbers made huge, negative or fractional; values of the
//! wrong type; members dropped; keys repeated; strings made long; ids pointed at other
//! nodes. Each mutation says what it did, so that a failure can be replayed by hand.
//! Files that are not one JSON document get mutations of their own: plain text
//! ([`mutate_text`], prompt templates) and JSON lines ([`mutate_lines`], transcripts
//! and results files).

// Each test file that includes this module uses the mutations of its inputs only.
#![allow(dead_code)]

use serde_json::Value;

/// A small seeded generator (xorshift64*): the same seed, the same mutations.
#[derive(Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1)
    }

    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// A number in `0..n` (`n` > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Numbers that break assumptions: past 16, 32 and 64 bits, negative, fractional, huge.
const NUMBERS: [&str; 10] = [
    "2147483648",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "-1",
    "-9223372036854775808",
    "1.5",
    "1e300",
    "65536",
    "0",
];

/// `text` (a JSON document) with one mutation, and what the mutation was.
pub fn mutate(rng: &mut Rng, text: &str) -> (Vec<u8>, String) {
    match rng.below(10) {
        0 => flip_byte(rng, text),
        1 => insert_byte(rng, text),
        2 => delete_bytes(rng, text),
        3 => cut_off(rng, text),
        4 => repeat_key(rng, text),
        kind => {
            let mut value: Value = serde_json::from_str(text).expect("the seed file is JSON");
            let what = match kind {
                5 => odd_number(rng, &mut value),
                6 => wrong_type(rng, &mut value),
                7 => drop_member(rng, &mut value),
                8 => long_string(rng, &mut value),
                _ => other_id(rng, &mut value),
            };
            let text = serde_json::to_string_pretty(&value).expect("JSON serializes");
            (text.into_bytes(), what)
        }
    }
}

/// `text` (plain text, a prompt template) with one mutation: a byte flipped, inserted
/// or deleted, the text cut off, a placeholder of no template added, or a line repeated
/// into a long text.
pub fn mutate_text(rng: &mut Rng, text: &str) -> (Vec<u8>, String) {
    match rng.below(6) {
        0 => flip_byte(rng, text),
        1 => insert_byte(rng, text),
        2 => delete_bytes(rng, text),
        3 => cut_off(rng, text),
        4 => {
            let at = rng.below(text.len() + 1);
            let at = (0..=at)
                .rev()
                .find(|&i| text.is_char_boundary(i))
                .unwrap_or(0);
            let mut out = text.to_owned();
            out.insert_str(at, "{{no_such_placeholder}}");
            (out.into_bytes(), format!("an unknown placeholder at {at}"))
        }
        _ => {
            // Up to about 4 MiB: past every limit on a template, well within a transcript's.
            let times = 1 + rng.below((4 << 20) / text.len().max(1));
            (
                text.repeat(times).into_bytes(),
                format!("the text {times} times"),
            )
        }
    }
}

/// `text` (JSON lines) with one of its lines mutated as a JSON document ([`mutate`]),
/// or, one time in four, the whole file's bytes mutated as text ([`mutate_text`]).
pub fn mutate_lines(rng: &mut Rng, text: &str) -> (Vec<u8>, String) {
    let lines: Vec<&str> = text.lines().collect();
    if lines.is_empty() || rng.below(4) == 0 {
        let (bytes, what) = mutate_text(rng, text);
        return (bytes, format!("the whole file: {what}"));
    }
    let n = rng.below(lines.len());
    let (line, what) = mutate(rng, lines[n]);
    // A pretty-printed mutation goes back on one line (JSON allows a space there).
    let line = match String::from_utf8(line) {
        Ok(text) => text.replace('\n', " ").into_bytes(),
        Err(e) => e.into_bytes(),
    };
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        out.extend_from_slice(if i == n { &line } else { l.as_bytes() });
        out.push(b'\n');
    }
    (out, format!("line {}: {what}", n + 1))
}

fn flip_byte(rng: &mut Rng, text: &str) -> (Vec<u8>, String) {
    let mut bytes = text.as_bytes().to_vec();
    let at = rng.below(bytes.len());
    let mask = 1 + rng.below(255) as u8;
    bytes[at] ^= mask;
    (bytes, format!("byte {at} xor {mask:#04x}"))
}

fn insert_byte(rng: &mut Rng, text: &str) -> (Vec<u8>, String) {
    const BYTES: [u8; 12] = [
        b'{', b'}', b'[', b']', b'"', b',', b':', b'\\', b'0', 0xff, 0xc3, 0x00,
    ];
    let mut bytes = text.as_bytes().to_vec();
    let at = rng.below(bytes.len() + 1);
    let b = *rng.pick(&BYTES);
    bytes.insert(at, b);
    (bytes, format!("byte {b:#04x} inserted at {at}"))
}

fn delete_bytes(rng: &mut Rng, text: &str) -> (Vec<u8>, String) {
    let mut bytes = text.as_bytes().to_vec();
    let at = rng.below(bytes.len());
    let n = (1 + rng.below(16)).min(bytes.len() - at);
    bytes.drain(at..at + n);
    (bytes, format!("{n} bytes deleted at {at}"))
}

fn cut_off(rng: &mut Rng, text: &str) -> (Vec<u8>, String) {
    let at = rng.below(text.len());
    (
        text.as_bytes()[..at].to_vec(),
        format!("cut off after {at} bytes"),
    )
}

/// Some object's first key written once more at its start, with another value.
fn repeat_key(rng: &mut Rng, text: &str) -> (Vec<u8>, String) {
    let compact: String =
        serde_json::to_string(&serde_json::from_str::<Value>(text).expect("the seed file is JSON"))
            .expect("JSON serializes");
    let starts: Vec<usize> = compact.match_indices("{\"").map(|(i, _)| i).collect();
    let Some(&at) = (!starts.is_empty()).then(|| rng.pick(&starts)) else {
        return (
            compact.into_bytes(),
            "no object to repeat a key of".to_owned(),
        );
    };
    let key_end = compact[at + 2..].find('"').expect("a key ends") + at + 2;
    let key = compact[at + 2..key_end].to_owned();
    let value = *rng.pick(&NUMBERS);
    let mut out = compact;
    out.insert_str(at + 1, &format!("\"{key}\":{value},"));
    (
        out.into_bytes(),
        format!("key {key:?} repeated at byte {at}"),
    )
}

/// JSON pointers to every value of `value`, the root excepted.
fn pointers(value: &Value) -> Vec<String> {
    fn walk(v: &Value, at: &str, out: &mut Vec<String>) {
        match v {
            Value::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    let p = format!("{at}/{i}");
                    walk(item, &p, out);
                    out.push(p);
                }
            }
            Value::Object(members) => {
                for (k, member) in members {
                    let p = format!("{at}/{}", k.replace('~', "~0").replace('/', "~1"));
                    walk(member, &p, out);
                    out.push(p);
                }
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk(value, "", &mut out);
    out
}

fn odd_number(rng: &mut Rng, value: &mut Value) -> String {
    let numbers: Vec<String> = pointers(value)
        .into_iter()
        .filter(|p| value.pointer(p).is_some_and(Value::is_number))
        .collect();
    let p = rng.pick(&numbers).clone();
    let n = *rng.pick(&NUMBERS);
    *value.pointer_mut(&p).expect("the pointer exists") =
        serde_json::from_str(n).expect("a JSON number");
    format!("{p} = {n}")
}

fn wrong_type(rng: &mut Rng, value: &mut Value) -> String {
    let all = pointers(value);
    let p = rng.pick(&all).clone();
    let replacement = match rng.below(6) {
        0 => Value::Null,
        1 => Value::Bool(true),
        2 => Value::from("text"),
        3 => Value::from(7),
        4 => Value::Array(vec![Value::from(1)]),
        _ => serde_json::json!({"x": 1}),
    };
    let what = format!("{p} = {replacement}");
    *value.pointer_mut(&p).expect("the pointer exists") = replacement;
    what
}

fn drop_member(rng: &mut Rng, value: &mut Value) -> String {
    let members: Vec<String> = pointers(value)
        .into_iter()
        .filter(|p| {
            let parent = &p[..p.rfind('/').expect("not the root")];
            value.pointer(parent).is_some_and(Value::is_object)
                || (parent.is_empty() && value.is_object())
        })
        .collect();
    if members.is_empty() {
        return "no member to drop".to_owned();
    }
    let p = rng.pick(&members).clone();
    let cut = p.rfind('/').expect("not the root");
    let key = p[cut + 1..].replace("~1", "/").replace("~0", "~");
    let parent = value
        .pointer_mut(&p[..cut])
        .and_then(Value::as_object_mut)
        .expect("an object");
    parent.shift_remove(&key);
    format!("{p} dropped")
}

fn long_string(rng: &mut Rng, value: &mut Value) -> String {
    let all = pointers(value);
    let p = rng.pick(&all).clone();
    *value.pointer_mut(&p).expect("the pointer exists") = Value::from("Z".repeat(20_000));
    format!("{p} = a string of 20000 characters")
}

/// An `id`, `from_id`, `to_id`, `subject` or `target` set to another id of the file, or
/// to one of no node.
fn other_id(rng: &mut Rng, value: &mut Value) -> String {
    let all = pointers(value);
    let is_id = |p: &String| {
        ["/id", "/from_id", "/to_id", "/subject", "/target"]
            .iter()
            .any(|end| p.ends_with(end))
    };
    let ids: Vec<String> = all.iter().filter(|p| is_id(p)).cloned().collect();
    if ids.is_empty() {
        return "no id to change".to_owned();
    }
    let p = rng.pick(&ids).clone();
    let from = rng.pick(&ids).clone();
    let new = if rng.below(4) == 0 {
        Value::from(99_999)
    } else {
        value.pointer(&from).cloned().unwrap_or(Value::Null)
    };
    let what = format!("{p} = {new}");
    *value.pointer_mut(&p).expect("the pointer exists") = new;
    what
}
