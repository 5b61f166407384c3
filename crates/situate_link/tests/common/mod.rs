//! What the link's tests share: free ports and a running manager with its link.
#![allow(dead_code)]

use std::time::Duration;

use situate::manager::{Handle, Request};
use situate_link::Link;

/// A TCP port nobody listens on right now.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
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
