//! Episodes and benchmark results as pages in the browser (`coherent view`,
//! `coherent.view`): one self-contained HTML file per episode (two side by side, if
//! asked), an index of a results file with a page per episode, and a loopback server
//! that follows a results file as it grows.
//!
//! - [`episode`]: what an episode's page shows, as data;
//! - [`scene`]: the scene at each step (pictures, positions, what robots hold);
//! - [`compare`]: two episodes together, and the first round they differ in;
//! - [`results`]: a results file's tables, figures and episodes;
//! - [`page`]: the HTML, its script and style (files in `assets/`, compiled in), the
//!   data embedded safely, the Content-Security-Policy;
//! - [`serve`]: the loopback server.

pub mod compare;
pub mod episode;
pub mod page;
pub mod results;
pub mod scene;
pub mod serve;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use coherent_agents::bench::{ReadLimits, ResultLine, read_results_within};
use coherent_agents::transcript;
use coherent_agents::transcript::Transcript;
use coherent_core::Task;
use coherent_core::files::Lines;
use coherent_core::text::shown;

use self::compare::Episodes;
use self::page::{Origin, Script};

/// An episode to show: its task, its transcript, and its cost when known.
#[derive(Debug)]
pub struct Shown<'a> {
    pub task: &'a Arc<Task>,
    pub transcript: &'a Transcript,
    /// From a results line (priced as the run was); `None` prices the recorded tokens
    /// with the built-in table.
    pub cost_usd: Option<f64>,
}

/// What a file given to `coherent view` holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Holds {
    /// An episode's transcript (its first line is the header).
    Transcript,
    /// A benchmark's results, one line per episode.
    Results,
}

/// Whether `path` is a transcript or a results file, by its first line (read within the
/// transcript's limit: a header line is the longest first line either may have).
pub fn holds(path: &Path, limits: ReadLimits) -> Result<Holds, String> {
    let limit = transcript::limit(limits.transcript_bytes);
    let mut lines = Lines::open(path, limit, limit).map_err(|e| e.to_string())?;
    while let Some(line) = lines.next_line().map_err(|e| e.to_string())? {
        if line.bytes.trim_ascii().is_empty() {
            continue;
        }
        let first: serde_json::Value = serde_json::from_slice(line.bytes)
            .map_err(|e| format!("{}: line 1: not JSON: {e}", path.display()))?;
        return Ok(
            if first.get("type").and_then(|t| t.as_str()) == Some("header") {
                Holds::Transcript
            } else {
                Holds::Results
            },
        );
    }
    Err(format!(
        "{}: empty: neither a transcript nor results",
        path.display()
    ))
}

/// A recorded episode read from `path` (a transcript of at most `max_bytes`): its task
/// and transcript.
pub fn read_episode(path: &Path, max_bytes: u64) -> Result<(Arc<Task>, Transcript), String> {
    let recorded = super::episode::recorded(path, max_bytes).map_err(|e| e.to_string())?;
    Ok((recorded.task, recorded.transcript))
}

/// The page of one episode.
pub fn episode_html(e: &Shown<'_>) -> Result<String, String> {
    let mut view = episode::view(e.task, e.transcript, e.cost_usd, "a-");
    let title = format!(
        "{} · {} · coherent view",
        view.header.task, view.header.method
    );
    let pictures = pictures(&mut view, "a-");
    let data = Episodes {
        kind: "episode",
        first_difference: None,
        episodes: vec![view],
    };
    page::html(&title, &data, &pictures, Script::Episode, Origin::File)
}

/// The page of two episodes side by side, stepping together, the first round where
/// their decisions differ marked.
pub fn compare_html(a: &Shown<'_>, b: &Shown<'_>) -> Result<String, String> {
    let first_difference = compare::first_difference(a.transcript, b.transcript);
    let mut va = episode::view(a.task, a.transcript, a.cost_usd, "a-");
    let mut vb = episode::view(b.task, b.transcript, b.cost_usd, "b-");
    let title = format!(
        "{} · {} and {} · coherent view",
        va.header.task, va.header.method, vb.header.method
    );
    let mut pictures = pictures(&mut va, "a-");
    pictures.extend(self::pictures(&mut vb, "b-"));
    let data = Episodes {
        kind: "compare",
        first_difference,
        episodes: vec![va, vb],
    };
    page::html(&title, &data, &pictures, Script::Episode, Origin::File)
}

