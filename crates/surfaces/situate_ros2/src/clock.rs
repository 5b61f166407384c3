//! ROS time: with `use_sim_time: true` the cycle follows `/clock` (`rosgraph_msgs/msg/Clock`)
//! from a simulator, as Gazebo-driven ROS 2 nodes do.
//!
//! The robot runs on its simulated clock, and this driver is its clock
//! ([`Request::ExternalClock`]): the manager runs a cycle only for the driver's
//! [`Request::Tick`], and only while it runs, so a `stop` (a client's, or a monitor's `pause`)
//! holds the cycle and a `run` lets the owed cycles through. The first `/clock` message anchors
//! the robot's time 0; from then on, whenever the clock has passed `n` whole periods since the
//! anchor, the robot has run exactly `n` cycles: one cycle per period of ROS time, none skipped
//! and none doubled, however the messages are spaced (a 10× clock in 1 ms messages, or one
//! message a second). When the clock stops, so does the cycle. A client's `step` runs the next
//! cycles as the clock's ticks come, even while the manager is stopped, and is answered then
//! (the manager's `spawned::Deferred`); the count is the manager's, so a driver asks for the
//! cycles due and the manager runs those not yet run. A clock that goes back (a simulator reset) re-anchors: the robot runs on from where it
//! is, never backwards, and says so in the log. So does a jump forward of more than
//! [`MAX_JUMP_S`] in one message (a simulator restarted at another time, or a `/clock` that is
//! no clock): the robot does not run the hours of cycles such a jump would owe.
//!
//! Messages are read on a Zenoh thread (the bounded CDR reader; one that cannot be read is
//! counted and ignored) and handed to the driver's thread through a slot that keeps the first
//! and the last message since the driver last looked (`Heard`): a driver that wakes late, on a
//! loaded machine, still anchors at the first message the robot heard, not at a later one. The
//! driver asks the manager for the cycles with `Tick` requests (at most [`MAX_STEP`] at once, so
//! a long jump of the clock leaves the robot answering between them).
//!
//! **Lock-step** (`Lockstep`, `lockstep: true`): the driver ticks one cycle at a time and
//! publishes the topics out after each; once a message's cycles have run, it puts the message's
//! time on the node's `~/cycle` topic, which a simulator waits for before its next step.

use std::sync::atomic::{AtomicBool, AtomicI64, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use situate_manager::{Handle, Request};
use zenoh::Wait;

use crate::msgs::{self, Clock};
use crate::{Ros2Error, Ros2Node};

/// `rosgraph_msgs/msg/Clock`, as rmw_zenoh names it.
pub const CLOCK_DDS: &str = "rosgraph_msgs::msg::dds_::Clock_";
/// Its RIHS01 hash (ROS 2 Jazzy; the Python tests check it against `rosbags`).
pub const CLOCK_HASH: &str = "RIHS01_692f7a66e93a3c83e71765d033b60349ba68023a8c689a79e48078bcb5c58564";

/// The most cycles one request runs: a jump of the clock is caught up in steps of this many.
pub const MAX_STEP: u64 = 1000;

/// The longest step forward of ROS time between two messages that is caught up cycle by cycle;
/// a longer one re-anchors, as a step back does.
pub const MAX_JUMP_S: i64 = 60;

/// The latest ROS time, shared with the bridge's publishers (for their stamps).
#[derive(Debug, Default)]
pub struct RosTime {
    /// ns since the epoch of ROS time; valid once `known`.
    ns: AtomicI64,
    known: AtomicBool,
}

impl RosTime {
    /// The latest `/clock` value, if one came.
    pub fn now(&self) -> Option<msgs::Time> {
        if !self.known.load(Ordering::Acquire) {
            return None;
        }
        Some(time_of(self.ns.load(Ordering::Acquire)))
    }
}

/// What the driver counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ClockStats {
    /// `/clock` messages read.
    pub messages: u64,
    /// Messages that could not be read.
    pub undecodable: u64,
    /// Cycles run for the clock.
    pub cycles: u64,
    /// Times the clock went back, or jumped forward more than [`MAX_JUMP_S`], and the anchor
    /// moved.
    pub resets: u64,
}

