//! Remote skills: asynchronous cskills served by another process (or
//! machine) over the link (docs/protocol.md, "Remote skills").
//!
//! On the manager's side a remote skill is an ordinary asynchronous cskill
//! whose body publishes the latest inputs and answers with the latest
//! outputs received — it never waits for the remote process, exactly as the
//! paper asks of asynchronous cskills ("respond immediately with the latest
//! answer").

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use serde_json::{json, Map, Value as Json};
use situate_core::{Context, Io, Resources, Skill, SkillDecl, SkillError, SkillType, Value};
use zenoh::{Session, Wait};

use crate::json::{param_from_json, value_from_json, value_to_json};

/// What the remote process sent last.
#[derive(Default)]
struct Latest {
    outputs: Vec<Option<Value>>,
    error: Option<String>,
    prints: Vec<String>,
    /// A message that did not fit the manifest (a fault).
    invalid: Option<String>,
    /// The serving process's liveliness token went away: it crashed or
    /// stopped. Until one is back, every run of the proxy is a fault.
    gone: bool,
    /// After a fault: replies to inputs of this cycle or earlier are stale
    /// (the host may answer several cycles' inputs after the one that failed),
    /// so a reactivated skill does not fault again on an old error.
    stale_through: Option<u64>,
    /// The serving process has shown up (a reply or its liveliness token):
    /// only then does a deadline apply.
    seen: bool,
    /// When inputs were first published after the last reply.
    waiting_since: Option<Instant>,
}

/// The manager's proxy of one remote skill instance.
pub struct RemoteSkill {
    session: Session,
    inputs_key: String,
    decl: Arc<SkillDecl>,
    params: Vec<Value>,
    latest: Arc<Mutex<Latest>>,
    /// How long an answer may take once the process has answered before.
    timeout: Option<Duration>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
    _alive: zenoh::pubsub::Subscriber<()>,
}

impl RemoteSkill {
    pub fn new(session: &Session, robot: &str, name: &str, decl: Arc<SkillDecl>) -> Result<RemoteSkill, String> {
        RemoteSkill::with_timeout(session, robot, name, decl, None)
    }

    /// [`RemoteSkill::new`] with a deadline: once the serving process has
    /// answered (or declared its liveliness token), inputs left unanswered
    /// for longer than `timeout` fault the skill — the process hangs.
    pub fn with_timeout(
        session: &Session,
        robot: &str,
        name: &str,
        decl: Arc<SkillDecl>,
        timeout: Option<Duration>,
    ) -> Result<RemoteSkill, String> {
        let latest = Arc::new(Mutex::new(Latest { outputs: vec![None; decl.outputs.len()], ..Latest::default() }));
        let sink = Arc::clone(&latest);
        let outputs_decl = Arc::clone(&decl);
        let subscriber = session
            .declare_subscriber(format!("situate/{robot}/remote/{name}/outputs"))
            .callback(move |sample| {
                let parsed = serde_json::from_slice::<Json>(&sample.payload().to_bytes());
                let mut l = sink.lock().unwrap_or_else(|p| p.into_inner());
                match parsed {
                    Ok(msg) => absorb(&mut l, &msg, &outputs_decl),
                    Err(e) => l.invalid = Some(format!("the remote process sent a message that is not JSON: {e}")),
                }
            })
            .wait()
            .map_err(|e| e.to_string())?;
        // A host declares a liveliness token while it serves; Zenoh withdraws
        // it when the host's session ends, however it ends (a C skill that
        // crashed its process included). A host that never declared one
        // (an older server) is simply never reported gone.
        let watch = Arc::clone(&latest);
        let alive = session
            .liveliness()
            .declare_subscriber(alive_key(robot, name))
            .history(true)
            .callback(move |sample| {
                let mut l = watch.lock().unwrap_or_else(|p| p.into_inner());
                match sample.kind() {
                    zenoh::sample::SampleKind::Put => {
                        l.gone = false;
                        l.seen = true;
                    }
                    zenoh::sample::SampleKind::Delete => {
                        l.gone = true;
                        // A new process gets its deadline once it answers, like the first.
                        l.seen = false;
                        l.waiting_since = None;
                        // A dead process's last answer is no answer.
                        l.outputs.iter_mut().for_each(|o| *o = None);
                    }
                }
            })
            .wait()
            .map_err(|e| e.to_string())?;
        Ok(RemoteSkill {
            _alive: alive,
            session: session.clone(),
            inputs_key: format!("situate/{robot}/remote/{name}/inputs"),
            params: decl.params.iter().map(|p| p.default.clone()).collect(),
            decl,
            latest,
            timeout,
            _subscriber: subscriber,
        })
    }

