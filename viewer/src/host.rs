//! Which `Host` a request may name: this viewer, and no other site.
//!
//! DNS rebinding: a page of `attacker.example`, whose name the attacker then points at
//! 127.0.0.1, talks to the viewer as its own site (same origin, so the browser lets it read the
//! answers and open the WebSocket), but its requests still say `Host: attacker.example:PORT`.
//! So a request is served only when its `Host` (and the authority of an absolute URI) names the
//! listening port and one of the viewer's own names: `127.0.0.1`, `localhost` and `[::1]`, the host
//! given to `--listen`, and, when that is all addresses (`0.0.0.0` or `[::]`), any IP address
//! (a rebinding attack needs a name; an IP address is the site it names).

use crate::listen::ListenAddress;

/// The hosts this viewer answers to.
#[derive(Debug, Clone)]
pub struct Hosts {
    /// Names accepted, lower-case, IPv6 addresses in brackets.
    names: Vec<String>,
    /// Whether any IP address is accepted too.
    any_ip: bool,
    /// The port a request must name.
    port: u16,
    /// The scheme's default port, which a `Host` without a port means.
    default_port: u16,
}

impl Hosts {
    /// The hosts of a viewer listening at `listen` on `port` (the port bound), over HTTPS or not.
    pub fn new(listen: &ListenAddress, port: u16, https: bool) -> Self {
        let mut names: Vec<String> = ["127.0.0.1", "localhost", "[::1]"].map(Into::into).into();
        if !names.contains(&listen.host) {
            names.push(listen.host.clone());
        }
        Self {
            names,
            any_ip: listen.ip().is_some_and(|ip| ip.is_unspecified()),
            port,
            default_port: if https { 443 } else { 80 },
        }
    }

    /// Whether `authority` (a `Host` header's value, `host[:port]`) names this viewer.
    ///
    /// The port must be written as browsers write it, in plain decimal digits without leading
    /// zeros: a number parser would also take `+8080` or `08080`, forms no browser sends, which
    /// only a hand-made request would use to slip past the check.
    pub fn accepts(&self, authority: &str) -> bool {
        let (host, port_matches) = match authority.rsplit_once(':') {
            // An IPv6 address without a port ends in `]`; its colons are not a port's.
            Some((host, port)) if !port.contains(']') => (host, port == self.port.to_string()),
            _ => (authority, self.port == self.default_port),
        };
        if !port_matches {
            return false;
        }
        let host = host.to_ascii_lowercase();
        self.names.contains(&host) || (self.any_ip && is_ip_literal(&host))
    }
}

/// Whether `host` is an IPv4 address or a bracketed IPv6 address.
fn is_ip_literal(host: &str) -> bool {
    match host.strip_prefix('[').and_then(|h| h.strip_suffix(']')) {
        Some(v6) => v6.parse::<std::net::Ipv6Addr>().is_ok(),
        None => host.parse::<std::net::Ipv4Addr>().is_ok(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hosts(listen: &str, https: bool) -> Hosts {
        let listen: ListenAddress = listen.parse().unwrap();
        Hosts::new(&listen, 8080, https)
    }

    #[test]
    fn the_viewers_own_names_on_its_port_only() {
        let loopback = hosts("127.0.0.1:0", false);
        for good in [
            "127.0.0.1:8080",
            "localhost:8080",
            "LOCALHOST:8080",
            "[::1]:8080",
        ] {
            assert!(loopback.accepts(good), "{good}");
        }
        for bad in [
            "attacker.example:8080",
            "127.0.0.1:8081",
            "127.0.0.1",
            "localhost",
            "[::1]",
            "192.168.1.5:8080",
            "localhost.:8080",
            "127.0.0.1:8080:8080",
            "127.0.0.1:+8080",
            "127.0.0.1:08080",
            "127.0.0.1: 8080",
            "127.0.0.1:",
            "",
            ":8080",
        ] {
            assert!(!loopback.accepts(bad), "{bad}");
        }
        let named = hosts("viewer.lan:0", true);
        assert!(named.accepts("viewer.lan:8080"));
        assert!(!named.accepts("192.168.1.5:8080"));
    }

    #[test]
    fn all_addresses_accept_any_ip_but_no_other_name() {
        let any = hosts("0.0.0.0:0", true);
        assert!(any.accepts("192.168.1.5:8080"));
        assert!(any.accepts("[fe80::1]:8080"));
        assert!(!any.accepts("attacker.example:8080"));
        assert!(!any.accepts("192.168.1.5:443"));
        let default_port = Hosts::new(&"0.0.0.0:443".parse().unwrap(), 443, true);
        assert!(default_port.accepts("192.168.1.5"));
        assert!(default_port.accepts("[::1]"));
    }
}
