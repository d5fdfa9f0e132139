//! How many joint steps a goal thing's own chain of actions still needs
//! (docs/planner.md, "Parallel plans").
//!
//! A thing that must end on or in a target moves only by actions that follow one
//! another: a grab, a put, and between them, when no robot that can grab it where it is
//! can also put it on the target, a relay through another place: put into a basket, the
//! quadrotor's take-off, its move and its landing, a robot dog's walk up to the basket
//! (a take-off clears every `CLOSE` edge to the basket's contents and a landing adds
//! none), its grab, its put. No two of these can share a joint step, so the length of
//! the shortest such chain is a lower bound on the joint steps left, however many robots
//! act.
//!
//! The chain is a shortest path over the thing's situations (where it rests, with whether
//! it is `ON_HIGH_SURFACE` and whether a dog is close to it; which robot holds it; which
//! basket it is in and where that basket is), computed once per search. Who may grab or
//! put where comes from [`crate::relaxed`], an over-approximation of every fact reachable
//! from the search's start: an edge is left out only when no reachable state has it, and
//! every edge costs at most the actions it stands for, so the bound never overestimates.
//! A state only looks up its situation, and a few of its edges: whether a dog is close
//! to the thing, whether the dog holding it is close to where it may put it, what the
//! flying quadrotor is above. One joint step changes the situation by at most one edge
//! and each of these by at most one, so the bound drops by at most one a joint step.
//!
//! A robot dog's walks count as well. A dog walks up only to what is in its own room, and
//! goes to another room only through a door of its room, one action a room, so a state
//! adds to a dog's grab the rooms the nearest dog must cross to the thing's room; after
//! the grab, the dog puts the thing on a place it may be close to already (one it may be
//! close to once it has walked up to the thing there), or it walks: the rooms to the
//! place's room and the step up to it. Doors count as open (a dog may open one on the
//! way): the rooms between two rooms are the fewest doors between them.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::graph::{Edge, Idx, NodeKind, RobotKind, State};
use crate::relaxed::Facts;
use crate::task::{GoalPredicate, Robot, RuleSet, Task};
use crate::vocab::{PropSet, Relation};

mod rooms;

use rooms::{FAR, Put, Puts, Rooms, Team};

/// The most nodes of a scene whose chains are followed: the analysis behind them takes
/// time and memory in the square of the nodes (a few megabytes here). A larger scene
/// keeps the bound without chains.
const CHAIN_NODES: usize = 1024;

/// The chains of a search's goal things; see the module's text.
#[derive(Debug)]
pub(crate) struct Chains {
    chains: Vec<Chain>,
    /// The team's arms, then its robot dogs.
    grabbers: Vec<Idx>,
    arms: usize,
    rooms: Rooms,
}

impl Chains {
    /// The chains of every `ON`/`INSIDE` goal predicate about an object, for `team`
    /// acting from `start`.
    pub fn new(task: &Task, start: &State, team: &[Robot], goal: &[GoalPredicate]) -> Chains {
        let subjects: Vec<&GoalPredicate> = goal
            .iter()
            .filter(|p| p.count == 1 && task.node(p.subject).kind == NodeKind::Object)
            .filter(|p| matches!(p.relation, Relation::On | Relation::Inside))
            .collect();
        if subjects.is_empty() || task.nodes.len() > CHAIN_NODES {
            return Chains {
                chains: Vec::new(),
                grabbers: Vec::new(),
                arms: 0,
                rooms: Rooms::default(),
            };
        }
        let world = World::new(task, start, team);
        let grabbers = world
            .arms
            .iter()
            .map(|&(a, _)| a)
            .chain(world.dogs.iter().copied())
            .collect();
        let chains = subjects.into_iter().map(|p| world.chain(p)).collect();
        Chains {
            chains,
            grabbers,
            arms: world.arms.len(),
            rooms: world.rooms,
        }
    }

    /// The longest chain still needed in `s`: no plan from `s` has fewer joint steps.
    pub fn bound(&self, task: &Task, s: &State) -> u16 {
        if self.chains.is_empty() {
            return 0;
        }
        let team = Team::new(task, s, &self.grabbers, self.arms, &self.rooms);
        self.chains
            .iter()
            .map(|c| c.left(task, s, &team))
            .max()
            .unwrap_or(0)
    }
}

