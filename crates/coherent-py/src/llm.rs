//! `LLM`: an OpenAI-compatible endpoint's settings, for the episodes' backend.

use coherent::session::endpoint::{Endpoint, Patience};
use coherent_agents::{ApiKey, OpenAiClient, OpenAiConfig, OutputMode};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::convert::py_repr;
use crate::errors;

/// How to reach an OpenAI-compatible endpoint. Arguments left out come from the
/// environment as on the command line (`OPENAI_BASE_URL`, `OPENAI_API_KEY`,
/// `COHERENT_MODEL`). The key is kept out of `repr`, transcripts and logs.
#[pyclass(name = "LLM", module = "coherent._coherent", frozen)]
pub(crate) struct PyLlm {
    pub config: OpenAiConfig,
}

#[pymethods]
impl PyLlm {
    #[new]
    #[pyo3(signature = (
        base_url = None, model = None, api_key = None, *, temperature = 0.0, seed = None,
        format = "json_schema", connect_timeout = 10.0, read_timeout = 120.0, timeout = 300.0,
        max_retries = 4, concurrency = 4
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        base_url: Option<String>,
        model: Option<String>,
        api_key: Option<String>,
        temperature: f32,
        seed: Option<u64>,
        format: &str,
        connect_timeout: f64,
        read_timeout: f64,
        timeout: f64,
        max_retries: u32,
        concurrency: usize,
    ) -> PyResult<PyLlm> {
        let format: OutputMode = serde_json::from_value(format.into()).map_err(|_| {
            PyValueError::new_err(format!(
                "format {format:?}: expected \"json_schema\", \"json_object\" or \"text\""
            ))
        })?;
        let endpoint = Endpoint {
            base_url,
            api_key: api_key.map(ApiKey::new),
            model,
            temperature,
            seed,
            format,
            patience: Patience {
                connect_timeout,
                read_timeout,
                timeout,
                max_retries,
            },
            requests: concurrency,
        };
        let config = endpoint.config().map_err(|e| errors::backend(py, e))?.ok_or_else(|| {
            errors::backend(
                py,
                "no endpoint: pass base_url= and model= (or set OPENAI_BASE_URL and COHERENT_MODEL)",
            )
        })?;
        // The client checks the rest (the model name, the URL); fail here, not mid-run.
        OpenAiClient::new(config.clone()).map_err(|e| errors::backend(py, e.to_string()))?;
        Ok(PyLlm { config })
    }

    #[getter]
    fn base_url(&self) -> &str {
        &self.config.base_url
    }

    #[getter]
    fn model(&self) -> &str {
        &self.config.model
    }

    /// Whether a key is set (the key itself cannot be read back).
    #[getter]
    fn has_api_key(&self) -> bool {
        self.config.api_key.is_some()
    }

    #[getter]
    fn temperature(&self) -> f32 {
        self.config.temperature
    }

    #[getter]
    fn seed(&self) -> Option<u64> {
        self.config.seed
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "LLM(base_url={}, model={}, api_key={}, temperature={:?})",
            py_repr(py, &self.config.base_url),
            py_repr(py, &self.config.model),
            if self.has_api_key() {
                "'[hidden]'"
            } else {
                "None"
            },
            self.config.temperature
        )
    }
}
