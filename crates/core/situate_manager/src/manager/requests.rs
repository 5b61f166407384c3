//! The manager's control API (paper 3.2.2): the requests a sequencer, the
//! link or the GUI sends between cycles — activation, parameters, queries,
//! monitors, run/stop/step — and the resolver that turns names in monitor
//! conditions into the manager's signals and parameters.

use super::slots::assemble;
use super::*;

impl Manager {
    pub(super) fn find(&self, name: &str) -> Result<usize, ControlError> {
        front::find(&self.graph, name)
    }

    pub(super) fn find_param(&self, skill: &str, param: &str) -> Result<(usize, usize), ControlError> {
        front::find_param(&self.graph, skill, param)
    }

    /// Required inputs of cskill `i` that no skill in `active` writes.
    pub(super) fn missing_inputs(&self, i: usize, active: &[bool]) -> Vec<usize> {
        let def = &self.graph.instances[i];
        if def.kind == SkillKind::Device {
            return Vec::new();
        }
        def.inputs
            .iter()
            .filter(|p| !p.optional)
            .flat_map(|p| p.leaves.iter().copied())
            .filter(|&l| !self.graph.leaves[l].writers.iter().any(|&(w, _)| active[w]))
            .collect()
    }

    pub(super) fn activate(&mut self, names: &[String], with_providers: bool) -> Result<Reply, ControlError> {
        let mut wanted = Vec::new();
        for n in names {
            wanted.push(self.find(n)?);
        }
        let mut active: Vec<bool> = self.insts.iter().map(|s| s.active).collect();
        for &i in &wanted {
            active[i] = true;
        }
        let mut queue: Vec<usize> = wanted.clone();
        while let Some(i) = queue.pop() {
            let missing = self.missing_inputs(i, &active);
            if missing.is_empty() {
                continue;
            }
            let providers: Vec<usize> = missing
                .iter()
                .filter_map(|&l| {
                    // The best writer: highest priority, then declaration order.
                    self.graph.leaves[l].writers.iter().map(|&(w, _)| w).max_by_key(|&w| self.rank(w))
                })
                .collect();
            if !with_providers || providers.len() < missing.len() {
                let mut signals: Vec<String> = missing.iter().map(|&l| self.graph.leaves[l].path.clone()).collect();
                signals.dedup();
                let mut provider_names: Vec<String> =
                    providers.iter().map(|&w| self.graph.instances[w].name.clone()).collect();
                provider_names.sort();
                provider_names.dedup();
                return Err(ControlError::MissingProviders {
                    skill: self.graph.instances[i].name.clone(),
                    signals,
                    providers: provider_names,
                });
            }
            for w in providers {
                if !active[w] {
                    active[w] = true;
                    queue.push(w);
                }
            }
        }
        // A body left behind that has not returned holds a thread (and perhaps a core): a fresh
        // one beside it would take another, and each reactivation one more.
        if let Some(i) = (0..active.len()).find(|&i| active[i] && !self.insts[i].active && self.still_running(i)) {
            return Err(ControlError::Invalid(format!(
                "cannot activate `{}`: its last body was left behind past its deadline and is still \
                 running (it holds a thread and perhaps a core); a fresh one is made once it returns \
                 (a body that never returns holds its thread until the program ends)",
                self.graph.instances[i].name
            )));
        }
        let mut changed = Vec::new();
        for (i, &on) in active.iter().enumerate() {
            if on && !self.insts[i].active {
                self.set_active(i, true);
                changed.push(self.graph.instances[i].name.clone());
            }
        }
        Ok(Reply::Activation { changed, at_cycle: self.cycle + 1 })
    }

    pub(super) fn deactivate(&mut self, names: &[String]) -> Result<Reply, ControlError> {
        let mut targets = Vec::new();
        for n in names {
            targets.push(self.find(n)?);
        }
        let mut changed = Vec::new();
        for i in targets {
            if self.insts[i].active {
                self.set_active(i, false);
                changed.push(self.graph.instances[i].name.clone());
            }
        }
        Ok(Reply::Activation { changed, at_cycle: self.cycle + 1 })
    }

