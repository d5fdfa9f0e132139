//! The pages, data in and HTML out: an episode's, two side by side, a results file's
//! index; and how a front end is told how far a long one is.

use std::path::Path;

use coherent_agents::bench::ResultLine;
use coherent_core::text::shown;

use super::compare::{self, Episodes};
use super::episode::{self, Given};
use super::page::{self, Origin, Script};
use super::results;
use crate::session::Result;

/// How far a view is, for a front end to show while it works.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Rounds of the episodes on the page followed so far, of all.
    Rounds { done: usize, of: usize },
    /// Pages of a results file's episodes written so far, of all.
    Pages { done: usize, of: usize },
}

/// Told how far a view is; `&|_| {}` for no one.
pub type Tell<'a> = &'a (dyn Fn(Progress) + Sync);

/// The page of one episode.
pub fn episode_html(e: &Given, tell: Tell<'_>) -> Result<String> {
    let mut view = episode::view(e, "a-", &mut |done, of| {
        tell(Progress::Rounds { done, of });
    });
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

/// The page of two episodes of one task side by side, stepping together, the first
/// round where their decisions differ marked.
pub fn compare_html(a: &Given, b: &Given, tell: Tell<'_>) -> Result<String> {
    let first_difference = compare::first_difference(&a.transcript, &b.transcript);
    // One count over both: the second episode's rounds follow the first's.
    let of = a.transcript.rounds.len() + b.transcript.rounds.len();
    let mut va = episode::view(a, "a-", &mut |done, _| {
        tell(Progress::Rounds { done, of });
    });
    let before = a.transcript.rounds.len();
    let mut vb = episode::view(b, "b-", &mut |done, _| {
        tell(Progress::Rounds {
            done: before + done,
            of,
        });
    });
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
) -> Result<String> {
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
