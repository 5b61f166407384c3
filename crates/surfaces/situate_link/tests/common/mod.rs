//! What the link's tests share: free ports and a running manager with its link.
#![allow(dead_code)]

use std::time::Duration;

use situate::manager::{ClockKind, Handle, Manager, Request, RobotFile, RobotSpec};
use situate_link::{Link, LinkConfig};

/// A TCP port nobody listens on right now.
pub fn free_port() -> u16 {
    situate_link::free_loopback_port().expect("a free port")
}

/// A manager on its own thread, served by a link; stopped on drop.
pub struct Running {
    pub handle: Handle,
    pub link: Option<Link>,
    pub join: Option<situate::manager::Joiner>,
    pub endpoint: String,
}

impl Drop for Running {
    fn drop(&mut self) {
        drop(self.link.take());
        let _ = self.handle.request_timeout(Request::Shutdown, Duration::from_secs(5));
        if let Some(j) = self.join.take() {
            let _ = j.join();
        }
    }
}

/// The toy robot `name` at 50 Hz (sonar and wheels, runaway and wander), on the wall clock,
/// served on a free port.
pub fn toy_robot(name: &str) -> Running {
    let text = format!(
        "robot: {name}\ncycle: {{rate_hz: 50}}\ndevices:\n  - {{name: sonar, type: toy.sonar}}\n  \
         - {{name: wheels, type: toy.wheels}}\nskills:\n  - {{name: runaway, type: toy.runaway}}\n  \
         - {{name: wander, type: toy.wander}}\n"
    );
    let file = RobotFile::parse(&format!("{name}.yaml"), &text).unwrap();
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let config = LinkConfig { listen: vec![endpoint.clone()], ..LinkConfig::default() };
    let session = Link::open(&config).unwrap();
    let spec = RobotSpec::from_file(&file).clock(ClockKind::Wall);
    let manager = Manager::build(&spec, &situate_toys::registry()).unwrap();
    let (handle, join) = manager.spawn(true);
    let link = Link::serve(name, handle.clone(), session, &config).unwrap();
    Running { handle, link: Some(link), join: Some(join), endpoint }
}
