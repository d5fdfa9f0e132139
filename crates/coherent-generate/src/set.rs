//! The driver: draws candidate tasks (each from its own seeded stream, so a draw is the
//! same whatever came before it and whichever thread works it out), works out their
//! ground truths on several threads (each takes the next draw when it is free), and
//! keeps them in draw order when they pass the request's filters, are new, and the
//! physics builds their scene; until the set is complete, the draws run out (an error
//! naming the knob that rejected most, with what it saw), or it is cancelled.

use std::collections::{BTreeMap, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};

use coherent_core::{Task, native};

use crate::compose::{Meta, task_value};
use crate::goal::{self, Pred};
use crate::phrase;
use crate::request::{KnobError, Request};
use crate::rng::{Rng, seed_of};
use crate::scene::{Scene, SceneRequest};
use crate::sheet::{Entry, Rejected, Split, Tally};
use crate::start::{Start, kinds_of};
use crate::truth::{self, Truth, Verdict};

/// A kept task: the task, its file's text, its manifest entry.
#[derive(Clone, Debug)]
pub struct Generated {
    pub task: Task,
    /// The file's bytes: the native task, pretty-printed, with a final newline.
    pub text: String,
    pub entry: Entry,
    pub truth: Box<Truth>,
}

/// Where a run is.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    pub kept: usize,
    pub wanted: usize,
    pub drawn: usize,
    pub budget: usize,
}

/// How a run ended that made its set, or was stopped.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub tally: Tally,
    pub scenes: Vec<Scene>,
    pub interrupted: bool,
}

/// A drawn candidate before its ground truth.
struct Draft {
    draw: u64,
    scene: usize,
    start: Start,
    goal: Vec<Pred>,
    instruction: String,
    key: u64,
}

/// What a worker made of one draw.
enum Worked {
    Rejected(Rejected),
    /// Solved, filtered and built in physics, or rejected by a filter after it was
    /// solved (the truth is kept for the datasheet's counts of what the filters saw).
    Solved(Box<Draft>, Box<Truth>, Option<Rejected>),
    Cancelled,
}

/// Makes the set `req` asks for, handing each kept task to `keep` (in order) and the
/// progress to `progress` after each draw. `cancel` stops it between tasks (the
/// searches in flight stop too): the tasks kept so far stand.
pub fn generate(
    req: &Request,
    cancel: &Arc<AtomicBool>,
    keep: &mut dyn FnMut(Generated) -> std::io::Result<()>,
    progress: &mut dyn FnMut(Progress),
) -> Result<Result<Outcome, std::io::Error>, KnobError> {
    req.check()?;
    let teams = req.team.compositions();
    let most = req.team.most();
    let spots = teams.iter().map(|c| c[0] + c[1]).max().unwrap_or(0);
    let scene_req = SceneRequest {
        rooms: req.rooms,
        upstairs: req.upstairs,
        closed: req.closed,
        counters: most[2],
        spots,
    };
    let scenes: Vec<Scene> = (0..req.scenes)
        .map(|i| Scene::generate(i, req.seed, &scene_req))
        .collect::<Result<_, _>>()?;
    let splits = splits(req.scenes, req.split, req.seed);
    let mut tally = Tally::default();
    for s in &splits {
        tally.by_split.entry(*s).or_default().0 += 1;
    }
    let pool = Pool::new(req, cancel);
    let mut limits = req.limits.clone();
    limits.cancel = Some(Arc::clone(&pool.stop));
    let made = std::thread::scope(|s| {
        for _ in 0..req.jobs.min(pool.budget) {
            s.spawn(|| pool.work(|d| work_one(req, &scenes, &teams, &limits, d)));
        }
        let made = keep_in_order(req, &scenes, &splits, &pool, &mut tally, keep, progress);
        pool.close();
        made
    });
    if let Err(e) = made {
        return Ok(Err(e));
    }
    let interrupted = pool.cancelled() && tally.kept < req.tasks;
    if !interrupted && tally.kept < req.tasks {
        return Err(unmet(req, &tally));
    }
    Ok(Ok(Outcome {
        tally,
        scenes,
        interrupted,
    }))
}

