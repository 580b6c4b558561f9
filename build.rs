//! Build script for the C API:
//! - regenerates `include/snakegrid.h` from `src/ffi/` with cbindgen (settings in
//!   `cbindgen.toml`), adding the SNAKEGRID_VERSION_* macros from Cargo.toml so they cannot
//!   drift; the header is committed and CI fails when the regenerated one differs;
//! - gives the shared library the SONAME `libsnakegrid.so.MAJOR`, so programs linked against
//!   an installed copy record that name rather than the build path;
//! - tells `tests/c_api.rs` the target triple, which it needs to drive the `cc` crate.

use std::env;
use std::path::PathBuf;

fn main() {
    let root =
        PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let version = |part: &str| {
        env::var(format!("CARGO_PKG_VERSION_{part}")).expect("cargo sets the version parts")
    };
    let (major, minor, patch) = (version("MAJOR"), version("MINOR"), version("PATCH"));

    // Cargo.toml for the version macros.
    for input in ["src/ffi", "src/lib.rs", "cbindgen.toml", "Cargo.toml"] {
        println!("cargo:rerun-if-changed={input}");
    }

    let mut config = cbindgen::Config::from_file(root.join("cbindgen.toml"))
        .expect("cbindgen.toml is readable and valid");
    config.after_includes = Some(format!(
        "\n#define SNAKEGRID_VERSION_MAJOR {major}\n#define SNAKEGRID_VERSION_MINOR {minor}\n\
         #define SNAKEGRID_VERSION_PATCH {patch}\n#define SNAKEGRID_VERSION \"{major}.{minor}.{patch}\"",
    ));
    let header = cbindgen::generate_with_config(&root, config).expect("cbindgen can read src/ffi");
    // write_to_file leaves the file alone when its content is unchanged, so builds that change
    // nothing in the API do not touch the committed header.
    header.write_to_file(root.join("include/snakegrid.h"));

    if env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libsnakegrid.so.{major}");
    }
    println!(
        "cargo:rustc-env=SNAKEGRID_TARGET={}",
        env::var("TARGET").expect("cargo sets TARGET")
    );
}
