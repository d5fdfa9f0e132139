//! The benchmark harness: [`bench`](mod@bench) runs methods x tasks x seeds into a results file
//! ([`results`]) over a [`subset`] of the tasks, reporting [`progress`], each line priced
//! from a [`prices`] table; [`report`] turns the results into the paper's tables. A run
//! is made of parts other executors share: [`choice`] (which backend), [`job`] (one
//! episode by its key) and [`ledger`] (the driver's side: the results file, what is left
//! to run, each result written once).

pub mod bench;
pub mod choice;
pub mod job;
pub mod ledger;
pub mod prices;
pub mod progress;
pub mod report;
pub mod results;
pub mod subset;
