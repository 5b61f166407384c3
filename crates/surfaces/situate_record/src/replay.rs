//! Deterministic replay (re-simulation) of a recording through a manager.
//!
//! The robot is built again from its robot file with every dskill, and every
//! skill not chosen to run live, replaced by a *player*: a synchronous
//! cskill with the same outputs, parameters and priority and no inputs,
//! which writes in each cycle what that skill wrote in the recording. The
//! live skills run their code now. The recorded activations and parameter
//! changes of the live skills are applied at the cycles they were applied
//! in; then each cycle's written leaves and resource winners are compared
//! with the recording, through the per-cycle fingerprint
//! ([`crate::hash::cycle_hash`]), and the first difference is named.
//!
//! What a replay needs, and the recording does not hold, is stated in
//! `docs/recording.md` ("Replay"): a serial executor, synchronous live
//! skills, the simulated clock, and no budget faults. A replay runs every
//! body to completion: [`cast`] lifts every deadline to the longest a robot
//! may have (a day), so a slow machine or a tight `budget_ms` in the robot
//! file faults nothing.

use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, OnceLock};

use serde_json::{json, Value as Json};
use situate_core::{Io, SignalType, Skill, SkillDecl, SkillError, SkillKind, SkillType, Value};
use situate_link::json::{param_from_json, value_from_json, value_to_json};
use situate_manager::graph::Graph;
use situate_manager::{Frame, Manager, Request};
use situate_robotfile::config::MAX_DEADLINE_MS;
use situate_robotfile::spec::RobotSpec;

use crate::hash::{cycle_hash, same};
use crate::read::Recording;

/// What each player writes in each cycle: instance name → cycle → one
/// value per output port (`None`: not written).
#[derive(Debug, Default)]
pub struct Tape {
    outputs: HashMap<String, HashMap<u64, Vec<Option<Value>>>>,
}

/// The tape, set once the manager (and so its graph) is built.
pub type SharedTape = Arc<OnceLock<Tape>>;

/// Which skills of a robot a replay runs, and which it plays from the log.
#[derive(Debug, Clone, Default)]
pub struct Cast {
    /// Instances whose code runs now.
    pub live: Vec<String>,
    /// Instances replaced by players.
    pub players: Vec<String>,
    /// The players' tape, to set once the manager is built ([`build_tape`]).
    pub tape: SharedTape,
}

/// Rewrites `spec` for a replay: every dskill, every skill whose type
/// `registry` does not have but `remote` declares (a skill served over the
/// link), and every skill not in `live` (when `live` is `Some`) becomes a
/// player, registered in `registry` as `replay.<instance>`, always active.
/// `live: None`: every skill that can run here runs live. A name in `live`
/// that is not a skill of the robot, or is a dskill, is an error naming it.
/// Every deadline (the robot's and each skill's `budget_ms` and
/// `liveness_ms`) becomes the longest allowed, a day: a replay runs bodies
/// to completion, however slow the machine.
pub fn cast(
    spec: &mut RobotSpec,
    registry: &mut situate_manager::Registry,
    remote: &[(String, SkillDecl)],
    live: Option<&[String]>,
) -> Result<Cast, String> {
    if let Some(live) = live {
        for name in live {
            let Some(s) = spec.skills.iter().find(|s| &s.name == name) else {
                let names = spec.skills.iter().map(|s| s.name.as_str());
                return Err(format!(
                    "--live {name}: no skill `{name}` in the robot{}",
                    situate_core::suggestion(name, names)
                ));
            };
            if registry.get(&s.type_name).is_some_and(|t| t.decl.kind == SkillKind::Device) {
                return Err(format!("--live {name}: `{name}` is a dskill; devices always play from the recording"));
            }
        }
    }
    let mut cast = Cast::default();
    // Deadlines are the wall clock's: the recording's cycles were not
    // faulted by this machine's speed, so the replay's must not be either.
    let no_deadline = Some(MAX_DEADLINE_MS);
    spec.budget_ms = no_deadline;
    spec.liveness_ms = no_deadline;
    for s in &mut spec.skills {
        s.budget_ms = no_deadline;
        s.liveness_ms = no_deadline;
        let decl = match registry.get(&s.type_name) {
            Some(t) => (*t.decl).clone(),
            None => match remote.iter().find(|(n, _)| n == &s.name) {
                Some((_, d)) => d.clone(),
                // An unknown type: the manager's build names it.
                None => continue,
            },
        };
        let runs_here = registry.get(&s.type_name).is_some() && decl.kind != SkillKind::Device;
        let is_live = runs_here && live.is_none_or(|l| l.contains(&s.name));
        if is_live {
            cast.live.push(s.name.clone());
            continue;
        }
        let type_name = format!("replay.{}", s.name);
        registry.add(player_type(&type_name, &decl, &s.name, Arc::clone(&cast.tape)));
        s.type_name = type_name;
        s.active = true;
        s.period_ms = None;
        s.section = None;
        s.remap.retain(|r| decl.outputs.iter().any(|o| o.name == r.port));
        cast.players.push(s.name.clone());
    }
    Ok(cast)
}

