//! One Foxglove connection: its hello (`serverInfo`, `advertise`), its place in the hub, its
//! keepalive, and the client's text messages.

use std::sync::atomic::Ordering;
use std::sync::Arc;

use axum::extract::ws::{Message, WebSocket};
use serde_json::{json, Value as Json};

use super::client::{Client, Hub};
use super::params::parameters;
use super::poller::parameter_values;
use super::protocol::{advertise, status, ERROR};
use super::schemas::history_schemas;
use super::{MAX_CLIENTS, MAX_PARAM_REQUESTS, QUEUE};
use crate::serve::{stopping, Keepalive};
use crate::Shared;

fn server_info(shared: &Shared) -> Json {
    json!({"op": "serverInfo", "name": "situate", "capabilities": ["parameters", "parametersSubscribe"], "supportedEncodings": ["json"],
        "metadata": {"robot_run": shared.run.id}, "sessionId": shared.run.id})
}

/// A client's place in the hub, given back however its session ends.
struct Member<'a> {
    hub: &'a Hub,
    client: Arc<Client>,
}

impl Drop for Member<'_> {
    fn drop(&mut self) {
        self.hub.leave(&self.client);
    }
}

pub(super) async fn session(shared: Arc<Shared>, mut socket: WebSocket) {
    let Some(history) = shared.history.as_ref() else { return };
    let (advertised, channel_count, known) = {
        let h = history.lock().unwrap_or_else(|p| p.into_inner());
        let known: Vec<String> = parameter_values(&h).into_iter().map(|(n, _)| n).collect();
        let count = h.layout().leaves.len() + 1 + history_schemas(&h).channels.len();
        (advertise(&h), count as u32, known)
    };
    let Some((client, mut rx)) = shared.foxglove.join(QUEUE) else {
        let m = status(ERROR, &format!("too many Foxglove clients (at most {MAX_CLIENTS})"));
        let keepalive = Keepalive::new(shared.ws_idle);
        let _ = keepalive.send(&mut socket, Message::Text(m.to_string().into())).await;
        keepalive.close(&mut socket).await;
        return;
    };
    let _member = Member { hub: &shared.foxglove, client: Arc::clone(&client) };
    let mut shutdown = shared.shutdown.clone();
    let mut keepalive = Keepalive::new(shared.ws_idle);
    tracing::debug!("Foxglove client connected");
    for m in [server_info(&shared), advertised] {
        if !keepalive.send(&mut socket, Message::Text(m.to_string().into())).await {
            return;
        }
    }
    loop {
        tokio::select! {
            _ = stopping(&mut shutdown) => {
                keepalive.close(&mut socket).await;
                break;
            }
            beat = keepalive.beat() => {
                if !keepalive.answer(beat, &mut socket, "Foxglove client").await {
                    break;
                }
            }
            incoming = socket.recv() => {
                keepalive.heard_from(&incoming);
                match incoming {
                    Some(Ok(Message::Text(text))) => {
                        handle_text(&shared, &client, text.as_str(), channel_count, &known)
                    }
                    Some(Ok(Message::Binary(_))) => {
                        client.offer_json(&status(ERROR, "this server takes no client messages in binary (no clientPublish)"));
                    }
                    Some(Ok(Message::Close(_))) | Some(Err(_)) | None => break,
                    Some(Ok(_)) => {}
                }
            }
            Some(m) = rx.recv() => {
                client.taken(&m);
                if !keepalive.send(&mut socket, m).await {
                    break;
                }
            }
        }
    }
    tracing::debug!(dropped = client.dropped(), "Foxglove client disconnected");
}

/// One client text message: `subscribe`, `unsubscribe`, `getParameters`, `setParameters`,
/// `subscribeParameterUpdates`, `unsubscribeParameterUpdates`.
/// Anything else is answered by a `status` error.
fn handle_text(shared: &Arc<Shared>, client: &Arc<Client>, text: &str, channels: u32, known: &[String]) {
    let msg: Json = match serde_json::from_str(text) {
        Ok(j @ Json::Object(_)) => j,
        Ok(_) => {
            client.offer_json(&status(ERROR, "a client message must be a JSON object with an `op`"));
            return;
        }
        Err(e) => {
            client.offer_json(&status(ERROR, &format!("the message is not JSON: {e}")));
            return;
        }
    };
    let op = msg.get("op").and_then(Json::as_str).unwrap_or("");
    let errors = match op {
        "subscribe" => client.subscribe(&msg, channels),
        "unsubscribe" => client.unsubscribe(&msg),
        "subscribeParameterUpdates" => client.subscribe_params(&msg),
        "unsubscribeParameterUpdates" => client.unsubscribe_params(&msg, known),
        "getParameters" | "setParameters" => {
            if client.param_requests.fetch_add(1, Ordering::SeqCst) >= MAX_PARAM_REQUESTS {
                client.param_requests.fetch_sub(1, Ordering::SeqCst);
                vec![format!("{op}: too many parameter requests waiting (at most {MAX_PARAM_REQUESTS})")]
            } else {
                let (shared, client) = (Arc::clone(shared), Arc::clone(client));
                tokio::task::spawn_blocking(move || {
                    for m in parameters(&shared, &msg) {
                        client.offer_json(&m);
                    }
                    client.param_requests.fetch_sub(1, Ordering::SeqCst);
                });
                vec![]
            }
        }
        "" => vec!["a client message needs an `op` (a string)".into()],
        other => vec![format!("unsupported op `{other}`")],
    };
    for e in errors {
        client.offer_json(&status(ERROR, &e));
    }
}
