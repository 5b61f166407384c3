//! The plain HTTP routes: `/metrics`, `/api/world`, and the web app's files (embedded at
//! compile time, or a placeholder page when it was not built).

use std::sync::Arc;

use axum::extract::State;
use axum::http::{header, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use serde_json::Value as Json;
use situate_manager::{ControlError, Reply, Request};

use crate::{ask, metrics, Shared};

mod assets {
    include!(concat!(env!("OUT_DIR"), "/assets.rs"));
}

/// `GET /metrics`: asks the manager off the server's thread (a scrape may wait for a cycle).
pub(crate) async fn metrics_page(State(shared): State<Arc<Shared>>) -> Response {
    match tokio::task::spawn_blocking(move || scrape(&shared)).await {
        Ok(Ok(text)) => ([(header::CONTENT_TYPE, metrics::CONTENT_TYPE)], text).into_response(),
        Ok(Err(e)) => {
            (StatusCode::SERVICE_UNAVAILABLE, format!("the skill manager did not answer: {e}\n")).into_response()
        }
        Err(_) => (StatusCode::INTERNAL_SERVER_ERROR, "the scrape failed\n").into_response(),
    }
}

fn scrape(shared: &Shared) -> Result<String, ControlError> {
    let stats = match ask(&shared.handle, Request::QueryStats)? {
        Reply::Stats(s) => s,
        other => return Err(ControlError::Invalid(format!("unexpected reply {other:?}"))),
    };
    let skills = match ask(&shared.handle, Request::QuerySkills)? {
        Reply::Skills(s) => s,
        other => return Err(ControlError::Invalid(format!("unexpected reply {other:?}"))),
    };
    let faults = shared.activity.lock().unwrap_or_else(|p| p.into_inner()).faults.clone();
    Ok(metrics::render(&stats, &skills, &faults))
}

pub(crate) async fn world(State(shared): State<Arc<Shared>>) -> Response {
    axum::Json(shared.world.clone().unwrap_or(Json::Null)).into_response()
}

fn content_type(path: &str) -> &'static str {
    match path.rsplit('.').next().unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "json" | "map" => "application/json",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        "ico" => "image/x-icon",
        "woff2" => "font/woff2",
        _ => "application/octet-stream",
    }
}

/// The page served when the web app was not built into this program.
pub const PLACEHOLDER: &str = "<!doctype html><html><head><meta charset=\"utf-8\"><title>situate GUI</title></head>\
<body><h1>situate GUI: the web app is not built</h1><p>This program was compiled without <code>web/dist</code>. \
Run <code>make gui</code> (or <code>scripts/gui.sh build</code>), then rebuild the program.</p></body></html>";

/// Whether the web app was embedded at compile time.
pub fn has_web_app() -> bool {
    !assets::ASSETS.is_empty()
}

pub(crate) async fn static_file(uri: Uri) -> Response {
    let path = uri.path().trim_start_matches('/');
    let path = if path.is_empty() { "index.html" } else { path };
    if let Some((_, bytes)) = assets::ASSETS.iter().find(|(p, _)| *p == path) {
        let cache = if path.starts_with("assets/") { "public, max-age=31536000, immutable" } else { "no-cache" };
        return ([(header::CONTENT_TYPE, content_type(path)), (header::CACHE_CONTROL, cache)], *bytes).into_response();
    }
    if path == "favicon.ico" {
        return StatusCode::NO_CONTENT.into_response();
    }
    if path == "index.html" {
        return ([(header::CONTENT_TYPE, "text/html; charset=utf-8")], PLACEHOLDER).into_response();
    }
    (StatusCode::NOT_FOUND, format!("no such file: /{path}")).into_response()
}
