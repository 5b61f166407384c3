//! A robot running on its own threads ([`Running`]), and stopping it: everything stopped
//! within [`signals::stop_bound`], or what did not stop said ([`Stuck`]).

use std::sync::atomic::Ordering;
use std::sync::Arc;

use situate::manager::{Control, Event, ManagerStats, SkillInfo};
use situate_link::Link;

use super::recording::recording_text;
use crate::signals;
use crate::sim::Simulation;

/// A robot running on its own threads, serving the link.
pub(crate) struct Running {
    pub(crate) handle: situate::manager::Handle,
    pub(crate) join: situate::manager::Joiner,
    pub(crate) events: crossbeam_channel::Receiver<Event>,
    pub(crate) served: Option<Link>,
    /// The ROS 2 bridge (its tokens withdrawn before the link's session closes).
    pub(crate) ros2: Option<situate_ros2::Bridge>,
    pub(crate) gui: Option<situate_gui::GuiServer>,
    pub(crate) sim: Option<Simulation>,
    pub(crate) robot: String,
    /// The endpoints the link listens on (empty without one).
    pub(crate) listen: Vec<String>,
    /// `--record`: ended after the manager, with what it holds.
    pub(crate) recorder: Option<situate_record::Recorder>,
    /// The link's `record` request: a recording it started is ended after
    /// the manager too.
    pub(crate) link_recorder: Option<Arc<crate::link_record::LinkRecorder>>,
}

/// What [`Running::finish`] leaves: the final statistics, the skills, and
/// the recording's outcome if one was made.
pub(crate) type Finished =
    (ManagerStats, Vec<SkillInfo>, Option<Result<situate_record::Summary, situate_record::RecordError>>);

impl Running {
    /// Stops everything and returns the final statistics, within
    /// [`signals::stop_bound`]: a cycle stuck in a skill's body (or a part
    /// that does not stop) is left behind, and the error says which.
    pub(crate) fn finish(self) -> Result<Finished, Stuck> {
        let Running { mut handle, join, served, ros2, gui, recorder, link_recorder, .. } = self;
        let stage = Arc::new(std::sync::atomic::AtomicU8::new(Stage::Stats as u8));
        let (tx, rx) = crossbeam_channel::bounded(1);
        let at = Arc::clone(&stage);
        // The teardown runs on a thread of its own, so that this one can give up on it.
        let teardown = move || {
            let stats = handle.stats();
            let skills = handle.skills();
            at.store(Stage::Gui as u8, Ordering::SeqCst);
            if let Some(gui) = gui {
                gui.stop();
            }
            at.store(Stage::Link as u8, Ordering::SeqCst);
            drop(ros2);
            drop(served);
            at.store(Stage::Cycle as u8, Ordering::SeqCst);
            let _ = handle.request(situate::manager::Request::Shutdown);
            let _ = join.join();
            // After the manager: every cycle it ran is in the file.
            let recorded = recorder.map(situate_record::Recorder::finish);
            match link_recorder.and_then(|l| l.finish()) {
                Some(Ok(s)) => tracing::info!("{}", recording_text(&s).trim_end()),
                Some(Err(e)) => tracing::error!("the recording started over the link: {e}"),
                None => {}
            }
            let _ = tx.send((stats, skills, recorded));
        };
        if let Err(e) = std::thread::Builder::new().name("situate-teardown".into()).spawn(teardown) {
            return Err(Stuck { stage: Stage::Spawn, detail: e.to_string() });
        }
        match rx.recv_timeout(signals::stop_bound()) {
            Ok((Ok(stats), Ok(skills), recorded)) => Ok((stats, skills, recorded)),
            Ok((Err(e), _, _) | (_, Err(e), _)) => Err(Stuck { stage: Stage::Stats, detail: e.to_string() }),
            Err(_) => {
                let stage = match stage.load(Ordering::SeqCst) {
                    s if s == Stage::Gui as u8 => Stage::Gui,
                    s if s == Stage::Link as u8 => Stage::Link,
                    s if s == Stage::Cycle as u8 => Stage::Cycle,
                    _ => Stage::Stats,
                };
                Err(Stuck { stage, detail: String::new() })
            }
        }
    }
}

/// Where [`Running::finish`] was when it gave up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stage {
    Spawn,
    Stats,
    Gui,
    Link,
    Cycle,
}

/// A stop that did not complete: what did not stop.
#[derive(Debug)]
pub(crate) struct Stuck {
    stage: Stage,
    detail: String,
}

impl std::fmt::Display for Stuck {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let bound = signals::bound_text();
        match self.stage {
            Stage::Spawn => write!(f, "could not stop the robot: {}", self.detail),
            Stage::Stats if !self.detail.is_empty() => {
                write!(f, "the manager did not give its final statistics: {}", self.detail)
            }
            Stage::Stats | Stage::Cycle => write!(
                f,
                "the cycle did not stop within {bound} of the shutdown request (it is stuck, most likely \
                 in a skill's body that does not return); exiting without it"
            ),
            Stage::Gui => write!(f, "the GUI did not stop within {bound}; exiting without it"),
            Stage::Link => write!(f, "the link did not close within {bound}; exiting without it"),
        }
    }
}

impl std::error::Error for Stuck {}
