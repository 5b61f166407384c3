//! Leaf slots and arbitration: each leaf's latest value with the cycle it
//! was written in and its writer; committing a run's outputs to them
//! (the paper's *update-record*, atomic per run); the rank that decides a
//! contested leaf; records taken apart into leaves and put back together.

use std::sync::Arc;

use situate_core::value::recycle;
use situate_core::{SignalType, Value};

use super::plan::{OutPort, Step};
use super::Manager;

/// One leaf slot of the cycle's data.
#[derive(Clone, Default)]
pub(super) struct Slot {
    pub(super) value: Option<Value>,
    /// The cycle it was last written in (0: never).
    pub(super) stamp: u64,
    /// (priority, declaration rank) of the writer that holds it this cycle.
    pub(super) rank: (i32, u32),
    pub(super) writer: u32,
}

impl Manager {
    pub(super) fn rank(&self, i: usize) -> (i32, u32) {
        (self.insts[i].priority, u32::MAX - i as u32)
    }

    /// [`Manager::commit`] for a step whose outputs are all plain ports, in
    /// its output buffers.
    #[inline]
    pub(super) fn commit_plain(&mut self, step: &Step, ports: &[OutPort]) -> Result<(), String> {
        let i = step.inst;
        // One output, the usual case: no loops.
        // A step whose outputs are typed by construction is not checked.
        if let [port] = ports {
            match &self.execs[i].outputs[0] {
                None => return Ok(()),
                Some(value) if !step.typed_outs && !port.check.admits(value) => return Err(self.wrong_output(i, 0)),
                Some(_) => {}
            }
            self.commit_plain_port(step, 0, port);
            return Ok(());
        }
        if !step.typed_outs {
            let outputs = &self.execs[i].outputs;
            for (p, (port, value)) in ports.iter().zip(outputs.iter()).enumerate() {
                if let Some(value) = value {
                    if !port.check.admits(value) {
                        return Err(self.wrong_output(i, p));
                    }
                }
            }
        }
        for (p, port) in ports.iter().enumerate() {
            if self.execs[i].outputs[p].is_some() {
                self.commit_plain_port(step, p, port);
            }
        }
        Ok(())
    }

    /// Commits output `p` (`Some`, checked) of a plain step.
    #[inline(always)]
    fn commit_plain_port(&mut self, step: &Step, p: usize, port: &OutPort) {
        let i = step.inst;
        let out = &mut self.execs[i].outputs[p];
        let slot = &mut self.slots[port.leaf];
        // A plain output's last value is its slot's while this skill holds
        // it, so a winning value is moved, not shared: `last_outputs` keeps
        // it only when it lost the slot (see `save_displaced`). So while
        // this skill held the slot its kept last output is empty (it is set
        // only when the skill loses or is displaced, and then the slot is
        // another's until this skill wins it again, which empties it), and
        // need not be looked at. (Unless another of its outputs writes the
        // same leaf: the slot's writer does not tell which port it was.)
        let held = slot.writer as usize == i && slot.stamp > 0 && !port.leaf_shared;
        // `out` is swapped with the slot's value, never moved through a
        // temporary: `out` then holds the value it replaced.
        match write_leaf_in_place(slot, out, self.cycle, step.rank, i) {
            Some(displaced) => {
                if !held {
                    if let Some(old) = self.insts[i].last_outputs[p].take() {
                        recycle(old);
                    }
                }
                // The value it replaced stays in the output buffer when it
                // was this skill's own: the next run recycles it on entry
                // ([`Exec::run`](crate::runner::Exec::run)), or writes into
                // it, long after the swap's stores (taking it now would
                // stall).
                if let Some(w) = displaced {
                    if let Some(old) = out.take() {
                        self.save_displaced(port.leaf, w, old);
                    }
                }
            }
            // Lost: kept as its last output (the previous one dropped).
            None => {
                let last = &mut self.insts[i].last_outputs[p];
                std::mem::swap(last, out);
                *out = None;
            }
        }
    }

    /// The fault of instance `i` whose output `p` is of the wrong type.
    #[cold]
    #[inline(never)]
    fn wrong_output(&self, i: usize, p: usize) -> String {
        let def = &self.graph.instances[i].outputs[p];
        match &self.execs[i].outputs[p] {
            Some(value) => wrong_output(&def.name, &def.ty, value),
            None => format!("output `{}`: no value", def.name),
        }
    }

