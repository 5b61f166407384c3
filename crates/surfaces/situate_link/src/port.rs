//! A free loopback port to listen on, chosen where outgoing connections do not go.
//!
//! A port the kernel picks (`bind` to port 0) comes from its range for outgoing connections'
//! local ports (Linux: `/proc/sys/net/ipv4/ip_local_port_range`, 32768-60999 by default). Once
//! the probe closes it, any program's next outgoing connection (a Zenoh client, say) may be
//! given it before the listener that asked for it binds it: "Address already in use", seen when
//! many robots and clients start at once (the tests, running side by side). Chosen at random
//! below that range, only another listener choosing the same port can take it first; callers
//! that can, try another then.

use std::hash::{BuildHasher, Hasher};
use std::net::TcpListener;

/// The lowest port chosen: above the registered ports most services use.
const LOWEST: u16 = 20000;

/// Where the range of outgoing connections' ports starts (Linux; elsewhere 32768).
fn outgoing_start() -> u16 {
    std::fs::read_to_string("/proc/sys/net/ipv4/ip_local_port_range")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|p| p.parse().ok()))
        .unwrap_or(32768)
}

/// A random number (std's hasher keys are random per `RandomState`).
fn random() -> u64 {
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(0);
    h.finish()
}

/// A loopback TCP port nobody listens on now, below the range of outgoing connections' ports
/// when there is room there (else one the kernel picks).
pub fn free_loopback_port() -> std::io::Result<u16> {
    let high = outgoing_start();
    if high > LOWEST + 1000 {
        let span = u64::from(high - LOWEST);
        for _ in 0..100 {
            let port = LOWEST + (random() % span) as u16;
            if TcpListener::bind(("127.0.0.1", port)).is_ok() {
                return Ok(port);
            }
        }
    }
    Ok(TcpListener::bind(("127.0.0.1", 0))?.local_addr()?.port())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_port_is_free_and_below_the_outgoing_range() {
        let port = free_loopback_port().expect("a port");
        let high = outgoing_start();
        if high > LOWEST + 1000 {
            assert!((LOWEST..high).contains(&port), "{port} not in {LOWEST}..{high}");
        }
        TcpListener::bind(("127.0.0.1", port)).expect("free");
    }
}
