//! The viewer's tests, in one test binary: the real `vas-viewer` (and, where frames are needed,
//! the real `vas-server` and `vas-client` binaries), plain HTTP and WebSocket clients, and
//! headless Chromium through chromedriver. Chromium and chromedriver are required: without them
//! the browser tests fail and say what to install.

mod harness;
mod hosts;
mod limits;
mod page;
mod pages;
mod remote;
mod replay;
mod requests;
mod serving;
mod users;
mod websocket;
mod xr;
