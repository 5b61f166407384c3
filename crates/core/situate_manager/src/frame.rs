//! What a tap receives each cycle ([`Manager::tap`](crate::Manager::tap)):
//! a [`Frame`], whose values are packed into a few flat buffers
//! ([`FrameValues`]).
//!
//! Why packed, and not a list of [`Value`]s: a cloned `Value` of an array is
//! its skill's buffer, shared. While a reader on another thread holds it, the
//! skill cannot write its next array in place, so every array of every cycle
//! is allocated anew and freed when the frame comes back; and the reader's
//! reading moves those buffers into its core's cache, so the cycle's writes
//! to them miss. Copying the numbers into flat buffers that the frames bring
//! back costs less than either: in `core record` (`bench/`), a recorded
//! cycle of the delivery robot went from 1.11–1.22× an unrecorded one to
//! 1.06–1.07×. Strings, bytes and records, rare in a cycle, are kept as
//! shared values.

use situate_core::{Value, ValueRef};

/// How a tap is made ([`Manager::tap`](crate::Manager::tap)): how many
/// frames its queue holds, and what the cycle does with a frame that finds
/// it full. A plain capacity (`tap(64)`) is a tap that drops.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TapOptions {
    /// Frames the queue holds (at least 1).
    pub capacity: usize,
    pub when_full: WhenFull,
}

impl TapOptions {
    /// A tap of `capacity` frames that drops when full.
    pub fn new(capacity: usize) -> TapOptions {
        TapOptions { capacity, when_full: WhenFull::Drop }
    }

    /// The same, but waiting for room under the simulated clock
    /// ([`WhenFull::WaitIfSimulated`]).
    pub fn wait_if_simulated(self) -> TapOptions {
        TapOptions { when_full: WhenFull::WaitIfSimulated, ..self }
    }
}

impl From<usize> for TapOptions {
    fn from(capacity: usize) -> TapOptions {
        TapOptions::new(capacity)
    }
}

/// What the cycle does with a frame that finds its tap's queue full.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum WhenFull {
    /// Drop it and count it ([`Drops`]): the cycle never waits for the
    /// reader (the GUI's history, a wall-clock recording).
    #[default]
    Drop,
    /// Under the simulated clock, wait until the reader makes room: no
    /// robot time passes while the cycle waits, so losing the frame would
    /// gain nothing (a recording). The queue then holds at most
    /// [`WAITING_CAPACITY`] frames: a longer one would not make the robot
    /// faster, only leave more for the reader to read when the robot stops.
    /// Under the wall clock, as [`WhenFull::Drop`]: a late cycle would be
    /// late for the devices.
    WaitIfSimulated,
}

/// The most frames a tap's queue holds when the cycle waits for its reader
/// ([`WhenFull::WaitIfSimulated`] on the simulated clock).
pub const WAITING_CAPACITY: usize = 512;

/// Past this many ranges, [`Drops`] grows its last range instead of adding
/// one: its memory is bounded however often a reader falls behind.
pub const MAX_DROP_RANGES: usize = 1024;

/// The cycles a tap lost to a full queue.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Drops {
    /// How many (exact).
    pub count: u64,
    /// Which, as (first, last) ranges of cycles, in order. At most
    /// [`MAX_DROP_RANGES`]; past that the last range is grown to the latest
    /// drop, so the ranges always cover every cycle lost (and then may cover
    /// some that were not).
    pub ranges: Vec<(u64, u64)>,
}

impl Drops {
    /// Counts the cycles `first..=last` as lost (after those already
    /// counted).
    pub fn add_range(&mut self, first: u64, last: u64) {
        if last < first {
            return;
        }
        self.add(first);
        self.count += last - first;
        if let Some((_, end)) = self.ranges.last_mut() {
            *end = (*end).max(last);
        }
    }