/// The team and the places, as one search sees them.
struct World<'t> {
    task: &'t Task,
    facts: Facts,
    /// The arms of the team and the surface each stands on.
    arms: Vec<(Idx, Idx)>,
    dogs: Vec<Idx>,
    /// The baskets of the team's quadrotors, with their quadrotor.
    baskets: Vec<(Idx, Idx)>,
    /// Per basket, where it may rest: the surfaces its quadrotor may land on, and the one
    /// it rests on at the start.
    spots: Vec<Vec<Idx>>,
    /// `reach[a][p]`: arm `a` (as in `arms`) may reach what is on or in `p`, and put on
    /// or into `p`.
    reach: Vec<Vec<bool>>,
    /// Nodes that never move: not grabable, not a robot, not a basket, and nothing
    /// under them is.
    fixed: Vec<bool>,
    /// Surfaces a quadrotor of the team may land on.
    landings: Vec<Idx>,
    /// Nodes a dog of the team is close to at the start.
    stale: Vec<bool>,
    /// Places something without `ON_HIGH_SURFACE` rests on or in at the start.
    low_there: Vec<bool>,
    /// Per place, whether a robot dog may be close to it ([`World::dog_reaches_place`]),
    /// found once for every chain.
    dog_places: Vec<bool>,
    rooms: Rooms,
}

