//! Wiring: from skill declarations to the signal graph, with its static checks.
//!
//! Every port connects to a signal path (its own name unless remapped). A
//! record-typed port is flattened into its *leaves* (`pose` of type
//! `{x: f64, y: f64}` → `pose.x`, `pose.y`), and the whole graph is kept at
//! leaf level. That one rule gives the paper's partial match: a consumer of
//! the record `pose` is ready once every leaf has been written this cycle,
//! whether one producer wrote the whole record or two producers wrote a field
//! each. A leaf written by several skills is a *resource*; each cycle the
//! highest-priority writer wins.
//!
//! [`Graph::build`] runs every static check `situate check` reports.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use situate_core::{suggestion, RecordType, SignalType, SkillKind, SkillType, Value};

use crate::config::Section;
use crate::registry::Registry;
use crate::spec::{BuildError, Diagnostic, RobotSpec, Severity, SkillSpec};
use crate::yaml::Pos;

/// A port bound to its signal.
#[derive(Debug, Clone)]
pub struct PortBinding {
    pub name: String,
    pub signal: String,
    pub ty: SignalType,
    pub optional: bool,
    /// The leaf slots this port covers, in the flattened order of `ty`.
    pub leaves: Vec<usize>,
}

/// A skill instance as wired.
#[derive(Clone)]
pub struct InstanceDef {
    pub name: String,
    pub skill_type: SkillType,
    pub kind: SkillKind,
    pub priority: i32,
    pub params: Vec<Value>,
    pub inputs: Vec<PortBinding>,
    pub outputs: Vec<PortBinding>,
    pub active: bool,
    pub period_s: Option<f64>,
    /// How long one run of its body may take in the cycle (sync cskills;
    /// under the simulated clock every body runs in the cycle, see
    /// [`InstanceDef::in_cycle_deadline`]).
    pub budget: std::time::Duration,
    /// How long a threaded body (async cskill, dskill) may stay inside one run.
    pub liveness: std::time::Duration,
}

impl InstanceDef {
    /// The deadline of one run of the body on a cycle thread: the budget of a
    /// sync cskill, the liveness deadline of an async cskill or a dskill
    /// (which run in the cycle under the simulated clock).
    pub fn in_cycle_deadline(&self) -> std::time::Duration {
        if self.kind.is_threaded() {
            self.liveness
        } else {
            self.budget
        }
    }
}

/// The default execution budget of a sync cskill's run: twice the cycle
/// period, at least 200 ms (long enough that a loaded machine's scheduling
/// never faults a healthy body, short enough that a blocked one is caught
/// before a robot has moved far on its last command).
pub fn default_budget(period_s: f64) -> std::time::Duration {
    std::time::Duration::from_secs_f64((2.0 * period_s).clamp(0.2, 86_400.0))
}

/// The default liveness deadline of an async cskill or a dskill: ten of its
/// periods, at least 2 s.
pub fn default_liveness(period_s: f64) -> std::time::Duration {
    std::time::Duration::from_secs_f64((10.0 * period_s).clamp(2.0, 86_400.0))
}

/// A leaf signal: one slot of the cycle's data.
#[derive(Debug, Clone)]
pub struct Leaf {
    pub path: String,
    pub ty: SignalType,
    /// (instance, output port) pairs that write it, in declaration order.
    pub writers: Vec<(usize, usize)>,
    /// (instance, input port) pairs that read it.
    pub readers: Vec<(usize, usize)>,
}

impl Leaf {
    /// A leaf with several writing skills is a resource.
    pub fn is_resource(&self) -> bool {
        self.writers.len() > 1
    }
}

/// The wired robot.
#[derive(Clone)]
pub struct Graph {
    pub robot: String,
    pub instances: Vec<InstanceDef>,
    pub leaves: Vec<Leaf>,
    pub leaf_index: HashMap<String, usize>,
    /// Record paths (proper prefixes of leaf paths) with the type assembled
    /// from their leaves.
    pub records: BTreeMap<String, SignalType>,
    pub warnings: Vec<Diagnostic>,
    /// Instance names to their index (requests name skills, up to a list of
    /// 1024 at a time: no scan of every instance per name).
    instance_index: HashMap<String, usize>,
}

pub(crate) fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

pub(crate) fn is_signal_path(s: &str) -> bool {
    !s.is_empty() && s.split('.').all(is_identifier)
}

