//! Which backend answers the model's roles, chosen once for `run`, `bench` and Python
//! alike: the built-in planner, the simulated backend (the planner with seeded mistakes),
//! an OpenAI-compatible endpoint, or the transcripts of an earlier benchmark; and each
//! episode's own backend of that choice. The endpoint's settings are what a front end
//! was told (flags, keyword arguments), completed from the environment
//! (`OPENAI_BASE_URL`, `OPENAI_API_KEY`, `COHERENT_MODEL`; [`complete`]); several base
//! URLs serve one model from several servers (the client spreads the requests over
//! them).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::backends::address::redacted;
use coherent_agents::bench::{EpisodeKey, ReadLimits, read_results_within};
use coherent_agents::llm::Backend;
use coherent_agents::transcript;
use coherent_agents::{ApiKey, OpenAiConfig};
use coherent_agents::{BackendInfo, BackendKind, BuiltinBackend, ErrorRates, OpenAiClient};
use coherent_core::planner::Limits;

use crate::session::error::{BackendProblem, Error};

/// The backend a front end names; `Auto` picks the simulated backend when error rates
/// are given, else the endpoint when one is configured, else the built-in planner.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BackendName {
    #[default]
    Auto,
    Builtin,
    Simulated,
    OpenAi,
    Replay,
}

/// Where the model endpoint's settings come from.
#[derive(Clone, Debug, Default)]
pub enum EndpointSource {
    /// No endpoint.
    #[default]
    None,
    /// A client already made (Python's `LLM`): the episodes ask through it, so that they
    /// and the calls a method makes through the same `LLM` share one client and its
    /// limit on requests in flight.
    Client(Arc<OpenAiClient>),
    /// These settings, what they leave unset taken from the environment ([`complete`]);
    /// no endpoint when neither configures one (the command line's flags).
    WithEnvironment(OpenAiConfig),
}

/// Two sources are the same when they configure the same: one client (the very one), or
/// equal settings.
impl PartialEq for EndpointSource {
    fn eq(&self, other: &EndpointSource) -> bool {
        match (self, other) {
            (EndpointSource::None, EndpointSource::None) => true,
            (EndpointSource::Client(a), EndpointSource::Client(b)) => Arc::ptr_eq(a, b),
            (EndpointSource::WithEnvironment(a), EndpointSource::WithEnvironment(b)) => a == b,
            _ => false,
        }
    }
}

/// Everything that decides the backend.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BackendRequest {
    pub name: BackendName,
    pub endpoint: EndpointSource,
    /// The simulated backend's error rates.
    pub sim_errors: Option<ErrorRates>,
    /// An earlier results file whose transcripts a replay answers from.
    pub replay_from: Option<PathBuf>,
    /// How much of that results file and of each transcript may be read.
    pub limits: ReadLimits,
}

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
    Replay(Arc<RecordedRun>),
}

/// An earlier run's finished episodes, by key: the transcripts a replay answers from.
#[derive(Debug)]
pub struct RecordedRun {
    /// The earlier results file.
    pub results: PathBuf,
    pub transcripts: HashMap<EpisodeKey, PathBuf>,
    /// The backend of the recordings (the first one's, when they differ).
    pub backend: BackendInfo,
    /// The most each transcript may hold.
    pub max_transcript_bytes: u64,
}

impl RecordedRun {
    /// The names of the methods it recorded, sorted.
    pub fn methods(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self.transcripts.keys().map(|k| k.method.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        names
    }

    /// The final episodes of the results file `results`, read within `limits`; every
    /// transcript they name is checked before any episode starts: a transcript that is
    /// gone, no regular file (a device that never ends) or too large would stop the run
    /// midway.
    pub fn read(results: &Path, limits: ReadLimits) -> Result<RecordedRun, Error> {
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
            return Err(Error::File {
                file: results.display().to_string(),
                line: None,
                message: "no finished episodes to replay".into(),
            });
        }
        let limit = transcript::limit(limits.transcript_bytes);
        for path in transcripts.values() {
            let meta = std::fs::metadata(path).map_err(|e| Error::File {
                file: path.display().to_string(),
                line: None,
                message: e.to_string(),
            })?;
            if !meta.is_file() {
                return Err(Error::File {
                    file: path.display().to_string(),
                    line: None,
                    message: "not a regular file (a device? a folder?): a transcript must be one"
                        .into(),
                });
            }
            if meta.len() > limit.bytes {
                return Err(coherent_agents::Error::file(limit.exceeded(path)).into());
            }
        }
        Ok(RecordedRun {
            results: results.to_owned(),
            transcripts,
            backend: backend.unwrap_or_else(BackendInfo::none),
            max_transcript_bytes: limits.transcript_bytes,
        })
    }
}

