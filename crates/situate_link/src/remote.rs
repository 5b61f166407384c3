//! Remote skills: asynchronous cskills served by another process (or
//! machine) over the link (docs/protocol.md, "Remote skills").
//!
//! On the manager's side a remote skill is an ordinary asynchronous cskill
//! whose body publishes the latest inputs and answers with the latest
//! outputs received — it never waits for the remote process, exactly as the
//! paper asks of asynchronous cskills ("respond immediately with the latest
//! answer").

use std::sync::{Arc, Mutex};

use serde_json::{json, Map, Value as Json};
use situate_core::{Io, Skill, SkillDecl, SkillError, SkillType, Value};
use zenoh::{Session, Wait};

use crate::json::{value_from_json, value_to_json};

/// What the remote process sent last.
#[derive(Default)]
struct Latest {
    outputs: Vec<Option<Value>>,
    error: Option<String>,
    prints: Vec<String>,
    /// A message that did not fit the manifest (a fault).
    invalid: Option<String>,
}

/// The manager's proxy of one remote skill instance.
pub struct RemoteSkill {
    session: Session,
    inputs_key: String,
    decl: Arc<SkillDecl>,
    params: Vec<Value>,
    latest: Arc<Mutex<Latest>>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
}

impl RemoteSkill {
    pub fn new(session: &Session, robot: &str, name: &str, decl: Arc<SkillDecl>) -> Result<RemoteSkill, String> {
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
        Ok(RemoteSkill {
            session: session.clone(),
            inputs_key: format!("situate/{robot}/remote/{name}/inputs"),
            params: decl.params.iter().map(|p| p.default.clone()).collect(),
            decl,
            latest,
            _subscriber: subscriber,
        })
    }

    /// The skill type of a remote instance: its declaration, and a maker that
    /// subscribes on `session`.
    pub fn skill_type(session: &Session, robot: &str, name: &str, decl: SkillDecl) -> SkillType {
        let decl = Arc::new(decl);
        let (session, robot, name) = (session.clone(), robot.to_string(), name.to_string());
        let d = Arc::clone(&decl);
        SkillType {
            decl,
            make: Arc::new(move || {
                Ok(Box::new(RemoteSkill::new(&session, &robot, &name, Arc::clone(&d))?) as Box<dyn Skill>)
            }),
        }
    }
}

fn absorb(l: &mut Latest, msg: &Json, decl: &SkillDecl) {
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
        if let Some(e) = l.invalid.take() {
            return Err(SkillError::new(e));
        }
        if let Some(e) = l.error.take() {
            return Err(SkillError::new(format!("the remote skill failed: {e}")));
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
