//! A benchmark's results as a page: the report's tables (`coherent_agents::report`, the
//! numbers `coherent bench --report` and `coherent.report` give), the figures the page
//! draws from them, and every episode with a link to its own page.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use coherent_agents::bench::{ResultLine, transcripts_dir};
use coherent_agents::report::{self, Report};
use coherent_core::text::{file_name_part, shown};
use serde::Serialize;

/// The index page's data.
#[derive(Debug, Serialize)]
pub struct ResultsView {
    pub kind: &'static str,
    /// The results file, as named.
    pub file: String,
    pub report: Report,
    pub episodes: Vec<Row>,
    /// Served on loopback: the file's length when read, which the page compares with
    /// the server's to follow the file as it grows; none for a page on disk.
    pub live: Option<u64>,
}

/// One episode (a results line).
#[derive(Debug, Serialize)]
pub struct Row {
    pub method: String,
    pub scene: String,
    pub task_id: i64,
    pub task_type: Option<String>,
    pub seed: u32,
    pub status: String,
    pub success: bool,
    pub steps: u32,
    pub gt_steps: Option<u32>,
    pub max_steps: u32,
    pub llm_calls: u32,
    pub tokens: u64,
    pub cost_usd: Option<f64>,
    pub wall_ms: f64,
    pub error: Option<String>,
    /// Its page, relative to the index; none when its transcript is not at hand.
    pub link: Option<String>,
    /// What an episode with events is measured against (docs/dynamic.md); absent
    /// without events.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference: Option<RowReference>,
}

/// An episode's reference, as its row shows it.
#[derive(Debug, Serialize)]
pub struct RowReference {
    /// The reference's steps; none when the goal is out of reach or its optimum unknown.
    pub steps: Option<u32>,
    /// Why the goal is out of reach for good, when it is.
    pub unreachable: Option<String>,
}

/// The lines with every name from the file shown as on a terminal, so that the tables
/// group and name them as the page shows them.
fn shown_lines(lines: &[ResultLine]) -> Vec<ResultLine> {
    lines
        .iter()
        .map(|l| ResultLine {
            method: shown(&l.method).into_owned(),
            scene: shown(&l.scene).into_owned(),
            task_type: l.task_type.as_deref().map(|t| shown(t).into_owned()),
            ..l.clone()
        })
        .collect()
}

/// The page's data for `lines` of the results file `file`; `links[i]` is line i's
/// episode page, when it has one.
pub fn view(
    file: &Path,
    lines: &[ResultLine],
    links: &[Option<String>],
    live: Option<u64>,
) -> ResultsView {
    let named = shown_lines(lines);
    let episodes = named
        .iter()
        .enumerate()
        .map(|(i, l)| Row {
            method: l.method.clone(),
            scene: l.scene.clone(),
            task_id: l.task_id,
            task_type: l.task_type.clone(),
            seed: l.seed,
            status: serde_json::to_value(l.status)
                .ok()
                .and_then(|v| v.as_str().map(str::to_owned))
                .unwrap_or_default(),
            success: l.success,
            steps: l.steps,
            gt_steps: l.gt_steps,
            max_steps: l.max_steps,
            llm_calls: l.llm_calls,
            tokens: l.prompt_tokens + l.completion_tokens,
            cost_usd: l.cost_usd,
            wall_ms: l.wall_ms,
            error: l.error.as_deref().map(|e| shown(e).into_owned()),
            link: links.get(i).cloned().flatten(),
            reference: l.reference.as_ref().map(|r| RowReference {
                steps: r.steps,
                unreachable: r.unreachable.as_deref().map(|u| shown(u).into_owned()),
            }),
        })
        .collect();
    // The tables of one run: a file that holds several (written by an earlier version,
    // or put together by hand) shows those of its last, whose settings the report has.
    let runs = report::groups(&named);
    let last = runs.last().map_or(&[][..], |run| run.lines.as_slice());
    ResultsView {
        kind: "results",
        file: shown(&file.display().to_string()).into_owned(),
        report: report::build(last).unwrap_or_else(|_| report::empty()),
        episodes,
        live,
    }
}

/// Where the transcript of `line` is: as the line names it, else in the transcripts
/// folder beside `results` (a results folder moved or viewed from elsewhere).
pub fn transcript_of(results: &Path, line: &ResultLine) -> Option<PathBuf> {
    let named = PathBuf::from(&line.transcript);
    if named.is_file() {
        return Some(named);
    }
    let file = named.file_name()?;
    let seed = named.parent().and_then(Path::file_name)?;
    let beside = transcripts_dir(results).join(seed).join(file);
    beside.is_file().then_some(beside)
}

/// Each line's page, relative to the index: `episodes/<seed folder>/<the transcript's
/// name>.html`, the name made of safe characters and at most 200 bytes
/// ([`file_name_part`]: a name from the file never leaves the folder nor is too long
/// for it). Two transcripts of one name (in two folders) get two pages: the later
/// line's name ends in `-2` (`-3`, ...), counted in the order of the lines, so that a
/// page keeps its name while the file grows.
pub fn page_names(lines: &[ResultLine]) -> Vec<String> {
    let mut taken = HashSet::new();
    lines
        .iter()
        .map(|line| {
            let stem = Path::new(&line.transcript)
                .file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
            let stem = file_name_part(&stem, MAX_PAGE_NAME);
            let mut name = format!("episodes/seed{}/{stem}.html", line.seed);
            let mut k = 1;
            while !taken.insert(name.clone()) {
                k += 1;
                name = format!("episodes/seed{}/{stem}-{k}.html", line.seed);
            }
            name
        })
        .collect()
}

/// The longest page name, in bytes, short of the usual 255 with room for a count and
/// `.html`.
const MAX_PAGE_NAME: usize = 200;
