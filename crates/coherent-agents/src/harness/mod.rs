//! The benchmark's bookkeeping, whatever runs its episodes (the session's local
//! executor, or workers on a cluster): which tasks ([`subset`]), the results file, one
//! JSON line per finished episode ([`results`]), the driver's side of a run that resumes
//! it and writes each result once ([`ledger`]), what a run reports as it goes
//! ([`progress`]), what tokens cost ([`prices`]), the settings that make lines
//! comparable ([`run_settings`]) and the paper's tables ([`report`]), with the makespan
//! table of runs with parallel episodes ([`speedup`]).
//! The crate root names this module `bench` too, with its main types at hand.

pub mod dynamic;
pub mod ledger;
pub mod prices;
pub mod progress;
pub mod report;
pub mod results;
pub mod run_settings;
pub mod speedup;
pub mod subset;

pub use crate::setting::{Difference, Setting};
pub use ledger::{BenchOutcome, EpisodeResult, Ledger, episode_keys};
pub use prices::{ModelUse, PriceTable};
pub use progress::{Event, Progress, Style, worth_a_line};
pub use report::Group;
pub use results::{DEFAULT_MAX_BYTES as DEFAULT_MAX_RESULTS_BYTES, ERROR_BYTES};
pub use results::{
    EpisodeKey, ReadLimits, ResultLine, ResultsFile, mark_orphans, read_results,
    read_results_opening, read_results_within, repair, transcripts_dir,
};
pub use run_settings::RunSettings;
pub use subset::{PAPER40, Selection, Subset, same_key_twice, select};
