//! Files that are not what they claim, through the `coherent` binary: every file the
//! program reads stops at its documented limit (a device that never ends, `/dev/zero`,
//! stands for a file of any size) with exit 2 and an error naming the file and the
//! limit; prompt templates that are no regular file are refused, a blank one is warned
//! of, `prompts export` never writes through a link; a price table that lists a model
//! twice or prices it absurdly is refused; a benchmark whose transcript cannot be
//! created skips that episode with its reason and goes on.

use std::path::Path;

use serde_json::json;

mod common;

use common::{coherent, demo, scratch, show, utf8};

const ENDLESS: &str = "/dev/zero";

/// Runs `coherent ARGS`, which must exit 2 saying `says` on stderr.
fn refused(args: &[&str], says: &str) {
    let out = coherent(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}\n{}", show(&out));
    assert!(
        err.contains(says),
        "{args:?}: expected {says:?}\n{}",
        show(&out)
    );
    assert!(!err.contains("panicked"), "{}", show(&out));
}

#[test]
fn a_transcript_that_never_ends_is_refused_at_its_limit_naming_the_flag() {
    let dir = scratch("endless-transcript");
    let out = utf8(&dir);
    refused(
        &["run", "--replay", ENDLESS, "--out", out],
        "error: /dev/zero: more than 64 MiB, the most a transcript may hold (raise it with \
         --max-transcript-mib)",
    );
    refused(
        &[
            "run",
            "--replay",
            ENDLESS,
            "--out",
            out,
            "--max-transcript-mib",
            "1",
        ],
        "/dev/zero: more than 1 MiB, the most a transcript may hold",
    );
    let svg = dir.join("scene.svg");
    refused(
        &["render", "--transcript", ENDLESS, "-o", utf8(&svg)],
        "/dev/zero: more than 64 MiB, the most a transcript may hold",
    );
    // A regular file is refused by its size, before a byte of it is read.
    let big = dir.join("big.jsonl");
    std::fs::File::create(&big)
        .and_then(|f| f.set_len(3 << 30))
        .expect("a sparse file of 3 GiB");
    refused(
        &["run", "--replay", utf8(&big), "--out", out],
        "big.jsonl: more than 64 MiB, the most a transcript may hold",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_other_file_a_command_reads_stops_at_its_limit() {
    let dir = scratch("endless-inputs");
    let demo = demo();
    let (demo, runs) = (utf8(&demo), dir.join("runs"));
    let task_file = "/dev/zero: more than 64 MiB, the most a task file may hold";
    refused(&["run", ENDLESS, "--out", utf8(&runs)], task_file);
    refused(&["plan", ENDLESS], task_file);
    refused(&["validate", ENDLESS], task_file);
    refused(
        &["run", demo, "--prices", ENDLESS, "--out", utf8(&runs)],
        "/dev/zero: more than 1 MiB, the most a price table may hold",
    );
    let results = dir.join("results.jsonl");
    let bench = |extra: &[&str], says: &str| {
        let mut args = vec!["bench", "--tasks", demo, "--methods", "optimal"];
        args.extend_from_slice(extra);
        refused(&args, says);
    };
    bench(
        &["--subset", ENDLESS, "--out", utf8(&results)],
        "/dev/zero: more than 1 MiB, the most a subset file may hold",
    );
    let results_line = "/dev/zero: line 1: longer than 1 MiB, the most a line of a results \
                        file may hold";
    // A results file that is no regular file is refused before anything is made beside
    // it (the lock's folder): not even `/dev/zero.transcripts` for a device.
    bench(
        &["--out", ENDLESS],
        "/dev/zero: not a regular file (a device, a pipe, a folder?): a results file must be one",
    );
    let pipe = dir.join("pipe.jsonl");
    let made = std::process::Command::new("mkfifo").arg(&pipe).status();
    assert!(made.expect("mkfifo runs").success());
    bench(&["--out", utf8(&pipe)], "pipe.jsonl: not a regular file");
    assert!(
        !dir.join("pipe.transcripts").exists(),
        "nothing is made for a run that cannot start"
    );
    refused(&["bench", "--report", ENDLESS], results_line);
    bench(
        &[
            "--backend",
            "replay",
            "--replay-from",
            ENDLESS,
            "--out",
            utf8(&results),
        ],
        results_line,
    );
    // A results file over its limit as a whole, by its size.
    let big = dir.join("big.jsonl");
    std::fs::File::create(&big)
        .and_then(|f| f.set_len(2 << 20))
        .expect("a sparse file");
    refused(
        &["bench", "--report", utf8(&big), "--max-results-mib", "1"],
        "big.jsonl: more than 1 MiB, the most a results file may hold (raise it with \
         --max-results-mib)",
    );
    // A results line whose transcript is a device: refused before any episode starts.
    let ran = coherent(&[
        "bench",
        "--tasks",
        demo,
        "--methods",
        "pefa",
        "--out",
        utf8(&results),
    ]);
    assert_eq!(ran.status.code(), Some(0), "{}", show(&ran));
    let text = std::fs::read_to_string(&results).expect("the results file");
    let mut line: serde_json::Value = serde_json::from_str(text.trim()).expect("one line");
    line["transcript"] = json!(ENDLESS);
    let pointing = dir.join("pointing.jsonl");
    std::fs::write(&pointing, format!("{line}\n")).expect("written");
    let replayed = dir.join("replayed.jsonl");
    let args = [
        "bench",
        "--tasks",
        demo,
        "--methods",
        "pefa",
        "--backend",
        "replay",
        "--replay-from",
        utf8(&pointing),
        "--out",
        utf8(&replayed),
    ];
    refused(&args, "/dev/zero: not a regular file");
    assert!(!replayed.exists(), "nothing ran");
    // `coherent view` reads a transcript or a results file within the same limits.
    refused(
        &["view", ENDLESS, "-o", utf8(&dir.join("page.html"))],
        "/dev/zero: more than 64 MiB, the most a transcript may hold (raise it with \
         --max-transcript-mib)",
    );
    let padded = dir.join("padded.jsonl");
    std::fs::write(&padded, format!("{line}\n{}", "\n".repeat(2 << 20))).expect("written");
    refused(
        &["view", utf8(&padded), "--max-results-mib", "1"],
        "padded.jsonl: more than 1 MiB, the most a results file may hold (raise it with \
         --max-results-mib)",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Makes a file at the path it is given.
type Make = Box<dyn FnOnce(&Path)>;

/// A prompt folder holding `assigner_user.txt` made by `make`.
fn prompt_folder(name: &str, make: impl FnOnce(&Path)) -> std::path::PathBuf {
    let dir = scratch(name);
    make(&dir.join("assigner_user.txt"));
    dir
}

#[test]
fn a_template_that_is_no_regular_file_or_too_large_is_refused() {
    let demo = demo();
    let runs = scratch("templates-runs");
    let cases: Vec<(&str, Make, &str)> = vec![
        (
            "folder",
            Box::new(|p| std::fs::create_dir(p).expect("a folder")),
            "not a regular file",
        ),
        (
            "fifo",
            Box::new(|p| {
                let made = std::process::Command::new("mkfifo").arg(p).status();
                assert!(made.expect("mkfifo runs").success());
            }),
            "not a regular file",
        ),
        (
            "device",
            Box::new(|p| std::os::unix::fs::symlink(ENDLESS, p).expect("a link")),
            "not a regular file",
        ),
        (
            "dangling",
            Box::new(|p| std::os::unix::fs::symlink("/nonexistent/x.txt", p).expect("a link")),
            "No such file",
        ),
        (
            "huge",
            Box::new(|p| {
                let text = format!("{{{{instruction}}}}{}", " ".repeat(2 << 20));
                std::fs::write(p, text).expect("written");
            }),
            "more than 1 MiB, the most a prompt template may hold",
        ),
    ];
    for (name, make, says) in cases {
        let dir = prompt_folder(&format!("template-{name}"), make);
        let args = [
            "run",
            utf8(&demo),
            "--prompts",
            utf8(&dir),
            "--out",
            utf8(&runs),
        ];
        refused(&args, says);
        refused(&args, "assigner_user.txt");
        let _ = std::fs::remove_dir_all(&dir);
    }
    assert!(
        std::fs::read_dir(&runs)
            .expect("the folder")
            .next()
            .is_none(),
        "no episode ran"
    );
    let _ = std::fs::remove_dir_all(&runs);
}

#[test]
fn a_blank_template_is_warned_of_and_export_never_writes_through_a_link() {
    let demo = demo();
    let dir = prompt_folder("template-blank", |p| {
        std::fs::write(p, "\n").expect("written");
    });
    let runs = dir.join("runs");
    let out = coherent(&[
        "run",
        utf8(&demo),
        "--prompts",
        utf8(&dir),
        "--out",
        utf8(&runs),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    assert!(
        err.contains("assigner_user.txt: the template is blank"),
        "{}",
        show(&out)
    );
    // A link in the folder, to a file outside it that does not exist yet.
    let export = scratch("export-link");
    let outside = export.join("outside.txt");
    let folder = export.join("prompts");
    std::fs::create_dir(&folder).expect("a folder");
    std::os::unix::fs::symlink(&outside, folder.join("central.txt")).expect("a link");
    for force in [false, true] {
        let mut args = vec!["prompts", "export", utf8(&folder)];
        if force {
            args.push("--force");
        }
        refused(&args, "central.txt: is a symbolic link");
        assert!(!outside.exists(), "nothing written through the link");
    }
    std::fs::remove_file(folder.join("central.txt")).expect("removed");
    let out = coherent(&["prompts", "export", utf8(&folder)]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let names: Vec<String> = std::fs::read_dir(&folder)
        .expect("the folder")
        .map(|e| {
            e.expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    // The eight templates of sequential episodes, the four of parallel ones and
    // llm-pddl's goal.
    assert_eq!(names.len(), 13, "the templates and nothing else: {names:?}");
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&export);
}

#[test]
fn a_price_table_with_a_model_twice_or_an_absurd_price_is_refused() {
    let dir = scratch("prices");
    let demo = demo();
    let runs = dir.join("runs");
    let empty = dir.join("empty.jsonl");
    std::fs::write(&empty, "").expect("an empty results file");
    for (name, text, says) in [
        (
            "twice.json",
            r#"{"m": {"input": 1, "output": 2}, "m": {"input": 3, "output": 4}}"#,
            "duplicate key \"m\"",
        ),
        (
            "huge.json",
            r#"{"m": {"input": 1e308, "output": 2}}"#,
            "prices must be numbers from 0 to 1000000",
        ),
        (
            "huge.toml",
            "[m]\ninput = 1\noutput = 1e300\n",
            "prices must be numbers from 0 to 1000000",
        ),
    ] {
        let file = dir.join(name);
        std::fs::write(&file, text).expect("written");
        refused(
            &[
                "run",
                utf8(&demo),
                "--prices",
                utf8(&file),
                "--out",
                utf8(&runs),
            ],
            says,
        );
        refused(
            &["bench", "--report", utf8(&empty), "--prices", utf8(&file)],
            says,
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A transcript that cannot be created (here a regular file where seed 1's folder goes,
/// which stops root too, unlike a folder's permissions) keeps that episode from running,
/// not the benchmark: its results line says why (status `interrupted`, so no final
/// result), the progress and the report's failed episodes say it too, and the run exits
/// 0. The same command, the way cleared, runs that episode alone.
#[test]
fn a_transcript_that_cannot_be_created_skips_its_episode_with_the_reason_and_resumes() {
    let dir = scratch("no-transcript");
    let out = dir.join("results.jsonl");
    let in_the_way = dir.join("results.transcripts/seed1");
    std::fs::create_dir_all(dir.join("results.transcripts")).expect("a folder");
    std::fs::write(&in_the_way, "").expect("a file in the way");
    let demo = demo();
    let args = [
        "bench",
        "--tasks",
        utf8(&demo),
        "--methods",
        "optimal",
        "--seeds",
        "2",
        "--out",
        utf8(&out),
    ];
    let first = coherent(&args);
    assert_eq!(first.status.code(), Some(0), "{}", show(&first));
    let lines: Vec<serde_json::Value> = std::fs::read_to_string(&out)
        .expect("the results file")
        .lines()
        .map(|l| serde_json::from_str(l).expect("a results line"))
        .collect();
    let seed = |n: u64| {
        lines
            .iter()
            .find(|l| l["seed"] == n)
            .unwrap_or_else(|| panic!("no line of seed {n}: {lines:?}"))
    };
    assert_eq!(seed(0)["status"], "success");
    let skipped = seed(1);
    assert_eq!(skipped["status"], "interrupted", "{skipped}");
    let why = skipped["error"].as_str().expect("the reason");
    let file = skipped["transcript"]
        .as_str()
        .expect("the transcript it would have been");
    assert!(
        why.starts_with(&format!("no transcript: {file}: ")) && file.contains("seed1/"),
        "{why}"
    );
    let progress = String::from_utf8_lossy(&first.stderr);
    assert!(
        progress.contains("optimal demo-apartment task 0 seed 1: interrupted: no transcript: "),
        "{}",
        show(&first)
    );
    let report = String::from_utf8_lossy(&first.stdout);
    assert!(
        report.contains("### Episodes that failed with an error")
            && report.contains(&format!("| optimal | 1 | no transcript: {file}: ")),
        "{}",
        show(&first)
    );

    std::fs::remove_file(&in_the_way).expect("the way cleared");
    let again = coherent(&args);
    assert_eq!(again.status.code(), Some(0), "{}", show(&again));
    assert!(
        String::from_utf8_lossy(&again.stderr)
            .contains("1 already finished in the results file, 1 to run"),
        "{}",
        show(&again)
    );
    let text = std::fs::read_to_string(&out).expect("the results file");
    let last: serde_json::Value =
        serde_json::from_str(text.lines().last().expect("a line")).expect("a results line");
    assert_eq!(
        (last["seed"].as_u64(), last["status"].as_str()),
        (Some(1), Some("success"))
    );
    assert!(Path::new(last["transcript"].as_str().expect("a transcript")).is_file());
    let _ = std::fs::remove_dir_all(&dir);
}