impl BackendRequest {
    /// The backend these settings ask for.
    pub fn choose(self) -> Result<BackendChoice, Error> {
        let (endpoint, client) = match self.endpoint {
            EndpointSource::None => (None, None),
            EndpointSource::Client(c) => (Some(c.config().clone()), Some(c)),
            EndpointSource::WithEnvironment(config) => (complete(config)?, None),
        };
        let name = match self.name {
            BackendName::Auto => match (&self.sim_errors, &endpoint) {
                (Some(_), Some(_)) => return Err(BackendProblem::RatesAndEndpoint.into()),
                (Some(_), None) => BackendName::Simulated,
                (None, Some(_)) => BackendName::OpenAi,
                (None, None) => BackendName::Builtin,
            },
            n => n,
        };
        if self.sim_errors.is_some() && name != BackendName::Simulated {
            return Err(BackendProblem::RatesNeedSimulated.into());
        }
        match (name, self.replay_from) {
            (BackendName::Replay, Some(file)) => Ok(BackendChoice::Replay(Arc::new(
                RecordedRun::read(&file, self.limits)?,
            ))),
            (BackendName::Replay, None) => Err(BackendProblem::ReplayNeedsFile.into()),
            (_, Some(_)) => Err(BackendProblem::FileNeedsReplay.into()),
            (BackendName::Simulated, None) => Ok(BackendChoice::Simulated(
                self.sim_errors.unwrap_or_default(),
            )),
            (BackendName::OpenAi, None) => {
                if let Some(client) = client {
                    return Ok(BackendChoice::OpenAi(client));
                }
                let config = endpoint.ok_or(BackendProblem::NoEndpoint)?;
                OpenAiClient::new(config)
                    .map(|c| BackendChoice::OpenAi(Arc::new(c)))
                    .map_err(|e| Error::Endpoint(e.to_string()))
            }
            (BackendName::Auto | BackendName::Builtin, None) => Ok(BackendChoice::Builtin),
        }
    }
}

/// `config` with what it leaves unset taken from the environment: the base URLs (each
/// given one may be a comma-separated list), the key and the model. An endpoint is
/// configured by a base URL, or by a key and a model (then OpenAI's own endpoint);
/// `None` when there is none.
pub fn complete(mut config: OpenAiConfig) -> Result<Option<OpenAiConfig>, Error> {
    let from_env = |name: &str| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
    if config.api_key.is_none() {
        config.api_key = from_env("OPENAI_API_KEY").map(ApiKey::new);
    }
    if config.model.is_empty() {
        config.model = from_env("COHERENT_MODEL").unwrap_or_default();
    }
    let mut base_urls: Vec<String> = config.base_urls.iter().flat_map(|l| url_list(l)).collect();
    if base_urls.is_empty() {
        base_urls = from_env("OPENAI_BASE_URL").map_or_else(Vec::new, |v| url_list(&v));
    }
    if base_urls.is_empty() {
        if config.api_key.is_none() || config.model.is_empty() {
            return Ok(None);
        }
        base_urls.push("https://api.openai.com/v1".to_owned());
    }
    if config.model.is_empty() {
        return Err(Error::Endpoint(format!(
            "an endpoint is configured ({}) but no model: pass --model or set COHERENT_MODEL",
            base_urls
                .iter()
                .map(|u| redacted(u))
                .collect::<Vec<_>>()
                .join(",")
        )));
    }
    config.base_urls = base_urls;
    Ok(Some(config))
}

/// The base URLs of a comma-separated list (`OPENAI_BASE_URL`, a `--base-url` value),
/// blanks left out.
pub fn url_list(list: &str) -> Vec<String> {
    list.split(',')
        .map(str::trim)
        .filter(|u| !u.is_empty())
        .map(str::to_owned)
        .collect()
}

