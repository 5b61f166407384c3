//! A blocking client of the link, for the `situate` program's client verbs
//! and for Rust sequencers.

use std::time::{Duration, Instant};

use serde_json::Value as Json;
use zenoh::{Session, Wait};

use crate::session::client_config;
use crate::LinkError;

/// How often a request that found nobody to ask is sent again (see [`Client::request`]).
const RETRY: Duration = Duration::from_millis(50);

/// An error reply from the manager: its `kind` and message.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct RemoteError {
    pub kind: String,
    pub message: String,
    /// The whole error object (extra members such as `column`).
    pub detail: Json,
}

/// Why a client call failed. Each displays as a sentence for a person,
/// never as the link's own data.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    #[error(transparent)]
    Link(#[from] LinkError),
    #[error(transparent)]
    Remote(#[from] RemoteError),
    /// Nobody answered: no manager serves that key (or its access rules
    /// drop the request).
    #[error(
        "no skill manager answered `{key}` within {} (is `situate run` running and reachable at {endpoints}, or did it refuse this client's credentials or access rules?)",
        seconds(*timeout)
    )]
    NoAnswer { key: String, timeout: Duration, endpoints: String },
    /// The request was still unanswered when the timeout ended it: the
    /// manager may be busy or stuck, or not there at all.
    #[error(
        "no answer from robot `{robot}` to `{verb}` within {} (is it running, is its cycle stuck, or do its access rules drop this request? a longer --timeout may help a busy one)",
        seconds(*timeout)
    )]
    TimedOut { robot: String, verb: String, timeout: Duration },
    /// The link itself refused or failed the request (Zenoh's error reply).
    #[error("`{key}` failed on the link: {detail}")]
    Failed { key: String, detail: String },
    #[error("could not send `{key}`: {detail}")]
    Send { key: String, detail: String },
    #[error(
        "no skill manager answered at {endpoints}: nothing could be reached there; is `situate run` running, and does it accept these credentials (user and password, certificates)?{detail}"
    )]
    NotReachable { endpoints: String, detail: String },
    #[error("several robots answered ({0}); name one with --robot")]
    Ambiguous(String),
    /// The robot named did not answer, and others did: most likely a misspelt name.
    #[error("robot `{robot}` did not answer; {} (name it with --robot)", answering_text(answering))]
    OtherRobots { robot: String, answering: Vec<String> },
    #[error("a reply that is not the protocol's JSON: {0}")]
    BadReply(String),
}

/// How long a request finds nobody serving its robot's key before [`Client::request`] asks
/// which robots do answer (a robot still starting declares its keys within this).
pub const NAMED_GRACE: Duration = Duration::from_secs(1);

/// `robot `a` did` / `robots `a`, `b` did`.
fn answering_text(robots: &[String]) -> String {
    let names: Vec<String> = robots.iter().map(|r| format!("`{r}`")).collect();
    match names.as_slice() {
        [one] => format!("robot {one} did"),
        _ => format!("robots {} did", names.join(", ")),
    }
}

/// A duration as a person writes it: `5 s`, `0.5 s`.
fn seconds(d: Duration) -> String {
    format!("{} s", d.as_secs_f64())
}

/// What an error reply from Zenoh says, as text (never its bytes' debug form).
fn reply_error_text(e: &zenoh::query::ReplyError) -> String {
    let bytes = e.payload().to_bytes();
    let text = String::from_utf8_lossy(&bytes);
    let text = text.trim();
    if text.is_empty() {
        "an error with no message".to_string()
    } else {
        let short: String = text.chars().take(200).collect();
        short
    }
}

/// A connection to the Zenoh network the managers are on.
pub struct Client {
    session: Session,
    endpoints: Vec<String>,
    pub timeout: Duration,
    /// The name this connection gives itself: sent as `monitor_add`'s
    /// `client` (unless the arguments name one), shown with its monitors.
    pub client_id: String,
    /// Per robot, the session that holds this connection's monitors
    /// ([`crate::client_session`]): opened at the first request about a
    /// monitor, ended when the connection is dropped.
    sessions: std::sync::Mutex<std::collections::HashMap<String, crate::client_session::ClientSession>>,
}

impl Client {
    pub fn connect(endpoints: &[String]) -> Result<Client, ClientError> {
        Client::connect_with(endpoints, None)
    }