/// Appends the leaves of a value of type `ty` at `path`.
pub(crate) fn flatten(path: &str, ty: &SignalType, out: &mut Vec<(String, SignalType)>) {
    match ty {
        SignalType::Record(r) => {
            for (field, fty) in &r.fields {
                flatten(&format!("{path}.{field}"), fty, out);
            }
        }
        other => out.push((path.to_string(), other.clone())),
    }
}

/// Where each input and output port of an instance was configured.
type PortPositions = (Vec<Option<Pos>>, Vec<Option<Pos>>);

struct Checker<'a> {
    spec: &'a RobotSpec,
    diags: Vec<Diagnostic>,
}

impl Checker<'_> {
    fn error(&mut self, pos: Option<Pos>, message: String) {
        self.diags.push(self.spec.diag(Severity::Error, pos, message));
    }
    fn warning(&mut self, pos: Option<Pos>, message: String) {
        self.diags.push(self.spec.diag(Severity::Warning, pos, message));
    }

    /// The diagnostics of a failed build: errors in file order, then warnings.
    fn finish(mut self) -> BuildError {
        self.diags.sort_by_key(|d| d.pos.map_or((usize::MAX, usize::MAX, usize::MAX), |p| (p.src, p.line, p.col)));
        let (errors, warnings): (Vec<_>, Vec<_>) = self.diags.into_iter().partition(Diagnostic::is_error);
        BuildError { diagnostics: errors.into_iter().chain(warnings).collect() }
    }
}

fn item_pos(s: &SkillSpec) -> Option<Pos> {
    s.name_pos.or(s.pos)
}

