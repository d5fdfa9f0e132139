//! Text from outside — a task file, a model's answer, a server's error — as it may be
//! shown on a terminal or written to a log: nothing in it can move the cursor, clear
//! the screen, start a new line or reorder what follows. Transcripts keep the raw text.

use std::borrow::Cow;
use std::fmt::Write;

/// Whether `c` must not reach a terminal as it is: control characters (C0, DEL, C1),
/// and the characters that change the direction of the text around them (the
/// bidirectional embeddings, overrides and isolates, and the invisible marks).
fn unsafe_char(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{061C}' | '\u{200E}' | '\u{200F}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}'
        )
}

/// `text` with every unsafe character escaped: `\n`, `\r` and `\t` as such, the others
/// as `\u{..}`; a backslash stays as it is. Borrowed when nothing needs escaping.
pub fn shown(text: &str) -> Cow<'_, str> {
    if !text.chars().any(unsafe_char) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if unsafe_char(c) => {
                let _ = write!(out, "\\u{{{:x}}}", u32::from(c));
            }
            c => out.push(c),
        }
    }
    Cow::Owned(out)
}

/// `text` with each of its lines [`shown`] and the line breaks between them kept: for a
/// message of several lines, each of which may quote a task file or a server.
pub fn shown_lines(text: &str) -> String {
    text.split('\n').map(shown).collect::<Vec<_>>().join("\n")
}

/// `text` cut to at most `max` bytes (at a character boundary), with a note of the
/// whole length when it was longer: for what a long answer or value may keep.
pub fn cut(text: &str, max: usize) -> Cow<'_, str> {
    if text.len() <= max {
        return Cow::Borrowed(text);
    }
    let mut end = max;
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    Cow::Owned(format!(
        "{}… [cut: {} bytes in all]",
        &text[..end],
        text.len()
    ))
}

/// `text` cut to its last `max` bytes or fewer (at a character boundary), after a note
/// of the whole length when it was longer: for an error whose end says the most, such
/// as a traceback.
pub fn cut_front(text: &str, max: usize) -> Cow<'_, str> {
    if text.len() <= max {
        return Cow::Borrowed(text);
    }
    let mut start = text.len() - max;
    while !text.is_char_boundary(start) {
        start += 1;
    }
    Cow::Owned(format!(
        "[cut: {} bytes in all] …{}",
        text.len(),
        &text[start..]
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_text_is_cut_at_a_character_boundary() {
        assert_eq!(cut("short", 10), "short");
        assert_eq!(cut("abcdef", 3), "abc… [cut: 6 bytes in all]");
        // "é" is two bytes: a cut inside it moves back before it.
        assert_eq!(cut("aé", 2), "a… [cut: 3 bytes in all]");
        assert_eq!(cut_front("abcdef", 3), "[cut: 6 bytes in all] …def");
        assert_eq!(cut_front("éa", 2), "[cut: 3 bytes in all] …a");
        assert_eq!(cut_front("short", 10), "short");
    }

    #[test]
    fn plain_text_is_borrowed() {
        assert!(matches!(shown("[grab] <apple>(9) — ok"), Cow::Borrowed(_)));
    }

    #[test]
    fn escapes_and_line_breaks_are_escaped() {
        assert_eq!(
            shown("a\x1b[2J\rsuccess=true\nb\tc"),
            "a\\u{1b}[2J\\rsuccess=true\\nb\\tc"
        );
        assert_eq!(shown("\u{9b}31m"), "\\u{9b}31m");
        assert_eq!(shown("\u{7f}"), "\\u{7f}");
    }

    #[test]
    fn direction_overrides_are_escaped() {
        assert_eq!(shown("abc\u{202E}fed"), "abc\\u{202e}fed");
        assert_eq!(shown("\u{2066}x\u{2069}"), "\\u{2066}x\\u{2069}");
    }
}
