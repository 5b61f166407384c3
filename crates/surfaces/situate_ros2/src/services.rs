//! Activation and parameters as ROS 2 services, the way rmw_zenoh serves them (`services: true`
//! in the `ros2:` section):
//!
//! - `<node>/<skill>/set_active` (`std_srvs/srv/SetBool`) for each skill: `data: true` activates
//!   it (with the skills that provide its inputs, as the link's `activate` does), `false`
//!   deactivates it;
//! - the node's parameter services, so `ros2 param list|get|set|describe|dump` work: each skill's
//!   parameter is the node's parameter `<skill>.<param>` (`get_parameters`, `set_parameters`,
//!   `list_parameters`, `describe_parameters`, `get_parameter_types`; `set_parameters_atomically`
//!   is not offered).
//!
//! rmw_zenoh's conventions for a service server: a queryable on
//! `<domain>/<service>/<pkg>::srv::dds_::<Name>_/<service type hash>`, a liveliness token of kind
//! `SS`, the request and the reply CDR-encoded, and the reply's attachment holding the request's
//! sequence number, a source timestamp and the client's GID (taken from the request's
//! attachment).
//!
//! The queryables' callbacks only queue the queries; a thread of the bridge answers them, so a
//! slow answer from the manager never holds up Zenoh's own threads. Every call gets an answer:
//! a call past the queue ([`QUEUE`] deep) gets an error reply at once, and so does a call made
//! while the bridge stops. A request is read only if it is at most [`MAX_REQUEST_BYTES`], and
//! every length in it is bounded by the bytes present ([`crate::decode`]); one that cannot be
//! read is refused in the reply when its type can say so (`SetBool`'s `success: false`,
//! `SetParameters`' one result with `successful: false`), with a Zenoh error reply otherwise.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use serde::{Deserialize, Serialize};
use situate_core::{ParamSpec, ParamType, Value};
use situate_manager::{Handle, Reply, Request, SkillInfo};
use zenoh::query::Query;
use zenoh::Wait;
use zenoh_ext::ZDeserializer;

use crate::msgs::{decode, encode};
use crate::rmw::{self, NodeName};
use crate::Ros2Error;

/// How long one answer may wait for the manager.
const REQUEST_TIMEOUT: Duration = Duration::from_secs(5);
/// Calls waiting for the bridge's thread; a call past them gets an error reply at once.
pub const QUEUE: usize = 256;
/// The largest request read; a larger one is refused without being read. ROS 2's parameter
/// requests are a few hundred bytes (`ros2 param load` sends a whole file's in one call).
pub const MAX_REQUEST_BYTES: usize = 1 << 20;

/// A ROS 2 service type: its name, its DDS name and its RIHS01 hash as ROS 2 Jazzy and later
/// compute it (the service's type description: request, response and event messages; checked by
/// `python/tests/test_ros2.py` against the hashes `rosbags` computes from the definitions).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SrvType {
    pub ros_name: &'static str,
    pub hash: &'static str,
}

impl SrvType {
    /// `pkg::srv::dds_::Name_`, as rmw_zenoh writes a service type in keys.
    pub fn dds_name(self) -> String {
        let mut parts = self.ros_name.split('/');
        let (package, _, ty) = (parts.next().unwrap_or(""), parts.next(), parts.next().unwrap_or(""));
        format!("{package}::srv::dds_::{ty}_")
    }
}

