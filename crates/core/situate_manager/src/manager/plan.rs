//! The compiled plan: the schedule of the active skills, flattened.
//!
//! When the active set (or a priority) changes, the schedule is compiled
//! into a [`Plan`]: the active cskills in topological order, grouped into
//! levels, each a [`Step`] that holds inline what its run needs — the
//! instance, its kind, its arbitration rank, its deadline, and the ranges of
//! its ports in two dense arrays of port entries (the leaf slot a plain port
//! reads or writes, and how to check an output's type without a call).
//! A cycle walks these arrays and touches no other wiring for plain ports:
//! the plan is the same size whatever the number of inactive skills, and
//! its entries sit next to each other in the order they run.

use situate_core::{ElemType, SignalType, SkillKind, Value};

use crate::graph::{topo_order, Graph, PortBinding};

/// A run of a body in the cycle with a deadline below this is always
/// timed exactly; longer ones are checked on the coarse clock, except in
/// a sampled cycle's window (see `Manager::exact`).
pub(crate) const PRECISE_DEADLINE_NS: u64 = 100_000_000;

#[derive(Default)]
pub(crate) struct Plan {
    /// The active dskills.
    pub devices: Vec<usize>,
    /// Ranges of `steps`, one per level.
    pub levels: Vec<(u32, u32)>,
    pub steps: Vec<Step>,
    /// The steps that may run the short way, in the order of `steps`.
    pub fast: Vec<Fast>,
    pub ins: Vec<InPort>,
    pub outs: Vec<OutPort>,
}

/// How a step's skill runs.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum StepKind {
    /// A sync cskill: runs when its required inputs are fresh.
    Sync,
    /// An async cskill run in the cycle (simulated clock): runs on the
    /// latest inputs.
    AsyncInCycle,
    /// An async cskill on its own thread: exchanged with, never run here.
    AsyncThreaded,
}

/// One active cskill in the plan.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Step {
    pub inst: usize,
    pub kind: StepKind,
    /// (priority, declaration rank): the higher wins a contested leaf.
    pub rank: (i32, u32),
    pub deadline_ns: u64,
    /// Time every run exactly (its deadline is short).
    pub precise: bool,
    /// Its ports in `Plan::ins` and `Plan::outs`.
    pub ins: (u32, u32),
    pub outs: (u32, u32),
    /// Every output is a plain port (one leaf, checked inline).
    pub plain_outs: bool,
    /// Every output is a plain port whose values are of its type by
    /// construction (`Skill::output_typed`): not checked when committed.
    pub typed_outs: bool,
    /// Every input is a plain port (one leaf, not a record), each on a
    /// slot of its own.
    pub plain_ins: bool,
    /// The slot of its input when it has exactly one, plain: the body reads
    /// it there, in place (kept inline: one look-up fewer per run).
    pub one_input: Option<usize>,
    /// The common step, run the short way: its entry in [`Plan::fast`].
    pub fast: Option<u32>,
}

/// A step that may run the short way (`walk::run_steps`): a sync cskill
/// with one required plain input, read in place, or none (a source, run
/// every cycle), and one plain output of its type by construction, on a
/// leaf no other skill writes (so never contested), with a deadline long
/// enough to be checked on the coarse clock. Its body is not timed on its
/// own outside a sampled cycle's window: the bodies run back to back this
/// way are timed together.
///
/// Kept apart from [`Step`], in [`Plan::fast`], in the order of the steps:
/// a stretch of such steps reads 32 bytes a step (two to a cache line)
/// instead of the step's two lines.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fast {
    /// Its step in [`Plan::steps`].
    pub step: u32,
    pub inst: u32,
    /// The slot of its one input; [`Fast::NO_INPUT`] for a source.
    pub input: u32,
    pub output: u32,
    /// Its step's rank (see [`Step::rank`]).
    pub rank: (i32, u32),
    /// Its step's deadline in µs (at least [`PRECISE_DEADLINE_NS`]; a
    /// longer one than `u32` holds is cut to `u32::MAX` µs, over an hour).
    pub deadline_us: u32,
    /// Its body's run splits in two, and its output is written straight
    /// into its slot after the body returned clean (`Skill::writes_output`
    /// and `Skill::fills_outputs`), with no spare buffer.
    pub in_slot: bool,
}