/// The `/clock` messages since the driver last looked, and whether it is to stop.
#[derive(Debug, Default)]
struct Heard {
    /// The first message's time and the last's (the same when one came).
    times: Option<(i64, i64)>,
    stop: bool,
}

#[derive(Default)]
struct Shared {
    latest: Mutex<Heard>,
    wake: Condvar,
    messages: AtomicU64,
    undecodable: AtomicU64,
    cycles: AtomicU64,
    resets: AtomicU64,
}

/// Lock-step (`lockstep: true`): the topics out, published by the driver as each cycle ends,
/// and the node's `~/cycle` publisher, put after them once the cycles a `/clock` message owed
/// have run.
pub(crate) struct Lockstep {
    pub(crate) topics: Vec<crate::Topic>,
    pub(crate) ack: zenoh::pubsub::Publisher<'static>,
    pub(crate) ack_gid: [u8; 16],
    pub(crate) ack_sequence: i64,
    /// Held while the publisher lives.
    pub(crate) _ack_token: zenoh::liveliness::LivelinessToken,
}

impl Lockstep {
    /// Declares the `~/cycle` publisher (entity `entity_id`) on `node`, blocking rather than
    /// dropping when the network is slow: a simulator waits for every one.
    pub(crate) fn declare(node: &Ros2Node, entity_id: u64, topics: Vec<crate::Topic>) -> Result<Lockstep, Ros2Error> {
        let fq = format!("{}/{}/cycle", node.name.namespace.trim_end_matches('/'), node.name.name);
        let key = node.name.service_key(&fq, CLOCK_DDS, CLOCK_HASH);
        let ack = node
            .session
            .declare_publisher(key.clone())
            .congestion_control(zenoh::qos::CongestionControl::Block)
            .wait()
            .map_err(|e| Ros2Error::Zenoh { what: format!("a publisher on `{key}`"), message: e.to_string() })?;
        let token_key = node.name.entity_token(&node.zid, node.node_id, entity_id, "MP", &fq, CLOCK_DDS, CLOCK_HASH);
        let token = node.declare_token(&token_key)?;
        tracing::info!(topic = %fq, %key, "lock-step: the cycles done are published");
        Ok(Lockstep { topics, ack, ack_gid: crate::rmw::gid(&token_key), ack_sequence: 0, _ack_token: token })
    }

    /// Publishes the topics out written since they were last published, stamped `stamp`.
    fn publish_outputs(&mut self, handle: &Handle, time: &RosTime) {
        crate::publish_new(handle, &mut self.topics, Some(time));
    }

    /// Says the robot has run its cycles up to ROS time `ns`.
    fn publish_done(&mut self, ns: i64) {
        let done = Clock { clock: time_of(ns) };
        let payload = match msgs::encode(&done) {
            Ok(p) => p,
            Err(e) => {
                tracing::warn!(error = %e, "lock-step: cannot encode ~/cycle");
                return;
            }
        };
        self.ack_sequence += 1;
        let attachment = crate::rmw::attachment(self.ack_sequence, crate::wall_ns(), &self.ack_gid);
        if let Err(e) = self.ack.put(payload).attachment(attachment).wait() {
            tracing::warn!(error = %e, "lock-step: the ~/cycle put failed");
        }
    }
}

fn time_of(ns: i64) -> msgs::Time {
    msgs::Time {
        sec: i32::try_from(ns.div_euclid(1_000_000_000)).unwrap_or(i32::MAX),
        nanosec: ns.rem_euclid(1_000_000_000) as u32,
    }
}

/// The running driver; dropping it stops it and undeclares its subscription.
pub struct ClockDriver {
    shared: Arc<Shared>,
    time: Arc<RosTime>,
    thread: Option<JoinHandle<()>>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
    _token: zenoh::liveliness::LivelinessToken,
}