impl<'t> World<'t> {
    fn new(task: &'t Task, start: &State, team: &[Robot]) -> World<'t> {
        let n = task.nodes.len();
        let facts = Facts::derive(task, start, team);
        let arms: Vec<(Idx, Idx)> = team
            .iter()
            .filter(|r| r.kind == RobotKind::RobotArm)
            .filter_map(|r| {
                start
                    .targets(r.node, Relation::On)
                    .next()
                    .map(|s| (r.node, s))
            })
            .collect();
        let dogs: Vec<Idx> = team
            .iter()
            .filter(|r| r.kind == RobotKind::RobotDog)
            .map(|r| r.node)
            .collect();
        let baskets: Vec<(Idx, Idx)> = team
            .iter()
            .filter(|r| r.kind == RobotKind::Quadrotor)
            .filter_map(|r| task.basket_of(r.node).map(|b| (b, r.node)))
            .collect();
        let robot = |x: Idx| matches!(task.node(x).kind, NodeKind::Robot(_));
        // What may come to rest on or in a reached place is reached, at any depth.
        let reach = arms
            .iter()
            .map(|&(arm, surface)| {
                let mut set = vec![false; n];
                set[surface.get()] = true;
                let mut grew = true;
                while grew {
                    grew = false;
                    for y in (0..n).map(|y| Idx(y as u16)) {
                        if set[y.get()] || y == arm || robot(y) {
                            continue;
                        }
                        if (0..n).any(|z| set[z] && facts.somewhere_at(y, Idx(z as u16))) {
                            set[y.get()] = true;
                            grew = true;
                        }
                    }
                }
                set
            })
            .collect();
        let mut fixed = vec![None; n];
        for x in 0..n {
            settle(task, start, Idx(x as u16), &mut fixed);
        }
        let landings: Vec<Idx> = (0..n)
            .map(|x| Idx(x as u16))
            .filter(|&x| task.node(x).properties.contains(PropSet::LANDABLE))
            .filter(|&x| facts.quadrotor_may_be_at(x))
            .collect();
        let spots = baskets
            .iter()
            .map(|&(b, _)| {
                let mut spots = landings.clone();
                spots.extend(
                    start
                        .targets(b, Relation::On)
                        .filter(|s| !landings.contains(s)),
                );
                spots
            })
            .collect();
        let mut stale = vec![false; n];
        for &d in &dogs {
            for x in start.targets(d, Relation::Close) {
                stale[x.get()] = true;
            }
        }
        let mut low_there = vec![false; n];
        for e in start.edges().iter().filter(|e| e.rel().is_location()) {
            if !start.on_high_surface(e.from()) && !robot(e.from()) {
                low_there[e.to().get()] = true;
            }
        }
        let fixed: Vec<bool> = fixed.into_iter().map(|f| f == Some(true)).collect();
        let rooms = Rooms::new(task, start, &fixed);
        let mut world = World {
            task,
            rooms,
            low_there,
            facts,
            arms,
            dogs,
            baskets,
            spots,
            reach,
            fixed,
            landings,
            stale,
            dog_places: Vec::new(),
        };
        world.dog_places = (0..n)
            .map(|q| world.dog_reaches_place(Idx(q as u16)))
            .collect();
        world
    }

    fn has(&self, x: Idx, p: PropSet) -> bool {
        self.task.node(x).properties.contains(p)
    }

    fn never(&self, x: Idx) -> bool {
        self.task.never_approached().contains(x)
    }

    /// A robot dog may walk up to something that stands on or in `q` (and so be close
    /// to `q`). On a high place a thing is low only if it was there at the start or a dog
    /// put it there: an arm's put and a basket's landing there set the flag. A dog's put
    /// needs a dog close to the place first, by another way than this one.
    fn child_approached(&self, q: Idx) -> bool {
        let high = self.has(q, PropSet::HIGH_HEIGHT) && !self.low_there[q.get()];
        self.task.node(q).kind != NodeKind::Floor
            && !high
            && (0..self.task.nodes.len()).map(|y| Idx(y as u16)).any(|y| {
                y != q && self.facts.somewhere_at(y, q) && !self.never(y) && self.facts.low(y)
            })
    }

    /// A robot dog may be close to place `q` (to put something on or into it).
    fn dog_reaches_place(&self, q: Idx) -> bool {
        if !self.facts.dog_may_be_at(q) {
            return false;
        }
        let direct = !self.never(q) && self.facts.low(q);
        let parent = (0..self.task.nodes.len()).map(|z| Idx(z as u16)).any(|z| {
            let approached = !self.never(z) && self.facts.low(z);
            approached
                && ((self.facts.at(q, Relation::On, z)
                    && self.has(z, PropSet::SURFACES)
                    && self.task.node(z).kind != NodeKind::Floor)
                    || (self.facts.at(q, Relation::Inside, z) && self.has(z, PropSet::CONTAINERS)))
        });
        direct || parent || self.child_approached(q) || self.stale[q.get()]
    }

    /// A robot dog may be close to thing `x` resting `rel` place `p`, `high` telling
    /// whether `x` is `ON_HIGH_SURFACE`; `None` for `p` a basket (its flag unknown).
    fn dog_grabs_at(&self, x: Idx, high: bool, rest: Option<(Relation, Idx)>) -> bool {
        let own = !high && !self.never(x);
        let place = rest.is_some_and(|(rel, p)| {
            let holds = match rel {
                Relation::On => {
                    self.has(p, PropSet::SURFACES) && self.task.node(p).kind != NodeKind::Floor
                }
                _ => self.has(p, PropSet::CONTAINERS),
            };
            holds && !self.never(p) && self.facts.low(p)
        });
        own || place || self.child_approached(x)
    }

    /// The chain of goal predicate `p`.
    fn chain(&self, p: &GoalPredicate) -> Chain {
        let n = self.task.nodes.len();
        let at = Layout {
            n,
            grabbers: self.arms.len() + self.dogs.len(),
            baskets: self.baskets.len(),
        };
        let mut g = Graph::new(at.len());
        let [low, high] = self.places(&mut g, &at, p);
        self.flights(&mut g, &at, p.subject);
        self.carriers(&mut g, &at);
        let x = p.subject;
        let dist = g.distances(&[(at.goal(), 0), (at.moved(), 2)]);
        let dog_puts = (!self.dogs.is_empty()).then(|| {
            [
                Puts::new(&dist, n, &self.rooms, &low),
                Puts::new(&dist, n, &self.rooms, &high),
            ]
        });
        let around = match &dog_puts {
            Some([low, high]) => [self.around(x, &low.near), self.around(x, &high.near)],
            None => [Vec::new(), Vec::new()],
        };
        // A place's grabs: by an arm, the chain after it; by a dog, only whether there is
        // one (its walks depend on where the dogs are).
        let mut grabs = vec![(FAR, false); 8 * n];
        for (i, (arm, dog)) in grabs.iter_mut().enumerate() {
            for &(to, cost) in &g.out[i] {
                match at.holder(to) {
                    Some(h) if h >= self.arms.len() => *dog = true,
                    _ => *arm = (*arm).min(dist[to].saturating_add(cost)),
                }
            }
        }
        Chain {
            x,
            rel: p.relation,
            target: p.target,
            dist,
            grabs,
            around,
            at,
            arms: self.arms.len(),
            baskets: self.baskets.clone(),
            fixed: self.fixed.clone(),
            dog_puts,
            carried: !self.never(x),
        }
    }

    /// Puts on or into every place and grabs from it; per flag, the dogs' puts (the
    /// place, the situation after and its room).
    fn places(&self, g: &mut Graph, at: &Layout, p: &GoalPredicate) -> [Vec<Put>; 2] {
        let n = self.task.nodes.len();
        let dog = |d: usize| self.arms.len() + d;
        let mut dogs_put = [Vec::new(), Vec::new()];
        let x = p.subject;
        let bits = [false, true];
        let compatible = self.task.meta.rules != RuleSet::Geometric;
        for q in (0..n).map(|q| Idx(q as u16)) {
            for (r, rel) in [(0, Relation::On), (1, Relation::Inside)] {
                let takes = match rel {
                    Relation::On => self.has(q, PropSet::SURFACES),
                    _ => self.has(q, PropSet::CONTAINERS),
                };
                if !takes || q == x {
                    continue;
                }
                let goal = q == p.target && rel == p.relation;
                let basket = self
                    .baskets
                    .iter()
                    .position(|&(b, _)| b == q)
                    .filter(|_| rel == Relation::Inside && !goal);
                let fixed = self.fixed[q.get()];
                // Where a put by grabber `by` leaves `x` with flag `hi`: on spot `s` for a
                // basket. The carrier argument needs a dog to be able to walk up to `x`
                // wherever it may walk up to the carrier.
                let rest = |hi: bool, s: Option<Idx>, by: usize| match (basket, s) {
                    _ if goal => at.goal(),
                    (Some(k), Some(s)) => at.basket_at(k, s.get(), hi, false),
                    _ if fixed => at.place(q.get(), r, hi, false),
                    _ if !self.never(x) => at.carry(by.min(self.arms.len())),
                    _ => at.moved(),
                };
                // The flags an arm's put may leave.
                let arm_flags: &[bool] = if compatible {
                    &[true]
                } else if !fixed || basket.is_some() {
                    &bits
                } else if self.has(q, PropSet::HIGH_HEIGHT) || !self.facts.low(q) {
                    &[true]
                } else {
                    &[false]
                };
                for hi in bits {
                    for (a, reach) in self.reach.iter().enumerate() {
                        for &after in arm_flags {
                            match basket {
                                Some(k) => {
                                    for &s in self.spots[k].iter().filter(|s| reach[s.get()]) {
                                        // A basket resting high is high, unless it was
                                        // there, low, at the start.
                                        let after = after || !self.low_at(s);
                                        g.edge(at.held(a, hi), rest(after, Some(s), a), 1);
                                    }
                                }
                                None if reach[q.get()] => {
                                    g.edge(at.held(a, hi), rest(after, None, a), 1)
                                }
                                None => {}
                            }
                        }
                    }
                    // Any dog may put it where one may (no place is one dog's alone, and
                    // the situation after is the same): the puts once, an edge a dog.
                    let put = |on: Option<Idx>, room| Put {
                        q,
                        to: rest(hi, on, dog(0)),
                        room,
                    };
                    let mut here = Vec::new();
                    match basket {
                        Some(k) if !self.dogs.is_empty() => {
                            for &s in self.spots[k]
                                .iter()
                                .filter(|&&s| self.dog_reaches_basket(q, s))
                            {
                                here.push(put(Some(s), self.rooms.of(s)));
                            }
                        }
                        None if !self.dogs.is_empty() && self.dog_places[q.get()] => {
                            here.push(put(None, self.rooms.of(q)));
                        }
                        _ => {}
                    }
                    for d in 0..self.dogs.len() {
                        for put in &here {
                            g.edge(at.held(dog(d), hi), put.to, 1);
                        }
                    }
                    dogs_put[usize::from(hi)].extend(here);
                    if goal || !fixed {
                        continue;
                    }
                    let by_dog =
                        self.facts.dog_may_be_at(q) && self.dog_grabs_at(x, hi, Some((rel, q)));
                    for fresh in bits {
                        let here = at.place(q.get(), r, hi, fresh);
                        for (a, reach) in self.reach.iter().enumerate() {
                            if reach[q.get()] {
                                g.edge(here, at.held(a, hi), 1);
                            }
                        }
                        for d in (0..self.dogs.len()).filter(|_| by_dog) {
                            g.edge(here, at.held(dog(d), hi), 1 + u16::from(fresh));
                        }
                    }
                }
            }
        }
        dogs_put
    }

    /// Per fixed place `q`, the fewest of `near` (the chains after a dog's put where it
    /// stands) over the places a dog may be close to once it has walked up to `x` resting
    /// on or in `q`, or to what `x` rests on or in, or to what rests on `x`: `q`, what may
    /// rest on or in `q` or on what stands on `x`, and what `q` stands on.
    fn around(&self, x: Idx, near: &[u16]) -> Vec<u16> {
        let n = self.task.nodes.len();
        let nodes = || (0..n).map(|y| Idx(y as u16));
        let on_x: Vec<Idx> = nodes().filter(|&z| self.facts.somewhere_at(z, x)).collect();
        let by_x = nodes()
            .filter(|&p| on_x.contains(&p) || on_x.iter().any(|&z| self.facts.somewhere_at(p, z)))
            .map(|p| near[p.get()])
            .fold(FAR, u16::min);
        nodes()
            .map(|q| {
                if !self.fixed[q.get()] {
                    return FAR;
                }
                nodes()
                    .filter(|&p| self.facts.somewhere_at(p, q) || self.facts.somewhere_at(q, p))
                    .map(|p| near[p.get()])
                    .fold(near[q.get()].min(by_x), u16::min)
            })
            .collect()
    }

    /// Baskets: grabs where they rest, take-offs, moves and landings.
    fn flights(&self, g: &mut Graph, at: &Layout, x: Idx) {
        let dog = |d: usize| self.arms.len() + d;
        let bits = [false, true];
        for (k, &(b, _)) in self.baskets.iter().enumerate() {
            for hi in bits {
                let in_air = self.dog_grabs_at(x, hi, None);
                for &s in &self.spots[k] {
                    let by_dog = self.facts.dog_may_be_at(s)
                        && (self.dog_grabs_at(x, hi, None) || self.dog_reaches_basket(b, s));
                    for fresh in bits {
                        let here = at.basket_at(k, s.get(), hi, fresh);
                        for (a, reach) in self.reach.iter().enumerate() {
                            if reach[s.get()] {
                                g.edge(here, at.held(a, hi), 1);
                            }
                        }
                        for d in (0..self.dogs.len()).filter(|_| by_dog) {
                            g.edge(here, at.held(dog(d), hi), 1 + u16::from(fresh));
                        }
                        g.edge(here, at.above(k, s.get(), true), 1);
                    }
                    let landed = if self.has(s, PropSet::HIGH_HEIGHT) {
                        true
                    } else if self.has(s, PropSet::LOW_HEIGHT) {
                        false
                    } else {
                        hi
                    };
                    let above = at.above(k, s.get(), hi);
                    if self.landings.contains(&s) {
                        g.edge(above, at.basket_at(k, s.get(), landed, true), 1);
                        g.edge(at.air(k, hi), above, 0);
                    }
                    g.edge(above, at.air(k, hi), 1);
                    for d in (0..self.dogs.len()).filter(|_| in_air) {
                        g.edge(above, at.held(dog(d), hi), 1);
                    }
                }
                for d in (0..self.dogs.len()).filter(|_| in_air) {
                    g.edge(at.air(k, hi), at.held(dog(d), hi), 1);
                }
            }
        }
    }

    /// What a carrier brings the thing to: after a put into something that moves, the
    /// carrier stands for the thing (its moves are the same grabs, puts and flights),
    /// wherever the robot that put it there may have found the carrier.
    fn carriers(&self, g: &mut Graph, at: &Layout) {
        let n = self.task.nodes.len();
        for c in 0..=self.arms.len() {
            let near = |q: Idx| match self.reach.get(c) {
                Some(reach) => reach[q.get()],
                None => self.facts.dog_may_be_at(q),
            };
            for q in (0..n)
                .map(|q| Idx(q as u16))
                .filter(|&q| self.fixed[q.get()] && near(q))
            {
                // A dog's put keeps the thing's own flag, whatever the carrier's.
                let hi = c < self.arms.len() && !self.low_at(q);
                for r in 0..2 {
                    g.edge(at.carry(c), at.place(q.get(), r, hi, false), 0);
                }
            }
            for (k, spots) in self.spots.iter().enumerate() {
                for &s in spots.iter().filter(|&&s| near(s)) {
                    let hi = c < self.arms.len() && !self.low_at(s);
                    g.edge(at.carry(c), at.basket_at(k, s.get(), hi, false), 0);
                }
            }
        }
    }

    /// Something without `ON_HIGH_SURFACE` may rest on or in fixed place `q`: it is not
    /// high, a dog may put something there (a dog's put keeps the flag), or something
    /// low rests there at the start. Otherwise what rests there was put by an arm or
    /// landed in a basket, and both set the flag on a high place.
    fn low_at(&self, q: Idx) -> bool {
        !self.has(q, PropSet::HIGH_HEIGHT) || self.dog_places[q.get()] || self.low_there[q.get()]
    }

    /// A robot dog may be close to basket `b` resting on `s`.
    fn dog_reaches_basket(&self, b: Idx, s: Idx) -> bool {
        if !self.facts.dog_may_be_at(s) {
            return false;
        }
        let own = !self.never(b) && !self.has(s, PropSet::HIGH_HEIGHT);
        let under = !self.never(s)
            && self.facts.low(s)
            && self.has(s, PropSet::SURFACES)
            && self.task.node(s).kind != NodeKind::Floor;
        // In a basket resting high, what was put in by an arm or landed with it is high.
        let high_spot = self.has(s, PropSet::HIGH_HEIGHT)
            && !self.low_there[s.get()]
            && !self.low_there[b.get()];
        own || under || (!high_spot && self.child_approached(b)) || self.stale[b.get()]
    }
}

/// Whether `x` never moves; memoised in `fixed`.
fn settle(task: &Task, s: &State, x: Idx, fixed: &mut [Option<bool>]) -> bool {
    if let Some(f) = fixed[x.get()] {
        return f;
    }
    // Guard against a cycle of location edges.
    fixed[x.get()] = Some(false);
    let node = task.node(x);
    let movable = node.properties.contains(PropSet::GRABABLE)
        || matches!(node.kind, NodeKind::Robot(_) | NodeKind::Tool);
    let f = !movable
        && s.out(x)
            .iter()
            .filter(|e| e.rel().is_location())
            .all(|e| settle(task, s, e.to(), fixed));
    fixed[x.get()] = Some(f);
    f
}

/// The numbering of a chain's situations.
#[derive(Clone, Copy, Debug)]
struct Layout {
    n: usize,
    grabbers: usize,
    baskets: usize,
}

impl Layout {
    /// Resting `ON` (`r` 0) or `INSIDE` (1) fixed place `q`, `hi` its flag, `fresh` when
    /// no dog is close to it.
    fn place(&self, q: usize, r: usize, hi: bool, fresh: bool) -> usize {
        ((q * 2 + r) * 2 + usize::from(hi)) * 2 + usize::from(fresh)
    }