    /// Counts `cycle` as lost (cycles come in increasing order).
    pub fn add(&mut self, cycle: u64) {
        self.count += 1;
        let full = self.ranges.len() >= MAX_DROP_RANGES;
        match self.ranges.last_mut() {
            Some((_, last)) if full || cycle <= last.saturating_add(1) => *last = (*last).max(cycle),
            _ => self.ranges.push((cycle, cycle)),
        }
    }
}

/// The values written in one cycle, leaf by leaf.
#[derive(Debug, Clone)]
pub struct Frame {
    pub cycle: u64,
    /// The manager's clock at the cycle, in seconds.
    pub time_s: f64,
    /// (leaf index in the graph, value), in leaf order.
    pub values: FrameValues,
    /// (instance index, line): the skills' prints of this cycle, verbose or not.
    pub prints: Vec<(usize, String)>,
    /// (leaf index, instance index): who won each resource written this cycle.
    pub winners: Vec<(usize, usize)>,
}

/// One cycle's (leaf, value) pairs, in the order pushed, packed: numbers and
/// arrays of numbers are copied into flat buffers (see the module's doc).
/// Read them with [`iter`](Self::iter); reuse the buffers with
/// [`clear`](Self::clear).
#[derive(Debug, Clone, Default)]
pub struct FrameValues {
    entries: Vec<Entry>,
    f64s: Vec<f64>,
    f32s: Vec<f32>,
    i64s: Vec<i64>,
    shared: Vec<Value>,
}

#[derive(Debug, Clone, Copy)]
struct Entry {
    leaf: u32,
    kind: Kind,
    /// Where the value starts in its buffer (for `Bool`: the value).
    start: u32,
    len: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Bool,
    I64,
    F64,
    F32s,
    F64s,
    I64s,
    /// In `shared`.
    Shared,
}

impl FrameValues {
    /// The number of values.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Adds a leaf's value (its numbers copied).
    pub fn push(&mut self, leaf: usize, value: &Value) {
        fn at<T>(buf: &[T]) -> u32 {
            buf.len() as u32
        }
        let (kind, start, len) = match value {
            Value::Bool(b) => (Kind::Bool, u32::from(*b), 0),
            Value::I64(x) => {
                let start = at(&self.i64s);
                self.i64s.push(*x);
                (Kind::I64, start, 1)
            }
            Value::F64(x) => {
                let start = at(&self.f64s);
                self.f64s.push(*x);
                (Kind::F64, start, 1)
            }
            Value::F32s(a) => {
                let start = at(&self.f32s);
                self.f32s.extend_from_slice(a);
                (Kind::F32s, start, a.len() as u32)
            }
            Value::F64s(a) => {
                let start = at(&self.f64s);
                self.f64s.extend_from_slice(a);
                (Kind::F64s, start, a.len() as u32)
            }
            Value::I64s(a) => {
                let start = at(&self.i64s);
                self.i64s.extend_from_slice(a);
                (Kind::I64s, start, a.len() as u32)
            }
            Value::Str(_) | Value::Bytes(_) | Value::Record(_) => {
                let start = at(&self.shared);
                self.shared.push(value.clone());
                (Kind::Shared, start, 1)
            }
        };
        self.entries.push(Entry { leaf: leaf as u32, kind, start, len });
    }

    /// The (leaf, value) pairs, in the order pushed.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = (usize, ValueRef<'_>)> + '_ {
        self.entries.iter().map(move |e| (e.leaf as usize, self.value(e)))
    }

    fn value(&self, e: &Entry) -> ValueRef<'_> {
        let (a, b) = (e.start as usize, e.start as usize + e.len as usize);
        match e.kind {
            Kind::Bool => ValueRef::Bool(e.start != 0),
            Kind::I64 => ValueRef::I64(self.i64s[a]),
            Kind::F64 => ValueRef::F64(self.f64s[a]),
            Kind::F32s => ValueRef::F32s(&self.f32s[a..b]),
            Kind::F64s => ValueRef::F64s(&self.f64s[a..b]),
            Kind::I64s => ValueRef::I64s(&self.i64s[a..b]),
            Kind::Shared => ValueRef::from(&self.shared[a]),
        }
    }

    /// Empties it, keeping its buffers; the shared values go to `release`
    /// (the cycle hands them to [`recycle`](situate_core::value::recycle)).
    pub fn clear(&mut self, release: impl FnMut(Value)) {
        self.entries.clear();
        self.f64s.clear();
        self.f32s.clear();
        self.i64s.clear();
        self.shared.drain(..).for_each(release);
    }

    /// Room for `values` more values, about (arrays may take more).
    pub fn reserve(&mut self, values: usize) {
        self.entries.reserve(values);
        self.f64s.reserve(values);
        self.i64s.reserve(values);
    }
}

