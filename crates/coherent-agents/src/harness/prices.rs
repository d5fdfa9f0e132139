//! What model tokens cost: a price table (USD per million input, cached input and output
//! tokens, by model name), built in (`prices.toml`, each entry with the date and the page
//! it was read from) and extended or overridden from a JSON or TOML file; and what an
//! episode's model calls cost ([`ModelUse`]), the one rule `coherent run`,
//! `coherent.run`, `load_episode` and a results line all price by.

use std::collections::BTreeMap;
use std::path::Path;

use coherent_core::files::{self, Limit, MIB};
use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::llm::{BackendInfo, Usage};
use crate::records::transcript::{Header, Round, Summary};

/// The price of one model, USD per million tokens.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Price {
    /// Prompt tokens.
    pub input: f64,
    /// Prompt tokens the server read from its cache; the input price when absent.
    #[serde(default)]
    pub cached_input: Option<f64>,
    /// Completion tokens.
    pub output: f64,
    /// When the price was read (`YYYY-MM-DD`).
    #[serde(default)]
    pub date: Option<String>,
    /// The page it was read from.
    #[serde(default)]
    pub source: Option<String>,
}

impl Price {
    /// The cost in USD of `usage`: cached prompt tokens at the cached price, the rest of
    /// the prompt at the input price, the completion at the output price.
    pub fn cost(&self, usage: &Usage) -> f64 {
        let cached = usage.cached_tokens.min(usage.prompt_tokens);
        let fresh = usage.prompt_tokens - cached;
        (fresh as f64 * self.input
            + cached as f64 * self.cached_input.unwrap_or(self.input)
            + usage.completion_tokens as f64 * self.output)
            / 1e6
    }

    fn check(&self, model: &str) -> Result<(), String> {
        let prices = [Some(self.input), self.cached_input, Some(self.output)];
        if prices
            .into_iter()
            .flatten()
            .all(|p| p.is_finite() && (0.0..=MAX_PRICE).contains(&p))
        {
            Ok(())
        } else {
            Err(format!(
                "{model:?}: prices must be numbers from 0 to {MAX_PRICE} (USD per million \
                 tokens)"
            ))
        }
    }
}

/// The highest price a table may give, USD per million tokens (a dollar a token): the
/// dearest hosted models cost a few hundred; a higher number is a mistake, and one near
/// the largest float would make every cost infinite.
pub const MAX_PRICE: f64 = 1e6;

/// The most a price table file may hold: a table of every hosted model is a few KiB.
pub const FILE_LIMIT: Limit = Limit {
    bytes: MIB,
    what: "a price table",
    raise: None,
};

/// Prices by model name.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct PriceTable {
    pub models: BTreeMap<String, Price>,
}

/// The built-in table's text.
const BUILTIN: &str = include_str!("../../prices.toml");

impl PriceTable {
    /// The built-in table: widely used hosted models.
    pub fn builtin() -> PriceTable {
        PriceTable::parse_toml(BUILTIN, "prices.toml").expect("the built-in price table parses")
    }

    /// A table in JSON: `{"MODEL": {"input": .., "cached_input": .., "output": ..}, ...}`;
    /// errors name `file`. A model listed twice is refused, as TOML refuses it.
    pub fn parse_json(text: &str, file: &str) -> Result<PriceTable, Error> {
        // The path of a key twice, as in task files: serde_json alone keeps the last.
        let value = coherent_core::json::parse(file, text.as_bytes()).map_err(|e| match e {
            coherent_core::Error::Malformed { path, message, .. } => {
                format_error(file, format!("{path}: {message}"))
            }
            other => format_error(file, other.to_string()),
        })?;
        let table: PriceTable =
            serde_json::from_value(value).map_err(|e| format_error(file, e.to_string()))?;
        table.checked(file)
    }

    /// A table in TOML: a `["MODEL"]` table per model with the keys of JSON's objects;
    /// errors name `file`.
    pub fn parse_toml(text: &str, file: &str) -> Result<PriceTable, Error> {
        let table: PriceTable =
            toml::from_str(text).map_err(|e| format_error(file, e.to_string()))?;
        table.checked(file)
    }

