//! A track: one value's changes over the history's window, and the last one before it.

use std::collections::VecDeque;

/// A value's changes over the window, in cycle order, and the last one before it.
#[derive(Debug, Clone)]
pub(super) struct Track<T> {
    pub(super) before: Option<(u64, T)>,
    pub(super) changes: VecDeque<(u64, T)>,
}

impl<T: PartialEq> Track<T> {
    pub(super) fn new(initial: Option<(u64, T)>) -> Self {
        Track { before: initial, changes: VecDeque::new() }
    }

    /// The latest change at or before `cycle`.
    pub(super) fn at(&self, cycle: u64) -> Option<&(u64, T)> {
        let n = self.changes.partition_point(|(c, _)| *c <= cycle);
        if n > 0 {
            self.changes.get(n - 1)
        } else {
            self.before.as_ref().filter(|(c, _)| *c <= cycle)
        }
    }

    fn last(&self) -> Option<&(u64, T)> {
        self.changes.back().or(self.before.as_ref())
    }

    /// Adds a change (in cycle order; one out of order is put in its place).
    pub(super) fn push(&mut self, cycle: u64, value: T) {
        match self.changes.back() {
            Some((c, _)) if *c > cycle => {
                let at = self.changes.partition_point(|(c, _)| *c <= cycle);
                self.changes.insert(at, (cycle, value));
            }
            _ => self.changes.push_back((cycle, value)),
        }
    }

    /// Adds a change only when it changes the value.
    pub(super) fn push_if_changed(&mut self, cycle: u64, value: T) {
        if self.last().map(|(_, v)| v != &value).unwrap_or(true) {
            self.push(cycle, value);
        }
    }

    /// Folds the changes before `first` into the one kept before the window.
    pub(super) fn trim(&mut self, first: u64) {
        while self.changes.front().is_some_and(|(c, _)| *c < first) {
            self.before = self.changes.pop_front();
        }
    }
}