impl FromIterator<(usize, Value)> for FrameValues {
    fn from_iter<I: IntoIterator<Item = (usize, Value)>>(iter: I) -> Self {
        let mut values = FrameValues::default();
        for (leaf, v) in iter {
            values.push(leaf, &v);
        }
        values
    }
}

impl From<Vec<(usize, Value)>> for FrameValues {
    fn from(v: Vec<(usize, Value)>) -> Self {
        v.into_iter().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use situate_core::record_value;

    #[test]
    fn drops_are_kept_as_ranges_and_bounded() {
        let mut d = Drops::default();
        for c in [3, 4, 5, 9, 10, 20] {
            d.add(c);
        }
        assert_eq!(d.count, 6);
        assert_eq!(d.ranges, [(3, 5), (9, 10), (20, 20)]);
        d.add_range(21, 30);
        d.add_range(40, 41);
        assert_eq!(d.count, 18);
        assert_eq!(d.ranges, [(3, 5), (9, 10), (20, 30), (40, 41)]);
        let mut d = Drops::default();
        for k in 0..(MAX_DROP_RANGES as u64 + 10) {
            d.add(2 * k);
        }
        assert_eq!(d.count, MAX_DROP_RANGES as u64 + 10);
        assert_eq!(d.ranges.len(), MAX_DROP_RANGES);
        // The last range covers every later drop.
        assert_eq!(d.ranges.last(), Some(&(2 * (MAX_DROP_RANGES as u64 - 1), 2 * (MAX_DROP_RANGES as u64 + 9))));
    }

    #[test]
    fn every_kind_of_value_comes_back_as_pushed_in_order() {
        let values = vec![
            (3, Value::Bool(true)),
            (1, Value::I64(-7)),
            (4, Value::F64(0.1)),
            (9, Value::F32s(vec![1.5, f32::NAN, -0.0].into())),
            (2, Value::F64s(vec![].into())),
            (5, Value::F64s(vec![2.0, 3.0].into())),
            (6, Value::I64s(vec![i64::MIN, 1].into())),
            (7, Value::Str("hi".into())),
            (8, Value::Bytes(vec![0u8, 255].into())),
            (0, record_value(vec![("x", Value::F64(1.0)), ("ok", Value::Bool(false))])),
            (10, Value::Bool(false)),
        ];
        let mut packed: FrameValues = values.clone().into();
        assert_eq!(packed.len(), values.len());
        for ((leaf, got), (want_leaf, want)) in packed.iter().zip(&values) {
            assert_eq!(leaf, *want_leaf);
            // Bit for bit: NaN and -0.0 too.
            assert_eq!(format!("{:?}", got.to_value()), format!("{want:?}"));
            if let (ValueRef::F32s(g), Value::F32s(w)) = (got, want) {
                assert!(g.iter().zip(w.iter()).all(|(a, b)| a.to_bits() == b.to_bits()));
            }
        }
        let mut released = 0;
        packed.clear(|_| released += 1);
        assert!(packed.is_empty());
        assert_eq!(released, 3, "the string, the bytes and the record");
        packed.push(1, &Value::F64(2.0));
        assert_eq!(packed.iter().collect::<Vec<_>>(), vec![(1, ValueRef::F64(2.0))]);
    }
}