    /// The skill type of a remote instance: its declaration, and a maker that
    /// subscribes on `session`.
    pub fn skill_type(session: &Session, robot: &str, name: &str, decl: SkillDecl) -> SkillType {
        RemoteSkill::skill_type_with_timeout(session, robot, name, decl, None)
    }

    /// [`RemoteSkill::skill_type`] with a deadline (see [`RemoteSkill::with_timeout`]).
    pub fn skill_type_with_timeout(
        session: &Session,
        robot: &str,
        name: &str,
        decl: SkillDecl,
        timeout: Option<Duration>,
    ) -> SkillType {
        let decl = Arc::new(decl);
        let (session, robot, name) = (session.clone(), robot.to_string(), name.to_string());
        let d = Arc::clone(&decl);
        SkillType {
            decl,
            make: Arc::new(move |_resources| {
                Ok(Box::new(RemoteSkill::with_timeout(&session, &robot, &name, Arc::clone(&d), timeout)?)
                    as Box<dyn Skill>)
            }),
        }
    }
}

/// The liveliness token of a remote skill's host.
pub fn alive_key(robot: &str, name: &str) -> String {
    format!("situate/{robot}/remote/{name}/alive")
}

fn absorb(l: &mut Latest, msg: &Json, decl: &SkillDecl) {
    let cycle = msg.get("cycle").and_then(Json::as_u64);
    if l.stale_through.is_some_and(|through| cycle.is_some_and(|c| c <= through)) {
        return;
    }
    l.seen = true;
    l.waiting_since = None;
    if let Some(e) = msg.get("error") {
        l.error = Some(e.as_str().map_or_else(|| e.to_string(), str::to_string));
    }
    if let Some(prints) = msg.get("prints").and_then(Json::as_array) {
        l.prints.extend(prints.iter().map(|p| p.as_str().map_or_else(|| p.to_string(), str::to_string)));
    }
    let Some(outputs) = msg.get("outputs") else { return };
    let Some(outputs) = outputs.as_object() else {
        l.invalid = Some("`outputs` must be an object of port: value".into());
        return;
    };
    for (port, value) in outputs {
        match decl.outputs.iter().position(|p| p.name == *port) {
            None => {
                l.invalid = Some(format!(
                    "the remote process sent an unknown output `{port}`{}",
                    situate_core::suggestion(port, decl.outputs.iter().map(|p| p.name.as_str()))
                ))
            }
            Some(i) => match value_from_json(value, &decl.outputs[i].ty) {
                Ok(v) => l.outputs[i] = Some(v),
                Err(e) => l.invalid = Some(format!("output `{port}`: {e}")),
            },
        }
    }
}

