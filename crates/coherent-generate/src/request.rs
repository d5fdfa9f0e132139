//! What a generated set is asked to be: its size and seed, its scenes, its teams, its
//! goals and the filters its tasks must pass ([`Request`]), with the parsing of the
//! knobs that the command line and Python share (`3`, `3-4`, `quadrotor=2,legged=0-3`,
//! `mono,trio`, `0.8,0.1,0.1`), and the error that names the knob.

use coherent_core::RobotKind;
use coherent_core::planner::{Limits, TaskType};

/// A request that cannot be met, or a knob that cannot be read: which knob, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct KnobError {
    /// The knob as the command line names it, `--team`.
    pub knob: &'static str,
    pub message: String,
}

impl std::fmt::Display for KnobError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.knob, self.message)
    }
}

impl std::error::Error for KnobError {}

pub(crate) fn knob<T>(knob: &'static str, message: String) -> Result<T, KnobError> {
    Err(KnobError { knob, message })
}

/// A closed range of whole numbers, `lo..=hi`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Span {
    pub lo: usize,
    pub hi: usize,
}

impl Span {
    pub const fn new(lo: usize, hi: usize) -> Span {
        Span { lo, hi }
    }

    pub fn contains(&self, n: usize) -> bool {
        self.lo <= n && n <= self.hi
    }

    /// `3` or `3-4`, for the knob `name`.
    pub fn parse(name: &'static str, text: &str) -> Result<Span, KnobError> {
        let bad = || KnobError {
            knob: name,
            message: format!("{text:?} is neither a number nor a range like 3-4"),
        };
        let (lo, hi) = match text.trim().split_once('-') {
            Some((a, b)) => (
                a.trim().parse().map_err(|_| bad())?,
                b.trim().parse().map_err(|_| bad())?,
            ),
            None => {
                let n = text.trim().parse().map_err(|_| bad())?;
                (n, n)
            }
        };
        if lo > hi {
            return knob(name, format!("{text:?}: the range runs backwards"));
        }
        Ok(Span { lo, hi })
    }
}

impl std::fmt::Display for Span {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.lo == self.hi {
            write!(f, "{}", self.lo)
        } else {
            write!(f, "{}-{}", self.lo, self.hi)
        }
    }
}

/// A closed range of ratios, `lo..=hi` (sequential steps over makespan).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ratio {
    pub lo: f64,
    pub hi: f64,
}

impl Ratio {
    /// `1.2-2` or `1.5`.
    pub fn parse(name: &'static str, text: &str) -> Result<Ratio, KnobError> {
        let bad = || KnobError {
            knob: name,
            message: format!("{text:?} is neither a number nor a range like 1.2-2.0"),
        };
        let number = |s: &str| -> Result<f64, KnobError> {
            let x: f64 = s.trim().parse().map_err(|_| bad())?;
            if x.is_finite() && x >= 1.0 {
                Ok(x)
            } else {
                knob(
                    name,
                    format!("{s:?}: a ratio of sequential steps to joint steps is at least 1"),
                )
            }
        };
        let (lo, hi) = match text.trim().split_once('-') {
            Some((a, b)) => (number(a)?, number(b)?),
            None => {
                let x = number(text)?;
                (x, x)
            }
        };
        if lo > hi {
            return knob(name, format!("{text:?}: the range runs backwards"));
        }
        Ok(Ratio { lo, hi })
    }

    pub fn contains(&self, x: f64) -> bool {
        // Ratios of small whole numbers: a hair of slack for 4/3 written as 1.333.
        self.lo - 1e-9 <= x && x <= self.hi + 1e-9
    }
}

/// The robot kinds in the order teams are written: `quadrotor`, `legged`, `arm`.
pub const KINDS: [RobotKind; 3] = [
    RobotKind::Quadrotor,
    RobotKind::RobotDog,
    RobotKind::RobotArm,
];

/// A kind's name in a team spec and the manifest.
pub fn kind_name(kind: RobotKind) -> &'static str {
    match kind {
        RobotKind::Quadrotor => "quadrotor",
        RobotKind::RobotDog => "legged",
        RobotKind::RobotArm => "arm",
    }
}

/// The most robots of one kind in a team.
pub const MAX_OF_KIND: usize = 8;
/// The most robots in a team.
pub const MAX_TEAM: usize = 16;

/// How many robots of each kind a team may have, and in all.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TeamSpec {
    /// Per kind, in [`KINDS`] order.
    pub kinds: [Span; 3],
    /// The team's size; `None`: whatever the kinds add up to.
    pub size: Option<Span>,
}

