//! What a run is given besides its task and backend, read once for `run`, `bench` and
//! Python alike: the prompt set (the built-in templates, with the files of a folder in
//! their place) and the price table (the built-in one, with a file's entries added).
//! Both are checked here, before any episode starts, so that a bad template costs no
//! model call.

use std::path::Path;

use coherent_agents::{PriceTable, PromptError, Prompts};

/// The prompt set: the built-in templates, with those of `dir` in their place.
pub fn prompt_set(dir: Option<&Path>) -> Result<Prompts, PromptError> {
    match dir {
        Some(dir) => Prompts::read_dir(dir),
        None => Ok(Prompts::builtin()),
    }
}

/// The price table: the built-in one, with the entries of the file at `file` (JSON, or
/// TOML for a `.toml` file) added or in place of those of the same model.
pub fn price_table(file: Option<&Path>) -> Result<PriceTable, String> {
    let builtin = PriceTable::builtin();
    match file {
        Some(file) => Ok(builtin.overridden_by(PriceTable::read(file)?)),
        None => Ok(builtin),
    }
}

/// A warning for each template of `prompts` (read from `origin`) that holds nothing but
/// white space, which a write cut short (a full disk) leaves: its prompts say nothing.
pub fn blank_warnings(origin: &Path, prompts: &Prompts) -> Vec<String> {
    prompts
        .blank_names()
        .into_iter()
        .map(|name| {
            format!(
                "{}: the template is blank, so its prompts tell the model nothing",
                origin.join(name).display()
            )
        })
        .collect()
}

/// One line about a prompt set that replaces built-in templates (`None` for the
/// built-in set): the files and the set's hash, as the transcript records them.
pub fn describe(prompts: &Prompts) -> Option<String> {
    let replaced = prompts.replaced_names();
    (!replaced.is_empty()).then(|| {
        format!(
            "prompts: {} in place of the built-in templates (set {})",
            replaced.join(", "),
            prompts.hash()
        )
    })
}
