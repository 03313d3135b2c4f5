//! The page's files, embedded in the binary: the only files the viewer serves.
//!
//! The table is fixed at compile time and looked up by exact path, so a request can name
//! nothing else (no `..`, no percent-decoding, no file system); the viewer runs the same from
//! any directory and needs nothing from the network.

/// One embedded file.
#[derive(Debug)]
pub struct Asset {
    /// The URL path it is served at.
    pub path: &'static str,
    /// Its `Content-Type`.
    pub content_type: &'static str,
    /// Its bytes.
    pub body: &'static [u8],
}

const HTML: &str = "text/html; charset=utf-8";
const JS: &str = "text/javascript; charset=utf-8";
const CSS: &str = "text/css; charset=utf-8";
const TEXT: &str = "text/plain; charset=utf-8";

/// An [`Asset`] served at `$path` from `assets/$file`.
macro_rules! asset {
    ($path:literal, $file:literal, $content_type:expr) => {
        Asset {
            path: $path,
            content_type: $content_type,
            body: include_bytes!(concat!("../assets/", $file)),
        }
    };
}

/// Every file the viewer serves. three.js is vendored (see `assets/vendor/README.md`); the
/// page's import map points `three` and `three/addons/` at these paths.
static ASSETS: &[Asset] = &[
    asset!("/", "index.html", HTML),
    asset!("/style.css", "style.css", CSS),
    asset!("/main.js", "main.js", JS),
    asset!("/connection.js", "connection.js", JS),
    asset!("/link.js", "link.js", JS),
    asset!("/view.js", "view.js", JS),
    asset!("/panel.js", "panel.js", JS),
    asset!("/xr.js", "xr.js", JS),
    asset!(
        "/vendor/three/three.module.min.js",
        "vendor/three/three.module.min.js",
        JS
    ),
    asset!(
        "/vendor/three/three.core.min.js",
        "vendor/three/three.core.min.js",
        JS
    ),
    asset!(
        "/vendor/three/addons/controls/OrbitControls.js",
        "vendor/three/addons/controls/OrbitControls.js",
        JS
    ),
    asset!(
        "/vendor/three/addons/webxr/VRButton.js",
        "vendor/three/addons/webxr/VRButton.js",
        JS
    ),
    asset!("/vendor/three/LICENSE", "vendor/three/LICENSE", TEXT),
];

/// The asset served at exactly `path`.
pub fn find(path: &str) -> Option<&'static Asset> {
    ASSETS.iter().find(|asset| asset.path == path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_asset_has_a_distinct_path_and_content() {
        for (index, asset) in ASSETS.iter().enumerate() {
            assert!(!asset.body.is_empty(), "{} is empty", asset.path);
            assert!(
                ASSETS[..index].iter().all(|other| other.path != asset.path),
                "{} is listed twice",
                asset.path
            );
        }
    }

    #[test]
    fn only_exact_paths_are_found() {
        assert!(find("/main.js").is_some());
        for path in [
            "/main.js/",
            "/./main.js",
            "//main.js",
            "/../main.js",
            "/%6Dain.js",
        ] {
            assert!(find(path).is_none(), "{path} was found");
        }
    }
}