/// A player's type for instance `instance` of a skill declared `decl`: a
/// synchronous cskill named `type_name` with `decl`'s outputs, parameters and
/// priority, and no inputs.
pub fn player_type(type_name: &str, decl: &SkillDecl, instance: &str, tape: SharedTape) -> SkillType {
    let mut d = decl.clone();
    d.type_name = type_name.to_string();
    d.doc = format!("replays `{instance}` ({}) from a recording", decl.type_name);
    d.kind = SkillKind::Sync;
    d.inputs.clear();
    d.claims.clear();
    let instance = instance.to_string();
    SkillType::new(d, move || {
        Ok(Box::new(Player { instance: instance.clone(), tape: Arc::clone(&tape) }) as Box<dyn Skill>)
    })
}

struct Player {
    instance: String,
    tape: SharedTape,
}

impl Skill for Player {
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        let tape = self.tape.get().ok_or_else(|| SkillError::new("replay: the recording is not loaded yet"))?;
        let cycle = io.cx.cycle();
        if let Some(values) = tape.outputs.get(&self.instance).and_then(|c| c.get(&cycle)) {
            for (out, v) in io.outputs.iter_mut().zip(values) {
                out.clone_from(v);
            }
        }
        Ok(())
    }

    fn set_param(&mut self, _index: usize, _value: &Value) {}
}

/// Builds the tape of the players (`players`: instance names) from the
/// recording, with the types of `graph`'s leaves. A recorded value that does
/// not fit its leaf's type is an error naming the cycle and the leaf.
pub fn build_tape(rec: &Recording, graph: &Graph, players: &[String]) -> Result<Tape, String> {
    let index: HashMap<&str, usize> = graph.instances.iter().enumerate().map(|(i, d)| (d.name.as_str(), i)).collect();
    let wanted: Vec<usize> = players.iter().filter_map(|p| index.get(p.as_str()).copied()).collect();
    let mut tape = Tape::default();
    let mut values: Vec<Option<(Value, usize)>> = vec![None; graph.leaves.len()];
    for (&cycle, recorded) in &rec.cycles {
        values.iter_mut().for_each(|v| *v = None);
        for (path, j) in &recorded.leaves {
            // A leaf the robot no longer has is written by no player.
            let Some(&leaf) = graph.leaf_index.get(path) else { continue };
            let def = &graph.leaves[leaf];
            let value = value_from_json(j, &def.ty).map_err(|e| format!("cycle {cycle}, `{path}`: {e}"))?;
            let writer = if def.is_resource() {
                rec.holder(path, cycle).and_then(|s| index.get(s).copied())
            } else {
                def.writers.first().map(|&(i, _)| i)
            };
            if let Some(w) = writer {
                values[leaf] = Some((value, w));
            }
        }
        for &i in &wanted {
            let def = &graph.instances[i];
            let mut outs: Vec<Option<Value>> = Vec::with_capacity(def.outputs.len());
            let mut any = false;
            for port in &def.outputs {
                let mine = port.leaves.iter().any(|&l| values[l].as_ref().is_some_and(|(_, w)| *w == i));
                let value = if mine {
                    let mut leaves = port.leaves.iter().map(|&l| values[l].as_ref().map(|(v, _)| v));
                    assemble(&port.ty, &mut leaves)
                } else {
                    None
                };
                any |= value.is_some();
                outs.push(value);
            }
            if any {
                tape.outputs.entry(def.name.clone()).or_default().insert(cycle, outs);
            }
        }
    }
    Ok(tape)
}

