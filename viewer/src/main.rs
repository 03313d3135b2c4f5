//! `vas-viewer`: serves a browser and WebXR view of a running vas server (see the library's
//! documentation for how it is built).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Context;
use clap::Parser;
use vas_viewer::settings::{Options, Settings};
use vas_viewer::{http, hub, link};

fn main() -> anyhow::Result<()> {
    let options = Options::parse();
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    // Before anything starts: a viewer that must not serve as told refuses here, with the reason.
    let settings = Settings::new(&options)?;

    let (hub, inbox) = hub::Hub::new();
    let hub = Arc::new(hub);
    let stop = Arc::new(AtomicBool::new(false));
    let link = {
        let (hub, stop) = (Arc::clone(&hub), Arc::clone(&stop));
        std::thread::Builder::new()
            .name("vas-link".into())
            .spawn(move || link::run(options.prefix.as_deref(), &hub, inbox, &stop))
            .context("start the link thread")?
    };

    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("start the async runtime")?;
    let served = runtime.block_on(http::serve(settings, Arc::clone(&hub)));

    stop.store(true, Ordering::Relaxed);
    if link.join().is_err() {
        tracing::error!("the link thread panicked");
    }
    served
}
