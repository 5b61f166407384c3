//! `include/situate.h` is generated from `src/abi.rs` by cbindgen: this test
//! fails when the committed header differs from a fresh one.
//! `SITUATE_BLESS=1 cargo test -p situate_cabi --test header` rewrites it.

use std::path::Path;

#[test]
fn the_committed_header_is_fresh() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(crate_dir.join("src/abi.rs"))
        .generate()
        .expect("cbindgen generates the header");
    let mut fresh = Vec::new();
    bindings.write(&mut fresh);
    let fresh = String::from_utf8(fresh).expect("UTF-8");
    let committed_path = crate_dir.join("../../../include/situate.h");
    if std::env::var_os("SITUATE_BLESS").is_some() {
        std::fs::write(&committed_path, &fresh).expect("write include/situate.h");
        return;
    }
    let committed = std::fs::read_to_string(&committed_path).unwrap_or_default();
    assert!(
        committed == fresh,
        "include/situate.h is stale (or missing): regenerate it with \
         `SITUATE_BLESS=1 cargo test -p situate_cabi --test header`"
    );
    assert!(fresh.contains("#define SITUATE_ABI_VERSION 2"), "{fresh}");
}
