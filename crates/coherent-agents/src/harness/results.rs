//! The results file of a benchmark run: one JSON line per finished episode, read back
//! with errors that point at the bad line and field, repaired after a crash that cut
//! the last line short.

use std::collections::HashSet;
use std::fs::OpenOptions;
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use coherent_core::Execution;
use coherent_core::files::{Limit, Lines, MIB, Opens};
use coherent_core::text::shown;
use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::harness::prices::PriceTable;
use crate::harness::run_settings::RunSettings;
use crate::llm::{BackendInfo, Usage};
use crate::records::lock;
use crate::records::transcript::{Reference, Status};

/// One finished episode: a line of the results file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResultLine {
    pub method: String,
    /// `sequential` (lines written before parallel episodes have none) or `parallel`.
    #[serde(default)]
    pub execution: Execution,
    pub scene: String,
    pub task_id: i64,
    /// `mono`, `dual` or `trio`; null when the planner finds no plan.
    pub task_type: Option<String>,
    /// The robots of the task's team; null in lines written before it was kept.
    #[serde(default)]
    pub team_size: Option<u32>,
    /// The seed index (0-based).
    pub seed: u32,
    /// The seed the episode actually ran with, derived from the index, method and task.
    #[serde(default)]
    pub episode_seed: u64,
    pub success: bool,
    pub status: Status,
    pub steps: u32,
    pub gt_steps: Option<u32>,
    #[serde(default)]
    pub optimal_steps: Option<u32>,
    pub max_steps: u32,
    /// The joint steps the episode took to reach the goal (its steps, one action each in a
    /// sequential episode); null when it did not reach it.
    #[serde(default)]
    pub makespan: Option<u32>,
    /// The fewest joint steps of the task, by the makespan search (the best plan's when
    /// the search stops before proving it); null in a run without parallel episodes, or
    /// when no plan is found.
    #[serde(default)]
    pub optimal_makespan: Option<u32>,
    /// The actions carried out; null in lines written before it was kept.
    #[serde(default)]
    pub actions: Option<u32>,
    pub llm_calls: u32,
    pub prompt_tokens: u64,
    pub completion_tokens: u64,
    /// The part of `prompt_tokens` read from the server's prompt cache.
    #[serde(default)]
    pub cached_tokens: u64,
    /// What the model calls cost in USD ([`ResultLine::priced`]); null when the model has
    /// no price.
    #[serde(default)]
    pub cost_usd: Option<f64>,
    pub wall_ms: f64,
    /// The simulated seconds the episode took (physics); null otherwise.
    #[serde(default)]
    pub sim_seconds: Option<f64>,
    /// The run's backend (even for a method that asks no model; see `uses_model`).
    pub backend: BackendInfo,
    #[serde(default = "yes")]
    pub uses_model: bool,
    #[serde(default)]
    pub error: Option<String>,
    pub transcript: String,
    /// The settings the episode ran with, which lines must share to be compared (absent
    /// from lines written before they were kept).
    #[serde(default)]
    pub settings: Option<RunSettings>,
    /// What an episode with events is measured against, and how the team recovered
    /// (docs/dynamic.md); absent without events.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<Reference>,
}

fn yes() -> bool {
    true
}

impl ResultLine {
    /// Whether the episode ended in a way that counts: success, budget spent, or a goal
    /// an event put out of reach, conceded.
    pub fn is_final(&self) -> bool {
        matches!(
            self.status,
            Status::Success | Status::Failure | Status::Conceded
        )
    }

    /// Whether the episode failed with an error its line names and has no final result:
    /// the method's own (status `error`), or why it could not go on (status
    /// `interrupted` with an `error`: a robot that stopped answering, a transcript that
    /// could not be created). Not a backend's failure, not Ctrl-C. The report lists
    /// these episodes.
    pub fn failed_with_error(&self) -> bool {
        match self.status {
            Status::Error => true,
            Status::Interrupted => self.error.is_some(),
            Status::Success | Status::Failure | Status::BackendError | Status::Conceded => false,
        }
    }

    /// The episode in words, as progress lines and warnings name it: `pefa demo-apartment
    /// task 0 seed 1`, the names from the file shown as on a terminal.
    pub fn episode(&self) -> String {
        format!(
            "{} {} task {} seed {}",
            shown(&self.method),
            shown(&self.scene),
            self.task_id,
            self.seed
        )
    }

