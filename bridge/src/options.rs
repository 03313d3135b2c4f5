//! The bridge's command line, and the zenoh configuration it makes of it.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Parser, ValueEnum};

/// Carries a vas server's services over Eclipse zenoh, for renderers, input devices and users on
/// other machines: outputs out (thinned where a renderer asks), input samples and control
/// requests in. Keys: `vas/<SESSION>/...` (docs/wire.md).
#[derive(Debug, Clone, Parser)]
#[command(name = "vas-bridge", version)]
pub struct Options {
    /// The server's iceoryx2 prefix (its `--prefix`); without, iceoryx2's configured one.
    #[arg(long, value_name = "P")]
    pub prefix: Option<String>,
    /// The session's name: every key starts with `vas/<NAME>/`, so that one zenoh network
    /// carries several sessions.
    #[arg(long, value_name = "NAME", default_value = "default")]
    pub session: String,
    /// zenoh's own JSON5 configuration file; --mode, --listen, --connect and
    /// --no-multicast-scouting override its settings.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// zenoh's mode [default: peer, or the configuration file's].
    #[arg(long, value_enum)]
    pub mode: Option<Mode>,
    /// An endpoint to listen on, e.g. `tcp/0.0.0.0:7447` (repeatable).
    #[arg(long = "listen", value_name = "ENDPOINT")]
    pub listen: Vec<String>,
    /// An endpoint of a peer or router to connect to, e.g. `tcp/192.168.1.2:7447` (repeatable).
    #[arg(long = "connect", value_name = "ENDPOINT")]
    pub connect: Vec<String>,
    /// Look for no peers by multicast: only --connect's (networks and containers that do not
    /// pass multicast).
    #[arg(long)]
    pub no_multicast_scouting: bool,
    /// Publish parts and hand frames thinned to HZ as well, on `.../parts/@<HZ>hz` and
    /// `.../hand/@<HZ>hz` (repeatable; events are never thinned).
    #[arg(
        long = "rate",
        value_name = "HZ",
        default_values_t = [90],
        value_parser = clap::value_parser!(u32).range(1..=10_000)
    )]
    pub rates: Vec<u32>,
    /// Take input samples for the user called NAME (repeatable); samples of other users are
    /// refused and counted. Without, every user of the scene.
    #[arg(long = "user", value_name = "NAME")]
    pub users: Vec<String>,
}

/// zenoh's modes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    /// Talks to peers directly (and to routers).
    Peer,
    /// Talks through one peer or router.
    Client,
    /// Routes for others.
    Router,
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::Peer => "peer",
            Mode::Client => "client",
            Mode::Router => "router",
        }
    }
}

impl Options {
    /// The zenoh configuration: the file's (or zenoh's defaults), with the command line's
    /// settings over it.
    pub fn zenoh_config(&self) -> anyhow::Result<zenoh::Config> {
        let mut config = match &self.config {
            Some(path) => zenoh::Config::from_file(path)
                .map_err(|error| anyhow::anyhow!("{error}"))
                .with_context(|| {
                    format!("cannot read the zenoh configuration {}", path.display())
                })?,
            None => zenoh::Config::default(),
        };
        let mut set = |key: &str, value: String| {
            config
                .insert_json5(key, &value)
                .map_err(|error| anyhow::anyhow!("{error}"))
                .with_context(|| format!("invalid zenoh setting {key} = {value}"))
        };
        if let Some(mode) = self.mode {
            set("mode", format!("{:?}", mode.name()))?;
        }
        if !self.listen.is_empty() {
            set("listen/endpoints", serde_json::to_string(&self.listen)?)?;
        }
        if !self.connect.is_empty() {
            set("connect/endpoints", serde_json::to_string(&self.connect)?)?;
        }
        if self.no_multicast_scouting {
            set("scouting/multicast/enabled", "false".to_owned())?;
        }
        Ok(config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Options, clap::Error> {
        Options::try_parse_from(std::iter::once("vas-bridge").chain(args.iter().copied()))
    }

    #[test]
    fn endpoints_and_mode_reach_the_zenoh_configuration() {
        let options = parse(&[
            "--mode",
            "client",
            "--connect",
            "tcp/127.0.0.1:7447",
            "--no-multicast-scouting",
        ])
        .expect("valid arguments");
        assert_eq!(options.rates, vec![90]);
        let config = options.zenoh_config().expect("a valid configuration");
        let json = |key: &str| config.get_json(key).expect("a known key");
        assert_eq!(json("mode"), "\"client\"");
        assert!(json("connect/endpoints").contains("tcp/127.0.0.1:7447"));
        assert_eq!(json("scouting/multicast/enabled"), "false");
    }

    #[test]
    fn bad_arguments_are_refused_with_the_reason() {
        assert!(parse(&["--rate", "0"]).is_err());
        assert!(parse(&["--mode", "satellite"]).is_err());
        let bad_endpoint = parse(&["--listen", "carrier-pigeon"]).expect("parsed");
        let error = bad_endpoint
            .zenoh_config()
            .expect_err("refused")
            .to_string();
        assert!(error.contains("listen/endpoints"), "{error}");
        let missing = parse(&["--config", "/nonexistent/zenoh.json5"]).expect("parsed");
        let error = format!("{:#}", missing.zenoh_config().expect_err("refused"));
        assert!(
            error.contains("cannot read the zenoh configuration"),
            "{error}"
        );
    }
}
