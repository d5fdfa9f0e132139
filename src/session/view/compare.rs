//! Two episodes side by side: the same steps shown together, and the first round in
//! which their decisions differ.

use coherent_agents::transcript::{Round, Transcript};
use coherent_core::Task;
use serde::Serialize;

use super::episode::EpisodeView;

/// The page's data for one episode, or two side by side.
#[derive(Debug, Serialize)]
pub struct Episodes {
    /// `episode` or `compare`.
    pub kind: &'static str,
    pub episodes: Vec<EpisodeView>,
    /// The first round whose decisions differ between the two; none when they decided
    /// alike in every round (or for one episode).
    pub first_difference: Option<u32>,
}

/// The step of the first round where `a` and `b` (episodes of `task_a` and `task_b`)
/// decide differently: another robot, or another action ([`Round::chosen`]); when one
/// ends earlier and they agree until then, the first round only the other has.
pub fn first_difference(
    (task_a, a): (&Task, &Transcript),
    (task_b, b): (&Task, &Transcript),
) -> Option<u32> {
    for (ra, rb) in a.rounds.iter().zip(&b.rounds) {
        if ra.chosen(task_a) != rb.chosen(task_b) {
            return Some(ra.step);
        }
    }
    let common = a.rounds.len().min(b.rounds.len());
    let longer = if a.rounds.len() > b.rounds.len() {
        a
    } else {
        b
    };
    longer.rounds.get(common).map(|r: &Round| r.step)
}
