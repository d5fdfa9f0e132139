//! The settings a benchmark run records in every results line, by name ([`Setting`]), and
//! one that differs between a results file and a run ([`Difference`]): what
//! [`crate::Error::SettingsDiffer`] lists. Below the error type, so that the error can
//! name them; the settings themselves are the harness's
//! (`crate::harness::run_settings`).

use std::fmt;

use coherent_core::text::shown;

/// One setting of a benchmark run (`crate::harness::run_settings::RunSettings`), for a
/// front end to name as its flag or argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Setting {
    Backend,
    Model,
    SimErrors,
    Temperature,
    ModelSeed,
    Seeds,
    Prompts,
    History,
    MaxSteps,
    MaxStates,
    Physics,
    Robots,
    /// The executions of the run.
    Execution,
    /// The version of coherent.
    Version,
    /// A method's own settings.
    Method,
    /// Lines that record no settings (written before results lines kept them).
    Unrecorded,
}

/// A setting that differs between the lines of a results file and a run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Difference {
    pub setting: Setting,
    /// The method, for [`Setting::Method`].
    pub method: Option<String>,
    /// Its value in the file, as shown.
    pub file: String,
    /// Its value now, as shown.
    pub now: String,
}

/// Both values shown escaped: the file's come from whatever wrote it (a model's name, a
/// method's own settings).
impl fmt::Display for Difference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} in the file, {} now",
            shown(&self.file),
            shown(&self.now)
        )
    }
}

/// The name of `setting` in a results line's `settings` object.
pub fn field(setting: Setting) -> &'static str {
    match setting {
        Setting::Backend => "backend",
        Setting::Model => "model",
        Setting::SimErrors => "sim_errors",
        Setting::Temperature => "temperature",
        Setting::ModelSeed => "model_seed",
        Setting::Seeds => "seeds",
        Setting::Prompts => "prompts",
        Setting::History => "history",
        Setting::MaxSteps => "max_steps",
        Setting::MaxStates => "max_states",
        Setting::Physics => "physics",
        Setting::Robots => "robots",
        Setting::Execution => "executions",
        Setting::Version => "coherent",
        Setting::Method => "method",
        Setting::Unrecorded => "settings",
    }
}