    /// The line with its `cost_usd` from `prices` ([`PriceTable::episode_cost`] of its
    /// backend's model and its tokens).
    pub fn priced(mut self, prices: &PriceTable) -> ResultLine {
        let usage = Usage {
            prompt_tokens: self.prompt_tokens,
            completion_tokens: self.completion_tokens,
            cached_tokens: self.cached_tokens,
        };
        self.cost_usd = prices.episode_cost(&self.backend.model, self.uses_model, &usage);
        self
    }

    pub fn key(&self) -> EpisodeKey {
        EpisodeKey {
            method: self.method.clone(),
            scene: self.scene.clone(),
            task_id: self.task_id,
            seed: self.seed,
            execution: self.execution,
        }
    }
}

/// What identifies an episode across runs.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EpisodeKey {
    pub method: String,
    pub scene: String,
    pub task_id: i64,
    pub seed: u32,
    pub execution: Execution,
}

/// A results file as read.
#[derive(Debug, Default)]
pub struct ResultsFile {
    pub lines: Vec<ResultLine>,
    /// Bytes of a last line cut off mid-write (0 when none); [`repair`] drops them.
    pub truncated_bytes: u64,
    /// Length of the well-formed part.
    pub good_len: u64,
}

/// The most a results file may hold unless told otherwise: about a million episodes'
/// lines.
pub const DEFAULT_MAX_BYTES: u64 = 1024 * MIB;

/// The most one line of a results file may hold: a line is well under 2 KiB, its error
/// cut at [`ERROR_BYTES`] when it is written.
pub const MAX_LINE_BYTES: u64 = MIB;

/// The most of an episode's error a results line keeps (the transcript has all of it).
pub const ERROR_BYTES: usize = 64 << 10;

/// How much a run may read back of the files it was given: its results file (to resume,
/// to replay from, to report) and each transcript it replays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReadLimits {
    pub results_bytes: u64,
    pub transcript_bytes: u64,
}

impl Default for ReadLimits {
    fn default() -> ReadLimits {
        ReadLimits {
            results_bytes: DEFAULT_MAX_BYTES,
            transcript_bytes: crate::records::transcript::DEFAULT_MAX_BYTES,
        }
    }
}

/// The limits of a results file of at most `bytes`.
fn limits(bytes: u64) -> (Limit, Limit) {
    let line = Limit {
        bytes: MAX_LINE_BYTES,
        what: "a results file",
        raise: None,
    };
    let total = Limit {
        bytes,
        what: "a results file",
        raise: Some("--max-results-mib"),
    };
    (line, total)
}

/// Reads a results file of at most [`DEFAULT_MAX_BYTES`] ([`read_results_within`]).
pub fn read_results(path: &Path) -> Result<ResultsFile, Error> {
    read_results_within(path, DEFAULT_MAX_BYTES)
}

/// Reads a results file of at most `max_bytes`. A last line without its newline that
/// does not parse is a write cut short (reported in `truncated_bytes`); any other bad
/// line is an error naming the file, the line and the JSON path.
pub fn read_results_within(path: &Path, max_bytes: u64) -> Result<ResultsFile, Error> {
    read_results_opening(path, max_bytes, Opens::Anything)
}

/// [`read_results_within`], opening only what `opens` allows.
pub fn read_results_opening(
    path: &Path,
    max_bytes: u64,
    opens: Opens,
) -> Result<ResultsFile, Error> {
    let (line_limit, total) = limits(max_bytes);
    let mut lines = Lines::open_as(path, line_limit, total, opens).map_err(Error::file)?;
    let mut out = ResultsFile::default();
    while let Some(line) = lines.next_line().map_err(Error::file)? {
        let parsed = std::str::from_utf8(line.bytes)
            .map_err(|e| e.to_string())
            .and_then(|s| {
                if s.trim().is_empty() {
                    return Ok(None);
                }
                let de = &mut serde_json::Deserializer::from_str(s);
                parse_line(de).map(Some)
            });
        match parsed {
            Ok(parsed) => {
                out.lines.extend(parsed);
                // A complete record missing only its newline is kept; repair adds it.
                out.good_len = line.end();
            }
            Err(_) if !line.complete() => {
                out.truncated_bytes = line.bytes.len() as u64;
            }
            Err(e) => return Err(Error::at_line(path, line.number, e)),
        }
    }
    Ok(out)
}

