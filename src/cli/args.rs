//! What `run` and `bench` share: the model endpoint's flags (one struct both flatten, so
//! that the same setting has the same flag, its defaults those of the endpoint settings,
//! [`OpenAiConfig::default`]), `--prompts` and `--prices`, the robots' flags
//! (`--robots ros2` and its namespace and waits), `--sim-errors`, `--execution`, the
//! method names (and `MODULE:CLASS`, a method written in Python, which the Python
//! package loads).

use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::{Args, ValueEnum};

use crate::session::Error;
use crate::session::backend::{EndpointSource, RecordedRun};
use crate::session::bench::recorded_method;
use crate::session::engine::{
    ApiKey, Backoff, Builtin, DEFAULT_NAMESPACE, ErrorRates, Execution, External, MethodSpec,
    OpenAiConfig, OutputMode, ReadLimits, number,
};
use crate::session::prompts::{PriceSource, PromptSource};
use crate::session::robots::Robots;

/// How the robots take their steps: `sequential`, one robot's action a step (the
/// paper's), or `parallel`, joint steps in which every robot may act at once.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExecutionFlag {
    Sequential,
    Parallel,
}

impl From<ExecutionFlag> for Execution {
    fn from(e: ExecutionFlag) -> Execution {
        match e {
            ExecutionFlag::Sequential => Execution::Sequential,
            ExecutionFlag::Parallel => Execution::Parallel,
        }
    }
}

/// The answer format asked for first; a server that refuses it gets the next one.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum AnswerFormat {
    JsonSchema,
    JsonObject,
    Text,
}

impl From<AnswerFormat> for OutputMode {
    fn from(f: AnswerFormat) -> OutputMode {
        match f {
            AnswerFormat::JsonSchema => OutputMode::JsonSchema,
            AnswerFormat::JsonObject => OutputMode::JsonObject,
            AnswerFormat::Text => OutputMode::Text,
        }
    }
}

/// How to reach an OpenAI-compatible endpoint, the same flags in `run` and `bench` (the old
/// spellings, `run`'s `--format` and `--concurrency` and `bench`'s `--llm-seed`, are
/// hidden aliases there for one release).
#[derive(Args, Debug)]
pub(crate) struct LlmArgs {
    /// OpenAI-compatible endpoint up to the version, e.g. http://127.0.0.1:8080/v1;
    /// repeat it (or give a comma-separated list) for servers of the same model: each
    /// request goes to the least busy, one that fails rests [env: OPENAI_BASE_URL]
    #[arg(long)]
    base_url: Vec<String>,
    /// API key [env: OPENAI_API_KEY]. Prefer the variable: flags show up in `ps`.
    #[arg(long)]
    api_key: Option<String>,
    /// Model name [env: COHERENT_MODEL].
    #[arg(long)]
    model: Option<String>,
    #[arg(long, default_value_t = OpenAiConfig::default().temperature)]
    pub temperature: f32,
    /// The model's sampling seed (sent to the server); for `run`, also the seed of the
    /// simulated backend's mistakes, of MCTS and of DMRS's speaking order.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Answer format asked for first; a server that refuses it gets the next one.
    #[arg(long, value_enum, default_value_t = AnswerFormat::JsonSchema)]
    pub answer_format: AnswerFormat,
    /// Seconds to wait for a connection.
    #[arg(long, default_value_t = OpenAiConfig::default().connect_timeout.as_secs_f64())]
    connect_timeout: f64,
    /// Seconds of silence allowed while reading a response.
    #[arg(long, default_value_t = OpenAiConfig::default().read_timeout.as_secs_f64())]
    read_timeout: f64,
    /// Seconds one request may take in all.
    #[arg(long, default_value_t = OpenAiConfig::default().total_timeout.as_secs_f64())]
    timeout: f64,
    /// Retries of a request after 408, 429, 5xx, connection errors and timeouts.
    #[arg(long, default_value_t = OpenAiConfig::default().backoff.max_retries)]
    max_retries: u32,
    /// Requests in flight at once (across all episodes of a benchmark).
    #[arg(long, default_value_t = OpenAiConfig::default().concurrency)]
    pub requests: usize,
    /// The most bytes a response body may have; a longer one is a failed call.
    #[arg(long, default_value_t = OpenAiConfig::default().max_response_bytes)]
    max_response_bytes: usize,
}