    fn held(&self, g: usize, hi: bool) -> usize {
        8 * self.n + g * 2 + usize::from(hi)
    }

    /// The grabber holding the thing in situation `i`, if `i` is one of [`Layout::held`].
    fn holder(&self, i: usize) -> Option<usize> {
        let g = i.checked_sub(8 * self.n)? / 2;
        (g < self.grabbers).then_some(g)
    }

    fn basket_at(&self, k: usize, s: usize, hi: bool, fresh: bool) -> usize {
        8 * self.n
            + 2 * self.grabbers
            + ((k * self.n + s) * 2 + usize::from(hi)) * 2
            + usize::from(fresh)
    }

    /// In basket `k` of a quadrotor flying above `s`.
    fn above(&self, k: usize, s: usize, hi: bool) -> usize {
        8 * self.n
            + 2 * self.grabbers
            + 4 * self.baskets * self.n
            + (k * self.n + s) * 2
            + usize::from(hi)
    }

    fn air(&self, k: usize, hi: bool) -> usize {
        8 * self.n + 2 * self.grabbers + 6 * self.baskets * self.n + k * 2 + usize::from(hi)
    }

    /// The goal holds.
    fn goal(&self) -> usize {
        8 * self.n + 2 * self.grabbers + 6 * self.baskets * self.n + 2 * self.baskets
    }