impl Skill for RemoteSkill {
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        let inputs: Map<String, Json> = self
            .decl
            .inputs
            .iter()
            .zip(io.inputs)
            .map(|(p, v)| (p.name.clone(), v.as_ref().map_or(Json::Null, value_to_json)))
            .collect();
        let params: Map<String, Json> =
            self.decl.params.iter().zip(&self.params).map(|(p, v)| (p.name.clone(), value_to_json(v))).collect();
        let msg = json!({"cycle": io.cx.cycle(), "time_s": io.cx.time_s(), "inputs": inputs, "params": params});
        // A put does not wait for the remote side (dropped under congestion).
        self.session
            .put(self.inputs_key.as_str(), msg.to_string())
            .wait()
            .map_err(|e| SkillError::new(format!("could not publish the inputs: {e}")))?;
        let mut l = self.latest.lock().unwrap_or_else(|p| p.into_inner());
        for line in l.prints.drain(..) {
            io.cx.print(line);
        }
        let now = Instant::now();
        if l.seen {
            l.waiting_since.get_or_insert(now);
        }
        let overdue = match (self.timeout, l.waiting_since) {
            (Some(limit), Some(since)) if now.duration_since(since) > limit => Some(limit),
            _ => None,
        };
        let fault = if let Some(e) = l.invalid.take() {
            Some(e)
        } else if l.gone {
            Some(
                "the process serving this remote skill is gone (it crashed or was stopped); start it again, \
                 then reactivate the skill"
                    .to_string(),
            )
        } else if let Some(e) = l.error.take() {
            Some(format!("the remote skill failed: {e}"))
        } else {
            overdue.map(|limit| {
                format!(
                    "no answer from the process serving this remote skill for over {} ms (timeout_ms): \
                     it may hang",
                    limit.as_millis()
                )
            })
        };
        if let Some(e) = fault {
            // The skill is deactivated now: what the host still sends about
            // this cycle's inputs or earlier ones is not for its next life.
            l.stale_through = Some(io.cx.cycle());
            l.error = None;
            l.waiting_since = None;
            l.outputs.iter_mut().for_each(|o| *o = None);
            return Err(SkillError::new(e));
        }
        for (slot, v) in io.outputs.iter_mut().zip(&l.outputs) {
            slot.clone_from(v);
        }
        Ok(())
    }

    fn set_param(&mut self, index: usize, value: &Value) {
        if let Some(p) = self.params.get_mut(index) {
            *p = value.clone();
        }
    }
}

// ---------------------------------------------------------------------------
// The skill's side: serving any registered skill type out of process.
// ---------------------------------------------------------------------------

/// Why a skill host could not start (a body's failure is not one: it is
/// reported to the manager, which faults the skill).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HostError {
    #[error("could not create an instance of `{type_name}`: {message}")]
    Make { type_name: String, message: String },
    #[error("Zenoh: {0}")]
    Zenoh(String),
}

/// Counters of a [`serve_skill`] run.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct HostStats {
    /// Inputs messages received.
    pub received: u64,
    /// Runs of the body (each on the latest inputs at the time).
    pub computed: u64,
    /// Inputs messages dropped because newer ones arrived first.
    pub dropped: u64,
    /// Messages answered with an error (a failed body, or inputs that do not
    /// fit the declaration).
    pub errors: u64,
}

#[derive(Default)]
struct Inbox {
    latest: Option<Vec<u8>>,
    stats: HostStats,
}

