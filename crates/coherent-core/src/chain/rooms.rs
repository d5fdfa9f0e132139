//! Where robot dogs walk, for the chains (the parent module): the rooms, the doors
//! between them, and a dog's puts of the thing in its hand by the room they are in.

use std::collections::VecDeque;

use smallvec::SmallVec;

use crate::graph::{Idx, State};
use crate::task::Task;

/// No chain reaches the goal from there.
pub(super) const FAR: u16 = u16::MAX;

/// The team as a state sees it: the grabbers (arms first), and the room each robot dog
/// is in.
pub(super) struct Team<'a> {
    pub grabbers: &'a [Idx],
    pub dog_rooms: SmallVec<[Option<u16>; 8]>,
    pub rooms: &'a Rooms,
}

impl<'a> Team<'a> {
    /// The team of `grabbers` (its `arms` first, then its robot dogs) in state `s`.
    pub fn new(
        task: &Task,
        s: &State,
        grabbers: &'a [Idx],
        arms: usize,
        rooms: &'a Rooms,
    ) -> Team<'a> {
        let dogs = &grabbers[arms..];
        let dog_rooms = if rooms.count > 1 {
            dogs.iter().map(|&d| rooms.robot(task, s, d)).collect()
        } else {
            smallvec::smallvec![None; dogs.len()]
        };
        Team {
            grabbers,
            dog_rooms,
            rooms,
        }
    }

    /// The fewest room moves of any robot dog to room `to`.
    pub fn nearest_dog(&self, to: Option<u16>) -> u16 {
        self.dog_rooms
            .iter()
            .map(|&r| self.rooms.between(r, to))
            .min()
            .unwrap_or(0)
    }
}

/// A robot dog's put: on or into place `q`, the situation after, and the room the dog
/// puts it in when that never changes.
#[derive(Clone, Copy)]
pub(super) struct Put {
    pub q: Idx,
    pub to: usize,
    pub room: Option<u16>,
}

/// A robot dog's puts of the thing in its hand, as the chains after them (the put
/// counted): by place, for a dog close to it; by room, for a dog that walks there.
#[derive(Debug)]
pub(super) struct Puts {
    pub near: Vec<u16>,
    by_room: Vec<u16>,
    /// Puts in no one room (into something that moves).
    anywhere: u16,
}

impl Puts {
    pub fn new(dist: &[u16], n: usize, rooms: &Rooms, puts: &[Put]) -> Puts {
        let mut near = vec![FAR; n];
        let mut by_room = vec![FAR; rooms.count];
        let mut anywhere = FAR;
        for put in puts {
            let d = dist[put.to].saturating_add(1);
            near[put.q.get()] = near[put.q.get()].min(d);
            let at = match put.room {
                Some(r) => &mut by_room[usize::from(r)],
                None => &mut anywhere,
            };
            *at = (*at).min(d);
        }
        Puts {
            near,
            by_room,
            anywhere,
        }
    }

    /// The chain from the thing in the hand of a dog in room `from` that walks up to
    /// where it puts it: the walk across rooms, the last step up to the place, the put.
    pub fn walked(&self, rooms: &Rooms, from: Option<u16>) -> u16 {
        let across = self
            .by_room
            .iter()
            .enumerate()
            .map(|(r, &d)| d.saturating_add(rooms.between(from, Some(r as u16))))
            .fold(self.anywhere, u16::min);
        across.saturating_add(1)
    }
}

/// The rooms as robots go between them: the room each node that never moves stands in,
/// and the fewest room moves from room to room through the doors, open or closed (a
/// closed door may be opened on the way). A robot dog walks up to a thing only in its
/// own room, and goes to another room only through a door of its room: one action a room.
#[derive(Debug, Default)]
pub(super) struct Rooms {
    /// Per node, its room (an index into `Task::rooms`) when it never moves.
    of: Vec<Option<u16>>,
    /// `apart[a * count + b]`: the room moves from room `a` to room `b`; 0 when no way
    /// is known.
    apart: Vec<u16>,
    pub count: usize,
}

impl Rooms {
    pub fn new(task: &Task, start: &State, fixed: &[bool]) -> Rooms {
        let count = task.rooms().len();
        let room = |r: Idx| task.rooms().iter().position(|&x| x == r).map(|i| i as u16);
        let n = task.nodes.len();
        // The room a node stands in, through the location edges of the start.
        let mut within = vec![None; n];
        for (x, at) in within.iter_mut().enumerate() {
            let mut y = Idx(x as u16);
            for _ in 0..n {
                if let Some(r) = room(y) {
                    *at = Some(r);
                    break;
                }
                let Some(e) = start.out(y).iter().find(|e| e.rel().is_location()) else {
                    break;
                };
                y = e.to();
            }
        }
        let mut next = vec![Vec::new(); count];
        for (i, &(door, r)) in task.doors().iter().enumerate() {
            let mut ends: Vec<u16> = task.doors()[i..]
                .iter()
                .filter(|&&(d, _)| d == door)
                .filter_map(|&(_, r)| room(r))
                .collect();
            ends.extend(within[door.get()]);
            if let Some(a) = room(r) {
                for &b in ends.iter().filter(|&&b| b != a) {
                    next[usize::from(a)].push(b);
                    next[usize::from(b)].push(a);
                }
            }
        }
        let mut apart = vec![0; count * count];
        for a in 0..count {
            let mut seen = vec![FAR; count];
            seen[a] = 0;
            let mut queue = VecDeque::from([a]);
            while let Some(r) = queue.pop_front() {
                for &b in &next[r] {
                    if seen[usize::from(b)] == FAR {
                        seen[usize::from(b)] = seen[r] + 1;
                        queue.push_back(usize::from(b));
                    }
                }
            }
            for (b, d) in seen.into_iter().enumerate() {
                apart[a * count + b] = if d == FAR { 0 } else { d };
            }
        }
        let of = within
            .into_iter()
            .zip(fixed)
            .map(|(r, &f)| r.filter(|_| f))
            .collect();
        Rooms { of, apart, count }
    }

    /// The room of `q` when `q` never moves.
    pub fn of(&self, q: Idx) -> Option<u16> {
        self.of.get(q.get()).copied().flatten()
    }

    /// The room moves from room `a` to room `b`, 0 when either is unknown.
    pub fn between(&self, a: Option<u16>, b: Option<u16>) -> u16 {
        match (a, b) {
            (Some(a), Some(b)) => self.apart[usize::from(a) * self.count + usize::from(b)],
            _ => 0,
        }
    }

    /// The room robot `r` is in, in `s` (a room never moves: its own index).
    pub fn robot(&self, task: &Task, s: &State, r: Idx) -> Option<u16> {
        self.of(crate::rules::room_of(task, s, r)?)
    }
}