/// A port's value from its leaves' values in flattened order (`None` if one
/// of them was not written).
fn assemble<'v>(ty: &SignalType, leaves: &mut impl Iterator<Item = Option<&'v Value>>) -> Option<Value> {
    match ty {
        SignalType::Record(r) => {
            let mut fields = Vec::with_capacity(r.fields.len());
            let mut complete = true;
            for (name, fty) in &r.fields {
                match assemble(fty, leaves) {
                    Some(v) => fields.push((Arc::from(name.as_str()), v)),
                    None => complete = false,
                }
            }
            complete.then(|| Value::Record(Arc::new(situate_core::RecordValue { fields })))
        }
        _ => leaves.next().flatten().cloned(),
    }
}

/// The first difference between a replayed cycle and the recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Divergence {
    pub cycle: u64,
    /// The signal leaf (or resource) that differs.
    pub signal: String,
    /// `value` (both wrote it, differently), `only_recorded`, `only_replayed`,
    /// `winner` (another skill holds the resource) or `missing_cycle` (the
    /// recording has no such cycle).
    pub what: &'static str,
    pub recorded: Json,
    pub replayed: Json,
    /// The other leaves that differ in the same cycle (downstream of
    /// `signal`, as a rule).
    pub others: Vec<String>,
}

impl Divergence {
    pub fn to_json(&self) -> Json {
        json!({"cycle": self.cycle, "signal": self.signal, "what": self.what,
               "recorded": self.recorded, "replayed": self.replayed, "others": self.others})
    }
}

impl std::fmt::Display for Divergence {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (c, s) = (self.cycle, &self.signal);
        match self.what {
            "value" => {
                write!(f, "cycle {c}: `{s}` was {} in the recording, {} in the replay", self.recorded, self.replayed)
            }
            "only_recorded" => {
                write!(f, "cycle {c}: `{s}` was written in the recording ({}), not in the replay", self.recorded)
            }
            "only_replayed" => {
                write!(f, "cycle {c}: `{s}` was written in the replay ({}), not in the recording", self.replayed)
            }
            "winner" => write!(
                f,
                "cycle {c}: resource `{s}` was held by {} in the recording, by {} in the replay",
                self.recorded, self.replayed
            ),
            _ => write!(f, "cycle {c}: the recording has no such cycle"),
        }
    }
}

/// A replay's outcome.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Outcome {
    /// Cycles replayed.
    pub cycles: u64,
    /// Of those, cycles whose fingerprint matched the recording's.
    pub matched: u64,
    /// The first cycle that differs, and where.
    pub first: Option<Divergence>,
    /// Cycles the recording lacks (dropped while recording): how many, and
    /// which as (first, last) ranges.
    pub dropped: u64,
    pub dropped_ranges: Vec<(u64, u64)>,
    /// The replay stopped before this cycle, the first one the recording
    /// lacks (up to `--to`): past it the players would write nothing where
    /// the robot had values, so nothing after it can be compared.
    pub stopped_before: Option<u64>,
}

impl Outcome {
    /// Every cycle of the recording was replayed and matched: some cycles
    /// compared, none differing, none missing from the recording.
    pub fn identical(&self) -> bool {
        self.first.is_none() && self.cycles > 0 && self.dropped == 0
    }
}

