//! Which backend answers the model's roles, chosen once for `run`, `bench` and Python
//! alike: the built-in planner, the simulated backend (the planner with seeded mistakes),
//! an OpenAI-compatible endpoint, or the transcripts of an earlier benchmark.

use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

use coherent_agents::bench::{BackendChoice, ReadLimits, Recorded};
use coherent_agents::{ErrorRates, OpenAiClient, OpenAiConfig};

/// The backend asked for; `Auto` picks the simulated backend when error rates are given,
/// else the endpoint when one is configured, else the built-in planner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BackendKind {
    Auto,
    Builtin,
    Simulated,
    OpenAi,
    Replay,
}

/// Everything that decides the backend.
#[derive(Debug)]
pub struct BackendRequest {
    pub kind: BackendKind,
    /// The endpoint, when one is configured ([`super::endpoint::Endpoint::config`]).
    pub endpoint: Option<OpenAiConfig>,
    /// The simulated backend's error rates.
    pub sim_errors: Option<ErrorRates>,
    /// An earlier results file whose transcripts a replay answers from.
    pub replay_from: Option<PathBuf>,
    /// How much of that results file and of each transcript may be read.
    pub limits: ReadLimits,
}

/// Why the settings do not fit together. Each front end words these in its own terms
/// (flags or keyword arguments), see [`Display`](fmt::Display) for the neutral text.
#[derive(Debug, PartialEq)]
pub enum BackendProblem {
    /// Error rates were given for a backend other than the simulated one.
    RatesNeedSimulated,
    /// Error rates and an endpoint were both given without naming a backend.
    RatesAndEndpoint,
    /// A replay without the results file it answers from.
    ReplayNeedsFile,
    /// A results file to replay from, for a backend other than replay.
    FileNeedsReplay,
    /// The OpenAI-compatible backend without an endpoint.
    NoEndpoint,
    /// The client or the recordings could not be set up.
    Setup(String),
}

impl fmt::Display for BackendProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BackendProblem::RatesNeedSimulated => {
                "simulated error rates need the simulated backend"
            }
            BackendProblem::RatesAndEndpoint => {
                "simulated errors are for the simulated backend: leave out the endpoint"
            }
            BackendProblem::ReplayNeedsFile => "a replay needs the earlier results file",
            BackendProblem::FileNeedsReplay => "a results file to replay from needs the replay backend",
            BackendProblem::NoEndpoint => {
                "the OpenAI-compatible backend needs an endpoint: a base URL (OPENAI_BASE_URL) and a model (COHERENT_MODEL)"
            }
            BackendProblem::Setup(why) => why,
        })
    }
}

impl BackendRequest {
    /// The backend these settings ask for.
    pub fn choose(self) -> Result<BackendChoice, BackendProblem> {
        let kind = match self.kind {
            BackendKind::Auto => match (&self.sim_errors, &self.endpoint) {
                (Some(_), Some(_)) => return Err(BackendProblem::RatesAndEndpoint),
                (Some(_), None) => BackendKind::Simulated,
                (None, Some(_)) => BackendKind::OpenAi,
                (None, None) => BackendKind::Builtin,
            },
            k => k,
        };
        if self.sim_errors.is_some() && kind != BackendKind::Simulated {
            return Err(BackendProblem::RatesNeedSimulated);
        }
        match (kind, self.replay_from) {
            (BackendKind::Replay, Some(file)) => Recorded::read(&file, self.limits)
                .map(|r| BackendChoice::Replay(Arc::new(r)))
                .map_err(BackendProblem::Setup),
            (BackendKind::Replay, None) => Err(BackendProblem::ReplayNeedsFile),
            (_, Some(_)) => Err(BackendProblem::FileNeedsReplay),
            (BackendKind::Simulated, None) => Ok(BackendChoice::Simulated(
                self.sim_errors.unwrap_or_default(),
            )),
            (BackendKind::OpenAi, None) => {
                let config = self.endpoint.ok_or(BackendProblem::NoEndpoint)?;
                OpenAiClient::new(config)
                    .map(|c| BackendChoice::OpenAi(Arc::new(c)))
                    .map_err(|e| BackendProblem::Setup(e.to_string()))
            }
            (BackendKind::Auto | BackendKind::Builtin, None) => Ok(BackendChoice::Builtin),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(kind: BackendKind) -> BackendRequest {
        BackendRequest {
            kind,
            endpoint: None,
            sim_errors: None,
            replay_from: None,
            limits: ReadLimits::default(),
        }
    }

    fn endpoint() -> Option<OpenAiConfig> {
        Some(OpenAiConfig::new("http://127.0.0.1:9/v1", "m"))
    }

    #[test]
    fn auto_follows_what_is_configured() {
        let rates = ErrorRates::parse("all=0.1").ok();
        assert!(matches!(
            request(BackendKind::Auto).choose(),
            Ok(BackendChoice::Builtin)
        ));
        let simulated = BackendRequest {
            sim_errors: rates,
            ..request(BackendKind::Auto)
        };
        assert!(matches!(
            simulated.choose(),
            Ok(BackendChoice::Simulated(_))
        ));
        let http = BackendRequest {
            endpoint: endpoint(),
            ..request(BackendKind::Auto)
        };
        assert!(matches!(http.choose(), Ok(BackendChoice::OpenAi(_))));
        let both = BackendRequest {
            endpoint: endpoint(),
            sim_errors: rates,
            ..request(BackendKind::Auto)
        };
        assert_eq!(both.choose().err(), Some(BackendProblem::RatesAndEndpoint));
    }

    #[test]
    fn settings_that_do_not_fit_are_refused() {
        let rates = BackendRequest {
            sim_errors: ErrorRates::parse("all=0.1").ok(),
            ..request(BackendKind::Builtin)
        };
        assert_eq!(
            rates.choose().err(),
            Some(BackendProblem::RatesNeedSimulated)
        );
        assert_eq!(
            request(BackendKind::Replay).choose().err(),
            Some(BackendProblem::ReplayNeedsFile)
        );
        let file = BackendRequest {
            replay_from: Some("r.jsonl".into()),
            ..request(BackendKind::Builtin)
        };
        assert_eq!(file.choose().err(), Some(BackendProblem::FileNeedsReplay));
        assert_eq!(
            request(BackendKind::OpenAi).choose().err(),
            Some(BackendProblem::NoEndpoint)
        );
    }
}