    /// Connects with extra Zenoh configuration merged in (credentials, TLS).
    pub fn connect_with(endpoints: &[String], extra: Option<&Json>) -> Result<Client, ClientError> {
        let session = zenoh::open(client_config(endpoints, extra)?).wait().map_err(|e| ClientError::NotReachable {
            endpoints: endpoints.join(", "),
            detail: unreachable_detail(&e.to_string()),
        })?;
        let client_id = format!("rs-{}-{}", std::process::id(), session.zid());
        Ok(Client {
            session,
            endpoints: endpoints.to_vec(),
            timeout: Duration::from_secs(5),
            client_id,
            sessions: Default::default(),
        })
    }

    pub fn session(&self) -> &Session {
        &self.session
    }

    fn no_answer(&self, key: &str) -> ClientError {
        ClientError::NoAnswer { key: key.into(), timeout: self.timeout, endpoints: self.endpoints.join(", ") }
    }

    /// Sends one request; returns the `ok` result or the error reply.
    pub fn request(&self, robot: &str, verb: &str, args: &Json) -> Result<Json, ClientError> {
        let key = format!("situate/{robot}/req/{verb}");
        let mut args = std::borrow::Cow::Borrowed(args);
        if verb == "monitor_add" && args.get("client").is_none() {
            if let Some(obj) = args.to_mut().as_object_mut() {
                obj.insert("client".into(), Json::String(self.client_id.clone()));
            }
        }
        if matches!(verb, "monitor_add" | "monitor_cancel") && args.get("session").is_none() {
            let secret = self.session_secret(robot)?;
            if let Some(obj) = args.to_mut().as_object_mut() {
                obj.insert("session".into(), Json::String(secret));
            }
        }
        // A get that finds nobody to ask ends at once with no reply (a robot that has opened its
        // endpoint but not yet declared its requests, just after it started): nothing was
        // delivered, so it is asked again until the timeout. A robot that took the request and
        // did not answer ends it with a `Timeout` reply instead, never asked again.
        let deadline = Instant::now() + self.timeout;
        let mut retried = false;
        // Nobody serving the key a while (`NAMED_GRACE`): are other robots there? Then the name
        // is likely misspelt, and the error names them at once instead of waiting out the
        // timeout for a robot that is not coming. Asked once; a robot still starting beside
        // none other is still waited for.
        let mut others_asked = false;
        let since = Instant::now();
        let (replies, reply) = loop {
            let left = deadline.saturating_duration_since(Instant::now()).max(Duration::from_millis(1));
            let replies = self
                .session
                .get(&key)
                .payload(args.to_string())
                .timeout(left)
                .wait()
                .map_err(|e| ClientError::Send { key: key.clone(), detail: e.to_string() })?;
            match replies.recv() {
                Ok(reply) => break (replies, reply),
                Err(_) if Instant::now() < deadline => {
                    retried = true;
                    if !others_asked && since.elapsed() >= NAMED_GRACE {
                        others_asked = true;
                        let left = deadline.saturating_duration_since(Instant::now());
                        let answering = self.robots_until(|found| !found.is_empty(), left)?;
                        if !answering.is_empty() && !answering.iter().any(|r| r == robot) {
                            return Err(ClientError::OtherRobots { robot: robot.into(), answering });
                        }
                    }
                    std::thread::sleep(RETRY.min(left))
                }
                Err(_) => return Err(self.no_answer(&key)),
            }
        };
        // Hold the channel until Zenoh ends the query (at once after an answer, at the timeout
        // at the latest): dropped earlier, Zenoh logs an error for what it still delivers, a
        // stray line on the client's stderr.
        while replies.recv().is_ok() {}
        let sample = reply.result().map_err(|e| match reply_error_text(e).as_str() {
            // Zenoh ends a query its timeout cut short with this error. After gets that found
            // nobody, it is the last one's short remainder running out (on a busy machine,
            // before Zenoh found nobody again): still nobody answered.
            "Timeout" if retried => self.no_answer(&key),
            "Timeout" => ClientError::TimedOut { robot: robot.into(), verb: verb.into(), timeout: self.timeout },
            detail => ClientError::Failed { key: key.clone(), detail: detail.into() },
        })?;
        let body: Json =
            serde_json::from_slice(&sample.payload().to_bytes()).map_err(|e| ClientError::BadReply(e.to_string()))?;
        if let Some(ok) = body.get("ok") {
            return Ok(ok.clone());
        }
        match body.get("error") {
            Some(err) => Err(RemoteError {
                kind: err.get("kind").and_then(Json::as_str).unwrap_or("unknown").into(),
                message: err.get("message").and_then(Json::as_str).unwrap_or("").into(),
                detail: err.clone(),
            }
            .into()),
            None => Err(ClientError::BadReply(body.to_string())),
        }
    }

