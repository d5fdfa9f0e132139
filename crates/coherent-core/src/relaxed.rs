//! A relaxed reachability analysis: an over-approximation of where things can ever be
//! when only some robot types act. Facts are only ever added (nothing is deleted,
//! visibility and hand capacity are ignored), so every fact of every reachable state is
//! derived. When a goal predicate is not derived, no plan of that team can reach it,
//! which rules out teams without searching their (often huge) state spaces. A team is
//! robot kinds (`may_reach`: the task types) or any set of the task's robots
//! (`may_reach_with`: how many robots a task needs).

use crate::graph::{Idx, NodeKind, RobotKind, State};
use crate::task::{GoalPredicate, Robot, RuleSet, Task};
use crate::vocab::{PropSet, Relation, StateSet};

/// Whether every goal predicate of `goal` might hold with only robots of `kinds` acting.
/// `false` is a proof that the team cannot reach the goal; `true` proves nothing.
pub fn may_reach(task: &Task, kinds: &[RobotKind], goal: &[GoalPredicate]) -> bool {
    let team: Vec<Robot> = task
        .robots
        .iter()
        .copied()
        .filter(|r| kinds.contains(&r.kind))
        .collect();
    may_reach_with(task, &team, goal)
}

/// Whether every goal predicate of `goal` might hold with only the robots of `team`
/// acting (the others stay where they are). `false` is a proof that this team cannot
/// reach the goal; `true` proves nothing.
pub fn may_reach_with(task: &Task, team: &[Robot], goal: &[GoalPredicate]) -> bool {
    let facts = Facts::derive(task, &task.init, team);
    goal.iter()
        .all(|p| p.count != 1 || facts.at(p.subject, p.relation, p.target))
}

/// What may ever hold from a start state when a team acts: every fact of every state
/// reachable from it is among these.
pub(crate) struct Facts {
    n: usize,
    /// `at[x][p]`: bit 0 = x may be ON p, bit 1 = x may be INSIDE p.
    at: Vec<u8>,
    in_room: Vec<bool>,
    low: Vec<bool>,
    /// basket_low_at[b * n + y]: basket `b` may rest on `y` without ON_HIGH_SURFACE.
    /// Landing sets the flag from the surface's height, so a basket on a high surface
    /// is always high; only its initial place can differ.
    basket_low_at: Vec<bool>,
    open: Vec<bool>,
    dog_close: Vec<bool>,
    /// `dog_holds[x]`: the robot dog may hold x.
    dog_holds: Vec<bool>,
    /// arm_holds[a * n + x]: arm `a` may hold x.
    arm_holds: Vec<bool>,
    dog_room: Vec<bool>,
    quad_room: Vec<bool>,
}