impl LlmArgs {
    /// The endpoint the flags give, with what they leave unset from the environment.
    pub fn endpoint(&self) -> Result<EndpointSource, Error> {
        let seconds = |s: f64, what: &str| {
            Duration::try_from_secs_f64(s).map_err(|_| {
                Error::Invalid(format!(
                    "--{what} {}: not a number of seconds from 0 to 1.8e19",
                    number(s)
                ))
            })
        };
        Ok(EndpointSource::WithEnvironment(OpenAiConfig {
            base_urls: self.base_url.clone(),
            api_key: self.api_key.clone().map(ApiKey::new),
            model: self.model.clone().unwrap_or_default(),
            temperature: self.temperature,
            seed: self.seed,
            connect_timeout: seconds(self.connect_timeout, "connect-timeout")?,
            read_timeout: seconds(self.read_timeout, "read-timeout")?,
            total_timeout: seconds(self.timeout, "timeout")?,
            backoff: Backoff {
                max_retries: self.max_retries,
                ..Backoff::default()
            },
            concurrency: self.requests.max(1),
            output: self.answer_format.into(),
            max_response_bytes: self.max_response_bytes,
        }))
    }
}

/// The prompt set and the price table, the same flags in `run` and `bench`.
#[derive(Args, Debug)]
pub(crate) struct PromptPriceArgs {
    /// A folder of prompt templates: its files replace the built-in templates of the same
    /// name (`coherent prompts export DIR` writes those), checked before any model call;
    /// or `paper-layout`, the built-in templates in the paper's layout.
    #[arg(long, value_name = "DIR")]
    pub prompts: Option<PathBuf>,
    /// A price table, JSON (TOML for a `.toml` file): USD per million input, cached input
    /// and output tokens by model, added to the built-in table; prices `cost_usd`.
    #[arg(long, value_name = "FILE")]
    pub prices: Option<PathBuf>,
}

impl PromptPriceArgs {
    /// The prompt set of `--prompts`.
    pub fn prompt_source(&self) -> PromptSource {
        self.prompts
            .as_deref()
            .map_or(PromptSource::Builtin, PromptSource::from_arg)
    }

    /// The built-in price table with the entries of `--prices`.
    pub fn price_source(&self) -> PriceSource {
        self.prices
            .clone()
            .map_or(PriceSource::Builtin, PriceSource::File)
    }

    /// Refuses `--prompts` for a replay, which renders the prompt set it recorded.
    pub fn no_prompts_for_a_replay(&self, flag: &str) -> Result<(), Error> {
        match &self.prompts {
            Some(_) => Err(Error::Invalid(format!(
                "--prompts and {flag} do not go together: a replay renders the prompt set \
                 its transcript recorded"
            ))),
            None => Ok(()),
        }
    }
}

/// Who carries the actions out.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum RobotsKind {
    /// This process: the rules, or Rapier too with --physics.
    Local,
    /// One ROS 2 action server per robot (`coherent robots serve`, or real robots).
    Ros2,
}

/// The flags of `coherent run` and `coherent bench` for robots over ROS 2.
#[derive(Args)]
pub(crate) struct RobotFlags {
    /// Who carries the actions out: `local` (this process), or `ros2` (one ROS 2 action
    /// server per robot at `/<namespace>/<robot>/execute`).
    #[arg(long, value_enum, default_value = "local")]
    robots: RobotsKind,
    /// With --robots ros2: the namespace of the robots' actions.
    #[arg(long, default_value = DEFAULT_NAMESPACE)]
    namespace: String,
    /// With --robots ros2: seconds a robot may stay silent during a step (no answer, no
    /// feedback, no result) before the step fails and the episode stops (exit 5).
    #[arg(long, default_value_t = 10.0, value_name = "SECONDS")]
    robot_timeout: f64,
    /// With --robots ros2: seconds to wait for every robot's server before the first
    /// step; exit 2 naming the robots without one.
    #[arg(long, default_value_t = 10.0, value_name = "SECONDS")]
    server_wait: f64,
}

