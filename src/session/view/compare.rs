//! Two episodes side by side: the same steps shown together, and the first round in
//! which their decisions differ.

use coherent_agents::transcript::{RobotPart, Round, Transcript};
use coherent_core::NodeId;
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

/// The step of the first round where episodes `a` and `b` decide differently: another
/// robot, or another action ([`Round::chosen`]; in a joint step, any robot's); when one
/// ends earlier and they agree until then, the first round only the other has.
pub fn first_difference(a: &Transcript, b: &Transcript) -> Option<u32> {
    for (ra, rb) in a.rounds.iter().zip(&b.rounds) {
        if decided(ra) != decided(rb) {
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

/// What a round decided: the robot and action it chose, or each robot's part of a joint
/// step and the action decided for it.
fn decided<'r>(r: &'r Round) -> Vec<(Option<NodeId>, Option<&'r str>)> {
    if r.parts.is_empty() {
        return vec![r.chosen()];
    }
    let action = |p: &'r RobotPart| p.decision.as_ref().and_then(|d| d.action.as_deref());
    r.parts.iter().map(|p| (Some(p.robot), action(p))).collect()
}
