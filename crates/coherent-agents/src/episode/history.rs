//! What a method remembers of its earlier rounds: the history window. PEFA's task
//! assigner reads the feedback of the last rounds, the baselines' prompts recall the last
//! executed actions, and a method written outside the crate is shown every earlier step;
//! each keeps them in a [`History`].

use std::collections::VecDeque;

/// Rounds of history the methods' prompts recall unless told otherwise: the paper's 5,
/// for PEFA's task assigner and the baselines alike (`pefa-no-history` is 0).
pub const HISTORY_WINDOW: usize = 5;

/// The last entries of a method's history, oldest first, at most `keep` of them (none
/// when `keep` is 0, the paper's "w/o history").
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct History<T> {
    entries: VecDeque<T>,
    keep: usize,
}

impl<T: Clone> History<T> {
    /// A history that keeps the last `keep` entries.
    pub fn new(keep: usize) -> History<T> {
        History {
            entries: VecDeque::new(),
            keep,
        }
    }

    /// A history that keeps every entry (what a method written outside the crate is
    /// shown: it picks its own window).
    pub fn whole() -> History<T> {
        History::new(usize::MAX)
    }

    /// Adds the newest entry, forgetting the oldest beyond the window.
    pub fn push(&mut self, entry: T) {
        if self.keep == 0 {
            return;
        }
        self.entries.push_back(entry);
        while self.entries.len() > self.keep {
            self.entries.pop_front();
        }
    }

    /// The entries kept, oldest first.
    pub fn entries(&self) -> Vec<T> {
        self.entries.iter().cloned().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_keeps_the_newest_entries_and_zero_keeps_none() {
        let mut h = History::new(2);
        for i in 1..=3 {
            h.push(i);
        }
        assert_eq!(h.entries(), [2, 3]);
        let mut none = History::new(0);
        none.push(1);
        assert!(none.entries().is_empty());
        let mut whole = History::whole();
        for i in 0..100 {
            whole.push(i);
        }
        assert_eq!(whole.entries().len(), 100);
    }
}