/// Serves one instance of `ty` as robot `robot`'s remote skill `name` until
/// `stop` is set: the skill's side of the protocol (docs/protocol.md,
/// "Remote skills"), for a skill type of any language the program can load
/// (a C or C++ library, a built-in Rust type, an in-process Python type).
///
/// The body runs on this thread, always on the *latest* inputs: when it is
/// slower than the manager's cycle, the inputs of the cycles it missed are
/// dropped, never queued. A failing body (error status, exception, Rust
/// panic) is answered with an error, which faults the skill in the manager;
/// after a panic the instance is made anew. Inputs that do not fit the
/// declaration (an unknown port, a wrong type, a parameter out of range) are
/// answered with an error naming the port, never run.
///
/// The instance is made with `resources` (the registry's that `ty` came
/// from). `ready` is called once the subscriptions are in place.
pub fn serve_skill(
    session: &Session,
    robot: &str,
    name: &str,
    ty: &SkillType,
    resources: &Resources,
    stop: &AtomicBool,
    ready: impl FnOnce(),
) -> Result<HostStats, HostError> {
    let make =
        || (ty.make)(resources).map_err(|message| HostError::Make { type_name: ty.decl.type_name.clone(), message });
    let mut host = Host { decl: Arc::clone(&ty.decl), skill: make()?, params: Vec::new(), cx: Context::default() };
    host.params = host.decl.params.iter().map(|p| p.default.clone()).collect();

    let inbox = Arc::new((Mutex::new(Inbox::default()), Condvar::new()));
    let sink = Arc::clone(&inbox);
    let publisher = session
        .declare_publisher(format!("situate/{robot}/remote/{name}/outputs"))
        .wait()
        .map_err(|e| HostError::Zenoh(e.to_string()))?;
    let subscriber = session
        .declare_subscriber(format!("situate/{robot}/remote/{name}/inputs"))
        .callback(move |sample| {
            let (lock, cv) = &*sink;
            let mut inbox = lock.lock().unwrap_or_else(|p| p.into_inner());
            inbox.stats.received += 1;
            if inbox.latest.replace(sample.payload().to_bytes().into_owned()).is_some() {
                inbox.stats.dropped += 1;
            }
            cv.notify_one();
        })
        .wait()
        .map_err(|e| HostError::Zenoh(e.to_string()))?;
    let token = session
        .liveliness()
        .declare_token(alive_key(robot, name))
        .wait()
        .map_err(|e| HostError::Zenoh(e.to_string()))?;
    ready();

    let (lock, cv) = &*inbox;
    loop {
        let message = {
            let mut guard = lock.lock().unwrap_or_else(|p| p.into_inner());
            loop {
                if stop.load(Ordering::SeqCst) {
                    break None;
                }
                if let Some(m) = guard.latest.take() {
                    break Some(m);
                }
                // Bounded only so that `stop` is noticed.
                guard = cv.wait_timeout(guard, Duration::from_millis(100)).unwrap_or_else(|p| p.into_inner()).0;
            }
        };
        let Some(message) = message else { break };
        let (reply, panicked) = host.compute(&message);
        if panicked {
            host.skill = make()?;
            for (i, v) in host.params.iter().enumerate() {
                host.skill.set_param(i, v);
            }
        }
        {
            let mut guard = lock.lock().unwrap_or_else(|p| p.into_inner());
            guard.stats.computed += 1;
            if reply.get("error").is_some() {
                guard.stats.errors += 1;
            }
        }
        if let Err(e) = publisher.put(reply.to_string()).wait() {
            tracing::warn!("remote skill `{name}`: could not publish the outputs: {e}");
        }
    }
    drop(token);
    drop(subscriber);
    let stats = lock.lock().unwrap_or_else(|p| p.into_inner()).stats.clone();
    Ok(stats)
}

/// One served instance and the parameter values it was last given.
struct Host {
    decl: Arc<SkillDecl>,
    skill: Box<dyn Skill>,
    params: Vec<Value>,
    cx: Context,
}

