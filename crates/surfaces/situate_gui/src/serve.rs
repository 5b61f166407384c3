//! The server's connections: the accept loop with its cap on connections and its header
//! timeout, and the WebSocket keepalive.
//!
//! Every connection holds a slot of a semaphore for as long as it lives, through a WebSocket
//! upgrade too (the slot travels inside the connection's socket). Past the cap a new connection
//! is answered `503` at once and closed, so idle or abusive clients cannot take every file
//! descriptor from the link and the GUI itself. A connection that does not send a whole request
//! head within [`crate::GuiConfig::header_timeout`] (idle, or between keep-alive requests, or
//! slowly) is closed by hyper; a WebSocket that sends nothing and answers no ping for
//! [`crate::GuiConfig::ws_idle_timeout`] is closed by [`Keepalive`].

use std::io;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;

use axum::extract::ws::{Message, WebSocket};
use axum::Router;
use hyper::server::conn::http1;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{watch, OwnedSemaphorePermit, Semaphore};
use tokio::time::{Instant, Interval, MissedTickBehavior};

/// How long connections are given to finish when the server stops.
const GRACE: Duration = Duration::from_secs(2);
/// After a failed accept (out of file descriptors, say), wait this long before the next: the
/// pending connection stays queued, and the loop does not spin.
const ACCEPT_BACKOFF: Duration = Duration::from_millis(100);
/// At most one warning per this long about refused connections or failed accepts.
const WARN_EVERY: Duration = Duration::from_secs(10);

/// The limits on the server's connections.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Limits {
    pub(crate) max_connections: usize,
    pub(crate) header_timeout: Duration,
}

/// A connection's socket with its slot: the slot is given back when the socket is dropped,
/// after a WebSocket upgrade as before it.
struct Counted {
    stream: TcpStream,
    _slot: OwnedSemaphorePermit,
}

impl AsyncRead for Counted {
    fn poll_read(self: Pin<&mut Self>, cx: &mut Context<'_>, buf: &mut ReadBuf<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().stream).poll_read(cx, buf)
    }
}

impl AsyncWrite for Counted {
    fn poll_write(self: Pin<&mut Self>, cx: &mut Context<'_>, buf: &[u8]) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.get_mut().stream).poll_write(cx, buf)
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().stream).poll_flush(cx)
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().stream).poll_shutdown(cx)
    }

    fn poll_write_vectored(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.get_mut().stream).poll_write_vectored(cx, bufs)
    }

    fn is_write_vectored(&self) -> bool {
        self.stream.is_write_vectored()
    }
}

/// Rate-limits a warning: says it at most once per [`WARN_EVERY`], with how often it happened.
struct Warner {
    last: Option<Instant>,
    since: u64,
}

impl Warner {
    fn new() -> Self {
        Warner { last: None, since: 0 }
    }

    /// Counts one occurrence; `Some(count)` when it is time to say so.
    fn note(&mut self) -> Option<u64> {
        self.since += 1;
        let due = self.last.is_none_or(|t| t.elapsed() >= WARN_EVERY);
        if !due {
            return None;
        }
        self.last = Some(Instant::now());
        Some(std::mem::take(&mut self.since))
    }
}

/// Answers a connection past the cap `503` without waiting for it, and closes it.
fn refuse(stream: TcpStream, answer: &[u8]) {
    // What the client sent already is read first: closing a socket with unread data resets it,
    // and the client could lose the answer.
    let mut sink = [0u8; 4096];
    for _ in 0..4 {
        match stream.try_read(&mut sink) {
            Ok(n) if n > 0 => {}
            _ => break,
        }
    }
    let _ = stream.try_write(answer);
}

/// The `503` written to a connection past the cap.
fn over_cap_answer(max: usize) -> Vec<u8> {
    let body = format!("the GUI serves at most {max} connections at once and every one is taken; try again later\n");
    format!(
        "HTTP/1.1 503 Service Unavailable\r\ncontent-type: text/plain; charset=utf-8\r\ncontent-length: {}\r\n\
         retry-after: 1\r\nconnection: close\r\n\r\n{body}",
        body.len()
    )
    .into_bytes()
}

