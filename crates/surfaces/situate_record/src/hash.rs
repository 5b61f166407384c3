//! The per-cycle fingerprint of a run: a 64-bit FNV-1a hash of every leaf
//! written in the cycle (its path and value, bit for bit) and of each
//! resource's winner (the resource's path and the skill's name).
//!
//! Names, not indexes, go in, so a robot file changed by a skill added
//! elsewhere still hashes the same cycle the same way. Floats go in by their
//! bits: `-0.0` differs from `0.0` and one NaN from another, as they may
//! differ downstream. FNV-1a is stable across Rust versions and platforms
//! (`std`'s hasher is not promised to be) and small enough to own; it is not
//! meant to resist anyone forging a collision.

use situate_core::{Value, ValueRef};

const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const PRIME: u64 = 0x0100_0000_01b3;

/// An FNV-1a 64 hasher over the canonical bytes of values.
#[derive(Debug, Clone, Copy)]
pub struct CycleHasher(u64);

impl Default for CycleHasher {
    fn default() -> Self {
        CycleHasher(OFFSET)
    }
}

impl CycleHasher {
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(PRIME);
        }
    }

    fn len(&mut self, n: usize) {
        self.bytes(&(n as u64).to_le_bytes());
    }

    fn str(&mut self, s: &str) {
        self.len(s.len());
        self.bytes(s.as_bytes());
    }

    /// A leaf written this cycle.
    pub fn leaf(&mut self, path: &str, value: ValueRef<'_>) {
        self.bytes(b"L");
        self.str(path);
        self.value(value);
    }

    /// Who holds a resource this cycle.
    pub fn winner(&mut self, resource: &str, skill: &str) {
        self.bytes(b"W");
        self.str(resource);
        self.str(skill);
    }

    fn value(&mut self, value: ValueRef<'_>) {
        match value {
            ValueRef::Bool(b) => self.bytes(&[0, u8::from(b)]),
            ValueRef::I64(x) => {
                self.bytes(&[1]);
                self.bytes(&x.to_le_bytes());
            }
            ValueRef::F64(x) => {
                self.bytes(&[2]);
                self.bytes(&x.to_bits().to_le_bytes());
            }
            ValueRef::Str(s) => {
                self.bytes(&[3]);
                self.str(s);
            }
            ValueRef::Bytes(b) => {
                self.bytes(&[4]);
                self.len(b.len());
                self.bytes(b);
            }
            ValueRef::F32s(a) => {
                self.bytes(&[5]);
                self.len(a.len());
                for x in a.iter() {
                    self.bytes(&x.to_bits().to_le_bytes());
                }
            }
            ValueRef::F64s(a) => {
                self.bytes(&[6]);
                self.len(a.len());
                for x in a.iter() {
                    self.bytes(&x.to_bits().to_le_bytes());
                }
            }
            ValueRef::I64s(a) => {
                self.bytes(&[7]);
                self.len(a.len());
                for x in a.iter() {
                    self.bytes(&x.to_le_bytes());
                }
            }
            ValueRef::Record(r) => {
                self.bytes(&[8]);
                self.len(r.fields.len());
                for (name, v) in &r.fields {
                    self.str(name);
                    self.value(v.into());
                }
            }
        }
    }

    pub fn finish(self) -> u64 {
        self.0
    }
}

/// A cycle's hash: its written leaves and its resources' winners, each in
/// the order of their paths (so the order a graph lists them in does not
/// matter).
pub fn cycle_hash<'a>(
    leaves: impl IntoIterator<Item = (&'a str, ValueRef<'a>)>,
    winners: impl IntoIterator<Item = (&'a str, &'a str)>,
) -> u64 {
    let mut leaves: Vec<_> = leaves.into_iter().collect();
    leaves.sort_unstable_by(|a, b| a.0.cmp(b.0));
    let mut winners: Vec<_> = winners.into_iter().collect();
    winners.sort_unstable();
    let mut h = CycleHasher::default();
    for (path, value) in leaves {
        h.leaf(path, value);
    }
    for (resource, skill) in winners {
        h.winner(resource, skill);
    }
    h.finish()
}