    /// On or in something that moves: a grab and a put at least, unless it is the goal.
    fn moved(&self) -> usize {
        self.goal() + 1
    }

    /// In or on a carrier that arm `c` put it in (`c` the number of arms: a dog).
    fn carry(&self, c: usize) -> usize {
        self.moved() + 1 + c
    }

    fn len(&self) -> usize {
        self.carry(self.grabbers) + 1
    }
}

/// Situations and their edges, with costs in actions.
struct Graph {
    out: Vec<Vec<(usize, u16)>>,
}

impl Graph {
    fn new(len: usize) -> Graph {
        Graph {
            out: vec![Vec::new(); len],
        }
    }

    fn edge(&mut self, from: usize, to: usize, cost: u16) {
        self.out[from].push((to, cost));
    }

    /// Each situation's fewest actions to a seed (Dijkstra over the reversed edges),
    /// each seed starting at its own distance.
    fn distances(&self, seeds: &[(usize, u16)]) -> Vec<u16> {
        let mut back = vec![Vec::new(); self.out.len()];
        for (from, edges) in self.out.iter().enumerate() {
            for &(to, cost) in edges {
                back[to].push((from, cost));
            }
        }
        let mut dist = vec![FAR; self.out.len()];
        let mut heap = BinaryHeap::new();
        for &(i, d) in seeds {
            if d < dist[i] {
                dist[i] = d;
                heap.push(Reverse((d, i)));
            }
        }
        while let Some(Reverse((d, i))) = heap.pop() {
            if d > dist[i] {
                continue;
            }
            for &(from, cost) in &back[i] {
                let nd = d.saturating_add(cost);
                if nd < dist[from] {
                    dist[from] = nd;
                    heap.push(Reverse((nd, from)));
                }
            }
        }
        dist
    }
}

/// One goal thing's chain: the fewest actions from each situation to the goal.
#[derive(Debug)]
struct Chain {
    x: Idx,
    rel: Relation,
    target: Idx,
    dist: Vec<u16>,
    /// Per place situation, the chain after its best grab by an arm (the grab counted),
    /// and whether a dog may grab the thing there.
    grabs: Vec<(u16, bool)>,
    /// Per flag and fixed place, the chain after a dog's put on a place it may be close
    /// to when it grabs the thing there ([`World::around`]).
    around: [Vec<u16>; 2],
    at: Layout,
    /// How many arms come first among the grabbers (the dogs follow).
    arms: usize,
    baskets: Vec<(Idx, Idx)>,
    fixed: Vec<bool>,
    /// Per flag, the chain from the thing in a dog's hand (the same for every dog); none
    /// when the team has no dog.
    dog_puts: Option<[Puts; 2]>,
    /// Whether a carrier stands for the thing (a dog may walk up to it).
    carried: bool,
}

impl Chain {
    /// The fewest actions of this chain from `s` (0 when the goal holds, or when the
    /// thing is somewhere the chain does not follow).
    fn left(&self, task: &Task, s: &State, team: &Team<'_>) -> u16 {
        let grabbers = team.grabbers;
        let x = self.x;
        if s.has(Edge::new(x, self.rel, self.target)) {
            return 0;
        }
        let mut rests = s.out(x).iter().filter(|e| e.rel().is_location());
        let (rest, more) = (rests.next(), rests.next());
        let hi = s.on_high_surface(x);
        let held = task
            .robots
            .iter()
            .any(|r| s.has(Edge::new(r.node, Relation::Hold, x)));
        let left = match (held, rest, more) {
            (true, None, _) => self.held(s, hi, team),
            (false, Some(e), None) => {
                let q = e.to();
                // A dog close to it now may grab it, whatever brought it close.
                let mut by_close = FAR;
                for (d, &dog) in grabbers[self.arms..].iter().enumerate() {
                    if s.has(Edge::new(dog, Relation::Close, x)) {
                        let held = self.dog_holding(s, hi, team, d);
                        by_close = by_close.min(held.saturating_add(1));
                    }
                }
                let fresh = by_close == FAR;
                let table = match self.baskets.iter().position(|&(b, _)| b == q) {
                    Some(k) if e.rel() == Relation::Inside => {
                        self.in_basket(task, s, k, hi, fresh, grabbers)
                    }
                    _ if self.fixed[q.get()] => {
                        let r = usize::from(e.rel() == Relation::Inside);
                        let (arm, dog) = self.grabs[self.at.place(q.get(), r, hi, fresh)];
                        match &self.dog_puts {
                            // A dog walks to its room and up to it, grabs it, and puts it
                            // where it stands or walks on from there.
                            Some(puts) if dog => {
                                let puts = &puts[usize::from(hi)];
                                let room = team.rooms.of(q);
                                let around = self.around[usize::from(hi)][q.get()];
                                let after = around.min(puts.walked(team.rooms, room));
                                let walk = team.nearest_dog(room);
                                arm.min(walk.saturating_add(2).saturating_add(after))
                            }
                            _ => arm,
                        }
                    }
                    // A grab and a put at least, wherever its carrier goes.
                    _ => self.carrier(task, s, q, grabbers).clamp(2, FAR - 1),
                };
                table.min(by_close)
            }
            // Held and resting somewhere at once, or resting in two places: a state
            // the rules reach only from odd task files.
            _ => FAR,
        };
        // Out of this abstraction's reach: leave the verdict to the search.
        if left == FAR { 0 } else { left }
    }

