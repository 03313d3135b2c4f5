//! `vas-client reset`, `load-scene`, `scenes` and `set-metaphor`: the control service's
//! requests from the command line. Each prints the server's answer (the scene served after it)
//! as JSON, or the server's reason for refusing it.

use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;
use vas_client::{Roles, SlidingMetaphor};
use vas_protocol::ControlResponse;

/// How long a scene load may take: a large assembly takes a while.
const LOAD_TIMEOUT: Duration = Duration::from_secs(600);

/// Arguments of `vas-client load-scene`.
#[derive(Debug, clap::Args)]
pub struct LoadSceneArgs {
    /// The scene file, as the server's file system sees it (relative paths are made absolute
    /// here, so they mean what they mean to this shell).
    #[arg(required_unless_present = "name", conflicts_with = "name")]
    file: Option<PathBuf>,
    /// Load the scene the server offers under this name instead (see `vas-client scenes`).
    #[arg(long)]
    name: Option<String>,
}

/// The metaphors by their names (`rubber-band`, `spiral-spring`, `incremental`), listed in
/// `--help` and in the error for any other name.
pub fn metaphor_parser() -> impl clap::builder::TypedValueParser<Value = SlidingMetaphor> {
    use clap::builder::{PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(SlidingMetaphor::ALL.map(SlidingMetaphor::name)).map(|name| {
        name.parse()
            .expect("the parser lets only the listed names through")
    })
}

/// `vas-client reset`.
pub fn reset(prefix: Option<&str>) -> anyhow::Result<()> {
    let client = super::connect(prefix, Roles::CONTROL)?;
    print(&client.reset(super::CONTROL_TIMEOUT)?)
}

/// `vas-client load-scene`.
pub fn load_scene(prefix: Option<&str>, args: &LoadSceneArgs) -> anyhow::Result<()> {
    let client = super::connect(prefix, Roles::CONTROL)?;
    let response = match (&args.name, &args.file) {
        (Some(name), _) => client.load_named_scene(name, LOAD_TIMEOUT)?,
        (None, Some(file)) => {
            let file = std::path::absolute(file)
                .with_context(|| format!("cannot make {} absolute", file.display()))?;
            let file = file.to_str().context("the scene path is not UTF-8")?;
            client.load_scene(file, LOAD_TIMEOUT)?
        }
        (None, None) => anyhow::bail!("give a scene file or --name"),
    };
    print(&response)
}

/// `vas-client scenes`: the names the server offers, one per line.
pub fn scenes(prefix: Option<&str>) -> anyhow::Result<()> {
    let client = super::connect(prefix, Roles::CONTROL)?;
    let mut out = std::io::stdout().lock();
    for name in client.scene_names(super::CONTROL_TIMEOUT)? {
        writeln!(out, "{name}")?;
    }
    Ok(())
}

/// `vas-client set-metaphor`.
pub fn set_metaphor(prefix: Option<&str>, metaphor: SlidingMetaphor) -> anyhow::Result<()> {
    let client = super::connect(prefix, Roles::CONTROL)?;
    print(&client.set_metaphor(metaphor, super::CONTROL_TIMEOUT)?)
}

/// The scene served after the request, as one JSON line.
fn print(response: &ControlResponse) -> anyhow::Result<()> {
    let summary = serde_json::json!({
        "scene": response.scene_name.as_str()?,
        "source": response.scene_source.as_str()?,
        "parts": response.part_count,
    });
    let mut out = std::io::stdout().lock();
    serde_json::to_writer(&mut out, &summary)?;
    writeln!(out)?;
    Ok(())
}
