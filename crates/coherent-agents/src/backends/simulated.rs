//! The simulated backend's mistakes: the built-in planner ([`crate::backends::builtin`])
//! making the errors language models make, each at its own seeded rate ([`ErrorRates`]),
//! for offline study of how methods recover. It is labelled `simulated` wherever its
//! results appear.

use coherent_core::text::number;
use coherent_core::{Idx, Task};

use crate::error::Error;
use crate::rng::Rng;

/// The kinds of mistakes the simulated backend makes, each with its own rate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Mistake {
    /// An action that is not in the robot's list.
    Hallucinate,
    /// The right step given to the wrong robot.
    WrongRobot,
    /// An answer that cannot be parsed.
    Malformed,
    /// A valid choice that is not a step of a shortest plan.
    Suboptimal,
}

/// Rates of the simulated backend's mistakes: each answer draws every kind
/// independently with its own probability, and makes the first that fires in the order
/// malformed, hallucinate, wrong robot, suboptimal (so `all=0.1` leaves
/// `0.9^4 = 0.66` of answers right).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorRates {
    pub hallucinate: f64,
    pub wrong_robot: f64,
    pub malformed: f64,
    pub suboptimal: f64,
}

impl ErrorRates {
    /// Every kind at `rate`.
    pub fn all(rate: f64) -> ErrorRates {
        ErrorRates {
            hallucinate: rate,
            wrong_robot: rate,
            malformed: rate,
            suboptimal: rate,
        }
    }

    /// `hallucinate=0.1,wrong_robot=0.1,malformed=0.05,suboptimal=0.1`; `all=0.1` sets
    /// every kind; kinds not named are 0.
    pub fn parse(spec: &str) -> Result<ErrorRates, Error> {
        ErrorRates::read(spec).map_err(Error::Invalid)
    }

    fn read(spec: &str) -> Result<ErrorRates, String> {
        let mut rates = ErrorRates::default();
        for part in spec.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (key, value) = part
                .split_once('=')
                .ok_or_else(|| format!("{part:?}: expected kind=rate"))?;
            let rate: f64 = value
                .trim()
                .parse()
                .ok()
                .filter(|r| (0.0..=1.0).contains(r))
                .ok_or_else(|| format!("{part:?}: the rate must be a number from 0 to 1"))?;
            match key.trim() {
                "all" => rates = ErrorRates::all(rate),
                "hallucinate" => rates.hallucinate = rate,
                "wrong_robot" => rates.wrong_robot = rate,
                "malformed" => rates.malformed = rate,
                "suboptimal" => rates.suboptimal = rate,
                other => {
                    return Err(format!(
                        "{other:?} is not an error kind (hallucinate, wrong_robot, malformed, suboptimal, all)"
                    ));
                }
            }
        }
        Ok(rates)
    }

    /// `hallucinate=0.1,wrong_robot=0.1,malformed=0.1,suboptimal=0.1`.
    pub fn label(&self) -> String {
        format!(
            "hallucinate={},wrong_robot={},malformed={},suboptimal={}",
            number(self.hallucinate),
            number(self.wrong_robot),
            number(self.malformed),
            number(self.suboptimal)
        )
    }

    /// The mistake of one answer: four uniform draws, one per kind, always all four so
    /// that the stream stays aligned whatever fires.
    pub(crate) fn draw(&self, rng: &mut Rng) -> Option<Mistake> {
        let draws = [rng.unit(), rng.unit(), rng.unit(), rng.unit()];
        [
            (self.malformed, Mistake::Malformed),
            (self.hallucinate, Mistake::Hallucinate),
            (self.wrong_robot, Mistake::WrongRobot),
            (self.suboptimal, Mistake::Suboptimal),
        ]
        .into_iter()
        .zip(draws)
        .find(|&((rate, _), u)| u < rate)
        .map(|((_, mistake), _)| mistake)
    }
}

/// Another robot of the team than `robot` (the same one when it is alone).
pub(crate) fn other_robot(task: &Task, robot: Idx, rng: &mut Rng) -> Idx {
    let others: Vec<Idx> = task
        .robots
        .iter()
        .map(|r| r.node)
        .filter(|&n| n != robot)
        .collect();
    if others.is_empty() {
        robot
    } else {
        others[rng.below(others.len())]
    }
}

/// A well-formed action that is not in `listed`: grabbing a random thing of the scene,
/// the most common invention of a model that has lost track of what it can reach.
pub(crate) fn hallucinated(task: &Task, listed: &[String], rng: &mut Rng) -> String {
    let all: Vec<Idx> = task.indices().collect();
    for _ in 0..32 {
        let n = all[rng.below(all.len())];
        let action = format!("[grab] {}", task.node(n).label());
        if !listed.contains(&action) {
            return action;
        }
    }
    "[grab] <nothing>(-1)".to_owned()
}