pub const SET_BOOL: SrvType = SrvType {
    ros_name: "std_srvs/srv/SetBool",
    hash: "RIHS01_abe9e4bb6b41b40e6789712c00ec8871923e089af3f667a79992a428cff2da0a",
};
pub const GET_PARAMETERS: SrvType = SrvType {
    ros_name: "rcl_interfaces/srv/GetParameters",
    hash: "RIHS01_bf9803d5c74cf989a5de3e0c2e99444599a627c7ff75f97b8c05b01003675cbc",
};
pub const SET_PARAMETERS: SrvType = SrvType {
    ros_name: "rcl_interfaces/srv/SetParameters",
    hash: "RIHS01_56eed9a67e169f9cb6c1f987bc88f868c14a8fc9f743a263bc734c154015d7e0",
};
pub const LIST_PARAMETERS: SrvType = SrvType {
    ros_name: "rcl_interfaces/srv/ListParameters",
    hash: "RIHS01_3e6062bfbb27bfb8730d4cef2558221f51a11646d78e7bb30a1e83afac3aad9d",
};
pub const DESCRIBE_PARAMETERS: SrvType = SrvType {
    ros_name: "rcl_interfaces/srv/DescribeParameters",
    hash: "RIHS01_845b484d71eb0673dae682f2e3ba3c4851a65a3dcfb97bddd82c5b57e91e4cff",
};
pub const GET_PARAMETER_TYPES: SrvType = SrvType {
    ros_name: "rcl_interfaces/srv/GetParameterTypes",
    hash: "RIHS01_da199c878688b3e530bdfe3ca8f74cb9fa0c303101e980a9e8f260e25e1c80ca",
};

// ----- the messages (rcl_interfaces and std_srvs, ROS 2 Jazzy) -----------------------------