    fn checked(self, file: &str) -> Result<PriceTable, Error> {
        for (model, price) in &self.models {
            price.check(model).map_err(|e| format_error(file, e))?;
        }
        Ok(self)
    }

    /// The table in the file at `path`: TOML when its name ends in `.toml`, else JSON; a
    /// file of more than [`FILE_LIMIT`] is refused.
    pub fn read(path: &Path) -> Result<PriceTable, Error> {
        let file = path.display().to_string();
        let bytes = files::read(path, &FILE_LIMIT).map_err(Error::file)?;
        let text =
            String::from_utf8(bytes).map_err(|e| format_error(&file, format!("not UTF-8: {e}")))?;
        if path.extension().is_some_and(|e| e == "toml") {
            PriceTable::parse_toml(&text, &file)
        } else {
            PriceTable::parse_json(&text, &file)
        }
    }

    /// This table with the entries of `over` added, replacing those of the same model.
    pub fn overridden_by(mut self, over: PriceTable) -> PriceTable {
        self.models.extend(over.models);
        self
    }

    /// The price of `model`: its own entry, else that of its name without a date suffix
    /// (`-2024-07-18`, `-20250929`).
    pub fn price(&self, model: &str) -> Option<&Price> {
        self.models
            .get(model)
            .or_else(|| self.models.get(undated(model)?))
    }

    /// What `usage` cost on `model`; `None` when the table has no price for it.
    pub fn cost(&self, model: &str, usage: &Usage) -> Option<f64> {
        self.price(model).map(|p| p.cost(usage))
    }

    /// What an episode's model calls cost, whatever its method: its tokens at `model`'s
    /// price; 0 for an episode that used no model (`uses_model` false, [`ModelUse`]) and
    /// no tokens; `None` when the model has no price.
    pub fn episode_cost(&self, model: &str, uses_model: bool, usage: &Usage) -> Option<f64> {
        let free = !uses_model && *usage == Usage::default();
        self.cost(model, usage).or(free.then_some(0.0))
    }
}

/// A [`Error::Format`] about the price file `file`.
fn format_error(file: &str, message: String) -> Error {
    Error::Format {
        file: file.to_owned(),
        line: None,
        message,
    }
}

/// What an episode's model calls amount to, read from its transcript alone, so that the
/// same transcript always costs the same: the model that answered, the tokens, and the
/// calls. An episode uses a model when it made model calls (through its backend, through
/// the project's client, or through its own clients, as a method written outside the
/// crate reports them); one that made none costs nothing.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelUse {
    /// Whose model priced the tokens: the episode's backend for a built-in method (none
    /// for one that asks no backend); for a method written outside the crate, the client
    /// its first call through the project's client went through (none without one).
    pub backend: BackendInfo,
    pub usage: Usage,
    /// Model calls made or reported.
    pub calls: u32,
}

impl ModelUse {
    /// The model use of the episode recorded as `header`, `rounds` and `summary`.
    pub fn of(header: &Header, rounds: &[Round], summary: &Summary) -> ModelUse {
        let backend = if header.external {
            rounds
                .iter()
                .flat_map(|r| &r.calls)
                .find_map(|c| c.client.clone())
                .unwrap_or_else(BackendInfo::none)
        } else {
            header.backend.clone()
        };
        ModelUse {
            backend,
            usage: Usage {
                prompt_tokens: summary.prompt_tokens,
                completion_tokens: summary.completion_tokens,
                cached_tokens: summary.cached_tokens,
            },
            calls: summary.llm_calls,
        }
    }

    /// Whether the episode used a model: it made model calls.
    pub fn uses_model(&self) -> bool {
        self.calls > 0
    }

    /// What the calls cost at `prices` ([`PriceTable::episode_cost`]).
    pub fn cost(&self, prices: &PriceTable) -> Option<f64> {
        prices.episode_cost(&self.backend.model, self.uses_model(), &self.usage)
    }
}

