//! Names from outside, through the `coherent` binary: a scene or a method whose name
//! holds terminal escapes is flagged by `validate` and shown escaped wherever it is
//! printed (step and transcript lines, progress lines, the tables' headers, Markdown and
//! CSV), and never reaches a file name raw; a 300-character scene runs and benches under
//! a shortened file name; `import` keeps every file inside its folder. SIGTERM stops
//! `run` and `bench` as Ctrl-C does; a number given to a flag is never echoed in three
//! hundred digits.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use serde_json::{Value, json};

mod common;

use common::{coherent, demo, scratch, show, silent_server, utf8};

/// The characters a terminal acts on that the names below carry.
const RAW: [char; 3] = ['\u{1b}', '\u{7}', '\u{202e}'];

/// The demo task under another scene name, written into `dir`.
fn demo_as(dir: &Path, file: &str, scene: &str) -> PathBuf {
    let text = std::fs::read_to_string(demo()).expect("the demo task");
    let mut task: Value = serde_json::from_str(&text).expect("JSON");
    task["scene"] = json!(scene);
    let path = dir.join(file);
    std::fs::write(&path, task.to_string()).expect("written");
    path
}

/// Every file name under `dir`, recursively.
fn names(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).expect("a folder") {
        let path = entry.expect("an entry").path();
        if path.is_dir() {
            out.extend(names(&path));
        }
        out.push(
            path.file_name()
                .expect("a name")
                .to_string_lossy()
                .into_owned(),
        );
    }
    out
}

fn safe_name(name: &str) -> bool {
    name.len() <= 255
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
}

fn raw_free(what: &str, text: &str) {
    assert!(!text.contains(RAW), "{what} carries raw escapes: {text:?}");
}