impl ClockDriver {
    /// Subscribes to `/clock` on `node` (holding its `MS` token, entity `entity_id`) and steps
    /// the robot behind `handle`, whose period is `period_s`, one cycle per period of ROS time.
    /// The manager's cycle follows this clock from now on ([`Request::ExternalClock`]): it runs
    /// while the manager runs, and a stop (a pausing monitor, a client's `stop`) holds it. With
    /// `lockstep`, the topics out are published by the driver as each cycle ends.
    pub(crate) fn start(
        node: &Ros2Node,
        entity_id: u64,
        handle: Handle,
        period_s: f64,
        lockstep: Option<Lockstep>,
    ) -> Result<ClockDriver, Ros2Error> {
        let shared = Arc::new(Shared::default());
        let time = Arc::new(RosTime::default());
        let key = node.name.service_key("/clock", CLOCK_DDS, CLOCK_HASH);
        let (s, t) = (Arc::clone(&shared), Arc::clone(&time));
        let subscriber = node
            .session
            .declare_subscriber(key.clone())
            .callback(move |sample| {
                s.messages.fetch_add(1, Ordering::Relaxed);
                let payload = sample.payload().to_bytes();
                match msgs::decode::<Clock>(&payload) {
                    Ok(c) => {
                        let ns = i64::from(c.clock.sec) * 1_000_000_000 + i64::from(c.clock.nanosec);
                        t.ns.store(ns, Ordering::Release);
                        t.known.store(true, Ordering::Release);
                        let mut latest = s.latest.lock().unwrap_or_else(|p| p.into_inner());
                        let first = latest.times.map_or(ns, |(first, _)| first);
                        latest.times = Some((first, ns));
                        s.wake.notify_one();
                    }
                    Err(e) => {
                        if s.undecodable.fetch_add(1, Ordering::Relaxed) == 0 {
                            tracing::warn!(error = %e, "a /clock message could not be read; ignored (and counted)");
                        }
                    }
                }
            })
            .wait()
            .map_err(|e| Ros2Error::Zenoh { what: format!("a subscriber on `{key}`"), message: e.to_string() })?;
        let token_key =
            node.name.entity_token(&node.zid, node.node_id, entity_id, "MS", "/clock", CLOCK_DDS, CLOCK_HASH);
        let token = node.declare_token(&token_key)?;
        handle
            .request_timeout(Request::ExternalClock { on: true }, Duration::from_secs(30))
            .map_err(|e| Ros2Error::Period(format!("the manager did not take the external clock: {e}")))?;
        let period_ns = (period_s * 1e9).round().max(1.0) as i64;
        let (s, t) = (Arc::clone(&shared), Arc::clone(&time));
        // Woken by a ManagerStarted event too: cycles owed while the robot was stopped run then.
        let events = handle.events();
        let thread = std::thread::Builder::new()
            .name("situate-ros-time".into())
            .spawn(move || Driver { shared: &s, time: &t, handle: &handle, events, period_ns, lockstep }.run())
            .map_err(Ros2Error::Thread)?;
        tracing::info!(%key, period_s, "the cycle follows ROS time (/clock)");
        Ok(ClockDriver { shared, time, thread: Some(thread), _subscriber: subscriber, _token: token })
    }

    /// The latest ROS time, for stamps.
    pub fn time(&self) -> Arc<RosTime> {
        Arc::clone(&self.time)
    }

    /// What it counted so far.
    pub fn stats(&self) -> ClockStats {
        let s = &self.shared;
        ClockStats {
            messages: s.messages.load(Ordering::Relaxed),
            undecodable: s.undecodable.load(Ordering::Relaxed),
            cycles: s.cycles.load(Ordering::Relaxed),
            resets: s.resets.load(Ordering::Relaxed),
        }
    }
}