impl Facts {
    pub(crate) fn derive(task: &Task, start: &State, team: &[Robot]) -> Facts {
        let n = task.nodes.len();
        let s = start;
        let mut f = Facts {
            n,
            at: vec![0; n * n],
            in_room: vec![false; n * n],
            low: (0..n).map(|i| !s.on_high_surface(Idx(i as u16))).collect(),
            basket_low_at: vec![false; n * n],
            open: (0..n).map(|i| s.states(Idx(i as u16)).is_open()).collect(),
            dog_close: vec![false; n],
            dog_holds: vec![false; n],
            arm_holds: vec![false; n * n],
            dog_room: vec![false; n],
            quad_room: vec![false; n],
        };
        for e in s.edges() {
            if e.rel().is_location() {
                f.add_at(e.from(), e.rel(), e.to());
                if task.node(e.from()).kind == NodeKind::Tool && f.low[e.from().get()] {
                    f.basket_low_at[e.from().get() * n + e.to().get()] = true;
                }
            }
        }
        let has_kind = |k: RobotKind| team.iter().any(|r| r.kind == k);
        let (dog, quad, arm) = (
            has_kind(RobotKind::RobotDog),
            has_kind(RobotKind::Quadrotor),
            has_kind(RobotKind::RobotArm),
        );
        let acts = |x: Idx| team.iter().any(|r| r.node == x);
        // A task may start with a robot next to something or holding it.
        for e in s.edges() {
            let (from, to) = (e.from().get(), e.to().get());
            if !acts(e.from()) {
                continue;
            }
            match (e.rel(), task.node(e.from()).kind) {
                (Relation::Close, NodeKind::Robot(RobotKind::RobotDog)) => f.dog_close[to] = true,
                (Relation::Hold, NodeKind::Robot(RobotKind::RobotDog)) => f.dog_holds[to] = true,
                (Relation::Hold, NodeKind::Robot(RobotKind::RobotArm)) => {
                    f.arm_holds[from * n + to] = true;
                }
                _ => {}
            }
        }
        let robots_of = |k: RobotKind| team.iter().filter(move |r| r.kind == k).map(|r| r.node);
        for r in team {
            if let Some(room) = crate::rules::room_of(task, s, r.node) {
                match r.kind {
                    RobotKind::RobotDog => f.dog_room[room.get()] = true,
                    RobotKind::Quadrotor => f.quad_room[room.get()] = true,
                    RobotKind::RobotArm => {}
                }
            }
        }
        let has = |x: usize, p: PropSet| task.nodes[x].properties.contains(p);
        let kind = |x: usize| task.nodes[x].kind;
        let mut changed = true;
        while changed {
            changed = false;
            // Rooms: a node is in a room if it is INSIDE it, on or in something that is,
            // or a door leading there; the basket wherever its quadrotor may fly.
            for x in 0..n {
                for p in 0..n {
                    if f.at[x * n + p] == 0 {
                        continue;
                    }
                    for r in task.rooms() {
                        let r = r.get();
                        if (p == r || f.in_room[p * n + r]) && !f.in_room[x * n + r] {
                            f.in_room[x * n + r] = true;
                            changed = true;
                        }
                    }
                }
            }
            for &(door, room) in task.doors() {
                changed |= set(&mut f.in_room, door.get() * n + room.get());
            }
            // Moving between rooms through doors that are or may become open (only the
            // robot dog opens doors).
            for &(door, room) in task.doors() {
                let d = door.get();
                if dog && s.states(door).contains(StateSet::CLOSED) && f.dog_room[room.get()] {
                    changed |= set(&mut f.open, d);
                }
                if !f.open[d] {
                    continue;
                }
                for &(door2, other) in task.doors() {
                    if door2 != door || other == room {
                        continue;
                    }
                    if dog && f.dog_room[room.get()] {
                        changed |= set(&mut f.dog_room, other.get());
                    }
                    if quad && f.quad_room[room.get()] {
                        changed |= set(&mut f.quad_room, other.get());
                    }
                }
            }
            for &r in task.rooms() {
                let r = r.get();
                for q in robots_of(RobotKind::Quadrotor) {
                    if quad && f.quad_room[r] {
                        changed |= f.add_at(q, Relation::Inside, Idx(r as u16));
                        if let Some(b) = task.basket_of(q) {
                            changed |= set(&mut f.in_room, b.get() * n + r);
                        }
                    }
                }
                for d in robots_of(RobotKind::RobotDog) {
                    if dog && f.dog_room[r] {
                        changed |= f.add_at(d, Relation::Inside, Idx(r as u16));
                        if let Some(floor) = task.floor_of(Idx(r as u16)) {
                            changed |= f.add_at(d, Relation::On, floor);
                        }
                    }
                }
            }
            if quad {
                changed |= f.fly(task, team);
            }
            if dog {
                changed |= f.dog(s, &has, &kind);
            }
            for a in robots_of(RobotKind::RobotArm).filter(|_| arm) {
                changed |= f.arm(task, s, a, &has);
            }
        }
        f
    }