#[test]
fn a_scene_with_escapes_is_flagged_and_shown_escaped_in_every_output_and_no_file_name() {
    let dir = scratch("escaped-scene");
    let scene = "lab\u{1b}]0;owned\u{7}\u{1b}[2J\u{202e}";
    let task = demo_as(&dir, "task.json", scene);
    let validated = coherent(&["validate", utf8(&task)]);
    assert_eq!(validated.status.code(), Some(1), "{}", show(&validated));
    let said = String::from_utf8_lossy(&validated.stdout);
    raw_free("validate", &said);
    assert!(
        said.contains("scene: the name \"lab\\u{1b}]0;owned\\u{7}"),
        "{said}"
    );
    let runs = dir.join("runs");
    let ran = coherent(&["run", utf8(&task), "--out", utf8(&runs)]);
    assert_eq!(ran.status.code(), Some(0), "{}", show(&ran));
    raw_free("run", &String::from_utf8_lossy(&ran.stdout));
    let results = dir.join("results.jsonl");
    let benched = coherent(&[
        "bench",
        "--tasks",
        utf8(&task),
        "--methods",
        "optimal,pefa",
        "--out",
        utf8(&results),
    ]);
    assert_eq!(benched.status.code(), Some(0), "{}", show(&benched));
    let tables = String::from_utf8_lossy(&benched.stdout);
    raw_free("bench", &tables);
    raw_free("bench progress", &String::from_utf8_lossy(&benched.stderr));
    assert!(tables.contains("lab\\u{1b}]0;owned\\u{7}"), "{tables}");
    for name in names(&dir) {
        assert!(safe_name(&name), "an unsafe file name: {name:?}");
    }
    // A results line whose method holds escapes, in both table formats; its episode in
    // parallel too, so that the makespan table names it as well.
    let text = std::fs::read_to_string(&results).expect("the results");
    let mut line: Value = serde_json::from_str(text.lines().next().expect("a line")).expect("JSON");
    line["method"] = json!("pe\u{1b}[31mfa|x,\"y\"\u{7}");
    let mut parallel = line.clone();
    parallel["execution"] = json!("parallel");
    let forged = dir.join("forged.jsonl");
    std::fs::write(&forged, format!("{line}\n{parallel}\n")).expect("written");
    for format in ["markdown", "csv"] {
        let out = coherent(&["bench", "--report", utf8(&forged), "--format", format]);
        assert_eq!(out.status.code(), Some(0), "{}", show(&out));
        let text = String::from_utf8_lossy(&out.stdout);
        raw_free(format, &text);
        assert!(text.contains("pe\\u{1b}[31mfa"), "{format}: {text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_scene_of_300_characters_runs_and_benches_under_a_shortened_file_name() {
    let dir = scratch("long-scene");
    let long = demo_as(&dir, "long.json", &"s".repeat(300));
    let validated = coherent(&["validate", utf8(&long)]);
    assert_eq!(validated.status.code(), Some(0), "{}", show(&validated));
    let runs = dir.join("runs");
    let ran = coherent(&["run", utf8(&long), "--out", utf8(&runs)]);
    assert_eq!(ran.status.code(), Some(0), "{}", show(&ran));
    let tasks = dir.join("tasks");
    std::fs::create_dir(&tasks).expect("a folder");
    demo_as(&tasks, "a.json", &"s".repeat(300));
    demo_as(&tasks, "b.json", "short");
    let results = dir.join("results.jsonl");
    let benched = coherent(&[
        "bench",
        "--tasks",
        utf8(&tasks),
        "--methods",
        "optimal,pefa",
        "--out",
        utf8(&results),
    ]);
    assert_eq!(benched.status.code(), Some(0), "{}", show(&benched));
    let lines = std::fs::read_to_string(&results).expect("the results");
    assert_eq!(lines.lines().count(), 4, "every episode ran: {lines}");
    let viewed = coherent(&["view", utf8(&results)]);
    assert_eq!(viewed.status.code(), Some(0), "{}", show(&viewed));
    assert!(
        String::from_utf8_lossy(&viewed.stdout).contains("and 4 episode pages"),
        "{}",
        show(&viewed)
    );
    for name in names(&dir) {
        assert!(safe_name(&name), "{name:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn import_keeps_every_file_inside_its_folder() {
    let dir = scratch("import-escape");
    let task = demo_as(&dir, "task.json", "../../escaped");
    let out = dir.join("a").join("b").join("out");
    let imported = coherent(&["import", utf8(&task), "-o", utf8(&out)]);
    assert_eq!(imported.status.code(), Some(0), "{}", show(&imported));
    assert!(!dir.join("escaped").exists() && !dir.join("a").join("escaped").exists());
    let written = names(&out);
    assert_eq!(written.len(), 2, "a folder and its task: {written:?}");
    assert!(written.iter().all(|n| safe_name(n)), "{written:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Starts `coherent ARGS`, waits for its first model request, sends SIGTERM, and
/// returns its exit status and output; it must end within 20 s.
fn terminated(args: &[&str], requests: &mpsc::Receiver<()>) -> (Option<i32>, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_coherent"))
        .args(args)
        .env_remove("OPENAI_API_KEY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("coherent starts");
    requests
        .recv_timeout(Duration::from_secs(60))
        .expect("a model request");
    let sent = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let start = Instant::now();
    while child.try_wait().expect("waitable").is_none() {
        if start.elapsed() > Duration::from_secs(20) {
            let _ = child.kill();
            panic!("still running 20 s after SIGTERM");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().expect("its output");
    (out.status.code(), show(&out))
}

/// The `status` of the last line of the JSON-lines file at `path`.
fn last_status(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).expect("readable");
    let last: Value = serde_json::from_str(text.lines().last().expect("a line")).expect("JSON");
    last["status"].clone()
}

#[test]
fn sigterm_stops_run_and_bench_as_ctrl_c_does_and_closes_their_records() {
    let dir = scratch("sigterm");
    let (url, requests) = silent_server();
    let demo = demo();
    let endpoint = ["--base-url", &url, "--model", "m", "--timeout", "600"];
    let runs = dir.join("runs");
    let mut args = vec!["run", utf8(&demo), "--out", utf8(&runs)];
    args.extend_from_slice(&endpoint);
    let (code, said) = terminated(&args, &requests);
    assert_eq!(code, Some(143), "{said}");
    let transcript = std::fs::read_dir(&runs)
        .expect("the transcripts")
        .next()
        .expect("one")
        .expect("an entry")
        .path();
    assert_eq!(last_status(&transcript), json!("interrupted"), "{said}");
    let results = dir.join("results.jsonl");
    let mut args = vec![
        "bench",
        "--tasks",
        utf8(&demo),
        "--methods",
        "pefa",
        "--out",
        utf8(&results),
    ];
    args.extend_from_slice(&endpoint);
    let (code, said) = terminated(&args, &requests);
    assert_eq!(code, Some(143), "{said}");
    assert_eq!(last_status(&results), json!("interrupted"), "{said}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn numbers_given_to_flags_are_echoed_short() {
    for (args, says) in [
        (
            vec!["robots", "serve", "DEMO", "--delay", "1e300"],
            "--delay must be seconds from 0 to 1.8e19, not 1e300",
        ),
        (
            vec![
                "run",
                "DEMO",
                "--robots",
                "ros2",
                "--robot-timeout",
                "1e300",
            ],
            "not 1e300",
        ),
        (
            vec![
                "run",
                "DEMO",
                "--base-url",
                "http://127.0.0.1:9/v1",
                "--model",
                "m",
                "--timeout",
                "1e300",
            ],
            "--timeout 1e300: not a number of seconds",
        ),
    ] {
        let demo = demo();
        let args: Vec<&str> = args
            .iter()
            .map(|a| if *a == "DEMO" { utf8(&demo) } else { a })
            .collect();
        let out = coherent(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}\n{}", show(&out));
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!err.contains("0000000000"), "{err}");
    }
}

/// `render` of a task whose names hold control characters writes well-formed XML: every
/// text of the picture goes through the one escaping of text that leaves the program
/// (`coherent_core::text::markup`), so that no character XML 1.0 forbids reaches the
/// file, even escaped. A raw ESC used to be written into the SVG, which then was not
/// XML (no browser drew it), while `render` said "wrote" and exited 0.
#[test]
fn a_render_of_names_with_control_characters_is_well_formed_xml() {
    let dir = scratch("render-escapes");
    let text = std::fs::read_to_string(demo()).expect("the demo task");
    let mut task: Value = serde_json::from_str(&text).expect("JSON");
    let evil = "\u{1b}]0;owned\u{7}\u{1b}[2J\n<b>&amp;\"'\u{0}\u{202e}\u{fffe}";
    task["scene"] = json!(format!("lab{evil}"));
    for node in task["graph"]["nodes"].as_array_mut().expect("nodes") {
        if node["category"] != "Agents" {
            let name = node["class_name"].as_str().expect("a name").to_owned();
            node["class_name"] = json!(format!("{name}{evil}"));
        }
    }
    let path = dir.join("task.json");
    std::fs::write(&path, task.to_string()).expect("written");
    let svg = dir.join("scene.svg");
    let out = coherent(&["render", utf8(&path), "-o", utf8(&svg)]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let picture = std::fs::read_to_string(&svg).expect("an SVG in UTF-8");
    let forbidden = |c: char| matches!(c, '\u{0}'..='\u{8}' | '\u{b}' | '\u{c}' | '\u{e}'..='\u{1f}' | '\u{fffe}' | '\u{ffff}');
    assert!(!picture.contains(forbidden), "a character XML 1.0 forbids");
    raw_free("the SVG", &picture);
    assert!(
        picture.contains("kitchen\\u{1b}]0;owned\\u{7}"),
        "shown as the terminal shows it"
    );
    let parsed = Command::new("python3")
        .args([
            "-c",
            "import sys, xml.etree.ElementTree as E; E.parse(sys.argv[1])",
            utf8(&svg),
        ])
        .output()
        .expect("python3 runs (it checks the SVG with the standard library's XML parser)");
    assert!(
        parsed.status.success(),
        "not well-formed XML: {}",
        String::from_utf8_lossy(&parsed.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
