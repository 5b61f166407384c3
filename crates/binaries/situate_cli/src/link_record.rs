//! The link's `record` request: start and stop a recording of the running
//! robot (docs/protocol.md, docs/recording.md).
//!
//! A client names a file, never a path: recordings go into one directory
//! the robot's operator chose (`--record-dir`, by default the directory the
//! robot was started in), and an existing file is never overwritten, so a
//! client on the network cannot write anywhere else on the robot's machine.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde_json::{json, Value as Json};
use situate::manager::Handle;
use situate_link::json::WireError;
use situate_link::VerbFn;
use situate_record::{RecordError, Recorder, Summary};

/// How long a start waits for the manager to install the tap.
const START_TIMEOUT: Duration = Duration::from_secs(10);

/// The recordings the link starts, one at a time.
pub(crate) struct LinkRecorder {
    dir: PathBuf,
    handle: Handle,
    metadata: BTreeMap<String, String>,
    current: Mutex<Option<Recorder>>,
}

impl LinkRecorder {
    pub(crate) fn new(dir: PathBuf, handle: Handle, metadata: BTreeMap<String, String>) -> Arc<LinkRecorder> {
        Arc::new(LinkRecorder { dir, handle, metadata, current: Mutex::new(None) })
    }

    /// The `record` verb for [`situate_link::Link::serve_with`].
    pub(crate) fn verb(self: &Arc<Self>) -> VerbFn {
        let me = Arc::clone(self);
        Arc::new(move |args: &Json| me.answer(args))
    }

    fn current(&self) -> std::sync::MutexGuard<'_, Option<Recorder>> {
        self.current.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn answer(&self, args: &Json) -> Result<Json, WireError> {
        let obj = args.as_object().cloned().unwrap_or_default();
        if let Some(extra) = obj.keys().find(|k| *k != "start" && *k != "stop") {
            return Err(WireError::bad_request(format!(
                "`record`: unknown argument `{extra}` (it takes `start: \"NAME.mcap\"` or `stop: true`)"
            )));
        }
        match (obj.get("start"), obj.get("stop")) {
            (Some(_), Some(_)) => Err(WireError::bad_request("`record`: `start` or `stop`, not both")),
            (Some(name), None) => {
                let name = name
                    .as_str()
                    .ok_or_else(|| WireError::bad_request("`record`: `start` expects a file name (a string)"))?;
                self.start(name)
            }
            (None, Some(Json::Bool(true))) => self.stop(),
            (None, Some(_)) => Err(WireError::bad_request("`record`: `stop` expects true")),
            (None, None) => {
                let current = self.current();
                Ok(json!({"recording": current.as_ref().map(|r| r.path().display().to_string()),
                          "dir": self.dir.display().to_string()}))
            }
        }
    }

    fn start(&self, name: &str) -> Result<Json, WireError> {
        check_name(name).map_err(|why| WireError::bad_request(format!("`record`: `{name}`: {why}")))?;
        let mut current = self.current();
        if let Some(r) = current.as_ref() {
            return Err(invalid(format!("`record`: already recording to {}; stop it first", r.path().display())));
        }
        let path = self.dir.join(name);
        if path.exists() {
            return Err(invalid(format!("`record`: {} exists; a recording never overwrites a file", path.display())));
        }
        let recorder = Recorder::start_running(&path, &self.handle, self.metadata.clone(), START_TIMEOUT)
            .map_err(|e| invalid(format!("`record`: {e}")))?;
        *current = Some(recorder);
        Ok(json!({"recording": path.display().to_string()}))
    }

    fn stop(&self) -> Result<Json, WireError> {
        let recorder = self.current().take().ok_or_else(|| invalid("`record`: nothing is being recorded".into()))?;
        let summary = recorder.finish().map_err(|e| invalid(format!("`record`: {e}")))?;
        Ok(crate::robot::recording_json(&summary))
    }

    /// Ends a recording still going when the robot stops (after the manager,
    /// so every cycle it ran is in the file).
    pub(crate) fn finish(&self) -> Option<Result<Summary, RecordError>> {
        self.current().take().map(Recorder::finish)
    }
}

fn invalid(message: String) -> WireError {
    WireError { kind: "invalid", message }
}

/// A recording's name from a client: a plain file name ending `.mcap`.
fn check_name(name: &str) -> Result<(), &'static str> {
    if name.contains(['/', '\\', '\0']) || Path::new(name).components().count() != 1 {
        return Err("a file name is expected, not a path (recordings go into the robot's --record-dir)");
    }
    if name.starts_with('.') {
        return Err("a file name may not start with a dot");
    }
    if name.len() > 200 {
        return Err("the name is longer than 200 bytes");
    }
    if !name.ends_with(".mcap") || name.len() == ".mcap".len() {
        return Err("the name must end in .mcap");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::check_name;

    #[test]
    fn a_recording_name_is_a_plain_mcap_file_name() {
        assert!(check_name("run-1.mcap").is_ok());
        for bad in ["../x.mcap", "/tmp/x.mcap", "a/b.mcap", ".hidden.mcap", "x.txt", ".mcap", "..", "a\\b.mcap"] {
            assert!(check_name(bad).is_err(), "{bad}");
        }
    }
}
