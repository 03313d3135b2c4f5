//! The committed C header is what the sources generate: a change to the interface that forgets
//! the header fails here (and so in CI).

use std::path::Path;

/// Set to regenerate the header instead of comparing.
const REGENERATE: &str = "VAS_REGENERATE_HEADER";

#[test]
fn the_committed_header_is_generated_from_the_sources() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_root_or_default(crate_dir);
    let mut generated = Vec::new();
    cbindgen::generate_with_config(crate_dir, config)
        .expect("cbindgen reads the sources")
        .write(&mut generated);
    let generated = String::from_utf8(generated).expect("the header is UTF-8");
    let path = crate_dir.join("include/vas_client.h");
    if std::env::var_os(REGENERATE).is_some() {
        std::fs::write(&path, &generated).expect("write the header");
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "client-c/include/vas_client.h differs from what the sources generate; regenerate it \
         with `{REGENERATE}=1 cargo test -p vas-client-c --test header` and commit it"
    );
}