/// Whether two values are the same bit for bit (`NaN` equals the same
/// `NaN`; `-0.0` is not `0.0`), as the hash sees them.
pub fn same(a: &Value, b: &Value) -> bool {
    let (mut x, mut y) = (CycleHasher::default(), CycleHasher::default());
    x.value(a.into());
    y.value(b.into());
    // Equal hashes of different values are possible but would need a
    // collision of FNV-1a on two values of one leaf: compare exactly too.
    x.finish() == y.finish() && exact(a, b)
}

fn exact(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::F64(x), Value::F64(y)) => x.to_bits() == y.to_bits(),
        (Value::F32s(x), Value::F32s(y)) => {
            x.len() == y.len() && x.iter().zip(y.iter()).all(|(p, q)| p.to_bits() == q.to_bits())
        }
        (Value::F64s(x), Value::F64s(y)) => {
            x.len() == y.len() && x.iter().zip(y.iter()).all(|(p, q)| p.to_bits() == q.to_bits())
        }
        (Value::Record(x), Value::Record(y)) => {
            x.fields.len() == y.fields.len()
                && x.fields.iter().zip(&y.fields).all(|((n, p), (m, q))| n == m && exact(p, q))
        }
        _ => a == b,
    }
}

/// The hash as the recording writes it: 16 hexadecimal digits.
pub fn hex(hash: u64) -> String {
    format!("{hash:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn of(leaves: &[(&str, Value)]) -> u64 {
        let mut h = CycleHasher::default();
        for (p, v) in leaves {
            h.leaf(p, v.into());
        }
        h.finish()
    }

    #[test]
    fn the_hash_tells_values_paths_and_float_bits_apart() {
        let base = of(&[("a", Value::F64(1.0)), ("b", Value::I64(2))]);
        assert_eq!(base, of(&[("a", Value::F64(1.0)), ("b", Value::I64(2))]));
        assert_ne!(base, of(&[("a", Value::F64(1.0)), ("b", Value::I64(3))]));
        assert_ne!(base, of(&[("a", Value::F64(1.0)), ("c", Value::I64(2))]));
        assert_ne!(of(&[("a", Value::F64(0.0))]), of(&[("a", Value::F64(-0.0))]));
        assert_ne!(of(&[("a", Value::F64(1.0))]), of(&[("a", Value::I64(1))]));
        // A path's end is not the next value's start.
        assert_ne!(of(&[("ab", Value::Str("c".into()))]), of(&[("a", Value::Str("bc".into()))]));
        // A known value, so the hash never changes unnoticed between versions.
        assert_eq!(hex(of(&[])), "cbf29ce484222325");
    }

    #[test]
    fn a_cycle_hash_does_not_depend_on_the_order_of_leaves() {
        let (a, b) = (Value::F64(1.0), Value::I64(2));
        assert_eq!(
            cycle_hash([("a", (&a).into()), ("b", (&b).into())], []),
            cycle_hash([("b", (&b).into()), ("a", (&a).into())], [])
        );
        assert_ne!(
            cycle_hash([("a", (&a).into())], [("drive", "x")]),
            cycle_hash([("a", (&a).into())], [("drive", "y")])
        );
    }

    #[test]
    fn same_compares_bits() {
        assert!(same(&Value::F64(f64::NAN), &Value::F64(f64::NAN)));
        assert!(!same(&Value::F64(0.0), &Value::F64(-0.0)));
        assert!(same(&Value::F32s(vec![1.0, 2.0].into()), &Value::F32s(vec![1.0, 2.0].into())));
        assert!(!same(&Value::F32s(vec![1.0, 2.0].into()), &Value::F32s(vec![1.0, 2.5].into())));
    }
}
