//! Build script for the C API:
//! - generates the header from `src/ffi/` with cbindgen (settings in `cbindgen.toml`) into
//!   `OUT_DIR`, adding the SNAKEGRID_VERSION_* macros from Cargo.toml so they cannot drift. The
//!   committed `include/snakegrid.h` is never written by a build: a test (tests/c_api.rs)
//!   compares it with this one and fails while it is stale, and
//!   `SNAKEGRID_UPDATE_HEADER=1 cargo test --test c_api header` copies the new one in;
//! - gives the shared library its SONAME: `libsnakegrid.so.0.MINOR` while the version is 0.x (a
//!   minor release may break the ABI), `libsnakegrid.so.MAJOR` from 1.0 on, so programs linked
//!   against an installed copy record that name rather than the build path;
//! - tells `tests/c_api.rs` the target triple (for the `cc` crate) and where the header is.

use std::env;
use std::path::PathBuf;

fn main() {
    let root =
        PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let version = |part: &str| {
        env::var(format!("CARGO_PKG_VERSION_{part}")).expect("cargo sets the version parts")
    };
    let (major, minor, patch) = (version("MAJOR"), version("MINOR"), version("PATCH"));
    let number = |part: &str| part.parse::<u64>().expect("version parts are numbers");

    // All of src/: the C API hands out some core types as they are (the metrics structs).
    // Cargo.toml for the version macros.
    for input in ["src", "cbindgen.toml", "Cargo.toml"] {
        println!("cargo:rerun-if-changed={input}");
    }

    let mut config = cbindgen::Config::from_file(root.join("cbindgen.toml"))
        .expect("cbindgen.toml is readable and valid");
    config.after_includes = Some(format!(
        "\n#define SNAKEGRID_VERSION_MAJOR {major}\n#define SNAKEGRID_VERSION_MINOR {minor}\n\
         #define SNAKEGRID_VERSION_PATCH {patch}\n#define SNAKEGRID_VERSION \"{major}.{minor}.{patch}\"\n\
         /* MAJOR * 10000 + MINOR * 100 + PATCH, for #if comparisons. */\n\
         #define SNAKEGRID_VERSION_NUMBER {}\n\n\
         /* Status-returning functions warn when their status is ignored. */\n\
         #if defined(__GNUC__) || defined(__clang__)\n\
         #define SNAKEGRID_MUST_USE __attribute__((warn_unused_result))\n\
         #else\n#define SNAKEGRID_MUST_USE\n#endif",
        number(&major) * 10_000 + number(&minor) * 100 + number(&patch),
    ));
    let header = cbindgen::generate_with_config(&root, config).expect("cbindgen can read src/ffi");
    let generated = out.join("snakegrid.h");
    header.write_to_file(&generated);
    println!(
        "cargo:rustc-env=SNAKEGRID_GENERATED_HEADER={}",
        generated.display()
    );

    if env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        let soname = if major == "0" {
            format!("libsnakegrid.so.0.{minor}")
        } else {
            format!("libsnakegrid.so.{major}")
        };
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,{soname}");
        println!("cargo:rustc-env=SNAKEGRID_SONAME={soname}");
    }
    println!(
        "cargo:rustc-env=SNAKEGRID_TARGET={}",
        env::var("TARGET").expect("cargo sets TARGET")
    );
}