impl Graph {
    /// Wires a robot and runs every static check. Warnings are kept in
    /// `warnings`; any error fails the build with all diagnostics found.
    pub fn build(spec: &RobotSpec, registry: &Registry) -> Result<Graph, BuildError> {
        let mut ck = Checker { spec, diags: Vec::new() };
        if !(spec.period_s.is_finite() && spec.period_s > 0.0 && spec.period_s <= 86_400.0) {
            ck.error(None, format!("cycle period must be > 0 s and at most a day, got {:?} s", spec.period_s));
        }
        for (key, ms) in [("budget_ms", spec.budget_ms), ("liveness_ms", spec.liveness_ms)] {
            if let Some(ms) = ms {
                if !(ms.is_finite() && ms > 0.0 && ms <= 86_400_000.0) {
                    ck.error(None, format!("cycle {key} must be > 0 and at most a day, got {ms:?}"));
                }
            }
        }

        // Instances: names, types, parameters, remaps.
        let mut instances: Vec<InstanceDef> = Vec::new();
        // Position of the remap (or the instance) for each port, for messages.
        let mut port_pos: Vec<PortPositions> = Vec::new();
        let mut specs: Vec<&SkillSpec> = Vec::new();
        // Duplicates are found in file order, so "first" means first in the file
        // whichever section comes first.
        let mut by_pos: Vec<usize> = (0..spec.skills.len()).collect();
        by_pos.sort_by_key(|&i| {
            item_pos(&spec.skills[i]).map_or((usize::MAX, usize::MAX, usize::MAX), |p| (p.src, p.line, p.col))
        });
        let mut duplicate = vec![false; spec.skills.len()];
        let mut seen: HashMap<&str, Option<Pos>> = HashMap::new();
        for &i in &by_pos {
            let s = &spec.skills[i];
            if let Some(first) = seen.get(s.name.as_str()) {
                let at = first
                    .map(|p| match spec.sources.get(p.src) {
                        Some(file) if item_pos(s).is_some_and(|q| q.src != p.src) => {
                            format!(" (first defined at {file}:{})", p.line)
                        }
                        _ => format!(" (first defined at line {})", p.line),
                    })
                    .unwrap_or_default();
                ck.error(item_pos(s), format!("duplicate skill name `{}`{at}", s.name));
                duplicate[i] = true;
            } else {
                seen.insert(&s.name, item_pos(s));
            }
        }
        // An entry left out (bad name, duplicate, unknown type) would make its
        // consumers' inputs look unprovided: one typo, many errors. Skip that check then.
        let mut incomplete = false;
        // A device listed under `skills:` (or a cskill under `devices:`) is
        // wired as the wrong kind: whatever the graph checks would say next
        // (an equal-priority conflict with the device it duplicates, …)
        // follows from that mistake, so it is reported alone.
        let mut misplaced = false;
        for (si, s) in spec.skills.iter().enumerate() {
            let noun = if s.section == Some(Section::Devices) { "device" } else { "skill" };
            if !is_identifier(&s.name) {
                ck.error(item_pos(s), format!("{noun} name `{}` is not an identifier (letters, digits, `_`)", s.name));
                incomplete = true;
                continue;
            }
            if duplicate[si] {
                incomplete = true;
                continue;
            }
            let Some(skill_type) = registry.get(&s.type_name) else {
                let msg = format!("{noun} `{}`: {}", s.name, registry.unknown(&s.type_name));
                ck.error(s.type_pos.or(item_pos(s)), msg);
                incomplete = true;
                continue;
            };
            let decl = &skill_type.decl;
            let wrong_section = match (s.section, decl.kind) {
                (Some(Section::Devices), SkillKind::Sync | SkillKind::Async) => Some(format!(
                    "device `{}`: `{}` is a computational skill (cskill); list it under `skills:`, not `devices:`",
                    s.name, decl.type_name
                )),
                (Some(Section::Skills), SkillKind::Device) => Some(format!(
                    "skill `{}`: `{}` is a device (dskill); list it under `devices:`, not `skills:`",
                    s.name, decl.type_name
                )),
                _ => None,
            };
            if let Some(message) = wrong_section {
                ck.error(s.type_pos.or(item_pos(s)), message);
                misplaced = true;
            }
            let mut params: Vec<Value> = decl.params.iter().map(|p| p.default.clone()).collect();
            for entry in &s.params {
                match decl.param(&entry.name) {
                    None => ck.error(
                        entry.name_pos.or(item_pos(s)),
                        format!(
                            "skill `{}`: unknown parameter `{}`{}",
                            s.name,
                            entry.name,
                            situate_core::param_suggestion(&entry.name, decl.params.iter().map(|p| p.name.as_str()))
                        ),
                    ),
                    Some((i, p)) => match p.check(&entry.value) {
                        Ok(v) => params[i] = v,
                        Err(mut e) => ck.error(entry.value_pos.or(item_pos(s)), {
                            // Quote the value as written: `1e300`, not its 301 digits.
                            if let Some(w) = &entry.written {
                                e.got.clone_from(w);
                            }
                            format!("skill `{}`: parameter `{}` {e}", s.name, entry.name)
                        }),
                    },
                }
            }
            let mut in_pos = vec![None; decl.inputs.len()];
            let mut out_pos = vec![None; decl.outputs.len()];
            let mut inputs: Vec<PortBinding> = decl
                .inputs
                .iter()
                .map(|p| PortBinding {
                    name: p.name.clone(),
                    signal: p.signal.clone(),
                    ty: p.ty.clone(),
                    optional: p.optional,
                    leaves: Vec::new(),
                })
                .collect();
            let mut outputs: Vec<PortBinding> = decl
                .outputs
                .iter()
                .map(|p| PortBinding {
                    name: p.name.clone(),
                    signal: p.signal.clone(),
                    ty: p.ty.clone(),
                    optional: false,
                    leaves: Vec::new(),
                })
                .collect();
            for r in &s.remap {
                if !is_signal_path(&r.signal) {
                    ck.error(
                        r.signal_pos.or(item_pos(s)),
                        format!(
                            "skill `{}`: remap target `{}` is not a signal name (identifiers joined by `.`)",
                            s.name, r.signal
                        ),
                    );
                    continue;
                }
                let mut found = false;
                for (i, p) in inputs.iter_mut().enumerate() {
                    if p.name == r.port {
                        p.signal = r.signal.clone();
                        in_pos[i] = r.signal_pos;
                        found = true;
                    }
                }
                for (i, p) in outputs.iter_mut().enumerate() {
                    if p.name == r.port {
                        p.signal = r.signal.clone();
                        out_pos[i] = r.signal_pos;
                        found = true;
                    }
                }
                if !found {
                    let ports = decl.inputs.iter().chain(&decl.outputs).map(|p| p.name.as_str());
                    ck.error(
                        r.port_pos.or(item_pos(s)),
                        format!("skill `{}`: remap of unknown port `{}`{}", s.name, r.port, suggestion(&r.port, ports)),
                    );
                }
            }
            for p in inputs.iter().chain(&outputs) {
                if !is_signal_path(&p.signal) {
                    ck.error(
                        item_pos(s),
                        format!(
                            "skill `{}`: port `{}` names signal `{}`, which is not a valid signal name",
                            s.name, p.name, p.signal
                        ),
                    );
                }
            }
            let period_s = s.period_ms.map(|ms| ms / 1000.0);
            if let Some(ms) = s.period_ms {
                if !(ms.is_finite() && ms > 0.0 && ms <= 86_400_000.0) {
                    ck.error(
                        item_pos(s),
                        format!("skill `{}`: period_ms must be > 0 and at most a day, got {ms:?}", s.name),
                    );
                }
            }
            for (key, ms) in [("budget_ms", s.budget_ms), ("liveness_ms", s.liveness_ms)] {
                if let Some(ms) = ms {
                    if !(ms.is_finite() && ms > 0.0 && ms <= 86_400_000.0) {
                        ck.error(
                            item_pos(s),
                            format!("skill `{}`: {key} must be > 0 and at most a day, got {ms:?}", s.name),
                        );
                    }
                }
            }
            let ms = |ms: Option<f64>| ms.filter(|ms| ms.is_finite() && *ms > 0.0 && *ms <= 86_400_000.0);
            let own_period = period_s.filter(|p| p.is_finite() && *p > 0.0).unwrap_or(spec.period_s);
            let budget = ms(s.budget_ms)
                .or(ms(spec.budget_ms))
                .map(|ms| std::time::Duration::from_secs_f64(ms / 1e3))
                .unwrap_or_else(|| default_budget(spec.period_s));
            let liveness = ms(s.liveness_ms)
                .or(ms(spec.liveness_ms))
                .map(|ms| std::time::Duration::from_secs_f64(ms / 1e3))
                .unwrap_or_else(|| default_liveness(own_period));
            let fallback = item_pos(s);
            port_pos.push((
                in_pos.into_iter().map(|p| p.or(fallback)).collect(),
                out_pos.into_iter().map(|p| p.or(fallback)).collect(),
            ));
            specs.push(s);
            instances.push(InstanceDef {
                name: s.name.clone(),
                kind: decl.kind,
                priority: s.priority.unwrap_or(decl.priority),
                skill_type: skill_type.clone(),
                params,
                inputs,
                outputs,
                active: s.active,
                period_s,
                budget,
                liveness,
            });
        }

        if misplaced {
            return Err(ck.finish());
        }

        // Leaves: every port flattened; first the outputs (so a leaf's type is
        // its first writer's), then the inputs.
        let mut leaves: Vec<Leaf> = Vec::new();
        let mut leaf_index: HashMap<String, usize> = HashMap::new();
        let mut flat = Vec::new();
        for pass in 0..2 {
            for (ii, inst) in instances.iter_mut().enumerate() {
                let ports = if pass == 0 { &mut inst.outputs } else { &mut inst.inputs };
                for (pi, port) in ports.iter_mut().enumerate() {
                    flat.clear();
                    flatten(&port.signal, &port.ty, &mut flat);
                    for (path, ty) in flat.drain(..) {
                        let li = *leaf_index.entry(path.clone()).or_insert_with(|| {
                            leaves.push(Leaf { path, ty, writers: Vec::new(), readers: Vec::new() });
                            leaves.len() - 1
                        });
                        if pass == 0 {
                            leaves[li].writers.push((ii, pi));
                        } else {
                            leaves[li].readers.push((ii, pi));
                        }
                        port.leaves.push(li);
                    }
                }
            }
        }
        let port_ref = |ii: usize, pi: usize, output: bool| -> (String, Option<Pos>, SignalType) {
            let inst = &instances[ii];
            let (p, pos) =
                if output { (&inst.outputs[pi], port_pos[ii].1[pi]) } else { (&inst.inputs[pi], port_pos[ii].0[pi]) };
            let dir = if output { "output" } else { "input" };
            (format!("`{}` ({dir} `{}`)", inst.name, p.name), pos, p.ty.clone())
        };

        // A path must not be both a value and a record.
        let mut paths: Vec<&str> = leaves.iter().map(|l| l.path.as_str()).collect();
        paths.sort_unstable();
        for w in paths.windows(2) {
            if w[1].starts_with(w[0]) && w[1].as_bytes().get(w[0].len()) == Some(&b'.') {
                let user = |leaf: &Leaf| {
                    let (i, p, out) = match (leaf.writers.first(), leaf.readers.first()) {
                        (Some(&(i, p)), _) => (i, p, true),
                        (None, Some(&(i, p))) => (i, p, false),
                        (None, None) => return (String::new(), None),
                    };
                    let (text, pos, _) = port_ref(i, p, out);
                    (text, pos)
                };
                let (ai, ap) = user(&leaves[leaf_index[w[0]]]);
                let (bi, _) = user(&leaves[leaf_index[w[1]]]);
                ck.error(
                    ap,
                    format!(
                        "signal `{}` is used both as a value, by {ai}, and as a record with field `{}`, by {bi}",
                        w[0],
                        &w[1][w[0].len() + 1..]
                    ),
                );
            }
        }

        let mut reported_conflicts = std::collections::HashSet::new();
        for leaf in &leaves {
            // Writers agree on the type; every writer feeds every reader.
            if let Some(&(w0, p0)) = leaf.writers.first() {
                let first_ty = leaf_ty(&instances[w0].outputs[p0], &leaf.path);
                for &(wi, pi) in &leaf.writers[1..] {
                    let ty = leaf_ty(&instances[wi].outputs[pi], &leaf.path);
                    if ty != first_ty {
                        let (a, _, _) = port_ref(w0, p0, true);
                        let (b, pos, _) = port_ref(wi, pi, true);
                        ck.error(
                            pos,
                            format!("type mismatch on signal `{}`: {a} writes {first_ty}, {b} writes {ty}", leaf.path),
                        );
                    }
                }
                for &(ri, pi) in &leaf.readers {
                    let want = leaf_ty(&instances[ri].inputs[pi], &leaf.path);
                    if !first_ty.feeds(&want) {
                        let (a, _, _) = port_ref(w0, p0, true);
                        let (b, pos, _) = port_ref(ri, pi, false);
                        ck.error(
                            pos,
                            format!(
                                "type mismatch on signal `{}`: {a} produces {first_ty}, {b} expects {want}",
                                leaf.path
                            ),
                        );
                    }
                }
            }
            // Equal-priority writers of one resource cannot be arbitrated: one
            // error per resource and priority, naming every such writer (not
            // one per pair: n writers would make n² errors). Name the resource
            // as the last writer's port does (`drive`, not `drive.v`).
            let mut by_priority: BTreeMap<i32, Vec<(usize, usize)>> = BTreeMap::new();
            for &(w, p) in &leaf.writers {
                let group = by_priority.entry(instances[w].priority).or_default();
                // One instance's ports on a leaf are adjacent.
                if group.last().is_none_or(|&(i, _)| i != w) {
                    group.push((w, p));
                }
            }
            for (priority, group) in by_priority {
                let Some(&(last, last_port)) = group.last().filter(|_| group.len() > 1) else { continue };
                let resource = instances[last].outputs[last_port].signal.clone();
                if !reported_conflicts.insert((resource.clone(), priority)) {
                    continue;
                }
                let pos = group.iter().rev().find_map(|&(i, _)| specs[i].priority_pos).or(item_pos(specs[last]));
                let names: Vec<&str> = group.iter().map(|&(i, _)| instances[i].name.as_str()).collect();
                let both = if names.len() == 2 { "both" } else { "all" };
                if group.iter().all(|&(i, _)| instances[i].kind == SkillKind::Device) {
                    // Two devices on one signal is most often a copy without a remap.
                    let (name, port) = (&instances[last].name, &instances[last].outputs[last_port].name);
                    ck.error(
                        item_pos(specs[last]),
                        format!(
                            "devices {} {both} write signal `{resource}` with priority {priority}; give each its \
                             own signal (e.g. `remap: {{{port}: {name}.{port}}}` on `{name}`) or different priorities",
                            and_list(&names)
                        ),
                    );
                    continue;
                }
                ck.error(
                    pos,
                    format!(
                        "skills {} {both} write resource `{resource}` with priority {priority}; give them different priorities",
                        and_list(&names)
                    ),
                );
            }
        }

        // Inputs nobody can provide: one message per port.
        if !incomplete {
            for (ii, inst) in instances.iter().enumerate() {
                for (pi, port) in inst.inputs.iter().enumerate() {
                    let missing: Vec<&str> = port
                        .leaves
                        .iter()
                        .filter(|&&l| leaves[l].writers.is_empty())
                        .map(|&l| leaves[l].path.as_str())
                        .collect();
                    if missing.is_empty() {
                        continue;
                    }
                    let dir = if port.optional { "optional input" } else { "input" };
                    let what = if missing.len() == port.leaves.len() { port.signal.as_str() } else { missing[0] };
                    let provided = leaves.iter().filter(|l| !l.writers.is_empty()).map(|l| l.path.as_str());
                    let near = suggestion(what, provided);
                    let fields = if missing.len() == port.leaves.len() || missing.len() == 1 {
                        String::new()
                    } else {
                        format!(" (nor {})", quote_list(&missing[1..]))
                    };
                    let msg = format!(
                        "`{}` ({dir} `{}`) reads signal `{what}`{fields}, which no skill or device provides{near}",
                        inst.name, port.name
                    );
                    let pos = port_pos[ii].0[pi];
                    if port.optional {
                        ck.warning(pos, msg);
                    } else {
                        ck.error(pos, msg);
                    }
                }
            }
        }

        // Data-flow loops among cskills: each strongly connected group of
        // skills that wait for one another in the same cycle.
        for group in loops(&instances, &leaves) {
            let names: Vec<&str> = group.iter().map(|&i| instances[i].name.as_str()).collect();
            let first = group.iter().filter_map(|&i| item_pos(specs[i])).min();
            let msg = if names.len() == 1 {
                format!("data-flow loop: skill `{}` reads its own output in the same cycle", names[0])
            } else {
                format!(
                    "data-flow loop among skills {}: each waits for another's output in the same cycle",
                    quote_list_capped(&names)
                )
            };
            ck.error(first, msg);
        }

        let mut records = BTreeMap::new();
        for leaf in &leaves {
            let mut path = leaf.path.as_str();
            while let Some(dot) = path.rfind('.') {
                path = &path[..dot];
                records.entry(path.to_string()).or_insert(SignalType::Bool);
            }
        }
        let record_names: Vec<String> = records.keys().cloned().collect();
        for name in record_names {
            let ty = record_type_at(&name, &leaves);
            records.insert(name, ty);
        }

        let warnings = match ck.diags.iter().any(Diagnostic::is_error) {
            true => return Err(ck.finish()),
            false => ck.diags,
        };
        let instance_index = instances.iter().enumerate().map(|(i, d)| (d.name.clone(), i)).collect();
        Ok(Graph { robot: spec.robot.clone(), instances, leaves, leaf_index, records, warnings, instance_index })
    }