impl Default for TeamSpec {
    /// One robot of each kind, as the paper's scenes have.
    fn default() -> TeamSpec {
        TeamSpec {
            kinds: [Span::new(1, 1); 3],
            size: None,
        }
    }
}

impl TeamSpec {
    /// `quadrotor=2,legged=0-3,arm=1` (`--team`) and the team's size (`--robots`), either
    /// may be absent: a kind the spec leaves out has 0 robots, or, with a size given and
    /// no `--team`, 0 to the size.
    pub fn parse(team: Option<&str>, size: Option<&str>) -> Result<TeamSpec, KnobError> {
        let size = size.map(|s| Span::parse("--robots", s)).transpose()?;
        let kinds = match team {
            None => match size {
                Some(s) => [Span::new(0, s.hi.min(MAX_OF_KIND)); 3],
                None => [Span::new(1, 1); 3],
            },
            Some(text) => {
                let mut kinds = [Span::new(0, 0); 3];
                let mut seen = [false; 3];
                for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
                    let Some((name, count)) = part.split_once('=') else {
                        return knob(
                            "--team",
                            format!(
                                "{part:?}: expected KIND=N or KIND=N-M (kinds: quadrotor, legged, arm)"
                            ),
                        );
                    };
                    let k = match name.trim() {
                        "quadrotor" | "quadrotors" => 0,
                        "legged" | "robot dog" | "dog" | "dogs" => 1,
                        "arm" | "arms" | "robot arm" => 2,
                        other => {
                            return knob(
                                "--team",
                                format!(
                                    "unknown robot kind {other:?} (kinds: quadrotor, legged, arm)"
                                ),
                            );
                        }
                    };
                    if seen[k] {
                        return knob("--team", format!("{} is given twice", kind_name(KINDS[k])));
                    }
                    seen[k] = true;
                    kinds[k] = Span::parse("--team", count)?;
                }
                kinds
            }
        };
        for (k, span) in kinds.iter().enumerate() {
            if span.hi > MAX_OF_KIND {
                return knob(
                    "--team",
                    format!(
                        "at most {MAX_OF_KIND} robots of a kind ({} asks {})",
                        kind_name(KINDS[k]),
                        span.hi
                    ),
                );
            }
        }
        let spec = TeamSpec { kinds, size };
        if let Some(s) = size
            && s.hi > MAX_TEAM
        {
            return knob(
                "--robots",
                format!("at most {MAX_TEAM} robots in a team (asked {s})"),
            );
        }
        if spec.compositions().is_empty() {
            let kinds: Vec<String> = KINDS
                .iter()
                .zip(&spec.kinds)
                .map(|(k, s)| format!("{}={s}", kind_name(*k)))
                .collect();
            let (name, why) = match size {
                Some(s) => (
                    "--robots",
                    format!("no team of {s} robots has {}", kinds.join(", ")),
                ),
                None => ("--team", "a team of no robot can do nothing".to_owned()),
            };
            return knob(name, why);
        }
        Ok(spec)
    }

    /// Every team the spec allows, as counts per kind in [`KINDS`] order: at least one
    /// robot, at most [`MAX_TEAM`], within the size.
    pub fn compositions(&self) -> Vec<[usize; 3]> {
        let [q, d, a] = self.kinds;
        let mut out = Vec::new();
        for nq in q.lo..=q.hi {
            for nd in d.lo..=d.hi {
                for na in a.lo..=a.hi {
                    let n = nq + nd + na;
                    if (1..=MAX_TEAM).contains(&n) && self.size.is_none_or(|s| s.contains(n)) {
                        out.push([nq, nd, na]);
                    }
                }
            }
        }
        out
    }

    /// The most robots of each kind any allowed team has.
    pub fn most(&self) -> [usize; 3] {
        let mut most = [0; 3];
        for c in self.compositions() {
            for k in 0..3 {
                most[k] = most[k].max(c[k]);
            }
        }
        most
    }
}

/// A task type's name.
pub fn parse_types(text: &str) -> Result<Vec<TaskType>, KnobError> {
    let mut out = Vec::new();
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let t = match part {
            "mono" => TaskType::Mono,
            "dual" => TaskType::Dual,
            "trio" => TaskType::Trio,
            other => {
                return knob(
                    "--type",
                    format!("unknown task type {other:?} (types: mono, dual, trio)"),
                );
            }
        };
        if !out.contains(&t) {
            out.push(t);
        }
    }
    if out.is_empty() {
        return knob("--type", "no type given (types: mono, dual, trio)".into());
    }
    Ok(out)
}