/// Takes the draws' results in draw order and keeps the tasks that pass, reporting the
/// progress after each; until the set is made, the draws run out, or it is cancelled.
fn keep_in_order(
    req: &Request,
    scenes: &[Scene],
    splits: &[Split],
    pool: &Pool,
    tally: &mut Tally,
    keep: &mut dyn FnMut(Generated) -> std::io::Result<()>,
    progress: &mut dyn FnMut(Progress),
) -> std::io::Result<()> {
    let mut seen: HashSet<u64> = HashSet::new();
    let mut ids = vec![0i64; scenes.len()];
    for d in 0..pool.budget {
        if tally.kept >= req.tasks || pool.cancelled() {
            break;
        }
        let w = pool.take(d);
        if matches!(w, Worked::Cancelled) {
            break;
        }
        if let Some((draft, truth)) = solved(w, tally) {
            if !seen.insert(draft.key) {
                tally.reject(Rejected::Duplicate);
            } else {
                let scene = &scenes[draft.scene];
                let task_id = ids[draft.scene];
                match finish(req, scene, &draft, truth, task_id, splits[draft.scene]) {
                    None => tally.reject(Rejected::Invalid),
                    Some(kept) => {
                        ids[draft.scene] += 1;
                        tally.keep(&kept.entry);
                        keep(kept)?;
                    }
                }
            }
        }
        progress(Progress {
            kept: tally.kept,
            wanted: req.tasks,
            drawn: tally.drawn,
            budget: pool.budget,
        });
    }
    Ok(())
}

/// A draw's result counted in `tally`: its draft and truth when it was solved and passed
/// the filters (a cancelled draw counts for nothing).
fn solved(w: Worked, tally: &mut Tally) -> Option<(Box<Draft>, Box<Truth>)> {
    match w {
        Worked::Cancelled => None,
        Worked::Rejected(why) => {
            tally.drawn += 1;
            tally.reject(why);
            None
        }
        Worked::Solved(draft, truth, filtered) => {
            tally.drawn += 1;
            tally.saw(truth.task_type, truth.steps(), truth.ratio(), truth.needed);
            match filtered {
                Some(why) => {
                    tally.reject(why);
                    None
                }
                None => Some((draft, truth)),
            }
        }
    }
}

/// The draws worked out on several threads, taken in draw order. A thread takes the
/// next draw as soon as it is free, up to `ahead` draws past the one awaited, so that
/// one slow search holds up no other thread (and the results waiting stay few).
struct Pool {
    ahead: usize,
    budget: usize,
    state: Mutex<Queue>,
    changed: Condvar,
    /// Ctrl-C.
    cancel: Arc<AtomicBool>,
    /// The searches' own flag: set on Ctrl-C and as soon as the set is made, when the
    /// draws still in flight are not needed.
    stop: Arc<AtomicBool>,
}

#[derive(Default)]
struct Queue {
    /// The next draw to hand out, and the draw awaited in order.
    next: usize,
    awaited: usize,
    done: BTreeMap<usize, Worked>,
    /// No more draws are handed out.
    closed: bool,
    /// Threads that ended without their draw's result (a panic in a search).
    lost: usize,
}

impl Pool {
    fn new(req: &Request, cancel: &Arc<AtomicBool>) -> Pool {
        Pool {
            // A search of a few seconds holds the draw awaited while the other threads
            // go on: with 4 draws a thread they soon waited too (a third of the wall time
            // of 600 tasks on 2 threads); the results that wait are a few kB each.
            ahead: (req.jobs * 64).max(64),
            budget: req.draws(),
            state: Mutex::new(Queue::default()),
            changed: Condvar::new(),
            cancel: Arc::clone(cancel),
            stop: Arc::new(AtomicBool::new(false)),
        }
    }

    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    fn lock(&self) -> MutexGuard<'_, Queue> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// One thread's loop: draws in turn, until the pool closes or they run out.
    fn work(&self, one: impl Fn(u64) -> Worked) {
        loop {
            let d = {
                let mut q = self.lock();
                loop {
                    if q.closed || q.next >= self.budget {
                        return;
                    }
                    if q.next < q.awaited + self.ahead {
                        break;
                    }
                    q = self.changed.wait(q).unwrap_or_else(PoisonError::into_inner);
                }
                q.next += 1;
                q.next - 1
            };
            let lost = Lost(self);
            let w = one(d as u64);
            std::mem::forget(lost);
            self.lock().done.insert(d, w);
            self.changed.notify_all();
        }
    }

