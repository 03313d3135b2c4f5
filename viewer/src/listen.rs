//! Where the viewer listens: `--listen HOST:PORT`, a host name (resolved) or an IP address, and
//! whether that is this machine only (loopback) or the network beyond it.

use std::net::{IpAddr, SocketAddr, ToSocketAddrs};
use std::str::FromStr;

use anyhow::Context;

/// `--listen`'s value as given: a host (a name, an IPv4 address or a bracketed IPv6 address)
/// and a port.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ListenAddress {
    /// The host as given, lower-cased; an IPv6 address keeps its brackets (as in a URL).
    pub host: String,
    /// The port; 0 picks a free one.
    pub port: u16,
}

impl FromStr for ListenAddress {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let (host, port) = text
            .rsplit_once(':')
            .ok_or_else(|| format!("{text:?} is not HOST:PORT"))?;
        let port = port
            .parse()
            .map_err(|_| format!("{port:?} is not a port number (0 to 65535)"))?;
        let bracketed = host.starts_with('[') && host.ends_with(']');
        if host.is_empty()
            || (host.contains(':') && !bracketed)
            || (bracketed && host[1..host.len() - 1].parse::<IpAddr>().is_err())
        {
            return Err(format!(
                "{host:?} is not a host name or IP address (IPv6 in brackets: [::1]:8080)"
            ));
        }
        Ok(Self {
            host: host.to_ascii_lowercase(),
            port,
        })
    }
}

impl std::fmt::Display for ListenAddress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.host, self.port)
    }
}

impl ListenAddress {
    /// The host without an IPv6 address's brackets, as a resolver takes it.
    fn bare_host(&self) -> &str {
        self.host.trim_start_matches('[').trim_end_matches(']')
    }

    /// The host as an IP address, if it is one.
    pub fn ip(&self) -> Option<IpAddr> {
        self.bare_host().parse().ok()
    }

    /// The addresses to listen on: the host's addresses (a name may have several, such as
    /// `localhost`'s 127.0.0.1 and ::1), each once, in the resolver's order.
    pub fn resolve(&self) -> anyhow::Result<Vec<SocketAddr>> {
        let resolved = (self.bare_host(), self.port)
            .to_socket_addrs()
            .with_context(|| format!("resolve --listen {self}"))?;
        let mut addresses: Vec<SocketAddr> = Vec::new();
        for address in resolved {
            if !addresses.contains(&address) {
                addresses.push(address);
            }
        }
        anyhow::ensure!(!addresses.is_empty(), "--listen {self} resolves to nothing");
        Ok(addresses)
    }
}

/// Whether any of `addresses` reaches beyond this machine.
pub fn beyond_loopback(addresses: &[SocketAddr]) -> bool {
    addresses.iter().any(|address| !address.ip().is_loopback())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_addresses_are_read_and_resolved() {
        let localhost: ListenAddress = "LocalHost:8080".parse().unwrap();
        assert_eq!(localhost.host, "localhost");
        let addresses = localhost.resolve().unwrap();
        assert!(
            addresses
                .iter()
                .all(|a| a.ip().is_loopback() && a.port() == 8080)
        );
        assert!(!beyond_loopback(&addresses));

        let v6: ListenAddress = "[::1]:0".parse().unwrap();
        assert_eq!(v6.ip(), Some(IpAddr::from([0u16, 0, 0, 0, 0, 0, 0, 1])));
        let any: ListenAddress = "0.0.0.0:8443".parse().unwrap();
        assert!(beyond_loopback(&any.resolve().unwrap()));

        for bad in [
            "8080",
            ":8080",
            "::1:8080",
            "[nothing]:1",
            "localhost:http",
            "a:70000",
        ] {
            assert!(bad.parse::<ListenAddress>().is_err(), "{bad}");
        }
    }
}