/// Serves `app` on `listener` until `shutdown` turns true, then lets the connections finish (for
/// at most [`GRACE`]).
pub(crate) async fn accept_loop(listener: TcpListener, app: Router, limits: Limits, shutdown: watch::Receiver<bool>) {
    let slots = Arc::new(Semaphore::new(limits.max_connections));
    let answer = over_cap_answer(limits.max_connections);
    // Every connection's task holds a receiver; the loop waits for the last to go.
    let (alive_tx, _) = watch::channel(());
    let (mut refused, mut failed) = (Warner::new(), Warner::new());
    loop {
        let mut stop = shutdown.clone();
        let (stream, peer) = tokio::select! {
            _ = stopping(&mut stop) => break,
            accepted = listener.accept() => match accepted {
                Ok(a) => a,
                Err(e) => {
                    if let Some(n) = failed.note() {
                        tracing::warn!(error = %e, times = n, "the GUI could not accept a connection");
                    }
                    tokio::time::sleep(ACCEPT_BACKOFF).await;
                    continue;
                }
            },
        };
        let Ok(slot) = Arc::clone(&slots).try_acquire_owned() else {
            refuse(stream, &answer);
            if let Some(n) = refused.note() {
                tracing::warn!(
                    max = limits.max_connections,
                    times = n,
                    "the GUI refused connections: every slot is taken"
                );
            }
            continue;
        };
        let io = TokioIo::new(Counted { stream, _slot: slot });
        let service = TowerToHyperService::new(app.clone());
        let mut stop = shutdown.clone();
        let alive = alive_tx.subscribe();
        tokio::spawn(async move {
            let _alive = alive;
            let conn = http1::Builder::new()
                .timer(TokioTimer::new())
                .header_read_timeout(limits.header_timeout)
                .serve_connection(io, service)
                .with_upgrades();
            tokio::pin!(conn);
            tokio::select! {
                result = conn.as_mut() => {
                    if let Err(e) = result {
                        tracing::debug!(%peer, error = %e, "a GUI connection ended");
                    }
                }
                _ = stopping(&mut stop) => {
                    conn.as_mut().graceful_shutdown();
                    let _ = tokio::time::timeout(GRACE, conn).await;
                }
            }
        });
    }
    drop(listener);
    let _ = tokio::time::timeout(GRACE, alive_tx.closed()).await;
}

/// Resolves once `stop` says the server is stopping (or its sender is gone).
pub(crate) async fn stopping(stop: &mut tokio::sync::watch::Receiver<bool>) {
    let _ = stop.wait_for(|s| *s).await;
}

/// What a WebSocket's keepalive says to do.
pub(crate) enum Beat {
    /// Send a ping.
    Ping,
    /// Nothing was heard for the idle timeout: close.
    Dead,
}

/// A WebSocket's keepalive: a ping every third of the idle timeout, and the connection declared
/// dead when nothing (no message, no pong) came for the whole timeout. A browser's tab answers
/// pings by itself, so a live page is never closed, however quiet.
pub(crate) struct Keepalive {
    idle: Duration,
    heard: Instant,
    ticker: Interval,
}

impl Keepalive {
    pub(crate) fn new(idle: Duration) -> Self {
        let period = (idle / 3).max(Duration::from_millis(1));
        let mut ticker = tokio::time::interval_at(Instant::now() + period, period);
        ticker.set_missed_tick_behavior(MissedTickBehavior::Delay);
        Keepalive { idle, heard: Instant::now(), ticker }
    }

    /// Notes what `recv` gave: any frame from the client (a pong included) shows it is alive.
    pub(crate) fn heard_from<T, E>(&mut self, incoming: &Option<Result<T, E>>) {
        if let Some(Ok(_)) = incoming {
            self.heard = Instant::now();
        }
    }

    /// Waits for the next beat.
    pub(crate) async fn beat(&mut self) -> Beat {
        self.ticker.tick().await;
        if self.heard.elapsed() >= self.idle {
            Beat::Dead
        } else {
            Beat::Ping
        }
    }

    /// Does what `beat` says: pings the client, or closes the connection of a client silent for
    /// the idle timeout (`who` names it in the log). `false`: the connection is done.
    pub(crate) async fn answer(&self, beat: Beat, socket: &mut WebSocket, who: &str) -> bool {
        match beat {
            Beat::Ping => self.send(socket, Message::Ping(Default::default())).await,
            Beat::Dead => {
                tracing::debug!("{who} silent for the idle timeout: closing");
                self.close(socket).await;
                false
            }
        }
    }

