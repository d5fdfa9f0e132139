//! What `run` and `bench` share: the model endpoint's flags (one struct both flatten, so
//! that the same setting has the same flag; resolving them with the environment is the
//! session layer's, [`crate::session::endpoint`]), `--prompts` and `--prices` (read by
//! [`crate::session::prompts`]), `--sim-errors`, the method names (and `MODULE:CLASS`, a
//! method written in Python, which the Python package loads).

use std::path::PathBuf;
use std::time::Duration;

use clap::{Args, ValueEnum};
use coherent_agents::episode::{External, Method, MethodSpec};
use coherent_agents::{ApiKey, ErrorRates, OpenAiConfig, OutputMode, PriceTable, Prompts};
use coherent_core::text::{number, shown};

use crate::session::endpoint::{Endpoint, Patience};
use crate::session::prompts;

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
    #[arg(long, default_value_t = 0.0)]
    pub temperature: f32,
    /// The model's sampling seed (sent to the server); for `run`, also the seed of the
    /// simulated backend's mistakes, of MCTS and of DMRS's speaking order.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Answer format asked for first; a server that refuses it gets the next one.
    #[arg(long, value_enum, default_value_t = AnswerFormat::JsonSchema)]
    pub answer_format: AnswerFormat,
    /// Seconds to wait for a connection.
    #[arg(long, default_value_t = Patience::default().connect_timeout)]
    connect_timeout: f64,
    /// Seconds of silence allowed while reading a response.
    #[arg(long, default_value_t = Patience::default().read_timeout)]
    read_timeout: f64,
    /// Seconds one request may take in all.
    #[arg(long, default_value_t = Patience::default().timeout)]
    timeout: f64,
    /// Retries of a request after 408, 429, 5xx, connection errors and timeouts.
    #[arg(long, default_value_t = Patience::default().max_retries)]
    max_retries: u32,
    /// Requests in flight at once (across all episodes of a benchmark).
    #[arg(long, default_value_t = 4)]
    pub requests: usize,
    /// The most bytes a response body may have; a longer one is a failed call.
    #[arg(long, default_value_t = OpenAiConfig::DEFAULT_MAX_RESPONSE_BYTES)]
    max_response_bytes: usize,
}

impl LlmArgs {
    /// The client's settings, when the flags or the environment configure an endpoint.
    pub fn config(&self) -> Result<Option<OpenAiConfig>, String> {
        Endpoint {
            base_urls: self.base_url.clone(),
            api_key: self.api_key.clone().map(ApiKey::new),
            model: self.model.clone(),
            temperature: self.temperature,
            seed: self.seed,
            format: self.answer_format.into(),
            patience: Patience {
                connect_timeout: self.connect_timeout,
                read_timeout: self.read_timeout,
                timeout: self.timeout,
                max_retries: self.max_retries,
            },
            requests: self.requests,
            max_response_bytes: self.max_response_bytes,
        }
        .config()
    }
}

/// The prompt set and the price table, the same flags in `run` and `bench`.
#[derive(Args, Debug)]
pub(crate) struct PromptPriceArgs {
    /// A folder of prompt templates: its files replace the built-in templates of the same
    /// name (`coherent prompts export DIR` writes those), checked before any model call.
    #[arg(long, value_name = "DIR")]
    pub prompts: Option<PathBuf>,
    /// A price table, JSON (TOML for a `.toml` file): USD per million input, cached input
    /// and output tokens by model, added to the built-in table; prices `cost_usd`.
    #[arg(long, value_name = "FILE")]
    pub prices: Option<PathBuf>,
}

impl PromptPriceArgs {
    /// The prompt set of `--prompts`; an error names the file, the line and the
    /// placeholder.
    /// A blank template is a warning on stderr.
    pub fn prompt_set(&self) -> Result<Prompts, String> {
        let set = prompts::prompt_set(self.prompts.as_deref()).map_err(|e| e.to_string())?;
        if let Some(dir) = &self.prompts {
            for warning in prompts::blank_warnings(dir, &set) {
                eprintln!("warning: {}", shown(&warning));
            }
        }
        Ok(set)
    }

    /// The built-in price table with the entries of `--prices`.
    pub fn price_table(&self) -> Result<PriceTable, String> {
        prompts::price_table(self.prices.as_deref())
    }

    /// Refuses `--prompts` for a replay, which renders the prompt set it recorded.
    pub fn no_prompts_for_a_replay(&self, flag: &str) -> Result<(), String> {
        match &self.prompts {
            Some(_) => Err(format!(
                "--prompts and {flag} do not go together: a replay renders the prompt set \
                 its transcript recorded"
            )),
            None => Ok(()),
        }
    }
}

/// The simulated backend's error rates of a `--sim-errors` flag, if given; a bad value is
/// an error naming the flag.
pub(crate) fn sim_errors(flag: Option<&str>) -> Result<Option<ErrorRates>, String> {
    flag.map(ErrorRates::parse)
        .transpose()
        .map_err(|e| format!("--sim-errors: {e}"))
}

/// A value of `--method` and `--methods`: a built-in method's name, or `MODULE:CLASS`,
/// a method written in Python (loaded when the command runs from the Python package).
pub(crate) fn method_name(value: &str) -> Result<String, String> {
    if Method::from_name(value).is_some() || value.contains(':') {
        return Ok(value.to_owned());
    }
    let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
    Err(format!(
        "not a method: the methods are {}, or MODULE:CLASS for one written in Python",
        names.join(", ")
    ))
}

/// Loads a method written in Python from `MODULE:CLASS` (an importable module or a `.py`
/// file, and the class or callable in it); the Python package's console script has one.
pub type LoadMethod<'a> = dyn Fn(&str) -> Result<External, String> + Send + Sync + 'a;

/// The method a value of [`method_name`] names: a built-in one, or one that `load` loads,
/// each of its steps limited to `step_timeout` seconds (`--step-timeout`).
pub(crate) fn method_spec(
    value: &str,
    load: Option<&LoadMethod<'_>>,
    step_timeout: Option<f64>,
) -> Result<MethodSpec, String> {
    if let Some(method) = Method::from_name(value) {
        return Ok(method.into());
    }
    let limit = step_timeout
        .map(|s| {
            Duration::try_from_secs_f64(s)
                .ok()
                .filter(|d| !d.is_zero())
                .ok_or_else(|| {
                    format!(
                        "--step-timeout must be seconds above 0 and at most 1.8e19, not {}",
                        number(s)
                    )
                })
        })
        .transpose()?;
    match load {
        Some(load) => load(value).map(|m| MethodSpec::External(m.with_step_timeout(limit))),
        None => Err(format!(
            "method {value}: a method written in Python needs the Python package: run the \
             `coherent` command that `pip install .` installs (or `python -m coherent._cli`), \
             not the plain binary"
        )),
    }
}
