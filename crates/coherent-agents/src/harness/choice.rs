//! Which backend answers a benchmark's model-using methods, and the earlier run a replay
//! answers from.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_core::planner::Limits;

use crate::backends::builtin::BuiltinBackend;
use crate::backends::llm::{Backend, BackendInfo};
use crate::backends::openai::OpenAiClient;
use crate::backends::simulated::ErrorRates;
use crate::harness::results::{EpisodeKey, ReadLimits, read_results_within};
use crate::records::transcript;

/// Which backend answers the model-using methods.
#[derive(Clone, Debug)]
pub enum BackendChoice {
    /// The optimal planner in every role.
    Builtin,
    /// The planner with seeded mistakes; each episode gets its own seed.
    Simulated(ErrorRates),
    /// One client shared by every episode (its own concurrency limit holds across them).
    OpenAi(Arc<OpenAiClient>),
    /// The transcripts of an earlier run: each episode answers from the recording with
    /// its method, task and seed, with the recorded settings, and must come out the same.
    Replay(Arc<Recorded>),
}

/// An earlier run's finished episodes, by key: the transcripts a replay answers from.
#[derive(Debug)]
pub struct Recorded {
    /// The earlier results file.
    pub results: PathBuf,
    pub transcripts: HashMap<EpisodeKey, PathBuf>,
    /// The backend of the recordings (the first one's, when they differ).
    pub backend: BackendInfo,
    /// The most each transcript may hold.
    pub max_transcript_bytes: u64,
}

impl Recorded {
    /// The final episodes of the results file `results`, read within `limits`.
    pub fn read(results: &Path, limits: ReadLimits) -> Result<Recorded, String> {
        let file = read_results_within(results, limits.results_bytes)?;
        let mut backend = None;
        let mut transcripts = HashMap::new();
        for line in file.lines.iter().filter(|l| l.is_final()) {
            if line.uses_model {
                backend.get_or_insert_with(|| line.backend.clone());
            }
            transcripts.insert(line.key(), PathBuf::from(&line.transcript));
        }
        if transcripts.is_empty() {
            return Err(format!(
                "{}: no finished episodes to replay",
                results.display()
            ));
        }
        // Checked before any episode starts: a transcript that is gone, is no regular
        // file (a device that never ends) or holds too much would stop the run midway.
        let limit = transcript::limit(limits.transcript_bytes);
        for path in transcripts.values() {
            let meta = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?;
            if !meta.is_file() {
                return Err(format!(
                    "{}: not a regular file (a device? a folder?): a transcript must be one",
                    path.display()
                ));
            }
            if meta.len() > limit.bytes {
                return Err(limit.exceeded(path).to_string());
            }
        }
        Ok(Recorded {
            results: results.to_owned(),
            transcripts,
            max_transcript_bytes: limits.transcript_bytes,
            backend: backend.unwrap_or(BackendInfo {
                kind: "none".into(),
                model: String::new(),
                base_url: None,
            }),
        })
    }
}

impl BackendChoice {
    /// The backend of one episode with seed `seed` (the simulated backend's mistakes are
    /// seeded per episode); `None` for a replay, whose backend depends on the episode's
    /// recording.
    pub fn for_episode(&self, limits: &Limits, seed: u64) -> Option<Arc<dyn Backend>> {
        Some(match self {
            BackendChoice::Builtin => Arc::new(BuiltinBackend::new(limits.clone())),
            BackendChoice::Simulated(rates) => {
                Arc::new(BuiltinBackend::simulated(limits.clone(), *rates, seed))
            }
            BackendChoice::OpenAi(client) => Arc::clone(client) as Arc<dyn Backend>,
            BackendChoice::Replay(_) => return None,
        })
    }

    pub fn info(&self) -> BackendInfo {
        match self {
            BackendChoice::Builtin => BuiltinBackend::new(Limits::default()).info(),
            BackendChoice::Simulated(rates) => {
                BuiltinBackend::simulated(Limits::default(), *rates, 0).info()
            }
            BackendChoice::OpenAi(client) => client.info(),
            BackendChoice::Replay(recorded) => BackendInfo {
                kind: "replay".into(),
                model: recorded.backend.model.clone(),
                base_url: None,
            },
        }
    }
}
