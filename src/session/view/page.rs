//! One HTML page that needs nothing else: the shell (`assets/page.html`), the style
//! and the script compiled into the binary, the data as JSON the script reads, the
//! scene's pictures as markup in inert templates.
//!
//! Untrusted text stays text: the data is JSON inside a `<script type="application/json">`
//! with every `<`, `>` and `&` written as a `\u` escape, so nothing in it can close the
//! element or start markup, and the script puts every string into the page as text. The
//! Content-Security-Policy allows no source but the page's own script and style (named
//! by their SHA-256), so even markup that got in could neither run nor load anything.

use base64::Engine as _;
use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::session::{Error, Result};

const SHELL: &str = include_str!("assets/page.html");
const STYLE: &str = include_str!("assets/view.css");
/// What every page's script starts with: building elements, text, keys, numbers.
const COMMON: &str = include_str!("assets/common.js");
const EPISODE: &str = include_str!("assets/episode.js");
const RESULTS: &str = include_str!("assets/results.js");

/// Which script draws the page.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Script {
    /// One episode, or two side by side.
    Episode,
    /// The tables, figures and episodes of a results file.
    Results,
}

/// Whether the page may ask its own server for fresh data (`coherent view --serve`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// A file that needs nothing: it makes no request at all.
    File,
    /// Served on loopback: it may fetch from where it came from, and nowhere else.
    Served,
}

/// The page: `title`, the `data` the script draws, and `pictures` (id, SVG markup of
/// our own drawing, its text escaped by the renderer) in `<template>` elements.
pub fn html(
    title: &str,
    data: &impl Serialize,
    pictures: &[(String, String)],
    script: Script,
    origin: Origin,
) -> Result<String> {
    let code = match script {
        Script::Episode => format!("{COMMON}\n{EPISODE}"),
        Script::Results => format!("{COMMON}\n{RESULTS}"),
    };
    let mut templates = String::new();
    for (id, svg) in pictures {
        templates.push_str(&format!(
            "<template id=\"{}\">{svg}</template>\n",
            attribute(id)
        ));
    }
    let policy = csp(&code, STYLE, origin);
    let json = script_json(data)?;
    Ok(fill(
        SHELL,
        &[
            ("{{CSP}}", &policy),
            ("{{TITLE}}", &attribute(title)),
            ("{{STYLE}}", STYLE),
            ("{{PICTURES}}", &templates),
            ("{{DATA}}", &json),
            ("{{SCRIPT}}", &code),
        ],
    ))
}

/// The policy: nothing from anywhere (no image, font, frame, form or connection) but
/// the inline script and style whose hashes it names; a served page may also fetch
/// from its own origin.
pub fn csp(script: &str, style: &str, origin: Origin) -> String {
    let connect = match origin {
        Origin::File => "'none'",
        Origin::Served => "'self'",
    };
    format!(
        "default-src 'none'; script-src '{}'; style-src '{}'; img-src 'none'; connect-src {connect}; base-uri 'none'; form-action 'none'",
        sha256(script),
        sha256(style)
    )
}

fn sha256(text: &str) -> String {
    let digest = Sha256::digest(text.as_bytes());
    format!(
        "sha256-{}",
        base64::engine::general_purpose::STANDARD.encode(digest)
    )
}

/// `data` as JSON that can sit inside a `<script>` element: `<`, `>` and `&` (which
/// JSON has only inside strings) as `\u` escapes, so that no `</script>` or `<!--`
/// can appear, and the two line separators JavaScript once refused in strings too.
pub fn script_json(data: &impl Serialize) -> Result<String> {
    // The data is the session's own structs, which always serialise: failing is a bug.
    let json = serde_json::to_string(data)
        .map_err(|e| Error::Internal(format!("the page's data: {e}")))?;
    let mut out = String::with_capacity(json.len() + json.len() / 16);
    for c in json.chars() {
        match c {
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            c => out.push(c),
        }
    }
    Ok(out)
}

/// `text` escaped for an HTML attribute or element text.
pub fn attribute(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// `html` (a whole page) in a frame of its own, as a notebook shows it inline: the page
/// keeps its own policy and script, sandboxed from the notebook (it may run its script,
/// nothing more).
pub fn framed(html: &str) -> String {
    format!(
        "<iframe sandbox=\"allow-scripts\" width=\"100%\" height=\"760\" frameborder=\"0\" title=\"coherent view\" srcdoc=\"{}\"></iframe>",
        attribute(html)
    )
}

/// `shell` with each marker replaced once, in one pass: what is put in is never read
/// again for markers.
fn fill(shell: &str, parts: &[(&str, &str)]) -> String {
    let mut out =
        String::with_capacity(shell.len() + parts.iter().map(|(_, v)| v.len()).sum::<usize>());
    let mut rest = shell;
    while let Some(at) = rest.find("{{") {
        out.push_str(&rest[..at]);
        rest = &rest[at..];
        match parts.iter().find(|(marker, _)| rest.starts_with(marker)) {
            Some((marker, value)) => {
                out.push_str(value);
                rest = &rest[marker.len()..];
            }
            None => {
                out.push_str("{{");
                rest = &rest[2..];
            }
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_in_a_script_element_cannot_close_it_or_open_markup() {
        let hostile =
            serde_json::json!({"answer": "</script><script>alert(1)</script><!-- & \u{2028}"});
        let json = script_json(&hostile).expect("serialisable");
        assert!(!json.contains('<') && !json.contains('>') && !json.contains('&'));
        let back: serde_json::Value = serde_json::from_str(&json).expect("still JSON");
        assert_eq!(back, hostile);
    }

    #[test]
    fn markers_in_what_is_filled_in_stay_as_they_are() {
        let page = fill(
            "a {{X}} b {{Y}} c {{Z}}",
            &[("{{X}}", "{{Y}}"), ("{{Y}}", "y")],
        );
        assert_eq!(page, "a {{Y}} b y c {{Z}}");
    }

    #[test]
    fn the_policy_names_the_hash_of_the_script_and_forbids_other_origins() {
        let policy = csp("x", "y", Origin::File);
        // SHA-256 of "x", base64.
        assert!(
            policy.contains("script-src 'sha256-LXEWQrcmsEQBYnyp+6wy9chTD7GQPMTbAiWHF5IaSIE='")
        );
        assert!(policy.starts_with("default-src 'none';"));
        assert!(policy.contains("connect-src 'none'"));
        assert!(csp("x", "y", Origin::Served).contains("connect-src 'self'"));
    }
}