impl Host {
    /// Runs the body on one inputs message; the reply to publish, and
    /// whether the body panicked.
    fn compute(&mut self, message: &[u8]) -> (Json, bool) {
        let msg = match serde_json::from_slice::<Json>(message) {
            Ok(Json::Object(m)) => m,
            Ok(_) => return (json!({"cycle": 0, "error": "the inputs message is not a JSON object"}), false),
            Err(e) => return (json!({"cycle": 0, "error": format!("the inputs message is not JSON: {e}")}), false),
        };
        let cycle = msg.get("cycle").and_then(Json::as_u64).unwrap_or(0);
        let time_s = msg.get("time_s").and_then(Json::as_f64).unwrap_or(0.0);
        let inputs = match self.inputs(&msg) {
            Ok(i) => i,
            Err(e) => return (json!({"cycle": cycle, "error": e}), false),
        };
        if let Err(e) = self.apply_params(&msg) {
            return (json!({"cycle": cycle, "error": e}), false);
        }
        let mut outputs = vec![None; self.decl.outputs.len()];
        self.cx.set(cycle, time_s);
        let skill = &mut self.skill;
        let cx = &mut self.cx;
        let run = catch_unwind(AssertUnwindSafe(|| skill.step(&mut Io { inputs: &inputs, outputs: &mut outputs, cx })));
        let prints = self.cx.take_prints();
        let mut reply = Map::new();
        reply.insert("cycle".into(), json!(cycle));
        let panicked = match run {
            Ok(Ok(())) => {
                let produced: Map<String, Json> = self
                    .decl
                    .outputs
                    .iter()
                    .zip(&outputs)
                    .filter_map(|(p, v)| v.as_ref().map(|v| (p.name.clone(), value_to_json(v))))
                    .collect();
                reply.insert("outputs".into(), Json::Object(produced));
                false
            }
            Ok(Err(e)) => {
                reply.insert("error".into(), json!(e.message));
                false
            }
            Err(panic) => {
                let what = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "a panic".into());
                reply.insert("error".into(), json!(format!("the body panicked: {what}")));
                true
            }
        };
        if !prints.is_empty() {
            reply.insert("prints".into(), json!(prints));
        }
        (Json::Object(reply), panicked)
    }

    /// The body's inputs from a message, checked against the declaration.
    fn inputs(&self, msg: &Map<String, Json>) -> Result<Vec<Option<Value>>, String> {
        let empty = Map::new();
        let given = match msg.get("inputs") {
            None | Some(Json::Null) => &empty,
            Some(Json::Object(m)) => m,
            Some(_) => return Err("`inputs` must be an object of port: value".into()),
        };
        let ty = &self.decl.type_name;
        if let Some(unknown) = given.keys().find(|k| !self.decl.inputs.iter().any(|p| &p.name == *k)) {
            return Err(format!(
                "the manager sent input `{unknown}`, which `{ty}` does not declare{} (does the robot file's \
                 `remote:` manifest match the type's?)",
                situate_core::suggestion(unknown, self.decl.inputs.iter().map(|p| p.name.as_str()))
            ));
        }
        self.decl
            .inputs
            .iter()
            .map(|port| match given.get(&port.name) {
                None | Some(Json::Null) if port.optional => Ok(None),
                None | Some(Json::Null) => {
                    Err(format!("input `{}` of `{ty}` is required but the message has none", port.name))
                }
                Some(j) => {
                    value_from_json(j, &port.ty).map(Some).map_err(|e| format!("input `{}` of `{ty}`: {e}", port.name))
                }
            })
            .collect()
    }

    /// Applies the parameters of a message that differ from the current ones.
    fn apply_params(&mut self, msg: &Map<String, Json>) -> Result<(), String> {
        let Some(given) = msg.get("params") else { return Ok(()) };
        let Some(given) = given.as_object() else { return Err("`params` must be an object of name: value".into()) };
        let ty = &self.decl.type_name;
        let mut changed = Vec::new();
        for (name, j) in given {
            let Some(i) = self.decl.params.iter().position(|p| &p.name == name) else {
                return Err(format!(
                    "the manager sent parameter `{name}`, which `{ty}` does not declare{}",
                    situate_core::suggestion(name, self.decl.params.iter().map(|p| p.name.as_str()))
                ));
            };
            let spec = &self.decl.params[i];
            let v = param_from_json(j)
                .map_err(|e| format!("parameter `{name}` of `{ty}`: {e}"))
                .and_then(|v| spec.check(&v).map_err(|e| format!("parameter `{name}` of `{ty}` {e}")))?;
            if v != self.params[i] {
                changed.push((i, v));
            }
        }
        // All checked before any is applied: a bad message changes nothing.
        for (i, v) in changed {
            self.skill.set_param(i, &v);
            self.params[i] = v;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use situate_core::{FnSkill, ParamSpec, ParamType, PortSpec, SignalType, SkillKind};

    /// `y = gain * x`; a panic on a negative x; a print every run.
    fn host() -> Host {
        let mut decl = SkillDecl::new("t.scale", SkillKind::Async);
        decl.inputs.push(PortSpec {
            name: "x".into(),
            signal: "x".into(),
            ty: SignalType::F64,
            optional: false,
            doc: String::new(),
        });
        decl.outputs.push(PortSpec {
            name: "y".into(),
            signal: "y".into(),
            ty: SignalType::F64,
            optional: false,
            doc: String::new(),
        });
        decl.params.push(ParamSpec::new("gain", ParamType::F64, Value::F64(2.0)).range(Some(0.0), Some(10.0)));
        let skill = FnSkill::new(&decl, |io: &mut Io<'_>, params: &[Value]| {
            let x = io.inputs[0].as_ref().and_then(Value::as_f64).unwrap_or_default();
            assert!(x >= 0.0, "negative x");
            io.cx.print(format!("x = {x}"));
            io.outputs[0] = Some(Value::F64(x * params[0].as_f64().unwrap_or_default()));
            Ok(())
        });
        let params = decl.params.iter().map(|p| p.default.clone()).collect();
        Host { decl: Arc::new(decl), skill: Box::new(skill), params, cx: Context::default() }
    }

    fn compute(h: &mut Host, msg: Json) -> (Json, bool) {
        h.compute(msg.to_string().as_bytes())
    }

    #[test]
    fn a_run_answers_outputs_prints_and_the_cycle() {
        let mut h = host();
        let (reply, panicked) = compute(&mut h, json!({"cycle": 7, "inputs": {"x": 1.5}, "params": {"gain": 3}}));
        assert!(!panicked);
        assert_eq!(reply, json!({"cycle": 7, "outputs": {"y": 4.5}, "prints": ["x = 1.5"]}));
        assert_eq!(h.params, vec![Value::F64(3.0)], "an integer for an f64 parameter becomes a float");
    }

    #[test]
    fn inputs_that_do_not_fit_the_declaration_are_answered_with_an_error_naming_the_port() {
        let mut h = host();
        for (msg, expected) in [
            (json!({"cycle": 1, "inputs": {"z": 1.0}}), "the manager sent input `z`, which `t.scale` does not declare"),
            (json!({"cycle": 1, "inputs": {}}), "input `x` of `t.scale` is required"),
            (json!({"cycle": 1, "inputs": {"x": "fast"}}), "input `x` of `t.scale`: expected f64"),
            (json!({"cycle": 1, "inputs": {"x": 1.0}, "params": {"gain": 11.0}}), "parameter `gain` of `t.scale`"),
            (json!({"cycle": 1, "inputs": {"x": 1.0}, "params": {"gian": 1.0}}), "did you mean `gain`"),
            (json!([1, 2]), "not a JSON object"),
        ] {
            let (reply, _) = compute(&mut h, msg.clone());
            let error = reply["error"].as_str().unwrap_or_else(|| panic!("{msg} was not refused: {reply}"));
            assert!(error.contains(expected), "{msg}: {error}");
            assert!(reply.get("outputs").is_none());
        }
        assert_eq!(h.params, vec![Value::F64(2.0)], "a refused message changes no parameter");
        assert_eq!(h.compute(b"{not json").0["error"].as_str().map(|e| e.contains("not JSON")), Some(true));
    }

    #[test]
    fn a_panicking_body_is_answered_with_its_message_and_reported_as_a_panic() {
        let mut h = host();
        let (reply, panicked) = compute(&mut h, json!({"cycle": 3, "inputs": {"x": -1.0}}));
        assert!(panicked);
        assert_eq!(reply["cycle"], json!(3));
        assert!(reply["error"].as_str().is_some_and(|e| e.contains("panicked: negative x")), "{reply}");
    }
}