    /// The chain of `c`, the carrier the thing is on or in, as if the thing were where the
    /// carrier is (see [`World::chain`]), high only when the thing and its carriers all
    /// are.
    fn carrier(&self, task: &Task, s: &State, mut c: Idx, grabbers: &[Idx]) -> u16 {
        if !self.carried {
            return FAR;
        }
        // A dog may walk up to the thing or to a carrier that is not high.
        let mut hi = s.on_high_surface(self.x);
        for _ in 0..task.nodes.len() {
            hi &= s.on_high_surface(c);
            if let Some(g) = grabbers
                .iter()
                .position(|&g| s.has(Edge::new(g, Relation::Hold, c)))
            {
                return self.dist[self.at.held(g, hi)];
            }
            let mut rests = s.out(c).iter().filter(|e| e.rel().is_location());
            let (Some(e), None) = (rests.next(), rests.next()) else {
                return FAR;
            };
            let q = e.to();
            if let Some(k) = self.baskets.iter().position(|&(b, _)| b == q) {
                return self.in_basket(task, s, k, hi, false, grabbers);
            }
            if self.fixed[q.get()] {
                let r = usize::from(e.rel() == Relation::Inside);
                return self.dist[self.at.place(q.get(), r, hi, false)];
            }
            c = q;
        }
        FAR
    }

