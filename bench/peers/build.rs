fn main() {
    // copper-rs's logging macros read their string index from here at
    // compile time (harmless without the `copper` feature).
    if let Ok(out) = std::env::var("OUT_DIR") {
        println!("cargo:rustc-env=LOG_INDEX_DIR={out}");
    }
}