    /// Draw `d`'s result, once a thread has it (passing Ctrl-C on to the searches while
    /// it waits); `Cancelled` if no thread can give it any more (one panicked).
    fn take(&self, d: usize) -> Worked {
        let mut q = self.lock();
        q.awaited = d;
        self.changed.notify_all();
        loop {
            if let Some(w) = q.done.remove(&d) {
                return w;
            }
            if q.lost > 0 {
                return Worked::Cancelled;
            }
            q = self
                .changed
                .wait_timeout(q, std::time::Duration::from_millis(50))
                .unwrap_or_else(PoisonError::into_inner)
                .0;
            if self.cancelled() {
                self.stop.store(true, Ordering::Relaxed);
            }
        }
    }

    /// No more draws; the searches in flight stop.
    fn close(&self) {
        self.stop.store(true, Ordering::Relaxed);
        self.lock().closed = true;
        self.changed.notify_all();
    }
}

/// Marks a thread that unwinds out of a draw, so that the draw awaited is not waited
/// for in vain (the panic itself surfaces when the threads are joined).
struct Lost<'p>(&'p Pool);

impl Drop for Lost<'_> {
    fn drop(&mut self) {
        self.0.lock().lost += 1;
        self.0.changed.notify_all();
    }
}

/// One draw: its team, start, goal and instruction, its ground truth, the filters, and
/// the physics' build of its scene.
fn work_one(
    req: &Request,
    scenes: &[Scene],
    teams: &[[usize; 3]],
    limits: &coherent_core::planner::Limits,
    d: u64,
) -> Worked {
    let draft = match draft(req, scenes, teams, d) {
        Ok(draft) => draft,
        Err(why) => return Worked::Rejected(why),
    };
    let scene = &scenes[draft.scene];
    let Ok(task) = read(scene, &draft, 0, None) else {
        return Worked::Rejected(Rejected::Invalid);
    };
    let truth = match truth::ground_truth(&task, limits) {
        Verdict::Solved(t) => t,
        Verdict::Unsolvable => return Worked::Rejected(Rejected::Unsolvable),
        Verdict::Undecided(coherent_core::Stop::Cancelled) => return Worked::Cancelled,
        Verdict::Undecided(_) => return Worked::Rejected(Rejected::Undecided),
    };
    if limits.cancelled() {
        return Worked::Cancelled;
    }
    let filtered = filter(req, &truth).or_else(|| physics(req, task, &truth));
    Worked::Solved(Box::new(draft), truth, filtered)
}

/// The draw `d`: its scene (the draws go round the scenes), team, start, goal and
/// instruction, from the draw's own stream.
fn draft(req: &Request, scenes: &[Scene], teams: &[[usize; 3]], d: u64) -> Result<Draft, Rejected> {
    let mut rng = Rng::new(seed_of(req.seed, "task", d));
    let si = (d % scenes.len() as u64) as usize;
    let scene = &scenes[si];
    let team = *rng.pick(teams);
    let start = Start::draw(scene, team, &mut rng).ok_or(Rejected::Start)?;
    let kinds = kinds_of(team);
    let bits: u8 = (0..3).filter(|&k| team[k] > 0).map(|k| 1u8 << k).sum();
    // The type wanted: one the request asks for and the team can do, else any the team
    // can do; then which kinds of robot.
    let sizes: Vec<usize> = if req.types.is_empty() {
        (1..=kinds.len()).collect()
    } else {
        req.types
            .iter()
            .map(|t| match t {
                coherent_core::planner::TaskType::Mono => 1,
                coherent_core::planner::TaskType::Dual => 2,
                coherent_core::planner::TaskType::Trio => 3,
            })
            .filter(|&n| n <= kinds.len())
            .collect()
    };
    if sizes.is_empty() {
        return Err(Rejected::Goal);
    }
    let size = *rng.pick(&sizes);
    let masks = goal::masks_of(bits, size);
    let mask = *rng.pick(&masks);
    let k = rng.between(req.predicates.lo, req.predicates.hi);
    let goal = goal::draw(scene, &start, k, mask, &mut rng).ok_or(Rejected::Goal)?;
    let instruction = phrase::instruction(scene, &start, &goal, &mut rng);
    let key = key_of(si, &start, &goal);
    Ok(Draft {
        draw: d,
        scene: si,
        start,
        goal,
        instruction,
        key,
    })
}

