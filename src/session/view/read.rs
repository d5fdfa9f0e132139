//! Reading what a view is given: whether a file is a transcript or a results file, and
//! an episode read from its transcript to show, whole rounds kept when its last line
//! was cut.

use std::path::Path;
use std::sync::Arc;

use coherent_agents::bench::ReadLimits;
use coherent_agents::run::replay::recorded_task;
use coherent_agents::transcript;
use coherent_core::files::{Lines, Opens};

use super::episode::Given;
use crate::session::{Error, Result};

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
pub fn holds(path: &Path, limits: ReadLimits, opens: Opens) -> Result<Holds> {
    let limit = transcript::limit(limits.transcript_bytes);
    let file_error = |message: String, line: Option<usize>| Error::File {
        file: path.display().to_string(),
        line,
        message,
    };
    let mut lines = Lines::open_as(path, limit, limit, opens).map_err(agents_error)?;
    while let Some(line) = lines.next_line().map_err(agents_error)? {
        if line.bytes.trim_ascii().is_empty() {
            continue;
        }
        let first: serde_json::Value = serde_json::from_slice(line.bytes)
            .map_err(|e| file_error(format!("not JSON: {e}"), Some(line.number)))?;
        return Ok(
            if first.get("type").and_then(|t| t.as_str()) == Some("header") {
                Holds::Transcript
            } else {
                Holds::Results
            },
        );
    }
    Err(file_error(
        "empty: neither a transcript nor results".into(),
        None,
    ))
}

/// A file error of coherent-core, as the session's.
fn agents_error(e: coherent_core::Error) -> Error {
    coherent_agents::Error::file(e).into()
}

/// The episode recorded in the transcript `path` (of at most `max_bytes`, opened only
/// as `opens` allows), with its whole lines when the last one was cut.
pub fn read_episode(path: &Path, max_bytes: u64, opens: Opens) -> Result<Given> {
    let read = transcript::read_to_show(path, max_bytes, opens)?;
    let task = Arc::new(recorded_task(&read.transcript, path)?);
    Ok(Given {
        task,
        transcript: read.transcript,
        cost_usd: None,
        cut: read.cut,
    })
}