    /// Writes instance `i`'s produced outputs to their leaves: all of them,
    /// or (when one is not of its port's type) none (update-record is atomic).
    pub(super) fn commit(&mut self, i: usize, outputs: &mut [Option<Value>]) -> Result<(), String> {
        let graph = Arc::clone(&self.graph);
        let def = &graph.instances[i];
        let mut parts = std::mem::take(&mut self.parts);
        parts.clear();
        // First check every output (records are taken apart into their leaves).
        for (port, value) in def.outputs.iter().zip(outputs.iter()) {
            let Some(value) = value else { continue };
            let ok = if let ([_], false) = (&port.leaves[..], matches!(port.ty, SignalType::Record(_))) {
                value.conforms(&port.ty)
            } else {
                decompose(&port.ty, value, &mut parts)
            };
            if !ok {
                parts.clear();
                self.parts = parts;
                return Err(wrong_output(&port.name, &port.ty, value));
            }
        }
        // Then write them.
        let rank = self.rank(i);
        let cycle = self.cycle;
        let mut leaf_values = parts.drain(..);
        for (p, port) in def.outputs.iter().enumerate() {
            let Some(value) = outputs[p].take() else { continue };
            if let ([leaf], false) = (&port.leaves[..], matches!(port.ty, SignalType::Record(_))) {
                if let Ok(Some((w, old))) = write_leaf(&mut self.slots[*leaf], value.clone(), cycle, rank, i) {
                    self.save_displaced(*leaf, w, old);
                }
            } else {
                for (&leaf, part) in port.leaves.iter().zip(&mut leaf_values) {
                    if let Ok(Some((w, old))) = write_leaf(&mut self.slots[leaf], part, cycle, rank, i) {
                        self.save_displaced(leaf, w, old);
                    }
                }
            }
            if let Some(old) = self.insts[i].last_outputs[p].replace(value) {
                if matches!(old, Value::Record(_)) {
                    // The output's buffer is empty (its value was taken
                    // above): the record it replaces goes there, a spare
                    // for a body that fills its outputs to write in place.
                    outputs[p] = Some(old);
                } else {
                    recycle(old);
                }
            }
        }
        drop(leaf_values);
        self.parts = parts;
        Ok(())
    }

    /// Another skill took over `leaf` from writer `w`: the value `w` last
    /// produced there is kept as its last output (a plain port's last output
    /// is otherwise read from its slot).
    pub(super) fn save_displaced(&mut self, leaf: usize, w: usize, old: Value) {
        let Some(&(_, p)) = self.graph.leaves[leaf].writers.iter().find(|&&(x, _)| x == w) else { return };
        let port = &self.graph.instances[w].outputs[p];
        if port.leaves.len() == 1 && !matches!(port.ty, SignalType::Record(_)) {
            if let Some(last) = self.insts[w].last_outputs.get_mut(p) {
                last.get_or_insert(old);
            }
        }
    }

    /// What instance `i` last produced on output `p`.
    pub(crate) fn last_output(&self, i: usize, p: usize) -> Option<Value> {
        if let Some(v) = &self.insts[i].last_outputs[p] {
            return Some(v.clone());
        }
        let port = &self.graph.instances[i].outputs[p];
        let [leaf] = port.leaves[..] else { return None };
        let slot = &self.slots[leaf];
        (slot.writer as usize == i && slot.stamp > 0).then(|| slot.value.clone()).flatten()
    }
}

/// Arbitration: writes `value` to `slot` unless a higher-ranked writer
/// wrote it this cycle (then `Err` hands the value back). `Ok` holds the
/// value it displaced when another writer had written it.
#[inline]
fn write_leaf(
    slot: &mut Slot,
    value: Value,
    cycle: u64,
    rank: (i32, u32),
    writer: usize,
) -> Result<Option<(usize, Value)>, Value> {
    if slot.stamp != cycle || rank > slot.rank {
        let old = slot.value.replace(value);
        let displaced = match old {
            Some(old) if slot.writer as usize != writer && slot.stamp > 0 => Some((slot.writer as usize, old)),
            Some(old) => {
                recycle(old);
                None
            }
            None => None,
        };
        slot.stamp = cycle;
        slot.rank = rank;
        slot.writer = writer as u32;
        Ok(displaced)
    } else {
        Err(value)
    }
}