    /// The secret of this connection's session with `robot`, opened now if need be.
    fn session_secret(&self, robot: &str) -> Result<String, ClientError> {
        let mut sessions = self.sessions.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(s) = sessions.get(robot) {
            return Ok(s.secret().to_string());
        }
        let opened = crate::client_session::ClientSession::open(&self.session, robot)
            .map_err(|detail| ClientError::Send { key: crate::client_session::token_key(robot, "…"), detail })?;
        let secret = opened.secret().to_string();
        sessions.insert(robot.to_string(), opened);
        Ok(secret)
    }

    /// The public id of this connection's session with `robot`, if one is open
    /// (what `monitor_list` shows as `session` for its monitors).
    pub fn session_id(&self, robot: &str) -> Option<String> {
        self.sessions.lock().unwrap_or_else(|p| p.into_inner()).get(robot).map(|s| s.id().to_string())
    }

    /// The robots whose managers answer `hello`.
    /// Asks until one answers or the timeout (at most 2 s) is over, as [`Client::request`]
    /// asks again a robot that is still starting.
    pub fn robots(&self) -> Result<Vec<String>, ClientError> {
        self.robots_until(|found| !found.is_empty(), self.timeout.min(Duration::from_secs(2)))
    }

    /// Asks `hello` of every robot until `enough` holds for those that answered, or `limit` is
    /// over; the robots that answered, sorted.
    fn robots_until(&self, enough: impl Fn(&[String]) -> bool, limit: Duration) -> Result<Vec<String>, ClientError> {
        let deadline = Instant::now() + limit;
        loop {
            let left = deadline.saturating_duration_since(Instant::now()).max(Duration::from_millis(1));
            let replies = self
                .session
                .get("situate/*/req/hello")
                .timeout(left)
                .wait()
                .map_err(|e| ClientError::Send { key: "situate/*/req/hello".into(), detail: e.to_string() })?;
            let mut robots = Vec::new();
            while let Ok(reply) = replies.recv() {
                if let Ok(sample) = reply.result() {
                    if let Ok(body) = serde_json::from_slice::<Json>(&sample.payload().to_bytes()) {
                        if let Some(r) = body.pointer("/ok/robot").and_then(Json::as_str) {
                            robots.push(r.to_string());
                        }
                    }
                }
            }
            robots.sort();
            robots.dedup();
            if enough(&robots) || Instant::now() >= deadline {
                return Ok(robots);
            }
            std::thread::sleep(RETRY.min(left));
        }
    }

    /// The robot to talk to: `name` if given, else the only one answering.
    pub fn resolve_robot(&self, name: Option<&str>) -> Result<String, ClientError> {
        if let Some(n) = name {
            return Ok(n.to_string());
        }
        let robots = self.robots()?;
        match robots.len() {
            0 => Err(self.no_answer("situate/*/req/hello")),
            1 => Ok(robots[0].clone()),
            _ => Err(ClientError::Ambiguous(robots.join(", "))),
        }
    }

    /// Subscribes to `situate/<robot>/<suffix>`; each payload is parsed as JSON.
    pub fn subscribe(
        &self,
        robot: &str,
        suffix: &str,
    ) -> Result<(zenoh::pubsub::Subscriber<()>, crossbeam_channel::Receiver<Json>), LinkError> {
        let (tx, rx) = crossbeam_channel::unbounded();
        let sub = self
            .session
            .declare_subscriber(format!("situate/{robot}/{suffix}"))
            .callback(move |sample| {
                if let Ok(j) = serde_json::from_slice::<Json>(&sample.payload().to_bytes()) {
                    let _ = tx.send(j);
                }
            })
            .wait()
            .map_err(|e| LinkError::Open(e.to_string()))?;
        Ok((sub, rx))
    }
}

/// What Zenoh said when nothing could be reached, as a parenthesis for the
/// message: nothing when it only repeats that (its text then holds Rust debug
/// output of the endpoints, `[Single(tcp/…)]`), else its first clause.
fn unreachable_detail(zenoh: &str) -> String {
    let first = zenoh.split(" at ").next().unwrap_or_default().trim();
    if first.is_empty() || first.starts_with("Unable to connect to any of") {
        String::new()
    } else {
        format!(" ({first})")
    }
}
