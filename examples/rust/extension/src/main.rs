//! `my-situate`: the whole `situate` program (every command, the built-in skill types) plus this
//! crate's own skill types, which robot files name like the built-in ones and `my-situate types`
//! lists, and the resource they are made with: the robot's emergency stop.

mod skills;

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

fn main() -> std::process::ExitCode {
    // One emergency stop for the whole program, made once, here: the function given to `skills`
    // runs wherever the program builds a registry, and each time provides a handle to this one.
    let estop = Arc::new(AtomicBool::new(false));
    if let Some(line) = std::env::var_os("ESTOP_LINE") {
        follow(PathBuf::from(line), estop.clone());
    }
    let ext = situate_cli::Extensions::default().skills(move |registry| {
        registry.register::<skills::Nearest>().register::<skills::Brake>().provide("estop", estop.clone());
    });
    std::process::ExitCode::from(situate_cli::main_with(std::env::args_os(), ext))
}

/// Keeps `estop` set while the e-stop line is pressed: a file that reads `0` while it is released,
/// such as a GPIO line's `/sys/class/gpio/gpioN/value`. Read once now (a robot started with the
/// button pressed never moves), then every 20 ms on a thread of its own. A line that reads
/// anything else, or cannot be read, counts as pressed, as a cut e-stop wire does.
fn follow(line: PathBuf, estop: Arc<AtomicBool>) {
    let pressed = move || !std::fs::read_to_string(&line).is_ok_and(|v| v.trim() == "0");
    estop.store(pressed(), Ordering::Release);
    std::thread::spawn(move || loop {
        std::thread::sleep(Duration::from_millis(20));
        estop.store(pressed(), Ordering::Release);
    });
}