/// [`write_leaf`] with the value in `value` (`Some`), swapped in place: if
/// it wins (`Some`), `value` then holds what the slot held, and the result
/// says whose it was when another writer had written it (`Some(writer)`);
/// if it loses (`None`), `value` is unchanged.
#[inline]
fn write_leaf_in_place(
    slot: &mut Slot,
    value: &mut Option<Value>,
    cycle: u64,
    rank: (i32, u32),
    writer: usize,
) -> Option<Option<usize>> {
    if slot.stamp != cycle || rank > slot.rank {
        std::mem::swap(&mut slot.value, value);
        let displaced =
            (value.is_some() && slot.writer as usize != writer && slot.stamp > 0).then_some(slot.writer as usize);
        slot.stamp = cycle;
        slot.rank = rank;
        slot.writer = writer as u32;
        Some(displaced)
    } else {
        None
    }
}

#[cold]
#[inline(never)]
fn wrong_output(port: &str, ty: &SignalType, value: &Value) -> String {
    format!("output `{port}` expects {ty}, the body produced a {}", value.kind_name())
}

/// Builds a value of type `ty` from leaf values given in flattened order.
pub(super) fn assemble<'v>(ty: &SignalType, leaves: &mut impl Iterator<Item = &'v Value>) -> Option<Value> {
    match ty {
        SignalType::Record(r) => {
            let mut fields = Vec::with_capacity(r.fields.len());
            for (name, fty) in &r.fields {
                fields.push((Arc::from(name.as_str()), assemble(fty, leaves)?));
            }
            Some(Value::Record(Arc::new(situate_core::RecordValue { fields })))
        }
        _ => leaves.next().cloned(),
    }
}

/// [`assemble`] into `into`: a record there that nobody else holds, of
/// the same fields, is written in place (nothing allocated); anything else
/// is replaced. `None` in `into` when the leaves run out.
pub(super) fn assemble_into<'v>(
    ty: &SignalType,
    leaves: &mut impl Iterator<Item = &'v Value>,
    into: &mut Option<Value>,
) {
    let filled = match into {
        Some(value) => fill(ty, leaves, value),
        None => false,
    };
    if !filled {
        *into = assemble(ty, leaves);
    }
}

/// Writes the leaves into `value` in place if it is a record of `ty`'s
/// shape that nobody else holds; false (nothing taken from `leaves`) if not.
fn fill<'v>(ty: &SignalType, leaves: &mut impl Iterator<Item = &'v Value>, value: &mut Value) -> bool {
    let (SignalType::Record(rt), Value::Record(rv)) = (ty, &mut *value) else { return false };
    let Some(rv) = Arc::get_mut(rv) else { return false };
    if !same_shape(rt, rv) {
        return false;
    }
    for ((_, fty), (_, field)) in rt.fields.iter().zip(rv.fields.iter_mut()) {
        if matches!(fty, SignalType::Record(_)) {
            if fill(fty, leaves, field) {
                continue;
            }
            let Some(v) = assemble(fty, leaves) else { return false };
            *field = v;
        } else {
            let Some(v) = leaves.next() else { return false };
            field.clone_from(v);
        }
    }
    true
}

/// Whether a record value has exactly the type's fields, in order (not
/// looking into nested records: [`fill`] does as it goes).
fn same_shape(rt: &situate_core::RecordType, rv: &situate_core::RecordValue) -> bool {
    rt.fields.len() == rv.fields.len()
        && rt.fields.iter().zip(&rv.fields).all(|((tn, _), (vn, _))| tn.as_str() == &**vn)
}

/// Splits a value of type `ty` into leaf values in flattened order; false if
/// the value does not conform.
pub(super) fn decompose(ty: &SignalType, value: &Value, out: &mut Vec<Value>) -> bool {
    match (ty, value) {
        (SignalType::Record(rt), Value::Record(rv)) => {
            rt.fields.len() == rv.fields.len()
                && rt
                    .fields
                    .iter()
                    .zip(&rv.fields)
                    .all(|((tn, tt), (vn, vv))| tn.as_str() == &**vn && decompose(tt, vv, out))
        }
        (SignalType::Record(_), _) => false,
        (t, v) => {
            if v.conforms(t) {
                out.push(v.clone());
                true
            } else {
                false
            }
        }
    }
}