/// An episode's pictures, taken out of its data, with their `<template>` ids:
/// `{ids}picture-{k}`.
fn pictures(view: &mut episode::EpisodeView, ids: &str) -> Vec<(String, String)> {
    std::mem::take(&mut view.scene.pictures)
        .into_iter()
        .enumerate()
        .map(|(k, svg)| (format!("{ids}picture-{k}"), svg))
        .collect()
}

/// The index page of `lines`, read from `file`; `links[i]`, when there is one, is the
/// page of line i's episode; `live`, the file's length when served (the page then
/// follows the file).
pub fn results_html(
    file: &Path,
    lines: &[ResultLine],
    links: &[Option<String>],
    live: Option<u64>,
) -> Result<String, String> {
    let origin = if live.is_some() {
        Origin::Served
    } else {
        Origin::File
    };
    let view = results::view(file, lines, links, live);
    let title = format!(
        "{} · coherent view",
        shown(
            &file
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
        )
    );
    page::html(&title, &view, &[], Script::Results, origin)
}

/// The page of a results line's episode, from its transcript of at most `max_bytes`
/// (priced as the line).
pub fn line_html(results: &Path, line: &ResultLine, max_bytes: u64) -> Result<String, String> {
    let path = results::transcript_of(results, line).ok_or_else(|| {
        format!(
            "{}: the transcript {} is not there",
            results.display(),
            shown(&line.transcript)
        )
    })?;
    let (task, t) = read_episode(&path, max_bytes)?;
    episode_html(&Shown {
        task: &task,
        transcript: &t,
        cost_usd: line.cost_usd,
    })
}

/// What [`results_site`] wrote.
#[derive(Debug)]
pub struct Site {
    pub index: PathBuf,
    pub pages: usize,
    /// Episodes without a page, and why (a transcript missing or unreadable).
    pub missing: Vec<String>,
}

/// Writes the index of the results file `results` to `dir/index.html` and each
/// episode's page under `dir/episodes/`, `threads` pages at once, reading each file
/// within `limits`.
pub fn results_site(
    results: &Path,
    dir: &Path,
    threads: usize,
    limits: ReadLimits,
) -> Result<Site, String> {
    let lines = read_results_within(results, limits.results_bytes)
        .map_err(|e| e.to_string())?
        .lines;
    let written: Vec<std::sync::Mutex<Option<Result<(), String>>>> =
        lines.iter().map(|_| std::sync::Mutex::new(None)).collect();
    let next = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(line) = lines.get(i) else { break };
                    let done = line_html(results, line, limits.transcript_bytes).and_then(|html| {
                        let path = dir.join(results::page_name(line));
                        write(&path, &html)
                    });
                    if let Ok(mut slot) = written[i].lock() {
                        *slot = Some(done);
                    }
                }
            });
        }
    });
    let outcome: Vec<Result<(), String>> = written
        .into_iter()
        .map(|m| {
            m.into_inner()
                .ok()
                .flatten()
                .unwrap_or_else(|| Err("not written".into()))
        })
        .collect();
    let links: Vec<Option<String>> = lines
        .iter()
        .zip(&outcome)
        .map(|(l, o)| o.is_ok().then(|| results::page_name(l)))
        .collect();
    let index = dir.join("index.html");
    write(&index, &results_html(results, &lines, &links, None)?)?;
    Ok(Site {
        index,
        pages: outcome.iter().filter(|o| o.is_ok()).count(),
        missing: lines
            .iter()
            .zip(&outcome)
            .filter_map(|(l, o)| {
                o.as_ref().err().map(|why| {
                    format!(
                        "{} {} task {} seed {}: {why}",
                        shown(&l.method),
                        shown(&l.scene),
                        l.task_id,
                        l.seed
                    )
                })
            })
            .collect(),
    })
}

/// Writes `text` to `path`, making its folder.
pub fn write(path: &Path, text: &str) -> Result<(), String> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}
