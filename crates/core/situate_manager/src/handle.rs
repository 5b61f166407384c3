//! The handle to a spawned manager and the event bus: how the control API
//! ([`crate::control`]) reaches a manager on its own thread. The API's
//! types live in `control`, which knows nothing of the manager; this module
//! is the part that calls into it (preparing requests on the sender's
//! thread, queueing them for the cycle thread).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crossbeam_channel::{Receiver, Sender, TrySendError};

use crate::control::{Control, ControlError, Event, Reply, Request};

/// A request on its way to a spawned manager, with what was done for it on
/// the sender's thread, and where its reply goes.
pub(crate) struct Envelope {
    pub request: Request,
    /// An `AddMonitor`'s conditions, compiled by the sender.
    pub monitor: Option<crate::manager::PreparedMonitorBox>,
    /// [`Handle::tap`]: install a tap made so (the request is then
    /// ignored) and send its receiver here.
    pub tap: Option<(crate::frame::TapOptions, Sender<crate::TapReceiver>)>,
    pub reply: Sender<Result<Reply, ControlError>>,
}

/// A cloneable, thread-safe handle to a manager running on its own thread
/// (see [`Manager::spawn`](crate::Manager::spawn)).
///
/// A request's work that needs only the robot's wiring — looking up names,
/// the "did you mean" of an unknown one, checking a parameter's value,
/// compiling a monitor's conditions — is done on the thread that sends it,
/// never on the cycle's: a refused request never reaches the manager.
#[derive(Clone)]
pub struct Handle {
    pub(crate) tx: Sender<Envelope>,
    pub(crate) bus: EventBus,
    pub(crate) graph: std::sync::Arc<crate::graph::Graph>,
}

impl Handle {
    /// A new stream of events, from now on.
    pub fn events(&self) -> Receiver<Event> {
        self.bus.subscribe()
    }

    /// The robot's wiring.
    pub fn graph(&self) -> &crate::graph::Graph {
        &self.graph
    }

    /// Taps the running manager's cycle from its next cycle on, as
    /// [`Manager::tap`](crate::Manager::tap) does before it is spawned (beside
    /// any tap it has). Gives up after `timeout`.
    pub fn tap(
        &self,
        options: impl Into<crate::frame::TapOptions>,
        timeout: Duration,
    ) -> Result<crate::TapReceiver, ControlError> {
        let (tx, rx) = crossbeam_channel::bounded(1);
        let (tap_tx, tap_rx) = crossbeam_channel::bounded(1);
        let envelope =
            Envelope { request: Request::QueryStats, monitor: None, tap: Some((options.into(), tap_tx)), reply: tx };
        self.tx.send(envelope).map_err(|_| ControlError::Disconnected)?;
        rx.recv_timeout(timeout).map_err(|_| ControlError::Disconnected)??;
        tap_rx.try_recv().map_err(|_| ControlError::Disconnected)
    }

    /// Sends `event` to every subscriber, as the manager would (a worker
    /// thread's failure, see [`crate::supervise`]); a `WorkerFailed` is
    /// counted in the stats.
    pub fn report(&self, event: Event) {
        self.bus.report(event);
    }

    /// Like [`Control::request`], giving up after `timeout`.
    pub fn request_timeout(&self, request: Request, timeout: Duration) -> Result<Reply, ControlError> {
        self.submit(request)?.wait(timeout)
    }

    /// Sends `request` without waiting for its reply, which comes through the
    /// returned [`Pending`]. The manager handles requests in the order they
    /// were submitted, so several can be submitted before waiting for any:
    /// the manager's thread then wakes once for all of them. A request the
    /// wiring alone refuses (an unknown name, a bad condition) is answered at
    /// once, here.
    pub fn submit(&self, mut request: Request) -> Result<Pending, ControlError> {
        let (tx, rx) = crossbeam_channel::bounded(1);
        match crate::manager::prepare(&self.graph, &mut request) {
            Ok(monitor) => self
                .tx
                .send(Envelope { request, monitor, tap: None, reply: tx })
                .map_err(|_| ControlError::Disconnected)?,
            Err(e) => {
                let _ = tx.send(Err(e));
            }
        }
        Ok(Pending { rx })
    }
}

/// The reply to come to a request sent with [`Handle::submit`].
#[derive(Debug)]
pub struct Pending {
    rx: Receiver<Result<Reply, ControlError>>,
}

impl Pending {
    /// Waits for the reply, at most `timeout` ([`ControlError::Disconnected`] after that).
    pub fn wait(self, timeout: Duration) -> Result<Reply, ControlError> {
        self.rx.recv_timeout(timeout).map_err(|_| ControlError::Disconnected)?
    }
}

impl Control for Handle {
    fn request(&mut self, request: Request) -> Result<Reply, ControlError> {
        let pending = self.submit(request)?;
        pending.rx.recv().map_err(|_| ControlError::Disconnected)?
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ClockKind, Manager, Registry, RobotSpec};

    #[test]
    fn submitted_requests_are_handled_in_the_order_sent() {
        let spec = RobotSpec::new("order").clock(ClockKind::Simulated).period_s(0.01);
        let m = Manager::build(&spec, &Registry::new()).unwrap_or_else(|e| panic!("{e}"));
        let (handle, join) = m.spawn(false);
        let limit = Duration::from_secs(60);
        // Every request is submitted before any reply is awaited.
        let pending: Vec<Pending> =
            [Request::Step { cycles: 3 }, Request::QueryStats, Request::Step { cycles: 2 }, Request::QueryStats]
                .into_iter()
                .map(|r| handle.submit(r).unwrap())
                .collect();
        let cycles: Vec<u64> = pending
            .into_iter()
            .filter_map(|p| match p.wait(limit).unwrap() {
                Reply::Stats(s) => Some(s.cycle),
                _ => None,
            })
            .collect();
        assert_eq!(cycles, [3, 5]);
        handle.request_timeout(Request::Shutdown, limit).unwrap();
        join.join().unwrap();
    }
}

/// How many events wait for a subscriber that is slow to read them.
const EVENT_QUEUE: usize = 4096;

/// The event subscribers, shared with handles.
#[derive(Clone, Default)]
pub struct EventBus {
    subscribers: Arc<Mutex<Vec<Sender<Event>>>>,
    /// Worker threads that panicked (see [`crate::supervise`]).
    pub(crate) worker_failures: Arc<AtomicU64>,
}

impl EventBus {
    pub fn subscribe(&self) -> Receiver<Event> {
        let (tx, rx) = crossbeam_channel::bounded(EVENT_QUEUE);
        self.subscribers.lock().unwrap_or_else(|p| p.into_inner()).push(tx);
        rx
    }

    pub(crate) fn send(&self, event: Event) {
        let mut subs = self.subscribers.lock().unwrap_or_else(|p| p.into_inner());
        // A subscriber that stopped reading loses events rather than holding
        // up the cycle; one that went away is dropped.
        subs.retain(|tx| !matches!(tx.try_send(event.clone()), Err(TrySendError::Disconnected(_))));
    }

    pub(crate) fn report(&self, event: Event) {
        if matches!(event, Event::WorkerFailed { .. }) {
            self.worker_failures.fetch_add(1, Ordering::Relaxed);
        }
        self.send(event);
    }

    pub(crate) fn has_subscribers(&self) -> bool {
        !self.subscribers.lock().unwrap_or_else(|p| p.into_inner()).is_empty()
    }
}