impl Fast {
    pub const NO_INPUT: u32 = u32::MAX;

    /// The slot of its one input, if it has one.
    #[inline(always)]
    pub fn input(&self) -> Option<usize> {
        (self.input != Fast::NO_INPUT).then_some(self.input as usize)
    }
}

/// How a body writes its outputs, asked once when it is made (the hidden
/// hooks of `Skill`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Outputs {
    /// Every output is of its port's type by construction
    /// (`Skill::output_typed`): not checked when committed.
    pub typed: bool,
    /// Every output is filled (`Skill::fills_outputs`) and set by every
    /// `Ok` run, and a run splits in two (`Skill::writes_output`): its
    /// outputs may be written straight into their slots.
    pub in_slot: bool,
}

/// An input port: `leaf` is its slot when `plain` (one leaf, not a
/// record); otherwise the graph's binding is used.
#[derive(Clone, Copy, Debug)]
pub(crate) struct InPort {
    pub leaf: usize,
    pub plain: bool,
    pub optional: bool,
}

/// An output port: as [`InPort`], with its type check.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OutPort {
    pub leaf: usize,
    pub check: Check,
    /// Another output of the same skill writes this leaf too (a slot's
    /// writer then does not tell which of its ports wrote it).
    pub leaf_shared: bool,
}

/// An output's type check without a call; `Record` for the ports that go
/// through `decompose` instead.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Check {
    Bool,
    I64,
    F64,
    Str,
    Bytes,
    /// An array of `elem`, of `len` elements if `Some`.
    Array(ElemType, Option<usize>),
    Record,
}

impl Check {
    fn of(port: &PortBinding) -> Check {
        if port.leaves.len() != 1 {
            return Check::Record;
        }
        match &port.ty {
            SignalType::Bool => Check::Bool,
            SignalType::I64 => Check::I64,
            SignalType::F64 => Check::F64,
            SignalType::Str => Check::Str,
            SignalType::Bytes => Check::Bytes,
            SignalType::Array { elem, len } => Check::Array(*elem, *len),
            SignalType::Record(_) => Check::Record,
        }
    }

    /// Whether `value` is of this (plain) type.
    #[inline]
    pub fn admits(self, value: &Value) -> bool {
        match (self, value) {
            (Check::Bool, Value::Bool(_))
            | (Check::I64, Value::I64(_))
            | (Check::F64, Value::F64(_))
            | (Check::Str, Value::Str(_))
            | (Check::Bytes, Value::Bytes(_)) => true,
            (Check::Array(ElemType::F32, len), Value::F32s(a)) => len.is_none_or(|n| n == a.len()),
            (Check::Array(ElemType::F64, len), Value::F64s(a)) => len.is_none_or(|n| n == a.len()),
            (Check::Array(ElemType::I64, len), Value::I64s(a)) => len.is_none_or(|n| n == a.len()),
            _ => false,
        }
    }
}