/// `model` without a trailing date, `-YYYY-MM-DD` or `-YYYYMMDD`; `None` without one.
fn undated(model: &str) -> Option<&str> {
    let digits = |s: &str, n: usize| s.len() == n && s.bytes().all(|b| b.is_ascii_digit());
    let mut parts = model.rsplitn(4, '-');
    let last = parts.next()?;
    if digits(last, 8) {
        let head = model.strip_suffix(last)?.strip_suffix('-')?;
        return (!head.is_empty()).then_some(head);
    }
    let (month, year, head) = (parts.next()?, parts.next()?, parts.next()?);
    (digits(last, 2) && digits(month, 2) && digits(year, 4) && !head.is_empty()).then_some(head)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn usage(prompt: u64, cached: u64, completion: u64) -> Usage {
        Usage {
            prompt_tokens: prompt,
            completion_tokens: completion,
            cached_tokens: cached,
        }
    }

    #[test]
    fn the_builtin_table_parses_and_every_entry_says_where_it_was_read() {
        let table = PriceTable::builtin();
        assert!(table.models.len() >= 5);
        for (model, price) in &table.models {
            let date = price.date.as_deref().unwrap_or_default();
            assert!(
                date.len() == 10 && date.starts_with("20"),
                "{model}: {date:?}"
            );
            let source = price.source.as_deref().unwrap_or_default();
            assert!(source.starts_with("https://"), "{model}: {source:?}");
            assert!(price.cached_input.is_some(), "{model}");
        }
    }

    #[test]
    fn costs_split_cached_and_fresh_prompt_tokens() {
        let price = Price {
            input: 2.0,
            cached_input: Some(0.5),
            output: 8.0,
            date: None,
            source: None,
        };
        // 600k fresh x 2 + 400k cached x 0.5 + 100k x 8, per million.
        let cost = price.cost(&usage(1_000_000, 400_000, 100_000));
        assert!((cost - (1.2 + 0.2 + 0.8)).abs() < 1e-12, "{cost}");
        // Without a cached price, cached tokens cost the input price.
        let plain = Price {
            cached_input: None,
            ..price
        };
        assert!((plain.cost(&usage(1_000_000, 400_000, 0)) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn json_and_toml_tables_and_overrides() {
        let json = PriceTable::parse_json(
            r#"{"smollm2-135m": {"input": 0.01, "output": 0.02}}"#,
            "p.json",
        )
        .expect("JSON");
        let toml = PriceTable::parse_toml(
            "[\"smollm2-135m\"]\ninput = 0.01\noutput = 0.02\n",
            "p.toml",
        )
        .expect("TOML");
        assert_eq!(json, toml);
        let table = PriceTable::builtin().overridden_by(json);
        assert!(table.price("smollm2-135m").is_some() && table.price("gpt-4o").is_some());
        let e = PriceTable::parse_json(r#"{"m": {"input": 1, "outptu": 2}}"#, "p.json")
            .expect_err("a typo")
            .to_string();
        assert!(e.starts_with("p.json: ") && e.contains("outptu"), "{e}");
        let e = PriceTable::parse_toml("[m]\ninput = -1\noutput = 2\n", "p.toml")
            .expect_err("a negative price")
            .to_string();
        assert!(e.contains("\"m\""), "{e}");
    }

    #[test]
    fn dated_model_names_take_the_undated_price() {
        let table = PriceTable::builtin();
        let base = table.price("gpt-4o-mini").expect("listed");
        assert_eq!(table.price("gpt-4o-mini-2024-07-18"), Some(base));
        let haiku = table.price("claude-haiku-4-5").expect("listed");
        assert_eq!(table.price("claude-haiku-4-5-20251001"), Some(haiku));
        assert!(table.price("gpt-4o-mini-x").is_none());
        assert!(table.price("no-such-model").is_none());
        assert_eq!(undated("m-2024-07-18"), Some("m"));
        assert_eq!(undated("m-20240718"), Some("m"));
        assert_eq!(undated("m-2024-7-18"), None);
        assert_eq!(undated("2024-07-18"), None);
        assert_eq!(undated("20240718"), None);
    }
}