/// `rcl_interfaces/msg/ParameterType`'s values.
mod ptype {
    pub const NOT_SET: u8 = 0;
    pub const BOOL: u8 = 1;
    pub const INTEGER: u8 = 2;
    pub const DOUBLE: u8 = 3;
    pub const STRING: u8 = 4;
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetBoolRequest {
    pub data: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetBoolResponse {
    pub success: bool,
    pub message: String,
}

#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ParameterValue {
    #[serde(rename = "type")]
    pub ty: u8,
    pub bool_value: bool,
    pub integer_value: i64,
    pub double_value: f64,
    pub string_value: String,
    pub byte_array_value: Vec<u8>,
    pub bool_array_value: Vec<bool>,
    pub integer_array_value: Vec<i64>,
    pub double_array_value: Vec<f64>,
    pub string_array_value: Vec<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    pub name: String,
    pub value: ParameterValue,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Names {
    pub names: Vec<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GetParametersResponse {
    pub values: Vec<ParameterValue>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetParametersRequest {
    pub parameters: Vec<Parameter>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetParametersResult {
    pub successful: bool,
    pub reason: String,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetParametersResponse {
    pub results: Vec<SetParametersResult>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ListParametersRequest {
    pub prefixes: Vec<String>,
    pub depth: u64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ListParametersResult {
    pub names: Vec<String>,
    pub prefixes: Vec<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ListParametersResponse {
    pub result: ListParametersResult,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GetParameterTypesResponse {
    pub types: Vec<u8>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FloatingPointRange {
    pub from_value: f64,
    pub to_value: f64,
    pub step: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IntegerRange {
    pub from_value: i64,
    pub to_value: i64,
    pub step: u64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterDescriptor {
    pub name: String,
    #[serde(rename = "type")]
    pub ty: u8,
    pub description: String,
    pub additional_constraints: String,
    pub read_only: bool,
    pub dynamic_typing: bool,
    /// At most one.
    pub floating_point_range: Vec<FloatingPointRange>,
    /// At most one.
    pub integer_range: Vec<IntegerRange>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DescribeParametersResponse {
    pub descriptors: Vec<ParameterDescriptor>,
}

// ----- the servers ---------------------------------------------------------------------------

/// What one queryable answers.
#[derive(Debug, Clone)]
enum Service {
    SetActive(String),
    GetParameters,
    SetParameters,
    ListParameters,
    DescribeParameters,
    GetParameterTypes,
}

impl Service {
    fn ty(&self) -> SrvType {
        match self {
            Service::SetActive(_) => SET_BOOL,
            Service::GetParameters => GET_PARAMETERS,
            Service::SetParameters => SET_PARAMETERS,
            Service::ListParameters => LIST_PARAMETERS,
            Service::DescribeParameters => DESCRIBE_PARAMETERS,
            Service::GetParameterTypes => GET_PARAMETER_TYPES,
        }
    }
}

/// What the service servers refused since the bridge started ([`crate::Bridge::service_stats`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ServiceStats {
    /// Calls that found [`QUEUE`] calls waiting, answered with an error reply at once.
    pub refused_queue_full: u64,
    /// Requests that could not be read (too large, truncated, a length past the bytes present,
    /// not CDR, a malformed rmw_zenoh attachment).
    pub malformed: u64,
}

/// The refusals, counted, and logged once per burst (a full queue) or once at all (malformed
/// requests) so a flood of bad calls cannot flood the log.
#[derive(Debug, Default)]
struct Refusals {
    queue_full: AtomicU64,
    /// Calls refused since the queue last filled up.
    burst: AtomicU64,
    in_burst: AtomicBool,
    malformed: AtomicU64,
    warned_malformed: AtomicBool,
}

impl Refusals {
    fn queue_full(&self, query: Query) {
        self.queue_full.fetch_add(1, Ordering::Relaxed);
        self.burst.fetch_add(1, Ordering::Relaxed);
        if !self.in_burst.swap(true, Ordering::Relaxed) {
            tracing::warn!(
                queue = QUEUE,
                "ROS 2 bridge: {QUEUE} service calls waiting; calls past them get an error reply until the queue drains"
            );
        }
        let message = format!("the ROS 2 bridge's service queue is full ({QUEUE} calls waiting): call again later");
        if let Err(e) = query.reply_err(message).wait() {
            tracing::debug!(key = %query.key_expr(), error = %e, "ROS 2 bridge: an error reply failed");
        }
    }

    /// Called when the queue is empty: a burst of refusals is over, and said so once.
    fn drained(&self) {
        if self.in_burst.swap(false, Ordering::Relaxed) {
            let refused = self.burst.swap(0, Ordering::Relaxed);
            tracing::warn!(
                refused,
                "ROS 2 bridge: the service queue drained; {refused} calls were refused while it was full"
            );
        }
    }

    fn malformed(&self, key: &str, message: &str) {
        self.malformed.fetch_add(1, Ordering::Relaxed);
        if self.warned_malformed.swap(true, Ordering::Relaxed) {
            tracing::debug!(key, message, "ROS 2 bridge: a request refused");
        } else {
            tracing::warn!(key, message, "ROS 2 bridge: a request refused (further ones are counted, not logged)");
        }
    }

    fn stats(&self) -> ServiceStats {
        ServiceStats {
            refused_queue_full: self.queue_full.load(Ordering::Relaxed),
            malformed: self.malformed.load(Ordering::Relaxed),
        }
    }
}

/// The bridge's service servers: held while they live.
pub(crate) struct Servers {
    queryables: Vec<zenoh::query::Queryable<()>>,
    _tokens: Vec<zenoh::liveliness::LivelinessToken>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    /// The queue, to answer what is left in it when the servers stop.
    waiting: crossbeam_channel::Receiver<(Service, Query)>,
    refusals: Arc<Refusals>,
    /// (fully qualified service name, key expression).
    pub(crate) names: Vec<(String, String)>,
}

const STOPPING: &str = "the ROS 2 bridge is stopping";

impl Servers {
    /// Declares `set_active` for each skill whose name is a valid ROS 2 name, and the node's
    /// parameter services; entity ids start at `first_entity_id`.
    pub(crate) fn start(
        handle: &Handle,
        session: &zenoh::Session,
        node: &NodeName,
        node_id: u64,
        first_entity_id: u64,
    ) -> Result<Servers, Ros2Error> {
        let skills = match handle.request_timeout(Request::QuerySkills, REQUEST_TIMEOUT) {
            Ok(Reply::Skills(s)) => s,
            Ok(other) => return Err(Ros2Error::Skills(format!("an unexpected reply: {other:?}"))),
            Err(e) => return Err(Ros2Error::Skills(e.to_string())),
        };
        let node_fq = node.resolve(&node.name);
        let mut services: Vec<(String, Service)> = Vec::new();
        for s in &skills {
            if rmw::valid_ros_name(&s.name, false) {
                services.push((format!("{node_fq}/{}/set_active", s.name), Service::SetActive(s.name.clone())));
            } else {
                tracing::warn!(skill = %s.name, "ROS 2 bridge: the skill's name is no ROS 2 name: no set_active service");
            }
        }
        for (name, service) in [
            ("get_parameters", Service::GetParameters),
            ("set_parameters", Service::SetParameters),
            ("list_parameters", Service::ListParameters),
            ("describe_parameters", Service::DescribeParameters),
            ("get_parameter_types", Service::GetParameterTypes),
        ] {
            services.push((format!("{node_fq}/{name}"), service));
        }

        let (tx, rx) = crossbeam_channel::bounded::<(Service, Query)>(QUEUE);
        let refusals = Arc::new(Refusals::default());
        let zid = session.zid().to_string();
        let mut queryables = Vec::new();
        let mut tokens = Vec::new();
        let mut names = Vec::new();
        for (k, (fq, service)) in services.into_iter().enumerate() {
            let ty = service.ty();
            let key = node.service_key(&fq, &ty.dds_name(), ty.hash);
            let tx = tx.clone();
            let refused = Arc::clone(&refusals);
            let queryable = session
                .declare_queryable(key.clone())
                .complete(true)
                .callback(move |query| match tx.try_send((service.clone(), query)) {
                    Ok(()) => {}
                    Err(crossbeam_channel::TrySendError::Full((_, query))) => refused.queue_full(query),
                    Err(crossbeam_channel::TrySendError::Disconnected((_, query))) => reply_error(&query, STOPPING),
                })
                .wait()
                .map_err(|e| Ros2Error::Zenoh { what: format!("a queryable on `{key}`"), message: e.to_string() })?;
            let token_key =
                node.entity_token(&zid, node_id, first_entity_id + k as u64, "SS", &fq, &ty.dds_name(), ty.hash);
            let token = session.liveliness().declare_token(token_key.clone()).wait().map_err(|e| Ros2Error::Zenoh {
                what: format!("the liveliness token `{token_key}`"),
                message: e.to_string(),
            })?;
            queryables.push(queryable);
            tokens.push(token);
            names.push((fq, key));
        }
        let stop = Arc::new(AtomicBool::new(false));
        let st = Arc::clone(&stop);
        let handle = handle.clone();
        let refused = Arc::clone(&refusals);
        let waiting = rx.clone();
        let thread = std::thread::Builder::new()
            .name("situate-ros2-srv".into())
            .spawn(move || {
                while !st.load(Ordering::SeqCst) {
                    if let Ok((service, query)) = rx.recv_timeout(Duration::from_millis(50)) {
                        answer(&handle, &service, &query, &refused);
                    }
                    if rx.is_empty() {
                        refused.drained();
                    }
                }
            })
            .map_err(Ros2Error::Thread)?;
        Ok(Servers { queryables, _tokens: tokens, stop, thread: Some(thread), waiting, refusals, names })
    }

    pub(crate) fn stats(&self) -> ServiceStats {
        self.refusals.stats()
    }

    pub(crate) fn stop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            if t.join().is_err() {
                tracing::warn!("the ROS 2 bridge's service thread panicked");
            }
        }
        // No call is taken after the queryables go; the calls still waiting are answered, not
        // dropped without a reply.
        self.queryables.clear();
        while let Ok((_, query)) = self.waiting.try_recv() {
            reply_error(&query, STOPPING);
        }
    }
}

impl Drop for Servers {
    fn drop(&mut self) {
        self.stop();
    }
}

/// The request's attachment: its sequence number and the client's GID. A call without one (a
/// plain Zenoh get) is answered with sequence number 0 and a zero GID.
fn request_id(query: &Query) -> Result<(i64, [u8; 16]), String> {
    let Some(attachment) = query.attachment() else { return Ok((0, [0; 16])) };
    let mut d = ZDeserializer::new(attachment);
    let sequence: i64 = d.deserialize().map_err(|_| "the attachment has no sequence number".to_string())?;
    let _stamp: i64 = d.deserialize().map_err(|_| "the attachment has no source timestamp".to_string())?;
    let gid: [u8; 16] = d.deserialize().map_err(|_| "the attachment has no 16-byte GID".to_string())?;
    Ok((sequence, gid))
}

fn answer(handle: &Handle, service: &Service, query: &Query, refusals: &Refusals) {
    let (sequence, gid) = match request_id(query) {
        Ok(id) => id,
        Err(e) => {
            let message = format!("a malformed rmw_zenoh attachment: {e}");
            refusals.malformed(query.key_expr().as_str(), &message);
            reply_error(query, &message);
            return;
        }
    };
    let payload = query.payload().map(|p| p.to_bytes()).unwrap_or_default();
    let response = match read_call(service, &payload) {
        Ok(call) => respond(handle, call),
        Err(message) => {
            refusals.malformed(query.key_expr().as_str(), &message);
            refusal(service, message)
        }
    };
    match response {
        Ok(bytes) => {
            let now_ns = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
                .unwrap_or(0);
            let attachment = rmw::attachment(sequence, now_ns, &gid);
            if let Err(e) = query.reply(query.key_expr().clone(), bytes).attachment(attachment).wait() {
                tracing::warn!(key = %query.key_expr(), error = %e, "ROS 2 bridge: a reply failed");
            }
        }
        Err(e) => reply_error(query, &e),
    }
}

fn reply_error(query: &Query, message: &str) {
    tracing::debug!(key = %query.key_expr(), message, "ROS 2 bridge: a service call refused");
    if let Err(e) = query.reply_err(message.to_string()).wait() {
        tracing::warn!(key = %query.key_expr(), error = %e, "ROS 2 bridge: an error reply failed");
    }
}

/// A request, read.
enum Call {
    SetActive(String, bool),
    Get(Names),
    Set(SetParametersRequest),
    List(ListParametersRequest),
    Describe(Names),
    Types(Names),
}

/// Reads a request: at most [`MAX_REQUEST_BYTES`], every length in it bounded by the bytes
/// present; `Err` names the service type and what is wrong where.
fn read_call(service: &Service, payload: &[u8]) -> Result<Call, String> {
    let ty = service.ty();
    if payload.len() > MAX_REQUEST_BYTES {
        return Err(format!(
            "a {} request of {} bytes is not read: requests are limited to {MAX_REQUEST_BYTES} bytes",
            ty.ros_name,
            payload.len()
        ));
    }
    fn req<'a, T: Deserialize<'a>>(payload: &'a [u8], ty: SrvType) -> Result<T, String> {
        decode(payload).map_err(|e| format!("cannot decode a {} request: {e}", ty.ros_name))
    }
    Ok(match service {
        Service::SetActive(skill) => Call::SetActive(skill.clone(), req::<SetBoolRequest>(payload, ty)?.data),
        Service::GetParameters => Call::Get(req(payload, ty)?),
        Service::SetParameters => Call::Set(req(payload, ty)?),
        Service::ListParameters => Call::List(req(payload, ty)?),
        Service::DescribeParameters => Call::Describe(req(payload, ty)?),
        Service::GetParameterTypes => Call::Types(req(payload, ty)?),
    })
}

fn out<T: Serialize>(msg: &T) -> Result<Vec<u8>, String> {
    encode(msg).map_err(|e| format!("cannot encode the response: {e}"))
}

/// The answer to a request that could not be read: in the response when its type can carry a
/// refusal (a ROS 2 client only logs a Zenoh error reply, and its call waits on), else `Err`
/// for a Zenoh error reply.
fn refusal(service: &Service, message: String) -> Result<Vec<u8>, String> {
    match service {
        Service::SetActive(_) => out(&SetBoolResponse { success: false, message }),
        // One result: the client's parameters cannot be counted in a request that cannot be read.
        Service::SetParameters => {
            out(&SetParametersResponse { results: vec![SetParametersResult { successful: false, reason: message }] })
        }
        Service::GetParameters | Service::ListParameters | Service::DescribeParameters | Service::GetParameterTypes => {
            Err(message)
        }
    }
}

/// Does a request and encodes the response; `Err` when the manager does not answer (the client
/// gets a Zenoh error reply saying so).
fn respond(handle: &Handle, call: Call) -> Result<Vec<u8>, String> {
    match call {
        Call::SetActive(skill, on) => out(&set_active(handle, &skill, on)),
        Call::Get(r) => {
            let params = parameters(handle)?;
            let values = r
                .names
                .iter()
                .map(|n| params.iter().find(|p| &p.0 == n).map_or_else(ParameterValue::default, |p| to_ros(&p.2)))
                .collect();
            out(&GetParametersResponse { values })
        }
        Call::Set(r) => {
            let params = parameters(handle)?;
            let results = r.parameters.iter().map(|p| set_parameter(handle, &params, p)).collect();
            out(&SetParametersResponse { results })
        }
        Call::List(r) => out(&ListParametersResponse { result: list(&parameters(handle)?, &r) }),
        Call::Describe(r) => {
            let params = parameters(handle)?;
            let descriptors = r
                .names
                .iter()
                .map(|n| match params.iter().find(|p| &p.0 == n) {
                    Some((name, spec, _)) => describe(name, spec),
                    None => ParameterDescriptor {
                        name: n.clone(),
                        ty: ptype::NOT_SET,
                        description: String::new(),
                        additional_constraints: String::new(),
                        read_only: false,
                        dynamic_typing: false,
                        floating_point_range: Vec::new(),
                        integer_range: Vec::new(),
                    },
                })
                .collect();
            out(&DescribeParametersResponse { descriptors })
        }
        Call::Types(r) => {
            let params = parameters(handle)?;
            let types = r
                .names
                .iter()
                .map(|n| params.iter().find(|p| &p.0 == n).map_or(ptype::NOT_SET, |p| type_of(p.1.ty)))
                .collect();
            out(&GetParameterTypesResponse { types })
        }
    }
}

fn set_active(handle: &Handle, skill: &str, on: bool) -> SetBoolResponse {
    let request = if on {
        Request::Activate { skills: vec![skill.to_string()], with_providers: true }
    } else {
        Request::Deactivate { skills: vec![skill.to_string()] }
    };
    match handle.request_timeout(request, REQUEST_TIMEOUT) {
        Ok(_) => SetBoolResponse {
            success: true,
            message: format!("`{skill}` {}", if on { "activated" } else { "deactivated" }),
        },
        Err(e) => SetBoolResponse { success: false, message: e.to_string() },
    }
}

/// Every skill's parameters as the node's: (`skill.param`, its spec, its value); `Err` when
/// the manager does not answer (the call gets an error reply, not an empty list).
fn parameters(handle: &Handle) -> Result<Vec<(String, ParamSpec, Value)>, String> {
    let skills: Vec<SkillInfo> = match handle.request_timeout(Request::QuerySkills, REQUEST_TIMEOUT) {
        Ok(Reply::Skills(s)) => s,
        Ok(other) => return Err(format!("the skill manager gave an unexpected reply: {other:?}")),
        Err(e) => return Err(format!("the skill manager did not answer: {e}")),
    };
    Ok(skills
        .into_iter()
        .flat_map(|s| {
            let skill = s.name;
            s.params.into_iter().map(move |(spec, v)| (format!("{skill}.{}", spec.name), spec, v))
        })
        .collect())
}

fn type_of(t: ParamType) -> u8 {
    match t {
        ParamType::Bool => ptype::BOOL,
        ParamType::I64 => ptype::INTEGER,
        ParamType::F64 => ptype::DOUBLE,
        ParamType::Str => ptype::STRING,
    }
}

fn to_ros(v: &Value) -> ParameterValue {
    let mut p = ParameterValue::default();
    match v {
        Value::Bool(b) => (p.ty, p.bool_value) = (ptype::BOOL, *b),
        Value::I64(i) => (p.ty, p.integer_value) = (ptype::INTEGER, *i),
        Value::F64(f) => (p.ty, p.double_value) = (ptype::DOUBLE, *f),
        Value::Str(s) => (p.ty, p.string_value) = (ptype::STRING, s.to_string()),
        _ => {}
    }
    p
}

/// A ROS 2 value as a value of a parameter of type `ty`: an integer is taken for a double (`ros2
/// param set … 1` sends an integer), nothing else is converted.
fn from_ros(p: &ParameterValue, ty: ParamType) -> Result<Value, String> {
    let name = |t: u8| match t {
        ptype::NOT_SET => "no value",
        ptype::BOOL => "a bool",
        ptype::INTEGER => "an integer",
        ptype::DOUBLE => "a double",
        ptype::STRING => "a string",
        _ => "an array",
    };
    match (ty, p.ty) {
        (ParamType::Bool, ptype::BOOL) => Ok(Value::Bool(p.bool_value)),
        (ParamType::I64, ptype::INTEGER) => Ok(Value::I64(p.integer_value)),
        (ParamType::F64, ptype::DOUBLE) => Ok(Value::F64(p.double_value)),
        (ParamType::F64, ptype::INTEGER) => Ok(Value::F64(p.integer_value as f64)),
        (ParamType::Str, ptype::STRING) => Ok(Value::Str(p.string_value.as_str().into())),
        (ty, got) => Err(format!("expects {}, got {}", ty.name(), name(got))),
    }
}

fn set_parameter(handle: &Handle, params: &[(String, ParamSpec, Value)], p: &Parameter) -> SetParametersResult {
    let refuse = |reason: String| SetParametersResult { successful: false, reason };
    let Some((_, spec, _)) = params.iter().find(|(n, _, _)| *n == p.name) else {
        return refuse(format!("no parameter `{}` (parameters are named `skill.param`)", p.name));
    };
    let value = match from_ros(&p.value, spec.ty) {
        Ok(v) => v,
        Err(e) => return refuse(format!("parameter `{}` {e}", p.name)),
    };
    let skill = p.name[..p.name.len() - spec.name.len() - 1].to_string();
    match handle.request_timeout(Request::SetParam { skill, param: spec.name.clone(), value }, REQUEST_TIMEOUT) {
        Ok(_) => SetParametersResult { successful: true, reason: String::new() },
        Err(e) => refuse(e.to_string()),
    }
}

/// `list_parameters` as rclcpp answers it: names under any of the prefixes (all without one),
/// at most `depth` dots below the prefix (0: any depth), and the prefixes of the names listed.
fn list(params: &[(String, ParamSpec, Value)], r: &ListParametersRequest) -> ListParametersResult {
    let within = |name: &str| {
        let rest = if r.prefixes.is_empty() {
            Some(name)
        } else {
            r.prefixes.iter().find_map(|pre| name.strip_prefix(pre.as_str())?.strip_prefix('.'))
        };
        rest.is_some_and(|rest| r.depth == 0 || (rest.matches('.').count() as u64) < r.depth)
    };
    let names: Vec<String> = params.iter().map(|p| p.0.clone()).filter(|n| within(n)).collect();
    let mut prefixes: Vec<String> =
        names.iter().filter_map(|n| n.rsplit_once('.').map(|(pre, _)| pre.to_string())).collect();
    prefixes.sort();
    prefixes.dedup();
    ListParametersResult { names, prefixes }
}

fn describe(name: &str, spec: &ParamSpec) -> ParameterDescriptor {
    let mut d = ParameterDescriptor {
        name: name.to_string(),
        ty: type_of(spec.ty),
        description: spec.doc.clone(),
        additional_constraints: if spec.unit.is_empty() { String::new() } else { format!("unit: {}", spec.unit) },
        read_only: false,
        dynamic_typing: false,
        floating_point_range: Vec::new(),
        integer_range: Vec::new(),
    };
    if spec.min.is_some() || spec.max.is_some() {
        match spec.ty {
            ParamType::F64 => d.floating_point_range.push(FloatingPointRange {
                from_value: spec.min.unwrap_or(f64::MIN),
                to_value: spec.max.unwrap_or(f64::MAX),
                step: 0.0,
            }),
            ParamType::I64 => d.integer_range.push(IntegerRange {
                from_value: spec.min.map_or(i64::MIN, |m| m.ceil() as i64),
                to_value: spec.max.map_or(i64::MAX, |m| m.floor() as i64),
                step: 0,
            }),
            _ => {}
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(name: &str, ty: ParamType) -> ParamSpec {
        ParamSpec::new(name, ty, Value::F64(0.0))
    }

    #[test]
    fn service_types_have_dds_names_and_rihs01_hashes() {
        assert_eq!(SET_BOOL.dds_name(), "std_srvs::srv::dds_::SetBool_");
        assert_eq!(GET_PARAMETERS.dds_name(), "rcl_interfaces::srv::dds_::GetParameters_");
        for t in [SET_BOOL, GET_PARAMETERS, SET_PARAMETERS, LIST_PARAMETERS, DESCRIBE_PARAMETERS, GET_PARAMETER_TYPES] {
            assert!(t.hash.starts_with("RIHS01_") && t.hash.len() == 7 + 64, "{t:?}");
        }
    }

    #[test]
    fn values_convert_both_ways_and_an_integer_is_taken_for_a_double() {
        for (v, ty) in [
            (Value::Bool(true), ParamType::Bool),
            (Value::I64(-3), ParamType::I64),
            (Value::F64(0.25), ParamType::F64),
            (Value::Str("a".into()), ParamType::Str),
        ] {
            assert_eq!(from_ros(&to_ros(&v), ty), Ok(v));
        }
        assert_eq!(from_ros(&to_ros(&Value::I64(2)), ParamType::F64), Ok(Value::F64(2.0)));
        assert_eq!(from_ros(&to_ros(&Value::F64(2.5)), ParamType::I64), Err("expects i64, got a double".to_string()));
        assert_eq!(
            from_ros(&ParameterValue::default(), ParamType::Bool),
            Err("expects bool, got no value".to_string())
        );
    }

    #[test]
    fn list_parameters_follows_prefixes_and_depth() {
        let p = |n: &str| (n.to_string(), spec("x", ParamType::F64), Value::F64(0.0));
        let params = vec![p("wander.speed"), p("wander.turn"), p("avoid.gain")];
        let all = list(&params, &ListParametersRequest { prefixes: vec![], depth: 0 });
        assert_eq!(all.names, vec!["wander.speed", "wander.turn", "avoid.gain"]);
        assert_eq!(all.prefixes, vec!["avoid", "wander"]);
        let wander = list(&params, &ListParametersRequest { prefixes: vec!["wander".into()], depth: 1 });
        assert_eq!(wander.names, vec!["wander.speed", "wander.turn"]);
        let shallow = list(&params, &ListParametersRequest { prefixes: vec![], depth: 1 });
        assert!(shallow.names.is_empty(), "{shallow:?}");
    }

    #[test]
    fn a_request_round_trips_through_cdr() {
        let r = SetParametersRequest {
            parameters: vec![Parameter {
                name: "wander.speed".into(),
                value: ParameterValue { ty: ptype::DOUBLE, double_value: 0.3, ..Default::default() },
            }],
        };
        let bytes = encode(&r).expect("encode");
        assert_eq!(&bytes[..4], &[0, 1, 0, 0], "CDR little-endian");
        assert_eq!(decode::<SetParametersRequest>(&bytes).expect("decode"), r);
        assert!(decode::<SetParametersRequest>(&bytes[..9]).is_err());
    }
}
