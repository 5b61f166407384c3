//! Which `Host` the server answers to: the guard against DNS rebinding.
//!
//! A web page at `http://evil.example:7690/` whose name the attacker then points at 127.0.0.1 is,
//! for the browser, the same origin as its own server: its requests reach this server with
//! `Host: evil.example:7690` (and an `Origin` to match), and could read the robot, deactivate its
//! skills and set its parameters. What tells such a request apart is the name in `Host`: the
//! server answers only to names that cannot be rebound by someone else's DNS: `localhost`, a
//! loopback address, the address it is bound to (any address when bound to 0.0.0.0 or `::`,
//! since an address in `Host` is not looked up), and the names it is told to allow
//! ([`crate::GuiConfig::allowed_hosts`], `--gui-allow-host NAME`).
//!
//! The port in `Host` is not compared: the name is what a rebinding attacker controls, and the
//! port a browser names differs from the bound one behind an SSH tunnel (`ssh -L 9000:…`), NAT or
//! a reverse proxy.

use std::net::{IpAddr, SocketAddr};
use std::sync::Arc;

use axum::extract::{Request, State};
use axum::http::{header, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

/// The longest `Host` echoed back in a refusal.
const ECHO_MAX: usize = 120;

/// The hosts one server answers to.
#[derive(Debug, Clone)]
pub(crate) struct HostRule {
    /// The address actually bound.
    bound: IpAddr,
    /// Names allowed besides, lower-case, without a port.
    names: Vec<String>,
}

/// A `Host` value split into its host (lower-case; an IPv6 address without its brackets) and
/// port, or `None` when it is not of the form `name[:port]`, `a.b.c.d[:port]` or `[v6][:port]`.
fn split_host(value: &str) -> Option<(String, Option<u16>)> {
    let (host, port) = if let Some(rest) = value.strip_prefix('[') {
        let (inside, after) = rest.split_once(']')?;
        inside.parse::<std::net::Ipv6Addr>().ok()?;
        let port = match after {
            "" => None,
            p => Some(p.strip_prefix(':')?),
        };
        (inside, port)
    } else {
        match value.split_once(':') {
            Some((h, p)) => (h, Some(p)),
            None => (value, None),
        }
    };
    let port = match port {
        None => None,
        Some(p) if !p.is_empty() && p.len() <= 5 && p.bytes().all(|b| b.is_ascii_digit()) => Some(p.parse().ok()?),
        Some(_) => return None,
    };
    let name_ok = !host.is_empty() && host.bytes().all(|b| b.is_ascii_alphanumeric() || b"-._:".contains(&b));
    name_ok.then(|| (host.to_ascii_lowercase(), port))
}

impl HostRule {
    /// The rule for a server bound to `bound`, allowing `allowed` besides (names or addresses,
    /// without a port); an entry that is not a host name is a configuration error naming it.
    pub(crate) fn new(bound: SocketAddr, allowed: &[String]) -> Result<Self, String> {
        let mut names = Vec::with_capacity(allowed.len());
        for entry in allowed {
            match split_host(entry.trim()) {
                Some((name, None)) => names.push(name),
                Some((name, Some(_))) => {
                    return Err(format!(
                        "allowed host `{entry}`: give the name without a port (`{name}`): any port is accepted"
                    ))
                }
                None => {
                    return Err(format!(
                        "allowed host `{entry}` is not a host name (letters, digits, `-` and `.`) or an address"
                    ))
                }
            }
        }
        Ok(HostRule { bound: bound.ip(), names })
    }

    /// Whether a request naming `host` (a `Host` header's value) is answered.
    pub(crate) fn allows(&self, host: &str) -> bool {
        let Some((name, _port)) = split_host(host) else { return false };
        if name == "localhost" || self.names.contains(&name) {
            return true;
        }
        match name.parse::<IpAddr>() {
            Ok(ip) => ip.is_loopback() || ip == self.bound || self.bound.is_unspecified(),
            Err(_) => false,
        }
    }
}

/// A refusal: the status and one line saying why and what to do.
fn refuse(status: StatusCode, line: String) -> Response {
    (status, [(header::CONTENT_TYPE, "text/plain; charset=utf-8")], line).into_response()
}

/// The middleware in front of every route: a request whose `Host` (and request-target
/// authority, when it has one) is not allowed is answered 403, one without a `Host` 400.
pub(crate) async fn check_host(State(rule): State<Arc<HostRule>>, request: Request, next: Next) -> Response {
    let mut hosts = request.headers().get_all(header::HOST).iter();
    let host = match (hosts.next(), hosts.next()) {
        (None, _) => {
            return refuse(StatusCode::BAD_REQUEST, "refused: no Host header (HTTP/1.1 requires one)\n".into());
        }
        (Some(_), Some(_)) => return refuse(StatusCode::BAD_REQUEST, "refused: more than one Host header\n".into()),
        (Some(h), None) => String::from_utf8_lossy(h.as_bytes()).into_owned(),
    };
    let authority = request.uri().authority().map(|a| a.as_str().to_string());
    let refused = [Some(host), authority].into_iter().flatten().find(|h| !rule.allows(h));
    let Some(refused) = refused else { return next.run(request).await };
    let echoed: String = refused.chars().take(ECHO_MAX).collect();
    let name = split_host(&refused).map(|(n, _)| n).unwrap_or_else(|| "NAME".into());
    tracing::warn!(host = %echoed, "GUI refused a request for another host (DNS rebinding?)");
    refuse(
        StatusCode::FORBIDDEN,
        format!(
            "refused: Host {echoed:?} is not this server's address, localhost or an allowed name (a guard against \
             DNS rebinding); to serve under this name, start with --gui-allow-host {name} (GuiConfig::allowed_hosts)\n"
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rule(bound: &str, allowed: &[&str]) -> HostRule {
        let allowed: Vec<String> = allowed.iter().map(|s| s.to_string()).collect();
        HostRule::new(bound.parse().expect("an address"), &allowed).expect("a rule")
    }

    #[test]
    fn loopback_names_the_bound_address_and_allowed_names_pass_any_other_name_does_not() {
        let local = rule("127.0.0.1:7690", &[]);
        for ok in
            ["127.0.0.1:7690", "127.0.0.1", "localhost:7690", "LOCALHOST", "[::1]:7690", "[::1]", "127.0.0.2:9000"]
        {
            assert!(local.allows(ok), "{ok}");
        }
        // A tunnel (`ssh -L 9000:127.0.0.1:7690`) names another port: still this server.
        assert!(local.allows("localhost:9000"));
        for bad in [
            "evil.example:7690",
            "evil.example",
            "localhost.evil.example:7690",
            "127.0.0.1.nip.io:7690",
            "192.168.1.5:7690",
            "",
            ":7690",
            "127.0.0.1:",
            "127.0.0.1:port",
            "127.0.0.1:123456",
            "[::1",
            "[evil]:80",
            "evil example",
            "user@127.0.0.1",
        ] {
            assert!(!local.allows(bad), "{bad:?}");
        }
        let lan = rule("10.0.0.5:80", &["Robot.LAN"]);
        assert!(lan.allows("10.0.0.5"), "a LAN address is reached by IP");
        assert!(lan.allows("10.0.0.5:80"));
        assert!(!lan.allows("10.0.0.6"), "another address");
        assert!(lan.allows("robot.lan:80"), "an allowed name, any case");
        assert!(!lan.allows("robot.lan.evil.example"));
        let any = rule("0.0.0.0:7690", &[]);
        assert!(any.allows("192.168.1.5:7690"), "bound to every interface: any address");
        assert!(any.allows("[fe80::1]:7690"));
        assert!(!any.allows("robot.lan:7690"), "names still need allowing");
        let v6 = rule("[::]:7690", &[]);
        assert!(v6.allows("10.1.2.3:7690"));
    }

    #[test]
    fn an_allowed_host_with_a_port_or_not_a_name_is_a_clear_error() {
        let bound: SocketAddr = "127.0.0.1:0".parse().expect("addr");
        let e = HostRule::new(bound, &["robot.lan:8080".into()]).expect_err("a port");
        assert!(e.contains("without a port") && e.contains("`robot.lan`"), "{e}");
        let e = HostRule::new(bound, &["http://robot.lan".into()]).expect_err("a URL");
        assert!(e.contains("http://robot.lan") && e.contains("not a host name"), "{e}");
        assert!(HostRule::new(bound, &["".into()]).is_err());
        let ok = HostRule::new(bound, &["robot.lan".into(), "[fd00::5]".into(), "10.0.0.9".into()]).expect("names");
        assert!(ok.allows("[fd00::5]:7690") && ok.allows("10.0.0.9"));
    }
}
