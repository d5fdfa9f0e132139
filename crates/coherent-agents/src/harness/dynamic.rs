//! The events table of a benchmark run on tasks with events (docs/dynamic.md): per
//! method, execution and kind of event, the success rate (an episode that conceded a goal
//! put out of reach for good counts as right), how many conceded, the steps over the
//! reference of the successful episodes, and the recovery: the share of events the team
//! recovered from, the rounds it took, the actions wasted meanwhile and the model calls
//! spent.
//!
//! Plain means over episodes, as in the makespan table.

use serde::Serialize;

use crate::harness::results::ResultLine;
use crate::harness::speedup::{row_name, row_order};
use crate::records::transcript::Status;
use coherent_core::Execution;

/// One method, execution and kind of event.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EventRow {
    pub method: String,
    pub execution: Execution,
    /// The kinds of the tasks' events, joined by `+`.
    pub kind: String,
    pub episodes: usize,
    pub sr: f64,
    /// Episodes that ended conceded.
    pub conceded: usize,
    /// Mean steps over the reference, of the successful episodes that have one.
    pub over_reference: Option<f64>,
    /// Events the team recovered from, of those it had to.
    pub recovered: usize,
    pub recoveries: usize,
    /// Mean rounds to recover, of the recoveries.
    pub recovery_rounds: Option<f64>,
    /// Mean actions wasted per event before recovering (or until the next event).
    pub wasted: Option<f64>,
    /// Mean model calls per event spent recovering.
    pub recovery_calls: Option<f64>,
}

fn mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// The rows, for the final lines with a reference; none when no line has one.
pub fn build(finals: &[&ResultLine]) -> Vec<EventRow> {
    let with: Vec<&ResultLine> = finals
        .iter()
        .copied()
        .filter(|l| l.reference.is_some())
        .collect();
    let kind = |l: &ResultLine| {
        l.reference
            .as_ref()
            .map_or(String::new(), |r| r.kinds.join("+"))
    };
    let mut keys: Vec<(String, Execution, String)> = with
        .iter()
        .map(|l| (l.method.clone(), l.execution, kind(l)))
        .collect();
    keys.sort_by_key(|(m, e, k)| (row_order(m, *e), k.clone()));
    keys.dedup();
    keys.into_iter()
        .map(|(method, execution, k)| {
            let lines: Vec<&ResultLine> = with
                .iter()
                .copied()
                .filter(|l| l.method == method && l.execution == execution && kind(l) == k)
                .collect();
            let n = lines.len();
            let refs = lines.iter().filter_map(|l| l.reference.as_ref());
            let recoveries: Vec<_> = refs.clone().flat_map(|r| &r.recoveries).collect();
            let rounds: Vec<f64> = recoveries
                .iter()
                .filter_map(|r| r.rounds.map(f64::from))
                .collect();
            let over: Vec<f64> = lines
                .iter()
                .filter(|l| l.status == Status::Success)
                .filter_map(|l| {
                    let r = l.reference.as_ref()?.steps?;
                    Some(f64::from(l.steps) - f64::from(r))
                })
                .collect();
            EventRow {
                kind: k,
                episodes: n,
                sr: lines.iter().filter(|l| l.success).count() as f64 / n as f64,
                conceded: lines
                    .iter()
                    .filter(|l| l.status == Status::Conceded)
                    .count(),
                over_reference: mean(&over),
                recovered: rounds.len(),
                recoveries: recoveries.len(),
                recovery_rounds: mean(&rounds),
                wasted: mean(
                    &recoveries
                        .iter()
                        .map(|r| f64::from(r.wasted))
                        .collect::<Vec<_>>(),
                ),
                recovery_calls: mean(
                    &recoveries
                        .iter()
                        .map(|r| f64::from(r.calls))
                        .collect::<Vec<_>>(),
                ),
                method,
                execution,
            }
        })
        .collect()
}

/// The table in Markdown (empty without rows); `name` writes a method's name for it.
pub fn markdown(rows: &[EventRow], name: fn(&str) -> String) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let opt = |x: Option<f64>, d: usize| x.map_or("-".into(), |x| format!("{x:.d$}"));
    let mut out = String::from("### Events: success and recovery\n\n");
    out.push_str(
        "SR counts an episode that conceded a goal put out of reach for good as right. \
         Over ref.: the successful episodes' steps over the reference (an oracle replanning \
         at each event). Recovered: the events after which the team carried out an action \
         that brought the goal nearer, of those that changed the world; rounds, wasted \
         actions and model calls per event until then (docs/dynamic.md).  \n\n",
    );
    out.push_str(
        "| Method | Events | Episodes | SR | Conceded | Over ref. | Recovered | Rounds | Wasted | Calls |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} | {} | {} | {:.3} | {} | {} | {}/{} | {} | {} | {} |\n",
            name(&row_name(&r.method, r.execution)),
            name(&r.kind),
            r.episodes,
            r.sr,
            r.conceded,
            opt(r.over_reference, 2),
            r.recovered,
            r.recoveries,
            opt(r.recovery_rounds, 2),
            opt(r.wasted, 2),
            opt(r.recovery_calls, 2)
        ));
    }
    out
}