impl Drop for ClockDriver {
    fn drop(&mut self) {
        {
            let mut latest = self.shared.latest.lock().unwrap_or_else(|p| p.into_inner());
            latest.stop = true;
            self.shared.wake.notify_one();
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The cycles owed at ROS time `now_ns`, with `anchor_ns` the robot's time 0.
pub fn cycles_due(anchor_ns: i64, now_ns: i64, period_ns: i64) -> u64 {
    u64::try_from((now_ns.saturating_sub(anchor_ns)) / period_ns.max(1)).unwrap_or(0)
}

/// Where the robot's cycles stand against ROS time: the anchor (ROS time `.0` is the robot's
/// cycle `.1`) and the last time heard.
#[derive(Debug, Default)]
struct Anchor {
    at: Option<(i64, u64)>,
    last: Option<i64>,
}

impl Anchor {
    /// Messages came, `first` to `now` (the driver may look once for several), while the
    /// robot's count is `cycle`. The first message ever (or the first after a reset) anchors
    /// the count: a driver that looks late still owes the cycles from it. A step back, or a
    /// jump forward of more than [`MAX_JUMP_S`], re-anchors at the time after it (moved to the
    /// count then, so the count stays continuous); that step is returned.
    fn hear(&mut self, first: i64, now: i64, cycle: u64) -> Option<(i64, i64)> {
        let wild = |from: i64, to: i64| !(0..=MAX_JUMP_S * 1_000_000_000).contains(&to.saturating_sub(from));
        let mut reset = None;
        let mut from_here = first;
        if let Some(l) = self.last.filter(|&l| wild(l, first)) {
            reset = Some((l, first));
        }
        if wild(first, now) {
            reset = Some((first, now));
            from_here = now;
        }
        if reset.is_some() {
            self.at = None;
        }
        self.last = Some(now);
        self.at.get_or_insert((from_here, cycle));
        reset
    }

    /// The last time heard and the robot's cycle count it owes, once a message came.
    fn target(&self, period_ns: i64) -> Option<(i64, u64)> {
        let (now, (a_ns, a_cycle)) = (self.last?, self.at?);
        Some((now, a_cycle.saturating_add(cycles_due(a_ns, now, period_ns))))
    }
}

/// While cycles are owed and the robot is stopped, it is asked again this often (a client's
/// `step` may have run them): the stop ends with a `ManagerStarted` event, which wakes the
/// driver at once.
const OWED_POLL: Duration = Duration::from_millis(20);

struct Driver<'a> {
    shared: &'a Shared,
    time: &'a RosTime,
    handle: &'a Handle,
    events: crossbeam_channel::Receiver<situate_manager::Event>,
    period_ns: i64,
    lockstep: Option<Lockstep>,
}

/// What a wait for the next thing to do found.
enum Woken {
    /// `/clock` messages came: the first one's time and the last one's.
    Clock(i64, i64),
    Look,
    Stop,
}

impl Driver<'_> {
    fn run(mut self) {
        let mut anchor = Anchor::default();
        // The manager's cycle count, as its last reply said.
        let mut cycle = match self.handle.request_timeout(Request::QueryStats, Duration::from_secs(30)) {
            Ok(situate_manager::Reply::Stats(s)) => s.cycle,
            _ => 0,
        };
        // A /clock message came whose cycles are not yet said done (lock-step).
        let mut unanswered = false;
        let mut owed = false;
        loop {
            match self.wait(owed) {
                Woken::Stop => return,
                Woken::Look => {}
                Woken::Clock(first, now) => {
                    if let Some((from, to)) = anchor.hear(first, now, cycle) {
                        self.shared.resets.fetch_add(1, Ordering::Relaxed);
                        let how = if to < from { "went back" } else { "jumped forward" };
                        tracing::warn!(from_ns = from, to_ns = to, "ROS time {how}: the cycle goes on from here");
                    }
                    unanswered = true;
                }
            }
            let Some((now, target)) = anchor.target(self.period_ns) else { continue };
            owed = false;
            // The topics out were published after the last cycle that ran (each is a query of the
            // manager: not asked twice for the same cycle).
            let mut published = false;
            // Ask even when nothing seems owed: a client's `step` may have moved the count.
            loop {
                let until = if self.lockstep.is_some() {
                    cycle.saturating_add(1).min(target.max(cycle))
                } else {
                    target.min(cycle.saturating_add(MAX_STEP))
                };
                let reply = self.handle.request_timeout(Request::Tick { until }, Duration::from_secs(600));
                let (ran, after) = match reply {
                    Ok(situate_manager::Reply::Ticked { ran, cycle }) => (ran, cycle),
                    Ok(other) => {
                        tracing::warn!(?other, "ROS time: an unexpected reply to a tick; the driver stops");
                        return;
                    }
                    Err(e) => {
                        tracing::warn!(error = %e, "ROS time: the manager did not step; the driver stops");
                        return;
                    }
                };
                self.shared.cycles.fetch_add(ran, Ordering::Relaxed);
                cycle = after;
                if ran > 0 {
                    if let Some(l) = self.lockstep.as_mut() {
                        l.publish_outputs(self.handle, self.time);
                        published = true;
                    }
                }
                if self.stopping() {
                    return;
                }
                if cycle >= target {
                    break;
                }
                if after < until {
                    // Stopped: the rest waits for a run (or a client's steps).
                    owed = true;
                    break;
                }
            }
            if !owed && unanswered {
                if let Some(l) = self.lockstep.as_mut() {
                    // Cycles a client's `step` ran (no tick ran one) have outputs to go out too.
                    if !published {
                        l.publish_outputs(self.handle, self.time);
                    }
                    l.publish_done(now);
                }
                unanswered = false;
            }
        }
    }

    fn stopping(&self) -> bool {
        self.shared.latest.lock().unwrap_or_else(|p| p.into_inner()).stop
    }

    /// Waits for a `/clock` message, or (`owed`) a `ManagerStarted` event or [`OWED_POLL`].
    fn wait(&self, owed: bool) -> Woken {
        let mut latest = self.shared.latest.lock().unwrap_or_else(|p| p.into_inner());
        loop {
            if latest.stop {
                return Woken::Stop;
            }
            if let Some((first, last)) = latest.times.take() {
                return Woken::Clock(first, last);
            }
            if owed {
                // Drained without holding the lock long: events are few (a start, a stop, prints).
                let started =
                    self.events.try_iter().any(|e| matches!(e, situate_manager::Event::ManagerStarted { .. }));
                if started {
                    return Woken::Look;
                }
                let (back, timeout) =
                    self.shared.wake.wait_timeout(latest, OWED_POLL).unwrap_or_else(|p| p.into_inner());
                latest = back;
                if timeout.timed_out() {
                    return Woken::Look;
                }
            } else {
                // Keep the events from piling up while nothing is owed.
                while self.events.try_recv().is_ok() {}
                latest = self.shared.wake.wait(latest).unwrap_or_else(|p| p.into_inner());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_cycle_per_whole_period_since_the_anchor() {
        let p = 10_000_000; // 10 ms
        assert_eq!(cycles_due(0, 0, p), 0);
        assert_eq!(cycles_due(0, 9_999_999, p), 0);
        assert_eq!(cycles_due(0, 10_000_000, p), 1);
        assert_eq!(cycles_due(5, 1_000_000_005, p), 100);
        assert_eq!(cycles_due(100, 50, p), 0, "before the anchor: none");
    }

    const MS: i64 = 1_000_000;

    #[test]
    fn a_driver_that_looks_late_anchors_at_the_first_message_the_robot_heard() {
        // Ticks at 100 ms and 200 ms came before the driver looked (a loaded machine): the
        // robot heard 100 ms first, so at 200 ms it owes one cycle, as if it had looked at once.
        let mut a = Anchor::default();
        assert_eq!(a.target(100 * MS), None, "no message: nothing owed");
        assert_eq!(a.hear(100 * MS, 200 * MS, 0), None);
        assert_eq!(a.target(100 * MS), Some((200 * MS, 1)));
        let mut at_once = Anchor::default();
        at_once.hear(100 * MS, 100 * MS, 0);
        at_once.hear(200 * MS, 200 * MS, 0);
        assert_eq!(at_once.target(100 * MS), a.target(100 * MS));
    }

    #[test]
    fn a_step_back_or_a_long_jump_re_anchors_where_the_count_is() {
        let mut a = Anchor::default();
        a.hear(0, 500 * MS, 0);
        assert_eq!(a.target(100 * MS), Some((500 * MS, 5)));
        // Back to 0 among the messages of one look: anchored at the time after the step.
        assert_eq!(a.hear(600 * MS, 0, 5), Some((600 * MS, 0)));
        assert_eq!(a.target(100 * MS), Some((0, 5)), "runs on from cycle 5, never backwards");
        // A jump of an hour between looks: re-anchored at the first message after it.
        let hour = 3600 * 1000 * MS;
        assert_eq!(a.hear(hour, hour + 300 * MS, 5), Some((0, hour)));
        assert_eq!(a.target(100 * MS), Some((hour + 300 * MS, 8)));
        // Steady steps never re-anchor.
        assert_eq!(a.hear(hour + 400 * MS, hour + 900 * MS, 8), None);
        assert_eq!(a.target(100 * MS), Some((hour + 900 * MS, 14)));
    }
}