/// Compares a replayed frame with the recording: `None` when they agree.
pub fn compare(rec: &Recording, graph: &Graph, frame: &Frame) -> Option<Divergence> {
    let name = |leaf: usize| graph.leaves.get(leaf).map_or("?", |l| l.path.as_str());
    let skill = |i: usize| graph.instances.get(i).map_or("?", |d| d.name.as_str());
    let hash = cycle_hash(
        frame.values.iter().map(|(l, v)| (name(l), v)),
        frame.winners.iter().map(|&(l, i)| (name(l), skill(i))),
    );
    let Some(recorded) = rec.cycles.get(&frame.cycle) else {
        return Some(Divergence {
            cycle: frame.cycle,
            signal: String::new(),
            what: "missing_cycle",
            recorded: Json::Null,
            replayed: Json::Null,
            others: Vec::new(),
        });
    };
    if recorded.hash == Some(hash) {
        return None;
    }
    // Find where: every leaf that differs, then the one whose writer read
    // no differing leaf (where the difference starts), else the first by path.
    let mut by_path: BTreeMap<&str, (Option<&Json>, Option<&Value>)> = BTreeMap::new();
    for (path, j) in &recorded.leaves {
        by_path.entry(path.as_str()).or_default().0 = Some(j);
    }
    // A cycle that differs is rare: its values are made owned to compare.
    let replayed: Vec<(usize, Value)> = frame.values.iter().map(|(l, v)| (l, v.to_value())).collect();
    for (l, v) in &replayed {
        by_path.entry(name(*l)).or_default().1 = Some(v);
    }
    let mut diffs: Vec<Divergence> = Vec::new();
    for (path, (r, v)) in by_path {
        let d = |what, recorded: Json, replayed: Json| Divergence {
            cycle: frame.cycle,
            signal: path.to_string(),
            what,
            recorded,
            replayed,
            others: Vec::new(),
        };
        match (r, v) {
            (Some(r), Some(v)) => {
                let ty = graph.leaf_index.get(path).map(|&l| &graph.leaves[l].ty);
                let equal = ty.and_then(|ty| value_from_json(r, ty).ok()).is_some_and(|rv| same(&rv, v));
                if !equal {
                    diffs.push(d("value", r.clone(), value_to_json(v)));
                }
            }
            (Some(r), None) => diffs.push(d("only_recorded", r.clone(), Json::Null)),
            (None, Some(v)) => diffs.push(d("only_replayed", Json::Null, value_to_json(v))),
            (None, None) => {}
        }
    }
    if !diffs.is_empty() {
        let differs = |leaf: usize| diffs.iter().any(|d| d.signal == graph.leaves[leaf].path);
        let reads_a_difference = |d: &Divergence| {
            let Some(&leaf) = graph.leaf_index.get(&d.signal) else { return false };
            graph.leaves[leaf]
                .writers
                .iter()
                .all(|&(w, _)| graph.instances[w].inputs.iter().any(|p| p.leaves.iter().any(|&l| differs(l))))
        };
        let at = diffs.iter().position(|d| !reads_a_difference(d)).unwrap_or(0);
        let others: Vec<String> =
            diffs.iter().enumerate().filter(|&(k, _)| k != at).map(|(_, d)| d.signal.clone()).collect();
        let mut first = diffs.swap_remove(at);
        first.others = others;
        return Some(first);
    }
    for &(l, i) in &frame.winners {
        let held = rec.holder(name(l), frame.cycle);
        if held != Some(skill(i)) {
            return Some(Divergence {
                cycle: frame.cycle,
                signal: name(l).to_string(),
                what: "winner",
                recorded: held.map_or(Json::Null, |s| json!(s)),
                replayed: json!(skill(i)),
                others: Vec::new(),
            });
        }
    }
    // The values agree but the fingerprint does not (a recording made by
    // another hash, or an FNV collision): name the cycle.
    Some(Divergence {
        cycle: frame.cycle,
        signal: String::new(),
        what: "value",
        recorded: json!(recorded.hash.map(crate::hash::hex)),
        replayed: json!(crate::hash::hex(hash)),
        others: Vec::new(),
    })
}

