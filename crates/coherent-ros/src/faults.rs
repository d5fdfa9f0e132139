//! Faults the reference servers inject for tests and demonstrations: a delay per action,
//! failures at a seeded rate, a robot that never answers, a robot that refuses goals, a
//! robot whose server never starts.

use std::time::Duration;

use crate::error::Error;

/// What goes wrong on purpose; the default is nothing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Faults {
    /// How long each action takes (feedback all along); zero acts at once.
    pub delay: Duration,
    /// The chance, 0 to 1, that a robot reports failure instead of acting.
    pub fail_rate: f64,
    /// Seeds the failures: the same seed fails the same goals of each robot.
    pub seed: u64,
    /// Robots (ROS names) that accept goals and then never answer.
    pub silent: Vec<String>,
    /// Robots (ROS names) whose server refuses every goal.
    pub refuse: Vec<String>,
    /// Robots (ROS names) whose server is never started.
    pub absent: Vec<String>,
}

impl Faults {
    /// Checks the rate and that every robot named is one of `robots`.
    pub fn check(&self, robots: &[String]) -> Result<(), Error> {
        if !(0.0..=1.0).contains(&self.fail_rate) {
            return Err(Error::Invalid(format!(
                "the failure rate must be between 0 and 1, not {}",
                coherent_core::text::number(self.fail_rate)
            )));
        }
        let unknown: Vec<&str> = self
            .silent
            .iter()
            .chain(&self.refuse)
            .chain(&self.absent)
            .filter(|r| !robots.contains(r))
            .map(String::as_str)
            .collect();
        if unknown.is_empty() {
            Ok(())
        } else {
            Err(Error::Invalid(format!(
                "no robot named {} in the task; its robots: {}",
                unknown.join(", "),
                robots.join(", ")
            )))
        }
    }

    pub fn is_silent(&self, robot: &str) -> bool {
        self.silent.iter().any(|r| r == robot)
    }

    pub fn refuses(&self, robot: &str) -> bool {
        self.refuse.iter().any(|r| r == robot)
    }

    pub fn is_absent(&self, robot: &str) -> bool {
        self.absent.iter().any(|r| r == robot)
    }

    /// The failure draws of one robot, seeded by the seed and the robot's name.
    pub fn draws(&self, robot: &str) -> Draws {
        let name = robot.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        });
        Draws {
            state: self.seed ^ name,
            rate: self.fail_rate,
        }
    }
}

/// A robot's sequence of "does this goal fail?" (SplitMix64).
#[derive(Clone, Debug)]
pub struct Draws {
    state: u64,
    rate: f64,
}

impl Draws {
    /// Whether the next goal fails.
    pub fn fails(&mut self) -> bool {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        // 53 random bits as a number in [0, 1).
        ((z >> 11) as f64) / ((1u64 << 53) as f64) < self.rate
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_follow_the_seed_and_the_rate() {
        let faults = Faults {
            fail_rate: 0.3,
            seed: 7,
            ..Faults::default()
        };
        let run = |f: &Faults, robot: &str| {
            let mut d = f.draws(robot);
            (0..1000).map(|_| d.fails()).collect::<Vec<bool>>()
        };
        let a = run(&faults, "quadrotor_11");
        assert_eq!(a, run(&faults, "quadrotor_11"));
        assert_ne!(a, run(&faults, "robot_dog_13"));
        let reseeded = Faults {
            seed: 8,
            ..faults.clone()
        };
        assert_ne!(a, run(&reseeded, "quadrotor_11"));
        let failures = a.iter().filter(|f| **f).count();
        assert!((240..360).contains(&failures), "{failures} of 1000");
        let never = Faults::default();
        assert!(run(&never, "quadrotor_11").iter().all(|f| !f));
        let always = Faults {
            fail_rate: 1.0,
            ..Faults::default()
        };
        assert!(run(&always, "quadrotor_11").iter().all(|f| *f));
    }

    #[test]
    fn faults_name_robots_of_the_task() {
        let robots = vec!["quadrotor_11".to_owned(), "robot_dog_13".to_owned()];
        let ok = Faults {
            silent: vec!["quadrotor_11".into()],
            refuse: vec!["robot_dog_13".into()],
            absent: vec!["quadrotor_11".into()],
            ..Faults::default()
        };
        assert_eq!(ok.check(&robots), Ok(()));
        assert!(ok.is_silent("quadrotor_11") && !ok.is_silent("robot_dog_13"));
        assert!(ok.refuses("robot_dog_13") && !ok.refuses("quadrotor_11"));
        assert!(ok.is_absent("quadrotor_11") && !ok.is_absent("robot_dog_13"));
        let drone = vec!["drone_1".to_owned()];
        for bad in [
            Faults {
                silent: drone.clone(),
                ..Faults::default()
            },
            Faults {
                refuse: drone.clone(),
                ..Faults::default()
            },
            Faults {
                absent: drone.clone(),
                ..Faults::default()
            },
        ] {
            let why = bad
                .check(&robots)
                .expect_err("drone_1 is no robot")
                .to_string();
            assert!(
                why.contains("drone_1") && why.contains("robot_dog_13"),
                "{why}"
            );
        }
        let rate = Faults {
            fail_rate: 1.5,
            ..Faults::default()
        };
        assert!(rate.check(&robots).is_err());
    }
}
