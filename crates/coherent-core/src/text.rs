//! Text from outside — a task file, a model's answer, a server's error — as it may be
//! shown on a terminal or written to a log: nothing in it can move the cursor, clear
//! the screen, start a new line or reorder what follows. Transcripts keep the raw text.
//! The same text in a file name ([`file_name_part`]) is made of safe characters only, and
//! in markup (an SVG, a page: [`markup`]) it is shown the same way, then escaped.

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

/// Whether `text` holds a character that a terminal acts on ([`shown`] escapes them).
pub fn has_unsafe(text: &str) -> bool {
    text.chars().any(unsafe_char)
}

/// `text` as part of a file name: ASCII letters, digits, `-`, `_` and `.` (not first),
/// at most `max` bytes (`max` >= 16). Any other character is `_`; when anything had to
/// change, the part ends in `-` and 8 hex digits of a hash of the whole text, so that
/// two texts that differ still give two names. Borrowed when `text` is already one.
pub fn file_name_part(text: &str, max: usize) -> Cow<'_, str> {
    let safe = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.');
    if !text.is_empty() && text.len() <= max && text.chars().all(safe) && !text.starts_with('.') {
        return Cow::Borrowed(text);
    }
    // FNV-1a, 32 bits: stable across runs and versions, unlike the standard hasher.
    let hash = text.bytes().fold(0x811c_9dc5_u32, |h, b| {
        (h ^ u32::from(b)).wrapping_mul(0x0100_0193)
    });
    let mut out: String = text
        .chars()
        .map(|c| if safe(c) { c } else { '_' })
        .take(max.saturating_sub(9))
        .collect();
    if out.starts_with('.') {
        out.replace_range(..1, "_");
    }
    Cow::Owned(format!("{out}-{hash:08x}"))
}

/// A number of a flag or a file as it may be echoed: as written for usual sizes, in
/// exponent form beyond (`1e300`, not its three hundred digits).
pub fn number(x: f64) -> String {
    if x == 0.0 || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
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

/// `text` as the text of an XML or HTML element or of a quoted attribute (an SVG, a
/// page): [`shown`] first, so that no control character reaches the file (XML 1.0
/// allows none but tab and the line breaks, not even as a character reference, and a
/// reader refuses the whole document for one), nor a direction override; then `&`, `<`,
/// `>`, `"` and `'` as entities, and the two noncharacters XML 1.0 also forbids,
/// U+FFFE and U+FFFF, as [`shown`] writes an escape. Borrowed when nothing needs either.
pub fn markup(text: &str) -> Cow<'_, str> {
    let special = ['&', '<', '>', '"', '\'', '\u{FFFE}', '\u{FFFF}'];
    let safe = shown(text);
    if !safe.contains(special) {
        return safe;
    }
    let mut out = String::with_capacity(safe.len() + 16);
    for c in safe.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            '\u{FFFE}' | '\u{FFFF}' => {
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
    cut_end(text, max, false)
}

/// [`cut`], the note counted in the `max` bytes (`max` leaving room for it, some 40
/// bytes): a text cut so is no longer than `max` and is left as it is when cut again.
/// For text that is recorded as it was cut and is cut again when the recording is
/// played back (a method's answer on replay).
pub fn cut_within(text: &str, max: usize) -> Cow<'_, str> {
    cut_end(text, max, true)
}

/// [`cut`] or [`cut_within`].
fn cut_end(text: &str, max: usize, within: bool) -> Cow<'_, str> {
    if text.len() <= max {
        return Cow::Borrowed(text);
    }
    let note = format!("… [cut: {} bytes in all]", text.len());
    let mut end = if within {
        max.saturating_sub(note.len())
    } else {
        max
    };
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    Cow::Owned(format!("{}{note}", &text[..end]))
}

/// `text` cut to its last `max` bytes or fewer (at a character boundary), after a note
/// of the whole length when it was longer: for an error whose end says the most, such
/// as a traceback.
pub fn cut_front(text: &str, max: usize) -> Cow<'_, str> {
    cut_start(text, max, false)
}

