//! Two episodes side by side: the same steps shown together, and the first round in
//! which their decisions differ.

use coherent_agents::transcript::{Round, Transcript};
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

/// What a round decided: which robot acts, and which action (none when it declined or
/// no usable decision came).
fn decided(r: &Round) -> (Option<i64>, Option<&str>) {
    let robot = r
        .proposal
        .as_ref()
        .map(|p| p.robot.0)
        .or_else(|| r.external.as_ref().and_then(|e| e.robot).map(|id| id.0));
    let action = r
        .decision
        .as_ref()
        .and_then(|d| d.action.as_deref())
        .or_else(|| r.external.as_ref().and_then(|e| e.action.as_deref()));
    (robot, action)
}

/// The step of the first round where `a` and `b` decide differently; when one ends
/// earlier and they agree until then, the first round only the other has.
pub fn first_difference(a: &Transcript, b: &Transcript) -> Option<u32> {
    let common = a.rounds.len().min(b.rounds.len());
    for (ra, rb) in a.rounds.iter().zip(&b.rounds) {
        if decided(ra) != decided(rb) {
            return Some(ra.step);
        }
    }
    let longer = if a.rounds.len() > b.rounds.len() {
        a
    } else {
        b
    };
    longer.rounds.get(common).map(|r| r.step)
}