impl RobotFlags {
    pub(crate) fn robots(&self) -> Result<Robots, Error> {
        match self.robots {
            RobotsKind::Local => Ok(Robots::Local),
            RobotsKind::Ros2 => Robots::ros2(&self.namespace, self.robot_timeout, self.server_wait),
        }
    }
}

/// The simulated backend's error rates of a `--sim-errors` flag, if given; a bad value is
/// an error naming the flag.
pub(crate) fn sim_errors(flag: Option<&str>) -> Result<Option<ErrorRates>, Error> {
    flag.map(ErrorRates::parse)
        .transpose()
        .map_err(|e| Error::Invalid(format!("--sim-errors: {e}")))
}

/// A value of `--method` and `--methods`: a built-in method's name, `MODULE:CLASS`, a
/// method written in Python (loaded when the command runs from the Python package), or
/// the name of one in a results file that `bench --backend replay` replays.
pub(crate) fn method_name(value: &str) -> Result<String, String> {
    let named = !value.is_empty()
        && !value.starts_with('.')
        && value
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
    if named || value.contains(':') {
        return Ok(value.to_owned());
    }
    Err(format!("not a method: {}", method_choices()))
}

/// The methods a flag takes, for its messages.
fn method_choices() -> String {
    let names: Vec<&str> = Builtin::ALL.iter().map(|m| m.name()).collect();
    format!(
        "the methods are {}, or MODULE:CLASS for one written in Python",
        names.join(", ")
    )
}

/// Loads a method written in Python from `MODULE:CLASS` (an importable module or a `.py`
/// file, and the class or callable in it); the Python package's console script has one.
pub type LoadMethod<'a> = dyn Fn(&str) -> Result<External, Error> + Send + Sync + 'a;

/// The method a value of [`method_name`] names: a built-in one, or one that `load` loads,
/// each of its steps limited to `step_timeout` seconds (`--step-timeout`); with
/// `replay_from` (`bench --backend replay`: the results file and the limits it is read
/// within), a name that is no built-in method's is the recorded method of that name,
/// which replays without its code.
pub(crate) fn method_spec(
    value: &str,
    load: Option<&LoadMethod<'_>>,
    step_timeout: Option<f64>,
    replay_from: Option<(&Path, ReadLimits)>,
) -> Result<MethodSpec, Error> {
    if let Some(method) = Builtin::from_name(value) {
        return Ok(method.into());
    }
    let limit = step_timeout
        .map(|s| {
            Duration::try_from_secs_f64(s)
                .ok()
                .filter(|d| !d.is_zero())
                .ok_or_else(|| {
                    Error::Invalid(format!(
                        "--step-timeout must be seconds above 0 and at most 1.8e19, not {}",
                        number(s)
                    ))
                })
        })
        .transpose()?;
    if let Some((results, limits)) = replay_from {
        // By the name the results file records; MODULE:CLASS only tells that name.
        let name = match load.filter(|_| value.contains(':')).map(|load| load(value)) {
            Some(Ok(method)) => method.name().to_owned(),
            Some(Err(e)) => {
                return Err(Error::Invalid(format!(
                    "method {value}: {e}; a replay runs the recorded decisions and needs no \
                     code: name the method as {} records it ({})",
                    results.display(),
                    RecordedRun::read(results, limits)?.methods().join(", ")
                )));
            }
            None => value.to_owned(),
        };
        return recorded_method(results, &name, limits);
    }
    match load {
        Some(load) if value.contains(':') => {
            load(value).map(|m| MethodSpec::External(m.with_step_timeout(limit)))
        }
        None if value.contains(':') => Err(Error::Invalid(format!(
            "method {value}: a method written in Python needs the Python package: run the \
             `coherent` command that `pip install .` installs (or `python -m coherent._cli`), \
             not the plain binary"
        ))),
        _ => Err(Error::Invalid(format!(
            "unknown method {value:?}: {}",
            method_choices()
        ))),
    }
}
