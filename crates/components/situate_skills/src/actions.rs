//! Skills that command the arm and the speaker.

use situate::prelude::*;
use situate_robot::{Arm, Target};

use crate::util::wrap;

/// Pushes a button: writes `arm.press` = `button` when the tracked barcode
/// (`target`, tracking the button's barcode) is within `reach` and within
/// `max_bearing` of straight ahead; tries again every `retry_s` while in
/// reach, until the arm's `presses` counter shows a hit (then silent until
/// re-activated). Silent when out of reach.
#[derive(Skill, Default)]
#[skill(name = "std.push_button")]
pub struct PushButton {
    /// The tracked barcode beside the button.
    #[input]
    target: Target,
    /// The arm's counters, when an arm reports them.
    #[input]
    arm: Option<Arm>,
    /// The push command, written when a push is tried.
    #[output(signal = "arm.press")]
    press: Option<i64>,
    /// The button to push (a car's floor panel: the floor number; a call button: any).
    #[param(default = 1)]
    button: i64,
    /// Largest distance from the robot's centre to the barcode, m.
    #[param(default = 0.6, min = 0.0, max = 5.0, unit = "m")]
    reach: f64,
    /// Largest bearing of the barcode off straight ahead, rad.
    #[param(default = 0.436, min = 0.0, max = 3.2, unit = "rad")]
    max_bearing: f64,
    /// Time between tries while no hit is seen, s.
    #[param(default = 2.0, min = 0.0, max = 600.0, unit = "s")]
    retry_s: f64,
    last_try: Option<f64>,
    presses_before: Option<i64>,
    done: bool,
}

impl Body for PushButton {
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.last_try = None;
        self.presses_before = None;
        self.done = false;
        Ok(())
    }

    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        if let (Some(arm), Some(before)) = (self.arm, self.presses_before) {
            if arm.presses > before && !self.done {
                self.done = true;
                sprint!(cx, "button {} pressed", self.button);
            }
        }
        if self.done {
            return Ok(());
        }
        let t = self.target;
        let in_reach = t.seen && t.distance <= self.reach && wrap(t.bearing).abs() <= self.max_bearing;
        let now = cx.time_s();
        let due = self.last_try.is_none_or(|last| now - last >= self.retry_s);
        if in_reach && due {
            self.press = Some(self.button);
            self.last_try = Some(now);
            if self.presses_before.is_none() {
                self.presses_before = self.arm.map(|a| a.presses);
            }
            sprint!(cx, "pushing button {}", self.button);
        }
        Ok(())
    }
}

/// Says `message` once after activation (and again whenever `message` is
/// changed while active): writes `speaker.say` in that run only, silent
/// otherwise.
#[derive(Skill, Default)]
#[skill(name = "std.say")]
pub struct Say {
    /// The text to say, written once.
    #[output(signal = "speaker.say")]
    say: Option<String>,
    /// What to say.
    #[param(default = "hello")]
    message: String,
    said: Option<String>,
}

impl Body for Say {
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.said = None;
        Ok(())
    }

    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        if self.said.as_deref() != Some(self.message.as_str()) {
            self.say = Some(self.message.clone());
            self.said = Some(self.message.clone());
            sprint!(cx, "saying {:?}", self.message);
        }
        Ok(())
    }
}