/// `train,validation,test` shares of the scenes, e.g. `0.8,0.1,0.1`.
pub fn parse_split(text: &str) -> Result<[f64; 3], KnobError> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let bad = || KnobError {
        knob: "--split",
        message: format!(
            "{text:?}: expected three shares, train,validation,test (e.g. 0.8,0.1,0.1)"
        ),
    };
    let [a, b, c] = parts[..] else {
        return Err(bad());
    };
    let mut out = [0.0; 3];
    for (o, p) in out.iter_mut().zip([a, b, c]) {
        *o = p.parse::<f64>().map_err(|_| bad())?;
        if !o.is_finite() || *o < 0.0 {
            return Err(bad());
        }
    }
    if out.iter().sum::<f64>() <= 0.0 {
        return knob("--split", format!("{text:?}: the shares add up to nothing"));
    }
    Ok(out)
}

/// Everything a generated set is asked to be.
#[derive(Clone, Debug)]
pub struct Request {
    /// How many tasks.
    pub tasks: usize,
    pub seed: u64,
    /// How many scenes the tasks are spread over.
    pub scenes: usize,
    /// Rooms per scene, both storeys together.
    pub rooms: Span,
    /// The chance that a scene of four rooms or more has a second storey.
    pub upstairs: f64,
    /// The chance that a door starts closed.
    pub closed: f64,
    pub team: TeamSpec,
    /// Goal predicates per task.
    pub predicates: Span,
    /// Keep only tasks of these types (empty: any).
    pub types: Vec<TaskType>,
    /// Keep only tasks that need this many robots at the fewest.
    pub needed: Option<Span>,
    /// Keep only tasks whose optimal plan has this many steps.
    pub steps: Option<Span>,
    /// Keep only tasks whose optimal steps over their makespan lie here.
    pub ratio: Option<Ratio>,
    /// Keep only tasks whose makespan is proven.
    pub proven_only: bool,
    /// Keep only tasks whose optimal plan runs in physics (every kept task's plan is
    /// carried out in Rapier; without it only the scene's building is checked).
    pub physics: bool,
    /// The bounds of every search.
    pub limits: Limits,
    /// The most candidates drawn; `None`: [`Request::default_draws`].
    pub max_draws: Option<usize>,
    /// Shares of the scenes in train, validation and test.
    pub split: [f64; 3],
    /// Threads that work out ground truths.
    pub jobs: usize,
}

impl Request {
    /// The draws a request may take before it says it cannot be met: 50 per task asked
    /// and 1,000 more (a filter that keeps one draw in 50 still gets there).
    pub fn default_draws(&self) -> usize {
        self.tasks.saturating_mul(50).saturating_add(1000)
    }

    /// The draw budget.
    pub fn draws(&self) -> usize {
        self.max_draws.unwrap_or_else(|| self.default_draws())
    }

    /// The checks that need no draw: a knob out of range, a type or a number of robots
    /// no team of the spec can give.
    pub fn check(&self) -> Result<(), KnobError> {
        if self.tasks == 0 {
            return knob("--tasks", "0: a set needs at least one task".into());
        }
        if self.scenes == 0 {
            return knob("--scenes", "a set needs at least one scene".into());
        }
        if self.rooms.lo < 2 || self.rooms.hi > MAX_ROOMS {
            return knob(
                "--rooms",
                format!("{} rooms: a scene has 2 to {MAX_ROOMS}", self.rooms),
            );
        }
        if self.predicates.lo == 0 || self.predicates.hi > MAX_PREDICATES {
            return knob(
                "--predicates",
                format!(
                    "{}: a goal has 1 to {MAX_PREDICATES} predicates",
                    self.predicates
                ),
            );
        }
        for (name, p) in [("--upstairs", self.upstairs), ("--closed", self.closed)] {
            if !(0.0..=1.0).contains(&p) {
                return knob(name, format!("{p} is not a chance between 0 and 1"));
            }
        }
        if self.jobs == 0 {
            return knob("--jobs", "at least one thread".into());
        }
        let teams = self.team.compositions();
        let kinds_of = |c: &[usize; 3]| c.iter().filter(|&&n| n > 0).count();
        let most_kinds = teams.iter().map(kinds_of).max().unwrap_or(0);
        for t in &self.types {
            let need = match t {
                TaskType::Mono => 1,
                TaskType::Dual => 2,
                TaskType::Trio => 3,
            };
            if need > most_kinds {
                return knob(
                    "--type",
                    format!(
                        "a {} task needs {need} kinds of robot, and the teams of --team/--robots have at most {most_kinds}",
                        t.name()
                    ),
                );
            }
        }
        if let Some(n) = self.needed {
            let largest = teams
                .iter()
                .map(|c| c.iter().sum::<usize>())
                .max()
                .unwrap_or(0);
            if n.lo > largest || n.hi == 0 {
                return knob(
                    "--needed",
                    format!("{n} robots needed, and the teams have 1 to {largest}"),
                );
            }
        }
        if let Some(s) = self.steps
            && s.hi == 0
        {
            return knob("--steps", "every task takes at least one step".into());
        }
        Ok(())
    }
}