/// The recorded activation and parameter changes of the live skills, by the
/// cycle they took effect in, as requests to make before that cycle.
pub fn requests(rec: &Recording, live: &[String]) -> BTreeMap<u64, Vec<Request>> {
    let is_live = |s: &str| live.iter().any(|l| l == s);
    let names = |j: &Json, key: &str| -> Vec<String> {
        j.get(key)
            .and_then(Json::as_array)
            .map(|a| a.iter().filter_map(Json::as_str).filter(|s| is_live(s)).map(String::from).collect())
            .unwrap_or_default()
    };
    let mut out: BTreeMap<u64, Vec<Request>> = BTreeMap::new();
    for (kind, j) in &rec.events {
        let Some(cycle) = j.get("cycle").and_then(Json::as_u64) else { continue };
        match kind.as_str() {
            "activation_applied" => {
                let (on, off) = (names(j, "activated"), names(j, "deactivated"));
                if !on.is_empty() {
                    // A skill switched off and on again before a cycle is listed as activated
                    // only, and its body was told both (`Skill::deactivate`, then `activate`:
                    // it started afresh). The replay's robot is in the recorded state, so a
                    // skill listed as activated that is on there was switched off and on:
                    // deactivating first does that again (and is nothing for one that is off).
                    let requests = out.entry(cycle).or_default();
                    requests.push(Request::Deactivate { skills: on.clone() });
                    requests.push(Request::Activate { skills: on, with_providers: false });
                }
                if !off.is_empty() {
                    out.entry(cycle).or_default().push(Request::Deactivate { skills: off });
                }
            }
            "priority_changed" => {
                let skill = j.get("skill").and_then(Json::as_str).unwrap_or_default().to_string();
                let priority = j.get("priority").and_then(Json::as_i64).and_then(|p| i32::try_from(p).ok());
                // A player's priority is the recorded one too: it may win or
                // lose against a live skill.
                if let Some(priority) = priority {
                    out.entry(cycle).or_default().push(Request::SetPriority { skill, priority });
                }
            }
            "param_changed" => {
                let field = |k: &str| j.get(k).and_then(Json::as_str).unwrap_or_default().to_string();
                let skill = field("skill");
                if !is_live(&skill) {
                    continue;
                }
                let Some(value) = j.get("value").and_then(|v| param_from_json(v).ok()) else { continue };
                out.entry(cycle).or_default().push(Request::SetParam { skill, param: field("param"), value });
            }
            _ => {}
        }
    }
    out
}

/// Replays `rec` through `manager` (built with players for every skill not
/// in `live`, and its tape set): the recorded cycles from the first to the
/// last, the live skills' recorded changes applied before the cycle they
/// took effect in. `on_cycle` sees each replayed frame and its comparison.
/// A refused request (a parameter the changed skill no longer has) is a
/// difference the comparison will show; it does not stop the replay.
pub fn run(
    rec: &Recording,
    manager: &mut Manager,
    live: &[String],
    on_cycle: impl FnMut(&Frame, Option<&Divergence>),
) -> Outcome {
    run_window(rec, manager, live, 0, u64::MAX, on_cycle)
}

/// [`run`], compared from cycle `from` and stopped after cycle `to`. The
/// cycles before `from` run too: a skill's memory is not in the recording,
/// so the only exact way to a cycle is from the start (the delivery's 4,900
/// cycles replay in about 0.2 s). A recording that lacks cycles (dropped
/// while recording) is replayed up to the first one it lacks
/// ([`Outcome::stopped_before`]); the cycles it lacks are in the outcome.
pub fn run_window(
    rec: &Recording,
    manager: &mut Manager,
    live: &[String],
    from: u64,
    to: u64,
    mut on_cycle: impl FnMut(&Frame, Option<&Divergence>),
) -> Outcome {
    let tap = manager.tap(4);
    let mut changes = requests(rec, live);
    let mut outcome = Outcome { dropped: rec.dropped_count, dropped_ranges: rec.dropped.clone(), ..Outcome::default() };
    let Some((_, last)) = rec.span() else { return outcome };
    let mut last = last.min(to);
    if let Some(gap) = rec.first_dropped_from(0).filter(|&gap| gap <= to) {
        outcome.stopped_before = Some(gap);
        last = last.min(gap.saturating_sub(1));
    }
    while manager.cycle_count() < last {
        let next = manager.cycle_count() + 1;
        for request in changes.remove(&next).unwrap_or_default() {
            if let Err(e) = manager.request(request) {
                tracing::warn!("replay: cycle {next}: a recorded change was refused: {e}");
            }
        }
        manager.cycle();
        while let Ok(frame) = tap.frames.try_recv() {
            if frame.cycle < from {
                continue;
            }
            outcome.cycles += 1;
            let diff = compare(rec, manager.graph(), &frame);
            match &diff {
                None => outcome.matched += 1,
                Some(d) if outcome.first.is_none() => outcome.first = Some(d.clone()),
                Some(_) => {}
            }
            on_cycle(&frame, diff.as_ref());
        }
    }
    outcome
}
