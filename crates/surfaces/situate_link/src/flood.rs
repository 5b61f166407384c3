//! A flood of worst-case requests from several real clients, for the test
//! and the benchmark that check the link cannot hurt the cycle (issue 17).
//!
//! Each client is its own Zenoh session on its own thread, keeping a number
//! of queries in flight and sending the next as soon as one is answered.
//! The requests are the costliest the protocol allows: names of the longest
//! size that name nothing (so the "did you mean" search runs), lists of the
//! most items, conditions of the longest size (valid ones, added and
//! cancelled again, and ones whose last name is unknown), every query verb,
//! and `monitor_add`/`monitor_cancel` churn.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use serde_json::{json, Value as Json};
use zenoh::handlers::FifoChannelHandler;
use zenoh::query::Reply;
use zenoh::Wait;

use crate::json::{MAX_CONDITION_CHARS, MAX_LIST_ITEMS, MAX_NAME_CHARS, MAX_PAYLOAD_BYTES};
use crate::{Client, ClientError};

/// What the flood aims at: a robot and some of its real names, so that the
/// requests reach the costliest paths (a known skill's parameters, an array
/// signal's elements).
#[derive(Debug, Clone)]
pub struct Target {
    pub endpoints: Vec<String>,
    pub robot: String,
    /// A skill of the robot.
    pub skill: String,
    /// A numeric array signal leaf of the robot (such as `sonar.range`).
    pub array_signal: String,
}

/// What the clients sent and got back.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FloodCount {
    pub sent: u64,
    /// Replies `ok` or `error` from the manager.
    pub answered: u64,
    /// Replies `unavailable` (the link's queue was full).
    pub busy: u64,
    /// Queries that ended with no reply.
    pub unanswered: u64,
    /// Monitors added (each cancelled again).
    pub monitors: u64,
}

impl std::ops::AddAssign for FloodCount {
    fn add_assign(&mut self, o: FloodCount) {
        self.sent += o.sent;
        self.answered += o.answered;
        self.busy += o.busy;
        self.unanswered += o.unanswered;
        self.monitors += o.monitors;
    }
}

/// Clients flooding a robot until [`Flood::stop`].
pub struct Flood {
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<Result<FloodCount, String>>>,
}

/// A name of the longest size that names nothing of the robot.
pub fn unknown_name(seed: usize) -> String {
    let head = format!("no_such_{seed}_");
    let mut s = head.clone();
    while s.len() < MAX_NAME_CHARS {
        s.push(char::from(b'a' + (s.len() % 26) as u8));
    }
    s
}

/// A valid condition of about `chars` characters over `signal`'s elements,
/// with nearly as many parts as a condition may have (40 comparisons; their
/// numbers padded with zeros to the length).
fn long_condition(signal: &str, chars: usize) -> String {
    const TERMS: usize = 40;
    let terms: Vec<String> = (0..TERMS).map(|i| format!("{signal}[{}] < {}.5", i % 4, 1000 + i)).collect();
    let bare = terms.iter().map(String::len).sum::<usize>() + 4 * (TERMS - 1);
    let pad = chars.saturating_sub(bare) / TERMS;
    terms.iter().map(|t| format!("{t}{}", "0".repeat(pad))).collect::<Vec<_>>().join(" || ")
}

/// The worst-case requests, as (verb, arguments); every one fits the
/// protocol's limits.
pub fn worst_case_requests(target: &Target) -> Vec<(&'static str, Json)> {
    let (skill, signal) = (&target.skill, &target.array_signal);
    let unknown = unknown_name(0);
    // A long valid condition whose last name is unknown: compiled to the end.
    let bad_tail = |chars: usize| {
        let tail = format!(" || {} > 1", unknown_name(1));
        format!("{}{tail}", long_condition(signal, chars - tail.len()))
    };
    // As many conditions of an `any` as the payload holds.
    let per = (MAX_PAYLOAD_BYTES - 1024) / 64 - 8;
    let any_bad: Vec<String> = (0..64).map(|_| bad_tail(per.min(MAX_CONDITION_CHARS))).collect();
    let any_good: Vec<String> = (0..64).map(|_| long_condition(signal, per.min(MAX_CONDITION_CHARS))).collect();
    let mut known_then_unknown: Vec<String> = vec![skill.clone(); MAX_LIST_ITEMS - 1];
    known_then_unknown.push(unknown.clone());
    let many_unknown: Vec<String> = (0..(MAX_PAYLOAD_BYTES - 64) / (MAX_NAME_CHARS + 3)).map(unknown_name).collect();
    vec![
        ("query", json!({"signal": unknown})),
        ("skill", json!({"skill": unknown})),
        ("get_param", json!({"skill": skill, "param": unknown})),
        ("set_param", json!({"skill": unknown, "param": unknown, "value": 1.0})),
        ("set_priority", json!({"skill": unknown, "priority": 3})),
        ("activate", json!({"skills": known_then_unknown})),
        ("deactivate", json!({"skills": many_unknown})),
        ("monitor_add", json!({"condition": bad_tail(MAX_CONDITION_CHARS)})),
        ("monitor_add", json!({"any": any_bad})),
        ("monitor_add", json!({"condition": long_condition(signal, MAX_CONDITION_CHARS), "mode": "level"})),
        ("monitor_add", json!({"any": any_good, "mode": "edge"})),
        ("monitor_add", json!({"condition": format!("{signal}[0] > -1"), "report": [unknown]})),
        ("query", json!({"signal": signal})),
        ("skills", json!({})),
        ("graph", json!({})),
        ("winners", json!({})),
        ("stats", json!({})),
        ("monitor_list", json!({})),
        ("monitor_cancel", json!({"monitor": 0})),
    ]
}

