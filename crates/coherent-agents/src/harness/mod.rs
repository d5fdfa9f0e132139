//! The benchmark harness: [`bench`](mod@bench) runs methods x tasks x seeds into a results file
//! ([`results`]) over a [`subset`] of the tasks, reporting [`progress`], each line priced
//! from a [`prices`] table; [`report`] turns the results into the paper's tables.

pub mod bench;
pub mod prices;
pub mod progress;
pub mod report;
pub mod results;
pub mod subset;