    /// Whether `x` may be `rel` (`ON` or `INSIDE`) `p`.
    pub(crate) fn at(&self, x: Idx, rel: Relation, p: Idx) -> bool {
        self.at[x.get() * self.n + p.get()] & bit(rel) != 0
    }

    /// Whether `x` may be on or in `p`.
    pub(crate) fn somewhere_at(&self, x: Idx, p: Idx) -> bool {
        self.at[x.get() * self.n + p.get()] != 0
    }

    /// Whether `x` may be without `ON_HIGH_SURFACE`.
    pub(crate) fn low(&self, x: Idx) -> bool {
        self.low[x.get()]
    }

    /// Whether `x` may be in a room a robot dog of the team may enter.
    pub(crate) fn dog_may_be_at(&self, x: Idx) -> bool {
        self.may_be_in(x.get(), &self.dog_room)
    }

    /// Whether `x` may be in a room a quadrotor of the team may fly to.
    pub(crate) fn quadrotor_may_be_at(&self, x: Idx) -> bool {
        self.may_be_in(x.get(), &self.quad_room)
    }

    fn add_at(&mut self, x: Idx, rel: Relation, p: Idx) -> bool {
        let cell = &mut self.at[x.get() * self.n + p.get()];
        let new = *cell & bit(rel) == 0;
        *cell |= bit(rel);
        new
    }

    /// Whether `x` may be in one of `rooms` (a robot's possible rooms).
    fn may_be_in(&self, x: usize, rooms: &[bool]) -> bool {
        (0..self.n).any(|r| rooms[r] && self.in_room[x * self.n + r])
    }

    /// The quadrotors of `team` land on landable surfaces of the rooms they may reach;
    /// what is in a basket loses ON_HIGH_SURFACE when it lands on a low surface.
    fn fly(&mut self, task: &Task, team: &[Robot]) -> bool {
        let n = self.n;
        let mut changed = false;
        for r in team.iter().filter(|r| r.kind == RobotKind::Quadrotor) {
            for s in 0..n {
                let landable = task.nodes[s].properties.contains(PropSet::LANDABLE);
                let reachable = self.may_be_in(s, &self.quad_room);
                if !landable || !reachable {
                    continue;
                }
                changed |= self.add_at(r.node, Relation::On, Idx(s as u16));
                let Some(b) = task.basket_of(r.node) else {
                    continue;
                };
                changed |= self.add_at(b, Relation::On, Idx(s as u16));
                if task.nodes[s].properties.contains(PropSet::LOW_HEIGHT) {
                    changed |= set(&mut self.basket_low_at, b.get() * n + s);
                    changed |= set(&mut self.low, b.get());
                    for x in 0..n {
                        if self.at[x * n + b.get()] & bit(Relation::Inside) != 0 {
                            changed |= set(&mut self.low, x);
                        }
                    }
                }
            }
        }
        changed
    }