impl BackendChoice {
    /// The backend of one episode with seed `seed`, its searches bounded by `limits`
    /// (the simulated backend's mistakes are seeded per episode). A replay's backend
    /// depends on the episode's recording ([`coherent_agents::Replay`]): none here.
    pub fn for_episode(&self, limits: &Limits, seed: u64) -> Result<Arc<dyn Backend>, Error> {
        Ok(match self {
            BackendChoice::Builtin => Arc::new(BuiltinBackend::new(limits.clone())),
            BackendChoice::Simulated(rates) => {
                Arc::new(BuiltinBackend::simulated(limits.clone(), *rates, seed))
            }
            BackendChoice::OpenAi(client) => Arc::clone(client) as Arc<dyn Backend>,
            BackendChoice::Replay(_) => return Err(BackendProblem::ReplayIsForBenchmarks.into()),
        })
    }

    /// The backend as transcripts and results lines name it.
    pub fn info(&self) -> BackendInfo {
        match self {
            BackendChoice::Builtin => BuiltinBackend::new(Limits::default()).info(),
            BackendChoice::Simulated(rates) => {
                BuiltinBackend::simulated(Limits::default(), *rates, 0).info()
            }
            BackendChoice::OpenAi(client) => client.info(),
            BackendChoice::Replay(recorded) => BackendInfo {
                kind: BackendKind::Replay,
                model: recorded.backend.model.clone(),
                base_url: None,
            },
        }
    }

    /// The sampling temperature an episode records: the endpoint's, for a model that
    /// samples; none for the planner's backends (a replay records its own).
    pub fn temperature(&self) -> Option<f32> {
        match self {
            BackendChoice::OpenAi(client) => Some(client.config().temperature),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(name: BackendName) -> BackendRequest {
        BackendRequest {
            name,
            ..BackendRequest::default()
        }
    }

    fn endpoint() -> EndpointSource {
        let config = OpenAiConfig::new("http://127.0.0.1:9/v1", "m");
        EndpointSource::Client(Arc::new(OpenAiClient::new(config).expect("a client")))
    }

    fn problem(r: Result<BackendChoice, Error>) -> Option<BackendProblem> {
        match r {
            Err(Error::Backend(p)) => Some(p),
            _ => None,
        }
    }

    #[test]
    fn auto_follows_what_is_configured() {
        let rates = ErrorRates::parse("all=0.1").ok();
        assert!(matches!(
            request(BackendName::Auto).choose(),
            Ok(BackendChoice::Builtin)
        ));
        let simulated = BackendRequest {
            sim_errors: rates,
            ..request(BackendName::Auto)
        };
        assert!(matches!(
            simulated.choose(),
            Ok(BackendChoice::Simulated(_))
        ));
        let http = BackendRequest {
            endpoint: endpoint(),
            ..request(BackendName::Auto)
        };
        assert!(matches!(http.choose(), Ok(BackendChoice::OpenAi(_))));
        let both = BackendRequest {
            endpoint: endpoint(),
            sim_errors: rates,
            ..request(BackendName::Auto)
        };
        assert_eq!(
            problem(both.choose()),
            Some(BackendProblem::RatesAndEndpoint)
        );
    }

    #[test]
    fn settings_that_do_not_fit_are_refused() {
        let rates = BackendRequest {
            sim_errors: ErrorRates::parse("all=0.1").ok(),
            ..request(BackendName::Builtin)
        };
        assert_eq!(
            problem(rates.choose()),
            Some(BackendProblem::RatesNeedSimulated)
        );
        assert_eq!(
            problem(request(BackendName::Replay).choose()),
            Some(BackendProblem::ReplayNeedsFile)
        );
        let file = BackendRequest {
            replay_from: Some("r.jsonl".into()),
            ..request(BackendName::Builtin)
        };
        assert_eq!(
            problem(file.choose()),
            Some(BackendProblem::FileNeedsReplay)
        );
        assert_eq!(
            problem(request(BackendName::OpenAi).choose()),
            Some(BackendProblem::NoEndpoint)
        );
    }

    #[test]
    fn base_urls_are_repeated_or_listed_with_commas() {
        assert_eq!(
            url_list(" http://a/v1, ,http://b/v1,"),
            ["http://a/v1", "http://b/v1"]
        );
        let given = OpenAiConfig {
            base_urls: vec!["http://a/v1,http://b/v1".into(), "http://c/v1".into()],
            model: "m".into(),
            ..OpenAiConfig::default()
        };
        let config = complete(given).expect("valid").expect("an endpoint");
        assert_eq!(
            config.base_urls,
            ["http://a/v1", "http://b/v1", "http://c/v1"]
        );
        assert_eq!(config.model, "m");
    }
}
