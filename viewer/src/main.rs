//! `vas-viewer`: serves a browser and WebXR view of a running vas server (see the library's
//! documentation for how it is built).

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Context;
use clap::Parser;
use vas_viewer::{http, hub, link};

/// Serves a browser and WebXR view of a running vas server.
#[derive(Debug, Parser)]
#[command(name = "vas-viewer", version, about)]
struct Args {
    /// iceoryx2 prefix of the server (its `--prefix`); default: the iceoryx2 configuration's.
    #[arg(long)]
    prefix: Option<String>,
    /// Address to serve the page on. The default accepts connections from this machine only;
    /// a headset reaches it over USB with `adb reverse` (see the README).
    #[arg(long, default_value = "127.0.0.1:8080")]
    listen: SocketAddr,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .with_writer(std::io::stderr)
        .init();

    let (hub, inbox) = hub::Hub::new();
    let hub = Arc::new(hub);
    let stop = Arc::new(AtomicBool::new(false));
    let link = {
        let (hub, stop) = (Arc::clone(&hub), Arc::clone(&stop));
        std::thread::Builder::new()
            .name("vas-link".into())
            .spawn(move || link::run(args.prefix.as_deref(), &hub, inbox, &stop))
            .context("start the link thread")?
    };

    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("start the async runtime")?;
    let served = runtime.block_on(http::serve(args.listen, Arc::clone(&hub)));

    stop.store(true, Ordering::Relaxed);
    if link.join().is_err() {
        tracing::error!("the link thread panicked");
    }
    served
}