    /// The type at a signal path: a leaf's, or a record's assembled from its leaves.
    pub fn signal_type(&self, path: &str) -> Option<SignalType> {
        self.leaf_index.get(path).map(|&i| self.leaves[i].ty.clone()).or_else(|| self.records.get(path).cloned())
    }

    /// The leaves under a path (one for a leaf, all fields' for a record).
    pub fn leaves_under(&self, path: &str) -> Vec<usize> {
        if let Some(&i) = self.leaf_index.get(path) {
            return vec![i];
        }
        match self.records.get(path) {
            Some(ty) => {
                let mut flat = Vec::new();
                flatten(path, ty, &mut flat);
                flat.iter().filter_map(|(p, _)| self.leaf_index.get(p).copied()).collect()
            }
            None => Vec::new(),
        }
    }

    pub fn instance(&self, name: &str) -> Option<usize> {
        self.instance_index.get(name).copied()
    }

    /// All signal names, leaves and records, for suggestions.
    pub fn signal_names(&self) -> impl Iterator<Item = &str> {
        self.leaves.iter().map(|l| l.path.as_str()).chain(self.records.keys().map(String::as_str))
    }
}

fn leaf_ty(port: &PortBinding, leaf_path: &str) -> SignalType {
    let mut flat = Vec::new();
    flatten(&port.signal, &port.ty, &mut flat);
    flat.into_iter().find(|(p, _)| p == leaf_path).map(|(_, t)| t).unwrap_or(SignalType::Bool)
}