    fn dog(
        &mut self,
        start: &State,
        has: &dyn Fn(usize, PropSet) -> bool,
        kind: &dyn Fn(usize) -> NodeKind,
    ) -> bool {
        let n = self.n;
        let mut changed = false;
        for x in 0..n {
            let approachable = !matches!(
                kind(x),
                NodeKind::Room | NodeKind::Robot(_) | NodeKind::Floor
            ) && !has(x, PropSet::HIGH_HEIGHT)
                && self.low[x]
                && self.may_be_in(x, &self.dog_room);
            if !approachable {
                continue;
            }
            changed |= set(&mut self.dog_close, x);
            for y in 0..n {
                let on_x = self.at[y * n + x] & bit(Relation::On) != 0;
                let in_x = self.at[y * n + x] & bit(Relation::Inside) != 0;
                let open_container = has(x, PropSet::CONTAINERS) && self.open[x];
                let surface = has(x, PropSet::SURFACES) && kind(x) != NodeKind::Floor;
                if (in_x && open_container) || (on_x && surface) {
                    changed |= set(&mut self.dog_close, y);
                }
                // Approaching a basket brings the dog close to where it rests, but only
                // where it can rest without ON_HIGH_SURFACE.
                let place_ok = kind(x) != NodeKind::Tool || self.basket_low_at[x * n + y];
                if self.at[x * n + y] != 0 && kind(y) != NodeKind::Floor && place_ok {
                    changed |= set(&mut self.dog_close, y);
                }
            }
        }
        for x in 0..n {
            if !self.dog_close[x] {
                continue;
            }
            if has(x, PropSet::GRABABLE) {
                changed |= set(&mut self.dog_holds, x);
            }
            let openable = has(x, PropSet::CONTAINERS) || kind(x) == NodeKind::Door;
            if openable && start.states(Idx(x as u16)).contains(StateSet::CLOSED) {
                changed |= set(&mut self.open, x);
            }
        }
        for h in 0..n {
            if !self.dog_holds[h] {
                continue;
            }
            for t in 0..n {
                if !self.dog_close[t] || t == h {
                    continue;
                }
                if has(t, PropSet::CONTAINERS) && self.open[t] {
                    changed |= self.add_at(Idx(h as u16), Relation::Inside, Idx(t as u16));
                }
                if has(t, PropSet::SURFACES) {
                    changed |= self.add_at(Idx(h as u16), Relation::On, Idx(t as u16));
                }
            }
        }
        changed
    }

    fn arm(
        &mut self,
        task: &Task,
        start: &State,
        arm: Idx,
        has: &dyn Fn(usize, PropSet) -> bool,
    ) -> bool {
        let n = self.n;
        let mut changed = false;
        let surfaces: Vec<usize> = (0..n)
            .filter(|&s| self.at[arm.get() * n + s] & bit(Relation::On) != 0)
            .collect();
        let mut reach = vec![false; n];
        for &s in &surfaces {
            for (x, r) in reach.iter_mut().enumerate() {
                *r |= x != arm.get() && self.at[x * n + s] & bit(Relation::On) != 0;
            }
        }
        let mut grew = true;
        while grew {
            grew = false;
            for y in 0..n {
                if !reach[y] && (0..n).any(|z| reach[z] && self.at[y * n + z] != 0) {
                    reach[y] = true;
                    grew = true;
                }
            }
        }
        let reached: Vec<usize> = (0..n).filter(|&x| reach[x]).collect();
        for &x in &reached {
            if has(x, PropSet::GRABABLE) {
                changed |= set(&mut self.arm_holds, arm.get() * n + x);
            }
            if has(x, PropSet::CONTAINERS) && start.states(Idx(x as u16)).contains(StateSet::CLOSED)
            {
                changed |= set(&mut self.open, x);
            }
        }
        for h in 0..n {
            if !self.arm_holds[arm.get() * n + h] {
                continue;
            }
            for &s in &surfaces {
                changed |= self.add_at(Idx(h as u16), Relation::On, Idx(s as u16));
                // Geometric rules: what an arm puts on a low top is not high any more.
                if task.meta.rules == RuleSet::Geometric && !has(s, PropSet::HIGH_HEIGHT) {
                    changed |= set(&mut self.low, h);
                }
            }
            for &t in reached.iter().filter(|&&t| t != h) {
                if has(t, PropSet::CONTAINERS) && self.open[t] {
                    changed |= self.add_at(Idx(h as u16), Relation::Inside, Idx(t as u16));
                }
                if has(t, PropSet::SURFACES) {
                    changed |= self.add_at(Idx(h as u16), Relation::On, Idx(t as u16));
                }
            }
        }
        changed
    }
}

fn bit(rel: Relation) -> u8 {
    if rel == Relation::Inside { 2 } else { 1 }
}

fn set(v: &mut [bool], i: usize) -> bool {
    let new = !v[i];
    v[i] = true;
    new
}