    pub(super) fn set_param(&mut self, skill: &str, param: &str, value: &Value) -> Result<Reply, ControlError> {
        let (i, p) = self.find_param(skill, param)?;
        let spec = &self.graph.instances[i].skill_type.decl.params[p];
        let value = spec.check(value).map_err(|e| ControlError::BadParam {
            skill: skill.into(),
            param: param.into(),
            reason: e.to_string(),
        })?;
        self.insts[i].params[p] = value.clone();
        self.insts[i].params_from = self.cycle + 1;
        match (self.insts[i].worker.as_ref(), self.execs[i].skill.as_mut()) {
            (_, Some(body)) => {
                // The skill's own code, on the cycle's thread: a panic faults the skill.
                let set = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| body.set_param(p, &value)));
                if let Err(panic) = set {
                    let cause =
                        format!("panicked in set_param (`{param}`): {}", crate::supervise::panic_message(&*panic));
                    // Its state is unknown: activating it again makes a fresh body.
                    self.insts[i].abandoned = true;
                    self.fault(i, cause);
                }
            }
            (Some(worker), None) => {
                worker.shared.lock().params.push((p, value.clone()));
                worker.shared.notify();
            }
            (None, None) => {}
        }
        self.bus.send(Event::ParamChanged { skill: skill.into(), param: param.into(), value, cycle: self.cycle + 1 });
        Ok(Reply::Done)
    }

    pub(super) fn query_signal(&self, path: &str) -> Result<SignalReading, ControlError> {
        let ty = self.graph.signal_type(path).ok_or_else(|| front::unknown_signal(&self.graph, path))?;
        let leaves = self.graph.leaves_under(path);
        let complete = leaves.iter().all(|&l| self.slots[l].value.is_some());
        let value = if complete {
            assemble(&ty, &mut leaves.iter().filter_map(|&l| self.slots[l].value.as_ref()))
        } else {
            None
        };
        let cycle = leaves.iter().map(|&l| self.slots[l].stamp).min().unwrap_or(0);
        let writer = leaves
            .first()
            .map(|&l| &self.slots[l])
            .filter(|s| s.stamp > 0)
            .map(|s| self.graph.instances[s.writer as usize].name.clone());
        Ok(SignalReading { signal: path.into(), ty, value, cycle, writer })
    }

    /// The prints a switched-off threaded skill made since its last exchange (its `deactivate`
    /// runs on its own thread after the cycle stopped looking at it): taken when it is asked
    /// about, so what `deactivate` said is seen while the skill is off.
    fn take_idle_prints(&mut self, i: usize) {
        if self.insts[i].active {
            return;
        }
        let Some(worker) = self.insts[i].worker.as_ref() else { return };
        let prints = std::mem::take(&mut worker.shared.lock().prints);
        if !prints.is_empty() {
            self.record_prints(i, prints);
        }
    }

    pub(super) fn skill_info(&self, i: usize) -> SkillInfo {
        let def = &self.graph.instances[i];
        let inst = &self.insts[i];
        let decl = &def.skill_type.decl;
        let port = |p: &crate::graph::PortBinding, value: Option<Value>| PortInfo {
            name: p.name.clone(),
            signal: p.signal.clone(),
            ty: p.ty.clone(),
            optional: p.optional,
            value,
        };
        SkillInfo {
            name: def.name.clone(),
            type_name: decl.type_name.clone(),
            kind: def.kind,
            doc: decl.doc.clone(),
            active: inst.active,
            faulted: inst.faulted.clone(),
            verbose: inst.verbose,
            priority: inst.priority,
            params: decl.params.iter().cloned().zip(inst.params.iter().cloned()).collect(),
            inputs: def
                .inputs
                .iter()
                .zip(&self.execs[i].inputs)
                .map(|(p, v)| port(p, v.clone().or_else(|| self.lent_input(i, p))))
                .collect(),
            outputs: def.outputs.iter().enumerate().map(|(k, p)| port(p, self.last_output(i, k))).collect(),
            timing: {
                let mut timing = inst.timing;
                timing.add_untimed(self.execs[i].untimed_runs, self.execs[i].untimed_ns);
                timing
            },
            prints: inst.prints.iter().cloned().collect(),
        }
    }

    pub(super) fn resource_winners(&self) -> Vec<ResourceWinner> {
        self.graph
            .leaves
            .iter()
            .enumerate()
            .filter(|(_, l)| l.is_resource())
            .map(|(li, l)| {
                let slot = &self.slots[li];
                let tally = self.tallies.iter().find(|t| t.leaf == li).copied().unwrap_or_default();
                let mut writers: Vec<String> =
                    l.writers.iter().map(|&(w, _)| self.graph.instances[w].name.clone()).collect();
                writers.dedup();
                ResourceWinner {
                    signal: l.path.clone(),
                    writers,
                    winner: (slot.stamp == self.cycle && slot.stamp > 0)
                        .then(|| self.graph.instances[slot.writer as usize].name.clone()),
                    cycle: slot.stamp,
                    switches: tally.switches,
                    held_cycles: tally.held,
                }
            })
            .collect()
    }

    pub(super) fn graph_info(&self) -> GraphInfo {
        let g = &self.graph;
        GraphInfo {
            skills: g
                .instances
                .iter()
                .enumerate()
                .map(|(i, d)| crate::control::GraphSkill {
                    name: d.name.clone(),
                    kind: d.kind,
                    active: self.insts[i].active,
                    priority: self.insts[i].priority,
                    inputs: d.inputs.iter().map(|p| p.signal.clone()).collect(),
                    outputs: d.outputs.iter().map(|p| p.signal.clone()).collect(),
                })
                .collect(),
            signals: g
                .leaves
                .iter()
                .map(|l| crate::control::GraphSignal {
                    signal: l.path.clone(),
                    ty: l.ty.clone(),
                    writers: l.writers.iter().map(|&(w, _)| g.instances[w].name.clone()).collect(),
                    readers: l.readers.iter().map(|&(r, _)| g.instances[r].name.clone()).collect(),
                })
                .collect(),
        }
    }

    pub(super) fn current_stats(&self) -> ManagerStats {
        ManagerStats {
            robot: self.graph.robot.clone(),
            cycle: self.cycle,
            time_s: self.time_s,
            running: self.running,
            period_s: self.period_s,
            last_cycle_ns: self.cycle_timing.last_ns,
            mean_cycle_ns: self.cycle_timing.mean_timed_ns(),
            max_cycle_ns: self.cycle_timing.max_ns,
            overruns: self.overruns,
            late_starts: self.late_starts,
            request_hold_ns: self.request_hold_ns,
            lost_ns: self.lost_ns,
            worker_failures: self.bus.worker_failures.load(std::sync::atomic::Ordering::Relaxed),
            rate_hz: match (self.running, self.interval_s) {
                (true, Some(dt)) if dt > 0.0 => 1.0 / dt,
                _ => 0.0,
            },
            active: self
                .insts
                .iter()
                .enumerate()
                .filter(|(_, s)| s.active)
                .map(|(i, _)| self.graph.instances[i].name.clone())
                .collect(),
        }
    }

    /// Installs a monitor compiled by [`front::prepare_monitor`] (on the
    /// caller's thread when it came through a handle), within the caps: the
    /// robot's and the session's.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn install_monitor(
        &mut self,
        prepared: PreparedMonitor,
        mode: crate::monitor::MonitorMode,
        pause: bool,
        report_asked: Vec<String>,
        session: Option<String>,
        client: Option<String>,
    ) -> Result<Reply, ControlError> {
        let PreparedMonitor { mut conditions, any, targets, reported } = prepared;
        let adding = conditions.len();
        let watched = self.monitors.condition_count();
        if watched + adding > MAX_MONITORS {
            // Every condition may be evaluated every cycle: their number bounds the cycle's cost.
            let adds = if any { format!("this one's {adding} would be") } else { "one more is".to_string() };
            return Err(ControlError::Invalid(format!(
                "monitor_add: this robot has {} monitors watching {watched} conditions; {adds} past \
                 the most it keeps ({MAX_MONITORS}); cancel some first",
                self.monitors.list.len()
            )));
        }
        let (mine, mine_watched) = self.monitors.count_of(session.as_deref());
        if mine_watched + adding > MAX_MONITORS_PER_SESSION {
            let who = match (&session, &client) {
                (Some(s), Some(c)) => format!("session `{}` (client `{c}`) has", short_session(s)),
                (Some(s), None) => format!("session `{}` has", short_session(s)),
                (None, _) => "the program's own requests have".to_string(),
            };
            let adds = if any { format!("this one's {adding} would be") } else { "one more is".to_string() };
            return Err(ControlError::Invalid(format!(
                "monitor_add: {who} {mine} monitors watching {mine_watched} conditions; {adds} past \
                 the most one session keeps ({MAX_MONITORS_PER_SESSION}); cancel some first"
            )));
        }
        // The compiled references become the manager's own.
        let ids: Vec<usize> = targets.into_iter().map(|t| self.intern(t)).collect();
        let global = |r: usize| ids.get(r).copied().unwrap_or(r);
        for c in &mut conditions {
            c.remap_refs(global);
        }
        let reported = reported.into_iter().map(|(name, r)| (name, global(r))).collect();
        Ok(Reply::MonitorAdded(self.monitors.add(
            conditions,
            any,
            mode,
            pause,
            reported,
            report_asked,
            session,
            client,
        )))
    }

    /// Cancels monitor `id` for `session` (its owner), or for anyone when `force`d.
    fn cancel_monitor(&mut self, id: u64, session: Option<String>, force: bool) -> Result<Reply, ControlError> {
        let owner = self.monitors.get(id).ok_or(ControlError::UnknownMonitor(id))?.session.clone();
        let reason = if owner == session {
            CancelReason::Owner
        } else if force {
            CancelReason::Forced
        } else {
            let whose = match &owner {
                Some(s) => format!("session `{}`", short_session(s)),
                None => "the program running the robot".to_string(),
            };
            return Err(ControlError::NotOwner(format!(
                "monitor_cancel: monitor {id} belongs to {whose}; only its session cancels it"
            )));
        };
        if let Some(m) = self.monitors.cancel(id) {
            self.monitor_cancelled(m, reason);
        }
        Ok(Reply::Done)
    }

    fn monitor_cancelled(&mut self, m: crate::monitor::Monitor, reason: CancelReason) {
        self.bus.send(Event::MonitorCancelled {
            monitor: m.id,
            condition: m.source,
            session: m.session,
            reason,
            cycle: self.cycle,
        });
    }

    /// The manager's id for a name a condition reads.
    fn intern(&mut self, target: RefTarget) -> usize {
        if let Some(i) = self.refs.iter().position(|t| *t == target) {
            return i;
        }
        self.refs.push(target);
        self.refs.len() - 1
    }

    /// Handles a request some of whose work was done on the sender's thread
    /// (see `front`): an `AddMonitor` comes with its conditions compiled.
    pub(crate) fn request_prepared(
        &mut self,
        request: Request,
        monitor: Option<PreparedMonitorBox>,
    ) -> Result<Reply, ControlError> {
        match (request, monitor) {
            (Request::AddMonitor { mode, pause, report, session, client, .. }, Some(prepared)) => {
                self.install_monitor(*prepared, mode, pause, report, session, client)
            }
            (request, _) => self.request(request),
        }
    }

    /// Handles one request between two cycles.
    pub fn request(&mut self, request: Request) -> Result<Reply, ControlError> {
        match request {
            Request::Activate { skills, with_providers } => self.activate(&skills, with_providers),
            Request::Deactivate { skills } => self.deactivate(&skills),
            Request::SetParam { skill, param, value } => self.set_param(&skill, &param, &value),
            Request::GetParam { skill, param } => {
                let (i, p) = self.find_param(&skill, &param)?;
                Ok(Reply::Param(self.insts[i].params[p].clone()))
            }
            Request::SetPriority { skill, priority } => {
                let i = self.find(&skill)?;
                self.insts[i].priority = priority;
                // The plan holds each step's rank.
                self.schedule_dirty = true;
                self.bus.send(Event::PriorityChanged { skill, priority, cycle: self.cycle + 1 });
                Ok(Reply::Done)
            }
            Request::SetVerbose { skill, verbose } => {
                let i = self.find(&skill)?;
                self.insts[i].verbose = verbose;
                Ok(Reply::Done)
            }
            Request::Phase { text, client } => {
                super::front::check_phase(&text)?;
                self.bus.send(Event::Phase { text, client, cycle: self.cycle + 1 });
                Ok(Reply::Done)
            }
            Request::QuerySignal { signal } => self.query_signal(&signal).map(Reply::Signal),
            Request::QuerySignals { signals } => {
                signals.iter().map(|s| self.query_signal(s)).collect::<Result<_, _>>().map(Reply::Signals)
            }
            Request::QuerySkill { skill } => {
                let i = self.find(&skill)?;
                self.take_idle_prints(i);
                Ok(Reply::Skill(Box::new(self.skill_info(i))))
            }
            Request::QuerySkills => {
                for i in 0..self.insts.len() {
                    self.take_idle_prints(i);
                }
                Ok(Reply::Skills((0..self.insts.len()).map(|i| self.skill_info(i)).collect()))
            }
            Request::QueryWinners => Ok(Reply::Winners(self.resource_winners())),
            Request::QueryGraph => Ok(Reply::Graph(self.graph_info())),
            Request::QueryStats => Ok(Reply::Stats(self.current_stats())),
            Request::AddMonitor { condition, mode, pause, report, session, client } => {
                let prepared = front::prepare_monitor(&self.graph, &condition, &report)?;
                self.install_monitor(prepared, mode, pause, report, session, client)
            }
            Request::CancelMonitor { monitor, session, force } => self.cancel_monitor(monitor, session, force),
            Request::EndSession { session } => {
                let gone = self.monitors.end_session(&session);
                let ids = gone.iter().map(|m| m.id).collect();
                for m in gone {
                    self.monitor_cancelled(m, CancelReason::SessionEnded);
                }
                Ok(Reply::MonitorsCancelled(ids))
            }
            Request::ListMonitors => Ok(Reply::Monitors(
                self.monitors
                    .list
                    .iter()
                    .map(|m| MonitorInfo {
                        monitor: m.id,
                        condition: m.source.clone(),
                        any: m.any.then(|| m.conditions.iter().map(|c| c.source().to_string()).collect()),
                        mode: m.mode,
                        fired: m.fired,
                        holds: m.holds,
                        pause: m.pause,
                        report: m.report_asked.clone(),
                        session: m.session.clone(),
                        client: m.client.clone(),
                    })
                    .collect(),
            )),
            Request::Run => {
                if !self.running {
                    self.running = true;
                    // The achieved rate is measured from here: a pause is not a slow cycle.
                    self.last_start = None;
                    self.interval_s = None;
                    self.bus.send(Event::ManagerStarted { cycle: self.cycle });
                }
                Ok(Reply::Done)
            }
            Request::Stop => {
                if self.running {
                    self.running = false;
                    self.bus.send(Event::ManagerStopped { cycle: self.cycle });
                }
                Ok(Reply::Done)
            }
            Request::Step { cycles } => {
                self.check_step(cycles)?;
                self.halt();
                for _ in 0..cycles {
                    self.cycle();
                    if self.paused {
                        // A pausing monitor ends a step where it fired, as it stops a run.
                        break;
                    }
                }
                Ok(Reply::Done)
            }
            Request::ExternalClock { on } => {
                self.external_clock = on;
                Ok(Reply::Done)
            }
            Request::Tick { until } => {
                self.check_tick(until)?;
                let from = self.cycle;
                while self.running && self.cycle < until {
                    if self.stop_at.is_some_and(|n| self.cycle >= n) {
                        // `--cycles N`: the external clock stops there too.
                        let _ = self.request(Request::Stop);
                        break;
                    }
                    self.cycle();
                }
                Ok(Reply::Ticked { ran: self.cycle - from, cycle: self.cycle })
            }
            Request::Shutdown => Ok(Reply::Done),
        }
    }

    pub(super) fn check_step(&self, cycles: u64) -> Result<(), ControlError> {
        front::check_step(cycles)
    }

    pub(super) fn check_tick(&self, until: u64) -> Result<(), ControlError> {
        if !self.external_clock {
            return Err(ControlError::Invalid("tick: the cycle does not follow an external clock".into()));
        }
        front::check_step(until.saturating_sub(self.cycle))
    }

    /// Stops a running cycle (before a step).
    pub(super) fn halt(&mut self) {
        if self.running {
            self.running = false;
            self.bus.send(Event::ManagerStopped { cycle: self.cycle });
        }
    }
}

impl Manager {
    /// What an input read in the last cycle when its buffer holds nothing after the run (the
    /// serial executor lent it the slot's value; a spawned manager hands bodies copies and
    /// drops them): its slots' values, when every one was written in that cycle (any time, for
    /// an async skill), a record put together from its fields' slots.
    fn lent_input(&self, i: usize, port: &crate::graph::PortBinding) -> Option<Value> {
        if !self.insts[i].active || port.leaves.is_empty() {
            return None;
        }
        let any_time = self.graph.instances[i].kind == situate_core::SkillKind::Async;
        if !port.leaves.iter().all(|&l| any_time || self.slots[l].stamp == self.cycle) {
            return None;
        }
        match port.leaves[..] {
            [leaf] if !matches!(port.ty, situate_core::SignalType::Record(_)) => self.slots[leaf].value.clone(),
            _ => {
                let slots = &self.slots;
                assemble(&port.ty, &mut port.leaves.iter().filter_map(|&l| slots[l].value.as_ref()))
            }
        }
    }
}

/// A session id as messages show it: its first 8 characters (enough to tell
/// sessions apart in a list, and no more of it than needed).
fn short_session(session: &str) -> &str {
    session.get(..8).unwrap_or(session)
}