fn record_type_at(path: &str, leaves: &[Leaf]) -> SignalType {
    // Fields in order of first appearance among the leaves.
    let prefix = format!("{path}.");
    let mut fields: Vec<(String, SignalType)> = Vec::new();
    for leaf in leaves {
        if let Some(rest) = leaf.path.strip_prefix(&prefix) {
            let field = rest.split('.').next().unwrap_or(rest);
            if fields.iter().any(|(f, _)| f == field) {
                continue;
            }
            let ty =
                if rest.contains('.') { record_type_at(&format!("{prefix}{field}"), leaves) } else { leaf.ty.clone() };
            fields.push((field.to_string(), ty));
        }
    }
    SignalType::Record(Arc::new(RecordType::new(fields)))
}

pub(crate) fn quote_list(names: &[&str]) -> String {
    names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
}

/// How many names a message lists before "and N more".
const LISTED_NAMES: usize = 10;

/// `a`, `b`, … and N more: at most [`LISTED_NAMES`] names.
fn quote_list_capped(names: &[&str]) -> String {
    match names.len() {
        n if n > LISTED_NAMES => format!("{} and {} more", quote_list(&names[..LISTED_NAMES]), n - LISTED_NAMES),
        _ => quote_list(names),
    }
}

/// `a` and `b`; `a`, `b` and `c`; `a`, …, `j` and N more.
fn and_list(names: &[&str]) -> String {
    match names {
        [] => String::new(),
        [one] => format!("`{one}`"),
        _ if names.len() > LISTED_NAMES => quote_list_capped(names),
        [init @ .., last] => format!("{} and `{last}`", quote_list(init)),
    }
}

