//! The viewer serves its embedded page and assets, and nothing else.

use std::path::Path;

use crate::harness::{Viewer, http_get};
use vas_testkit::{forget_prefix, unique_prefix};

/// Every file the page loads, by its URL path and its file under `assets/`.
const ASSETS: &[(&str, &str)] = &[
    ("/", "index.html"),
    ("/style.css", "style.css"),
    ("/main.js", "main.js"),
    ("/connection.js", "connection.js"),
    ("/link.js", "link.js"),
    ("/view.js", "view.js"),
    ("/panel.js", "panel.js"),
    ("/xr.js", "xr.js"),
    (
        "/vendor/three/three.module.min.js",
        "vendor/three/three.module.min.js",
    ),
    (
        "/vendor/three/three.core.min.js",
        "vendor/three/three.core.min.js",
    ),
    (
        "/vendor/three/addons/controls/OrbitControls.js",
        "vendor/three/addons/controls/OrbitControls.js",
    ),
    (
        "/vendor/three/addons/webxr/VRButton.js",
        "vendor/three/addons/webxr/VRButton.js",
    ),
];

#[tokio::test]
async fn the_page_and_its_assets_are_served_and_nothing_else() {
    let prefix = unique_prefix("viewer_assets");
    let viewer = Viewer::start(&prefix);
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    for (path, file) in ASSETS {
        let (status, body) = http_get(viewer.address, path).await;
        assert_eq!(status, 200, "GET {path}");
        let expected = std::fs::read(assets.join(file)).expect("the asset's source");
        assert!(body == expected, "GET {path} is not assets/{file}");
    }
    let (_, page) = http_get(viewer.address, "/").await;
    let page = String::from_utf8(page).expect("the page is UTF-8");
    assert!(
        page.contains(r#""three": "/vendor/three/three.module.min.js""#),
        "the import map points three.js at the viewer's own copy"
    );

    for path in [
        "/nothing-here",
        "/index.html/",
        "/../Cargo.toml",
        "/%2e%2e/",
        "/%2e%2e/Cargo.toml",
        "/%2E%2E/%2E%2E/etc/passwd",
        "/vendor/../main.js",
        "/vendor/three/../../../Cargo.toml",
        "/assets/main.js",
        "/src/main.rs",
        "//etc/passwd",
        "/main.js%00",
    ] {
        let (status, _) = http_get(viewer.address, path).await;
        assert_eq!(status, 404, "GET {path}");
    }
    drop(viewer);
    // SAFETY: the viewer, the only process on this prefix, has ended.
    unsafe { forget_prefix(&prefix) };
}
