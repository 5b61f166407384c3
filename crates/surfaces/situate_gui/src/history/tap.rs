//! A history's source: a live manager's tap and events, or any channels of frames and events.

use situate_manager::{Event, Frame, Manager, TapReceiver};

use super::{Layout, TAP_QUEUE};

/// A live manager's tap for a history: its frames and events from before it was spawned, and its
/// layout. Make it with [`HistoryTap::new`] before [`Manager::spawn`] and give it to
/// [`crate::serve_with_history`].
/// [`HistoryTap::from_channels`] feeds a history from any source (a recording's reader, a test).
pub struct HistoryTap {
    pub(crate) frames: crossbeam_channel::Receiver<Frame>,
    /// The manager's tap, for the count of frames it dropped.
    pub(crate) tap: Option<TapReceiver>,
    pub(crate) events: crossbeam_channel::Receiver<Event>,
    pub(crate) layout: Layout,
    pub(crate) observed_from: u64,
}

impl HistoryTap {
    /// Taps `manager`'s cycle ([`Manager::tap`], which never makes the cycle wait: a frame that
    /// finds the queue full is dropped and counted) and subscribes to its events. Beside a
    /// recording's tap: each tap gets every cycle.
    pub fn new(manager: &mut Manager) -> HistoryTap {
        let tap = manager.tap(TAP_QUEUE);
        let events = manager.events();
        HistoryTap {
            frames: tap.frames.clone(),
            tap: Some(tap),
            events,
            layout: Layout::of(manager.graph()),
            observed_from: manager.cycle_count(),
        }
    }

    /// Frames and events from any source, in cycle order, named by `layout`; the skills' state
    /// as in `layout` from cycle `observed_from` on. The history takes them as they come until
    /// both channels close (a source may block on a full bounded channel: nothing waits on it).
    pub fn from_channels(
        layout: Layout,
        frames: crossbeam_channel::Receiver<Frame>,
        events: crossbeam_channel::Receiver<Event>,
        observed_from: u64,
    ) -> HistoryTap {
        HistoryTap { frames, tap: None, events, layout, observed_from }
    }

    /// Frames lost before they reached the history (a live tap's full queue).
    pub(crate) fn dropped(&self) -> u64 {
        self.tap.as_ref().map(TapReceiver::dropped).unwrap_or(0)
    }
}