/// The data-flow loops among cskills (Tarjan's strongly connected
/// components): groups of two or more, or one skill reading its own output.
fn loops(instances: &[InstanceDef], leaves: &[Leaf]) -> Vec<Vec<usize>> {
    let n = instances.len();
    let node = |i: usize| instances[i].kind != SkillKind::Device;
    let mut succ: Vec<Vec<usize>> = vec![Vec::new(); n];
    for leaf in leaves {
        for &(w, _) in &leaf.writers {
            for &(r, _) in &leaf.readers {
                if node(w) && node(r) && !succ[w].contains(&r) {
                    succ[w].push(r);
                }
            }
        }
    }
    struct Tarjan<'a> {
        succ: &'a [Vec<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        groups: Vec<Vec<usize>>,
    }
    impl Tarjan<'_> {
        fn visit(&mut self, v: usize) {
            self.index[v] = Some(self.next);
            self.low[v] = self.next;
            self.next += 1;
            self.stack.push(v);
            self.on_stack[v] = true;
            for k in 0..self.succ[v].len() {
                let w = self.succ[v][k];
                match self.index[w] {
                    None => {
                        self.visit(w);
                        self.low[v] = self.low[v].min(self.low[w]);
                    }
                    Some(iw) if self.on_stack[w] => self.low[v] = self.low[v].min(iw),
                    Some(_) => {}
                }
            }
            if Some(self.low[v]) == self.index[v] {
                let mut group = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack[w] = false;
                    group.push(w);
                    if w == v {
                        break;
                    }
                }
                if group.len() > 1 || self.succ[v].contains(&v) {
                    group.sort_unstable();
                    self.groups.push(group);
                }
            }
        }
    }
    let mut t = Tarjan {
        succ: &succ,
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        groups: Vec::new(),
    };
    for v in 0..n {
        if node(v) && t.index[v].is_none() {
            t.visit(v);
        }
    }
    t.groups.sort();
    t.groups
}