    /// The chain from basket `k` (the thing or its carrier in it, `hi` and `fresh` its
    /// flag and whether no dog is close to it): where the basket rests, or from the air.
    /// A basket in the air is high once it has taken off; one that starts in the air
    /// without the flag may be walked up to by a dog, which is then close to what is in it.
    fn in_basket(
        &self,
        task: &Task,
        s: &State,
        k: usize,
        hi: bool,
        fresh: bool,
        grabbers: &[Idx],
    ) -> u16 {
        let (b, quad) = self.baskets[k];
        if let Some(spot) = s.targets(b, Relation::On).next() {
            return self.dist[self.at.basket_at(k, spot.get(), hi, fresh)];
        }
        let mut best = s
            .targets(quad, Relation::Above)
            .map(|a| self.dist[self.at.above(k, a.get(), hi)])
            .fold(self.dist[self.at.air(k, hi)].saturating_add(1), u16::min);
        if !s.on_high_surface(b) && !task.never_approached().contains(b) {
            for d in self.arms..grabbers.len() {
                let held = self.dist[self.at.held(d, hi)];
                best = best.min(held.saturating_add(1 + u16::from(fresh)));
            }
        }
        best
    }

    /// The chain from the thing held: by an arm, its table; by a dog, one action more
    /// unless the dog is already close to where it puts it. No other robot sees what a
    /// robot holds, so none takes it from its hand.
    fn held(&self, s: &State, hi: bool, team: &Team<'_>) -> u16 {
        let grabbers = team.grabbers;
        let Some(g) = grabbers
            .iter()
            .position(|&g| s.has(Edge::new(g, Relation::Hold, self.x)))
        else {
            return FAR;
        };
        let Some(d) = g.checked_sub(self.arms) else {
            return self.dist[self.at.held(g, hi)];
        };
        self.dog_holding(s, hi, team, d)
    }

    /// The chain from the thing in the hand of robot dog `d` (as in the team's dogs):
    /// a put where it stands, or a walk first.
    fn dog_holding(&self, s: &State, hi: bool, team: &Team<'_>, d: usize) -> u16 {
        let Some(puts) = &self.dog_puts else {
            return FAR;
        };
        let puts = &puts[usize::from(hi)];
        let walk = puts.walked(team.rooms, team.dog_rooms[d]);
        s.targets(team.grabbers[self.arms + d], Relation::Close)
            .map(|q| puts.near[q.get()])
            .fold(walk, u16::min)
    }
}