impl Plan {
    /// Compiles the schedule of the skills `active` says are active:
    /// cskills in topological order (ties: declaration order), grouped into
    /// levels (a skill is one level after the latest of its writers).
    /// `outputs(i)`: how instance `i`'s body writes its outputs (read when
    /// the body was made).
    pub fn compile(
        graph: &Graph,
        active: impl Fn(usize) -> bool,
        priority: impl Fn(usize) -> i32,
        threaded: impl Fn(usize) -> bool,
        outputs: impl Fn(usize) -> Outputs,
    ) -> Plan {
        let order = topo_order(&graph.instances, &graph.leaves, &active);
        let mut level = vec![0usize; graph.instances.len()];
        let mut levels: Vec<Vec<usize>> = Vec::new();
        for &i in &order {
            let mut l = 0;
            for port in &graph.instances[i].inputs {
                for &leaf in &port.leaves {
                    for &(w, _) in &graph.leaves[leaf].writers {
                        if w != i && active(w) && graph.instances[w].kind != SkillKind::Device {
                            l = l.max(level[w] + 1);
                        }
                    }
                }
            }
            level[i] = l;
            if levels.len() <= l {
                levels.resize_with(l + 1, Vec::new);
            }
            levels[l].push(i);
        }
        let mut plan = Plan {
            devices: (0..graph.instances.len())
                .filter(|&i| active(i) && graph.instances[i].kind == SkillKind::Device)
                .collect(),
            ..Plan::default()
        };
        for mut skills in levels {
            skills.sort_unstable();
            let first = plan.steps.len() as u32;
            for i in skills {
                let def = &graph.instances[i];
                let ins0 = plan.ins.len() as u32;
                plan.ins.extend(def.inputs.iter().map(|p| InPort {
                    leaf: p.leaves.first().copied().unwrap_or(0),
                    plain: p.leaves.len() == 1 && !matches!(p.ty, SignalType::Record(_)),
                    optional: p.optional,
                }));
                let outs0 = plan.outs.len() as u32;
                plan.outs.extend(def.outputs.iter().map(|p| OutPort {
                    leaf: p.leaves.first().copied().unwrap_or(0),
                    check: Check::of(p),
                    leaf_shared: def.outputs.iter().filter(|q| q.leaves.first() == p.leaves.first()).count() > 1,
                }));
                let deadline_ns = def.in_cycle_deadline().as_nanos().min(u64::MAX as u128) as u64;
                let kind = match (def.kind, threaded(i)) {
                    (SkillKind::Async, true) => StepKind::AsyncThreaded,
                    (SkillKind::Async, false) => StepKind::AsyncInCycle,
                    _ => StepKind::Sync,
                };
                let plain_outs = plan.outs[outs0 as usize..].iter().all(|o| o.check != Check::Record);
                plan.steps.push(Step {
                    inst: i,
                    kind,
                    rank: (priority(i), u32::MAX - i as u32),
                    deadline_ns,
                    precise: deadline_ns < PRECISE_DEADLINE_NS,
                    ins: (ins0, plan.ins.len() as u32),
                    outs: (outs0, plan.outs.len() as u32),
                    plain_outs,
                    typed_outs: plain_outs && outputs(i).typed,
                    plain_ins: {
                        // Lent inputs must come from distinct slots.
                        let ins = &plan.ins[ins0 as usize..];
                        ins.iter().all(|p| p.plain)
                            && ins.iter().enumerate().all(|(a, p)| ins[..a].iter().all(|q| q.leaf != p.leaf))
                    },
                    one_input: match plan.ins[ins0 as usize..] {
                        [InPort { leaf, plain: true, .. }] => Some(leaf),
                        _ => None,
                    },
                    fast: None,
                });
                let k = plan.steps.len() - 1;
                let step = &mut plan.steps[k];
                let input = match plan.ins[ins0 as usize..] {
                    [] => Some(Fast::NO_INPUT),
                    [InPort { leaf, plain: true, optional: false }] => Some(leaf as u32),
                    _ => None,
                };
                if let (Some(input), [out]) = (input, &plan.outs[outs0 as usize..]) {
                    let sole_writer = graph.leaves[out.leaf].writers.len() == 1;
                    if step.kind == StepKind::Sync && step.typed_outs && !step.precise && sole_writer {
                        step.fast = Some(plan.fast.len() as u32);
                        plan.fast.push(Fast {
                            step: k as u32,
                            inst: i as u32,
                            input,
                            output: out.leaf as u32,
                            rank: step.rank,
                            deadline_us: (deadline_ns / 1_000).min(u32::MAX as u64) as u32,
                            in_slot: outputs(i).in_slot,
                        });
                    }
                }
            }
            plan.levels.push((first, plan.steps.len() as u32));
        }
        plan
    }

    /// Whether level `l` has more than one step (only such a level can run
    /// in parallel).
    pub fn parallel_level(&self, l: usize) -> bool {
        self.levels.get(l).is_some_and(|&(a, b)| b - a > 1)
    }

    /// The steps of level `l`.
    pub fn level(&self, l: usize) -> Option<std::ops::Range<usize>> {
        self.levels.get(l).map(|&(a, b)| a as usize..b as usize)
    }
}
