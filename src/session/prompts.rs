//! What a run is given besides its task and backend, read once for `run`, `bench` and
//! Python alike: the prompt set (the built-in templates, with others in their place) and
//! the price table (the built-in one, with entries added). Both are read before any
//! episode starts, so that a bad template costs no model call.

use std::path::{Path, PathBuf};

use coherent_agents::{PriceTable, Prompts, templates};
use coherent_core::Execution;

use crate::session::error::Error;

/// Where a run's prompt templates come from.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum PromptSource {
    /// The built-in templates.
    #[default]
    Builtin,
    /// The built-in templates in the paper's layout ([`templates::PAPER_LAYOUT`]).
    PaperLayout,
    /// A folder whose template files replace the built-in ones of the same name.
    Folder(PathBuf),
    /// Template texts by file name, in place of the built-in ones of that name (Python's
    /// dict, a worker's copy of the driver's set).
    Texts(Vec<(String, String)>),
}

impl PromptSource {
    /// What `--prompts ARG` (and `prompts="ARG"`) names: the built-in set of that name
    /// (`paper-layout`), else a folder (`./paper-layout` is the folder of that name).
    pub fn from_arg(arg: &Path) -> PromptSource {
        if arg == Path::new(templates::PAPER_LAYOUT) {
            PromptSource::PaperLayout
        } else {
            PromptSource::Folder(arg.to_owned())
        }
    }

    /// The prompt set; an error names the file, the line and the placeholder.
    pub fn read(self) -> Result<Prompts, Error> {
        Ok(match self {
            PromptSource::Builtin => Prompts::builtin(),
            PromptSource::PaperLayout => Prompts::paper_layout(),
            PromptSource::Folder(dir) => Prompts::read_dir(&dir)?,
            PromptSource::Texts(files) => Prompts::from_texts(Path::new("prompts"), files)?,
        })
    }
}

/// Where a run's prices come from.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum PriceSource {
    /// The built-in table.
    #[default]
    Builtin,
    /// A price file (JSON, or TOML for a `.toml` file) whose entries are added to the
    /// built-in table, in place of those of the same model.
    File(PathBuf),
    /// The entries of a JSON object by model, added likewise (Python's dict, a worker's
    /// copy of the driver's table).
    Json(String),
}

impl PriceSource {
    /// The price table.
    pub fn read(self) -> Result<PriceTable, Error> {
        let builtin = PriceTable::builtin();
        Ok(match self {
            PriceSource::Builtin => builtin,
            PriceSource::File(file) => builtin.overridden_by(PriceTable::read(&file)?),
            PriceSource::Json(text) => {
                builtin.overridden_by(PriceTable::parse_json(&text, "prices")?)
            }
        })
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

/// Writes every template of the set `from` names (the built-in one by default) into
/// `dir` (made when missing), one file each, and overwrites templates already there when
/// `overwrite`; returns the files written.
pub fn export(dir: &Path, overwrite: bool, from: PromptSource) -> Result<Vec<PathBuf>, Error> {
    Ok(templates::export(dir, overwrite, &from.read()?)?)
}

/// One line about a prompt set that replaces built-in templates (`None` for the
/// built-in set): the files and the set's hash, as the transcripts of `executions`
/// record it (a parallel episode's hash covers the parallel templates too).
pub fn describe(prompts: &Prompts, executions: &[Execution]) -> Option<String> {
    let replaced = prompts.replaced_names();
    let sets: Vec<String> = match executions {
        [one] => vec![prompts.hash(*one).to_owned()],
        several => several
            .iter()
            .map(|e| format!("{} {e}", prompts.hash(*e)))
            .collect(),
    };
    (!replaced.is_empty()).then(|| {
        format!(
            "prompts: {} in place of the built-in templates (set {})",
            replaced.join(", "),
            sets.join(", ")
        )
    })
}
