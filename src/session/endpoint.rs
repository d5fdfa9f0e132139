//! The model endpoint: the settings a front end was told (flags, keyword arguments),
//! completed from the environment (`OPENAI_BASE_URL`, `OPENAI_API_KEY`,
//! `COHERENT_MODEL`). Several base URLs serve one model from several servers (the client
//! spreads the requests over them).

use coherent_agents::{ApiKey, OpenAiConfig};

use crate::session::error::Error;

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
            base_urls.join(",")
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

#[cfg(test)]
mod tests {
    use super::*;

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