/// Whether the physics builds the task's scene and, with `--physics`, carries its
/// optimal plan out; the reason if not.
fn physics(req: &Request, task: Task, truth: &Truth) -> Option<Rejected> {
    let layout = task.meta.geometry.clone()?;
    let task = Arc::new(task);
    if let Err(_e) = coherent_sim::PhysicalEnv::with_layout(Arc::clone(&task), layout) {
        return Some(Rejected::Physics);
    }
    (req.physics && !coherent_sim::execute_plan(&task, &truth.plan).physics_ok)
        .then_some(Rejected::PlanPhysics)
}

/// The filter a solved task fails, if any.
fn filter(req: &Request, t: &Truth) -> Option<Rejected> {
    if !req.types.is_empty() && !t.task_type.is_some_and(|k| req.types.contains(&k)) {
        return Some(Rejected::Type);
    }
    if let Some(n) = req.needed
        && !t.needed.is_some_and(|k| n.contains(k))
    {
        return Some(Rejected::Needed);
    }
    if let Some(s) = req.steps
        && !s.contains(t.steps())
    {
        return Some(Rejected::Steps);
    }
    if let Some(r) = req.ratio
        && !r.contains(t.ratio())
    {
        return Some(Rejected::Ratio);
    }
    if req.proven_only && !t.makespan_proven {
        return Some(Rejected::Unproven);
    }
    None
}

/// The task of a draft as its file says it, read back by the native reader.
fn read(
    scene: &Scene,
    draft: &Draft,
    task_id: i64,
    truth: Option<&Truth>,
) -> coherent_core::Result<Task> {
    let name = format!("draw-{}", draft.draw);
    let meta = Meta {
        task_id,
        name: &name,
        instruction: &draft.instruction,
        goal: &draft.goal,
        ground_truth: truth.map(Truth::steps),
    };
    let value = task_value(scene, &draft.start, &meta);
    native::read(&format!("{}/task-{task_id:04}.json", scene.name), &value)
}

/// A kept draft as its task, file text and manifest entry; `None` if it does not read
/// back (it was read once before its ground truth, so it always does).
fn finish(
    req: &Request,
    scene: &Scene,
    draft: &Draft,
    truth: Box<Truth>,
    task_id: i64,
    split: Split,
) -> Option<Generated> {
    let task = read(scene, draft, task_id, Some(&truth)).ok()?;
    let text = serde_json::to_string_pretty(&native::to_value(&task)).unwrap_or_default() + "\n";
    let entry = Entry {
        id: format!("{}/task-{task_id:04}", scene.name),
        scene: scene.name.clone(),
        task_id,
        seed: req.seed,
        draw: draft.draw,
        team: draft.start.team,
        task_type: truth.task_type,
        needed: truth.needed,
        predicates: draft.goal.len(),
        steps: truth.steps(),
        makespan: truth.makespan(),
        makespan_lower: truth.makespan_lower,
        proven: truth.makespan_proven,
        split,
    };
    Some(Generated {
        task,
        text,
        entry,
        truth,
    })
}

/// Which split each scene is in: the scenes in a seeded order, the first shares of them
/// in test and validation (at least one each when there are three scenes or more and
/// the share is not zero), the rest in train. Also the split of the scenes of tasks
/// that come with none (the training data's, `coherent export sft`).
pub fn splits(scenes: usize, shares: [f64; 3], seed: u64) -> Vec<Split> {
    let mut order: Vec<usize> = (0..scenes).collect();
    Rng::new(seed_of(seed, "split", 0)).shuffle(&mut order);
    let total: f64 = shares.iter().sum();
    let count = |share: f64| {
        let n = (scenes as f64 * share / total).round() as usize;
        if share > 0.0 && scenes >= 3 {
            n.max(1)
        } else {
            n
        }
    };
    let test = count(shares[2]).min(scenes);
    let validation = count(shares[1]).min(scenes - test);
    let mut out = vec![Split::Train; scenes];
    for (k, &s) in order.iter().enumerate() {
        if k < test {
            out[s] = Split::Test;
        } else if k < test + validation {
            out[s] = Split::Validation;
        }
    }
    out
}