/// Kahn's algorithm over the cskills selected by `include`: producers before
/// consumers, ties in declaration order. dskills are left out: their
/// readings are taken before the data flow and their commands after it.
/// Returns the instances in order; any left out (besides dskills) sit on a loop.
pub(crate) fn topo_order(instances: &[InstanceDef], leaves: &[Leaf], include: impl Fn(usize) -> bool) -> Vec<usize> {
    let n = instances.len();
    let node = |i: usize| instances[i].kind != SkillKind::Device && include(i);
    let mut indegree = vec![0usize; n];
    let mut succ: Vec<Vec<usize>> = vec![Vec::new(); n];
    for leaf in leaves {
        for &(w, _) in &leaf.writers {
            if !node(w) {
                continue;
            }
            for &(r, _) in &leaf.readers {
                if node(r) && !succ[w].contains(&r) {
                    succ[w].push(r);
                    indegree[r] += 1;
                }
            }
        }
    }
    let mut ready: std::collections::BTreeSet<usize> = (0..n).filter(|&i| node(i) && indegree[i] == 0).collect();
    let mut order = Vec::new();
    while let Some(i) = ready.pop_first() {
        order.push(i);
        for &s in &succ[i] {
            indegree[s] -= 1;
            if indegree[s] == 0 {
                ready.insert(s);
            }
        }
    }
    order
}