fn parse_line(
    de: &mut serde_json::Deserializer<serde_json::de::StrRead<'_>>,
) -> Result<ResultLine, String> {
    // A key twice in one object is refused: serde_json alone would keep the last one.
    let value = coherent_core::json::value(&mut *de).map_err(|e| format!("invalid JSON: {e}"))?;
    de.end().map_err(|e| format!("invalid JSON: {e}"))?;
    serde_json::from_value::<ResultLine>(value.clone()).map_err(|e| {
        // Name the field: serde_json's messages say what, not where.
        let field = missing_or_bad_field(&value);
        format!("{e}{field}")
    })
}

/// ` (at $.field)` for the first field of a results line that is absent or has the
/// wrong JSON type, to point at the culprit.
fn missing_or_bad_field(value: &serde_json::Value) -> String {
    use serde_json::Value as V;
    let Some(map) = value.as_object() else {
        return " (at $: expected an object)".into();
    };
    type Check = fn(&V) -> bool;
    let expect: [(&str, Check); 14] = [
        ("method", V::is_string),
        ("scene", V::is_string),
        ("task_id", V::is_i64),
        ("seed", V::is_u64),
        ("success", V::is_boolean),
        ("status", V::is_string),
        ("steps", V::is_u64),
        ("max_steps", V::is_u64),
        ("llm_calls", V::is_u64),
        ("prompt_tokens", V::is_u64),
        ("completion_tokens", V::is_u64),
        ("wall_ms", V::is_number),
        ("backend", V::is_object),
        ("transcript", V::is_string),
    ];
    for (name, ok) in expect {
        match map.get(name) {
            None => return format!(" (at $.{name}: missing)"),
            Some(v) if !ok(v) => return format!(" (at $.{name}: found {v})"),
            Some(_) => {}
        }
    }
    String::new()
}

/// Cuts a results file back to its well-formed part and ends it with a newline, so
/// that appended lines start on their own line.
pub fn repair(path: &Path, file: &ResultsFile) -> Result<(), Error> {
    let io = |e: io::Error| Error::io(path, &e);
    let mut f = OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .map_err(io)?;
    f.set_len(file.good_len).map_err(io)?;
    if file.good_len > 0 {
        f.seek(SeekFrom::Start(file.good_len - 1)).map_err(io)?;
        let mut last = [0u8];
        f.read_exact(&mut last).map_err(io)?;
        if last[0] != b'\n' {
            f.seek(SeekFrom::End(0)).map_err(io)?;
            f.write_all(b"\n").map_err(io)?;
        }
    }
    f.flush().map_err(io)
}

/// Renames to `*.jsonl.unfinished` every transcript under [`transcripts_dir`] of `out`
/// that none of `lines` points to: an episode killed mid-run (or between its last round
/// and its results line) left it, and the episode runs again. A transcript whose writer
/// still holds it (an episode running in another process) is left alone. Returns the
/// new names.
pub fn mark_orphans(out: &Path, lines: &[ResultLine]) -> Result<Vec<PathBuf>, Error> {
    let dir = transcripts_dir(out);
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    // By the file itself, whatever spelling of the folder the lines were written with.
    let pointed: HashSet<PathBuf> = lines
        .iter()
        .filter_map(|l| Path::new(&l.transcript).canonicalize().ok())
        .collect();
    let io = |p: &Path, e: io::Error| Error::io(p, &e);
    let mut marked = Vec::new();
    let mut folders = vec![dir];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).map_err(|e| io(&folder, e))? {
            let path = entry.map_err(|e| io(&folder, e))?.path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|x| x == "jsonl")
                && !pointed.contains(&path.canonicalize().map_err(|e| io(&path, e))?)
                && !being_written(&path).map_err(|e| io(&path, e))?
            {
                let mut renamed = path.clone().into_os_string();
                renamed.push(".unfinished");
                let renamed = PathBuf::from(renamed);
                std::fs::rename(&path, &renamed).map_err(|e| io(&path, e))?;
                marked.push(renamed);
            }
        }
    }
    marked.sort();
    Ok(marked)
}

/// Whether the transcript at `path` is locked by its writer, which is still running.
fn being_written(path: &Path) -> io::Result<bool> {
    let file = std::fs::File::open(path)?;
    // Taken and, as the file closes, released at once: only a writer's lock stays.
    Ok(!lock::try_exclusive(&file)?)
}

/// `results.jsonl` -> `results.transcripts/`, next to it.
pub fn transcripts_dir(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map_or_else(|| "results".into(), |s| s.to_string_lossy().into_owned());
    out.with_file_name(format!("{stem}.transcripts"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transcripts_sit_next_to_the_results() {
        assert_eq!(
            transcripts_dir(Path::new("out/results.jsonl")),
            Path::new("out/results.transcripts")
        );
    }
}