/// [`cut_front`], the note counted in the `max` bytes, as [`cut_within`] counts it.
pub fn cut_front_within(text: &str, max: usize) -> Cow<'_, str> {
    cut_start(text, max, true)
}

/// [`cut_front`] or [`cut_front_within`].
fn cut_start(text: &str, max: usize, within: bool) -> Cow<'_, str> {
    if text.len() <= max {
        return Cow::Borrowed(text);
    }
    let note = format!("[cut: {} bytes in all] …", text.len());
    let kept = if within {
        max.saturating_sub(note.len())
    } else {
        max
    };
    let mut start = text.len() - kept;
    while !text.is_char_boundary(start) {
        start += 1;
    }
    Cow::Owned(format!("{note}{}", &text[start..]))
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
    fn text_cut_within_its_limit_is_cut_again_to_itself() {
        let long = format!("é{}", "x".repeat(10_000));
        for max in [40, 41, 64, 1000] {
            let once = cut_within(&long, max);
            assert!(once.len() <= max, "{max}: {} bytes", once.len());
            assert!(once.ends_with("[cut: 10002 bytes in all]"), "{once}");
            assert_eq!(cut_within(&once, max), once);
            let front = cut_front_within(&long, max);
            assert!(front.len() <= max && front.starts_with("[cut: 10002 bytes in all] …x"));
            assert_eq!(cut_front_within(&front, max), front);
        }
        // A cut inside "é" moves past it: the note and the text after.
        let t = format!("{}é{}", "a".repeat(50), "b".repeat(50));
        let kept = format!("[cut: 102 bytes in all] …{}", "b".repeat(50));
        assert_eq!(cut_front_within(&t, 27 + 51), kept);
        assert_eq!(cut_within("short", 5), "short");
    }

    #[test]
    fn file_name_parts_are_safe_short_and_distinct() {
        assert_eq!(file_name_part("env0", 64), "env0");
        assert_eq!(file_name_part("s1-apartment_2.b", 64), "s1-apartment_2.b");
        let evil = file_name_part("a\u{1b}[2J/../b\u{7}", 64);
        assert!(
            evil.starts_with("a__2J_.._b_-") && evil.len() == 20,
            "{evil}"
        );
        assert_ne!(file_name_part("a/b", 64), file_name_part("a_b", 64));
        assert!(file_name_part("..", 64).starts_with("_."));
        let long = "x".repeat(300);
        let part = file_name_part(&long, 64);
        assert_eq!(part.len(), 64);
        assert_ne!(part, file_name_part(&"x".repeat(301), 64));
        assert_eq!(file_name_part("", 64).len(), 9);
        assert_eq!(file_name_part("é", 64).len(), 10);
    }

    #[test]
    fn numbers_are_echoed_short() {
        assert_eq!(number(1e300), "1e300");
        assert_eq!(number(0.2), "0.2");
        assert_eq!(number(-1.0), "-1");
        assert_eq!(number(0.0), "0");
        assert_eq!(number(f64::NAN), "NaN");
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
    fn markup_holds_no_character_xml_forbids_and_no_markup_of_its_own() {
        assert_eq!(markup("mug 7"), "mug 7");
        assert!(matches!(markup("mug 7"), Cow::Borrowed(_)));
        assert_eq!(
            markup("a\u{1b}[2J<b>&\"'\n\u{0}\u{ffff}"),
            "a\\u{1b}[2J&lt;b&gt;&amp;&quot;&#39;\\n\\u{0}\\u{ffff}"
        );
        assert_eq!(markup("\u{202E}x"), "\\u{202e}x");
    }

    #[test]
    fn direction_overrides_are_escaped() {
        assert_eq!(shown("abc\u{202E}fed"), "abc\\u{202e}fed");
        assert_eq!(shown("\u{2066}x\u{2069}"), "\\u{2066}x\\u{2069}");
    }
}