/// A hash of the scene, the goal and the whole start (FNV-1a, stable across builds):
/// two drafts with one key are the same task.
fn key_of(scene: usize, start: &Start, goal: &[Pred]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: u64| {
        for b in x.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    eat(scene as u64);
    for p in goal {
        eat(p.relation as u64);
        eat(p.subject as u64);
        eat(p.target as u64);
    }
    for r in &start.robots {
        eat(r.id as u64);
        match r.pose {
            crate::start::Pose::Arm(p) => eat(p as u64),
            crate::start::Pose::Quad { on, .. } => match on {
                crate::start::Landing::Top(p) => eat(p as u64),
                crate::start::Landing::Floor(room, at) => {
                    eat(room as u64 + 1_000_000);
                    eat(u64::from(at[0].to_bits()));
                    eat(u64::from(at[1].to_bits()));
                }
            },
            crate::start::Pose::Dog(room, at) => {
                eat(room as u64);
                eat(u64::from(at[0].to_bits()));
                eat(u64::from(at[1].to_bits()));
            }
        }
    }
    for t in &start.things {
        eat(t.piece as u64 * 2 + u64::from(t.inside));
        eat(u64::from(t.pos[0].to_bits()));
        eat(u64::from(t.pos[2].to_bits()));
    }
    h
}

/// The error for a request the draws could not meet: the reason that rejected most
/// draws, with the knob behind it and what the draws had.
fn unmet(req: &Request, tally: &Tally) -> KnobError {
    let (why, n) = tally
        .rejected
        .iter()
        .max_by_key(|(_, n)| **n)
        .map(|(w, n)| (*w, *n))
        .unwrap_or((Rejected::Goal, 0));
    let range = |r: Option<(usize, usize)>| {
        r.map_or("none solved".to_owned(), |(a, b)| format!("{a} to {b}"))
    };
    let (knob, saw) = match why {
        Rejected::Type => (
            "--type",
            format!("the types drawn were {:?}", tally.seen_types),
        ),
        Rejected::Needed => (
            "--needed",
            format!("the robots needed were {}", range(tally.seen_needed)),
        ),
        Rejected::Steps => (
            "--steps",
            format!("the optimal steps were {}", range(tally.seen_steps)),
        ),
        Rejected::Ratio => (
            "--ratio",
            tally.seen_ratio.map_or("none solved".to_owned(), |(a, b)| {
                format!("sequential steps / makespan were {a:.2} to {b:.2}")
            }),
        ),
        Rejected::Unproven => (
            "--proven",
            "raise --max-states or --max-memory to prove more".to_owned(),
        ),
        Rejected::Duplicate => (
            "--tasks",
            format!(
                "the {} scenes hold fewer distinct tasks of this kind; add --scenes",
                req.scenes
            ),
        ),
        Rejected::Undecided => (
            "--max-states",
            "the searches stopped at their limits; raise --max-states or --max-memory".to_owned(),
        ),
        Rejected::Start => (
            "--team",
            "the scenes have too few counters or too little floor for the teams; add --rooms"
                .to_owned(),
        ),
        Rejected::PlanPhysics => (
            "--physics",
            "the optimal plans of the scenes drawn fail in physics too often for these teams"
                .to_owned(),
        ),
        Rejected::Goal | Rejected::Unsolvable | Rejected::Physics | Rejected::Invalid => (
            "--predicates",
            "the scenes offer few goals of this size for these teams and types".to_owned(),
        ),
    };
    KnobError {
        knob,
        message: format!(
            "after {} draws (--max-draws {}), {} of {} tasks kept; {n} draws were rejected for {}: {saw}",
            tally.drawn,
            req.draws(),
            tally.kept,
            req.tasks,
            why.describe()
        ),
    }
}