impl Request {
    /// The request as the command line that makes it, every knob written out in one
    /// order (not as it was typed): what the datasheet names, the same from the command
    /// line and from Python. The threads and the output folder make no difference to
    /// the set and are left out.
    pub fn command(&self) -> String {
        let mut out = format!(
            "coherent generate --tasks {} --seed {} --scenes {} --rooms {} --upstairs {} --closed {}",
            self.tasks, self.seed, self.scenes, self.rooms, self.upstairs, self.closed
        );
        let team: Vec<String> = KINDS
            .iter()
            .zip(&self.team.kinds)
            .map(|(k, s)| format!("{}={s}", kind_name(*k)))
            .collect();
        out.push_str(&format!(" --team {}", team.join(",")));
        if let Some(size) = self.team.size {
            out.push_str(&format!(" --robots {size}"));
        }
        out.push_str(&format!(" --predicates {}", self.predicates));
        if !self.types.is_empty() {
            let names: Vec<&str> = self.types.iter().map(|t| t.name()).collect();
            out.push_str(&format!(" --type {}", names.join(",")));
        }
        if let Some(n) = self.needed {
            out.push_str(&format!(" --needed {n}"));
        }
        if let Some(s) = self.steps {
            out.push_str(&format!(" --steps {s}"));
        }
        if let Some(r) = self.ratio {
            out.push_str(&format!(" --ratio {}-{}", r.lo, r.hi));
        }
        if self.proven_only {
            out.push_str(" --proven");
        }
        if self.physics {
            out.push_str(" --physics");
        }
        out.push_str(&format!(
            " --max-states {} --max-memory {} --max-draws {} --split {},{},{} -o DIR",
            self.limits.max_states,
            self.limits.max_memory >> 20,
            self.draws(),
            self.split[0],
            self.split[1],
            self.split[2]
        ));
        out
    }
}

/// The most rooms in a scene.
pub const MAX_ROOMS: usize = 16;
/// The most predicates in a goal.
pub const MAX_PREDICATES: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_and_teams_parse() {
        assert_eq!(Span::parse("--rooms", "3-4"), Ok(Span::new(3, 4)));
        assert_eq!(Span::parse("--rooms", "5"), Ok(Span::new(5, 5)));
        assert_eq!(
            Span::parse("--rooms", "4-3").expect_err("refused").knob,
            "--rooms"
        );
        let t = TeamSpec::parse(Some("quadrotor=2,legged=3,arm=2"), None).expect("team");
        assert_eq!(t.compositions(), vec![[2, 3, 2]]);
        let t = TeamSpec::parse(None, Some("3-4")).expect("size");
        assert!(
            t.compositions()
                .iter()
                .all(|c| (3..=4).contains(&c.iter().sum::<usize>()))
        );
        assert!(t.compositions().contains(&[0, 0, 4]));
        let e = TeamSpec::parse(Some("quadrotor=0"), None).expect_err("refused");
        assert_eq!(e.knob, "--team");
        let e = TeamSpec::parse(Some("arm=1"), Some("3")).expect_err("refused");
        assert_eq!(e.knob, "--robots");
        assert_eq!(
            TeamSpec::parse(Some("cat=1"), None)
                .expect_err("refused")
                .knob,
            "--team"
        );
    }

    #[test]
    fn ratios_and_splits_parse() {
        let r = Ratio::parse("--ratio", "1.2-2").expect("ratio");
        assert!(r.contains(1.5) && !r.contains(2.5));
        assert!(Ratio::parse("--ratio", "0.5").is_err());
        assert_eq!(parse_split("0.8,0.1,0.1"), Ok([0.8, 0.1, 0.1]));
        assert!(parse_split("1,2").is_err());
        assert_eq!(
            parse_types("trio,mono"),
            Ok(vec![TaskType::Trio, TaskType::Mono])
        );
    }
}
