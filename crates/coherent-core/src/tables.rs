//! The tables of an A* search over [`State`]s: every state met, by index, with what the
//! search knows of it; a hash table of indices that finds duplicates; an open list, a
//! bucket queue on `f`; and an estimate of the bytes they take, which
//! [`crate::planner::Limits::max_memory`] bounds. The sequential planner and the
//! makespan search share them; the makespan search orders its open states by joint
//! steps, then actions, in an open list of its own, and leaves these buckets empty.

use std::hash::BuildHasher;

use hashbrown::HashTable;
use rustc_hash::FxBuildHasher;

use crate::graph::State;

/// What the search knows of one state besides the state itself; `P` is how it was
/// reached (one robot's action, or a joint step).
#[derive(Clone, Copy)]
pub(crate) struct Info<P> {
    pub hash: u64,
    /// The state it was best reached from, and how.
    pub parent: u32,
    pub step: P,
    /// Best known cost, and the heuristic.
    pub g: u16,
    pub h: u16,
    pub closed: bool,
}

/// Every state met, by index (a hash table of indices finds duplicates), and the open
/// list, a bucket queue on `f`; with the bytes they take.
pub(crate) struct Tables<P> {
    pub states: Vec<State>,
    pub info: Vec<Info<P>>,
    table: HashTable<u32>,
    pub buckets: Vec<Vec<u32>>,
    /// Bytes of the states' own blocks and of the buckets' blocks.
    state_bytes: usize,
    bucket_bytes: usize,
}

/// What the allocator adds to each block, roughly.
const BLOCK_OVERHEAD: usize = 16;

impl<P: Copy> Tables<P> {
    /// The tables with the start state, reached by `root`, as state 0 (not queued).
    pub fn new(start: &State, h: u16, root: P) -> Tables<P> {
        let mut t = Tables {
            states: Vec::new(),
            info: Vec::new(),
            table: HashTable::new(),
            buckets: Vec::new(),
            state_bytes: 0,
            bucket_bytes: 0,
        };
        t.insert(start.clone(), FxBuildHasher.hash_one(start), 0, root, 0, h);
        t
    }

    pub fn find(&self, hash: u64, s: &State) -> Option<usize> {
        self.table
            .find(hash, |&j| self.states[j as usize] == *s)
            .map(|&j| j as usize)
    }

    /// Adds a state met for the first time (the caller queues it).
    pub fn insert(&mut self, s: State, hash: u64, parent: u32, step: P, g: u16, h: u16) {
        let j = self.states.len() as u32;
        let info = &self.info;
        self.table
            .insert_unique(hash, j, |&k| info[k as usize].hash);
        self.state_bytes += s.heap_bytes() + BLOCK_OVERHEAD;
        self.states.push(s);
        self.info.push(Info {
            hash,
            parent,
            step,
            g,
            h,
            closed: false,
        });
    }

    /// Puts state `i` in the bucket of its `f`.
    pub fn queue(&mut self, i: u32) {
        let info = self.info[i as usize];
        let f = usize::from(info.g) + usize::from(info.h);
        if self.buckets.len() <= f {
            self.buckets.resize_with(f + 1, Vec::new);
        }
        let bucket = &mut self.buckets[f];
        let before = bucket.capacity();
        bucket.push(i);
        self.bucket_bytes += (bucket.capacity() - before) * size_of::<u32>();
    }

    /// The estimated bytes of the tables; with `more`, after adding a state whose own
    /// block takes `more` bytes, counting the doubling of a full vector or table that
    /// the addition would cause.
    pub fn bytes(&self, more: Option<usize>) -> usize {
        let grown = |len: usize, cap: usize| match more {
            Some(_) if len == cap => cap.max(4) * 2,
            _ => cap,
        };
        let table = grown(self.table.len(), self.table.capacity()) * (size_of::<u32>() + 1) * 8 / 7;
        self.state_bytes
            + more.map_or(0, |b| b + BLOCK_OVERHEAD)
            + grown(self.states.len(), self.states.capacity()) * size_of::<State>()
            + grown(self.info.len(), self.info.capacity()) * size_of::<Info<P>>()
            + table
            + self.buckets.capacity() * size_of::<Vec<u32>>()
            + self.bucket_bytes
    }

    /// How state `at` was reached from the start (state 0), first step first.
    pub fn unwind(&self, mut at: usize) -> Vec<P> {
        let mut plan = Vec::new();
        while at != 0 {
            plan.push(self.info[at].step);
            at = self.info[at].parent as usize;
        }
        plan.reverse();
        plan
    }
}