impl Flood {
    /// Starts `clients` clients, each keeping `in_flight` queries out.
    pub fn start(target: &Target, clients: usize, in_flight: usize) -> Result<Flood, ClientError> {
        let stop = Arc::new(AtomicBool::new(false));
        let requests = Arc::new(worst_case_requests(target));
        let mut sessions = Vec::new();
        for _ in 0..clients {
            sessions.push(Client::connect(&target.endpoints)?);
        }
        let threads = sessions
            .into_iter()
            .enumerate()
            .map(|(k, client)| {
                let (stop, requests, robot) = (Arc::clone(&stop), Arc::clone(&requests), target.robot.clone());
                std::thread::Builder::new()
                    .name(format!("flood-{k}"))
                    .spawn(move || flood(&client, &robot, &requests, k, in_flight.max(1), &stop))
                    .map_err(|e| ClientError::Send { key: "flood".into(), detail: e.to_string() })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Flood { stop, threads })
    }

    /// Stops the clients (each waits for the answers it still expects) and
    /// sums what they counted; an error if a reply was not the protocol's.
    pub fn stop(self) -> Result<FloodCount, String> {
        self.stop.store(true, Ordering::SeqCst);
        let mut total = FloodCount::default();
        for t in self.threads {
            total += t.join().map_err(|_| "a flood client panicked".to_string())??;
        }
        Ok(total)
    }
}

type Replies = FifoChannelHandler<Reply>;

fn send(client: &Client, robot: &str, verb: &str, args: &Json) -> Result<Replies, String> {
    client
        .session()
        .get(format!("situate/{robot}/req/{verb}"))
        .payload(args.to_string())
        .timeout(Duration::from_secs(60))
        .wait()
        .map_err(|e| format!("could not send `{verb}`: {e}"))
}

fn flood(
    client: &Client,
    robot: &str,
    requests: &[(&'static str, Json)],
    offset: usize,
    in_flight: usize,
    stop: &AtomicBool,
) -> Result<FloodCount, String> {
    let mut count = FloodCount::default();
    let mut out: VecDeque<(&'static str, Replies)> = VecDeque::new();
    let mut next = offset;
    loop {
        let stopping = stop.load(Ordering::SeqCst);
        while !stopping && out.len() < in_flight {
            let (verb, args) = &requests[next % requests.len()];
            next += 1;
            out.push_back((verb, send(client, robot, verb, args)?));
            count.sent += 1;
        }
        let Some((verb, replies)) = out.pop_front() else { return Ok(count) };
        let Ok(reply) = replies.recv() else {
            count.unanswered += 1;
            continue;
        };
        let body: Json = match reply.result() {
            Ok(sample) => serde_json::from_slice(&sample.payload().to_bytes())
                .map_err(|e| format!("`{verb}`: a reply that is not JSON: {e}"))?,
            Err(_) => {
                count.unanswered += 1;
                continue;
            }
        };
        if body.pointer("/error/kind").and_then(Json::as_str) == Some("unavailable") {
            count.busy += 1;
        } else if body.get("ok").is_some() || body.get("error").is_some() {
            count.answered += 1;
        } else {
            return Err(format!("`{verb}`: a reply that is neither ok nor error: {body}"));
        }
        // Churn: every monitor added is cancelled again.
        if let Some(id) = body.pointer("/ok/monitor").and_then(Json::as_u64) {
            count.monitors += 1;
            out.push_back(("monitor_cancel", send(client, robot, "monitor_cancel", &json!({"monitor": id}))?));
            count.sent += 1;
        }
    }
}