    /// Sends `message`, giving up when the client has not taken it within the idle timeout (a
    /// client that does not read would otherwise hold the session forever). `false`: the
    /// connection is done.
    pub(crate) async fn send(&self, socket: &mut WebSocket, message: Message) -> bool {
        matches!(tokio::time::timeout(self.idle, socket.send(message)).await, Ok(Ok(())))
    }

    /// Sends a close frame, waiting at most a second for the client to take it.
    pub(crate) async fn close(&self, socket: &mut WebSocket) {
        let within = self.idle.min(Duration::from_secs(1));
        let _ = tokio::time::timeout(within, socket.send(Message::Close(None))).await;
    }
}

#[cfg(test)]
mod tests {
    use std::io::{Read, Write};
    use std::net::{SocketAddr, TcpStream};
    use std::time::Instant;

    use situate::manager::Control;
    use situate_manager::Request;

    use super::*;
    use crate::tests::robot;
    use crate::{serve, serve_with_history, GuiConfig, HistoryTap};

    /// How long a test waits for what must come; far above what it takes on a loaded machine.
    const BOUND: Duration = Duration::from_secs(30);

    /// Reads `stream` until the server closes it, for at most [`BOUND`]: what came, and whether
    /// it was closed (`false`: still open at the bound, or reset).
    fn read_until_closed(mut stream: TcpStream) -> (String, bool) {
        stream.set_read_timeout(Some(Duration::from_millis(500))).expect("timeout");
        let deadline = std::time::Instant::now() + BOUND;
        let (mut got, mut chunk) = (Vec::new(), [0u8; 4096]);
        while std::time::Instant::now() < deadline {
            match stream.read(&mut chunk) {
                Ok(0) => return (String::from_utf8_lossy(&got).into_owned(), true),
                Ok(n) => got.extend_from_slice(&chunk[..n]),
                Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut) => {}
                Err(e) if e.kind() == io::ErrorKind::ConnectionReset => {
                    return (String::from_utf8_lossy(&got).into_owned(), true)
                }
                Err(e) => panic!("reading: {e}"),
            }
        }
        (String::from_utf8_lossy(&got).into_owned(), false)
    }

    /// `GET /api/world`, asked again while the server answers 503, until [`BOUND`].
    fn get_until_served(addr: SocketAddr) -> String {
        let deadline = std::time::Instant::now() + BOUND;
        loop {
            let page = crate::tests::http(
                addr,
                &format!("GET /api/world HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"),
            );
            if !page.starts_with("HTTP/1.1 503") || std::time::Instant::now() > deadline {
                return page;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    #[test]
    fn past_the_cap_a_connection_is_answered_503_and_a_freed_slot_serves_again() {
        let (mut handle, join) = robot();
        let config = GuiConfig { max_connections: 3, header_timeout: Duration::from_secs(600), ..GuiConfig::default() };
        let gui = serve(handle.clone(), config).expect("serve");
        let addr = gui.local_addr();
        // Idle connections that hold every slot (accepted in the order they were made).
        let mut held: Vec<TcpStream> = (0..3).map(|_| TcpStream::connect(addr).expect("connect")).collect();
        for _ in 0..4 {
            let (answer, closed) = read_until_closed(TcpStream::connect(addr).expect("connect"));
            assert!(answer.starts_with("HTTP/1.1 503"), "past the cap: {answer:?}");
            assert!(answer.contains("at most 3 connections"), "{answer}");
            assert!(closed, "closed at once");
        }
        // A slot given back (its client left) serves the next request.
        drop(held.pop());
        let page = get_until_served(addr);
        assert!(page.starts_with("HTTP/1.1 200"), "{page}");
        // A WebSocket holds its slot too. (The slot of the request just served may be given back
        // a moment after its client saw the end: asked again while refused.)
        let deadline = Instant::now() + BOUND;
        let mut ws = loop {
            match tungstenite::client(format!("ws://{addr}/ws"), TcpStream::connect(addr).expect("connect")) {
                Ok((ws, _)) => break ws,
                Err(e) if Instant::now() < deadline => drop(e),
                Err(e) => panic!("no WebSocket: {e}"),
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let (answer, _) = read_until_closed(TcpStream::connect(addr).expect("connect"));
        assert!(answer.starts_with("HTTP/1.1 503"), "the WebSocket took the freed slot: {answer:?}");
        let _ = ws.close(None);
        drop(held);
        let page = get_until_served(addr);
        assert!(page.starts_with("HTTP/1.1 200"), "{page}");
        gui.stop();
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn idle_and_slow_connections_are_closed_after_the_header_timeout_and_the_server_still_answers() {
        let (mut handle, join) = robot();
        let config =
            GuiConfig { max_connections: 4, header_timeout: Duration::from_millis(300), ..GuiConfig::default() };
        let gui = serve(handle.clone(), config).expect("serve");
        let addr = gui.local_addr();
        // More than the cap: silent ones, ones that stop halfway through their head, and one
        // that stays after its request (keep-alive).
        let mut streams = Vec::new();
        for i in 0..10 {
            let mut s = TcpStream::connect(addr).expect("connect");
            if i % 3 == 1 {
                s.write_all(b"GET /api/world HTTP/1.1\r\nHost: 127.0.0.1\r\n").expect("write");
            }
            streams.push(s);
        }
        for s in streams.into_iter() {
            let (answer, closed) = read_until_closed(s);
            assert!(closed, "an idle connection is closed: {answer:?}");
            assert!(answer.is_empty() || answer.starts_with("HTTP/1.1 503"), "{answer:?}");
        }
        let page = get_until_served(addr);
        assert!(page.starts_with("HTTP/1.1 200"), "the server still answers: {page}");
        // Kept alive after its answer, then idle: closed too.
        let deadline = Instant::now() + BOUND;
        loop {
            let mut kept = TcpStream::connect(addr).expect("connect");
            kept.write_all(format!("GET /api/world HTTP/1.1\r\nHost: {addr}\r\n\r\n").as_bytes()).expect("write");
            let (answer, closed) = read_until_closed(kept);
            if answer.starts_with("HTTP/1.1 503") && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(20));
                continue;
            }
            assert!(answer.starts_with("HTTP/1.1 200"), "{answer:?}");
            assert!(closed, "idle after its answer, a keep-alive connection is closed too");
            break;
        }
        gui.stop();
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    /// A WebSocket opened by hand that never answers a ping (nor sends anything).
    fn silent_socket(addr: SocketAddr, path: &str) -> TcpStream {
        let mut s = TcpStream::connect(addr).expect("connect");
        let request = format!(
            "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n\
             Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n"
        );
        s.write_all(request.as_bytes()).expect("write");
        s
    }

    #[test]
    fn a_websocket_that_answers_no_ping_is_closed_and_one_that_does_stays() {
        let spec =
            situate::manager::RobotSpec::new("idle").skill(situate::manager::SkillSpec::new("sonar", "toy.sonar"));
        let mut manager =
            situate::manager::Manager::build(&spec, &situate_toys::registry()).expect("the toy robot builds");
        let tap = HistoryTap::new(&mut manager);
        let (mut handle, join) = manager.spawn(true);
        // Long enough that a live client stalled by a loaded machine still answers in time.
        let idle = Duration::from_millis(3000);
        let gui =
            serve_with_history(handle.clone(), GuiConfig { ws_idle_timeout: idle, ..GuiConfig::default() }, Some(tap))
                .expect("serve");
        let addr = gui.local_addr();
        // Silent sockets, on both WebSocket routes: read (telemetry keeps coming), never answered.
        for path in ["/ws", "/foxglove"] {
            let (answer, closed) = read_until_closed(silent_socket(addr, path));
            assert!(answer.starts_with("HTTP/1.1 101"), "{path}: {answer:?}");
            assert!(closed, "{path}: a socket that answers no ping is closed");
        }
        let deadline = Instant::now() + BOUND;
        while gui.clients() > 0 && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
        }
        assert_eq!(gui.clients(), 0, "the closed tab is gone");
        // A live client (tungstenite answers pings as a browser does) outlasts the idle timeout.
        let stream = TcpStream::connect(addr).expect("connect");
        stream.set_read_timeout(Some(BOUND)).expect("timeout");
        let (mut ws, _) = tungstenite::client(format!("ws://{addr}/ws"), stream).expect("ws");
        let (mut pings, until) = (0, Instant::now() + idle * 2);
        while Instant::now() < until {
            match ws.read() {
                Ok(tungstenite::Message::Ping(_)) => pings += 1,
                Ok(tungstenite::Message::Close(c)) => panic!("a live client was closed: {c:?}"),
                Ok(_) => {}
                Err(e) => panic!("a live client was cut: {e}"),
            }
        }
        assert!(pings >= 1, "the server pings");
        assert_eq!(gui.clients(), 1);
        let _ = ws.close(None);
        gui.stop();
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }
}
