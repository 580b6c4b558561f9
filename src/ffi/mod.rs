//! The C API (`include/snakegrid.h`, generated from this module by cbindgen in build.rs).
//!
//! A thin layer over [`crate::generate`] and [`crate::io::run`]: it turns C arguments into Rust
//! values, Rust results into opaque handles and plain structs, and every error or panic into a
//! status code with a message. No part of the method lives here. This is the crate's only
//! `unsafe` code; each block says why it holds.
//!
//! - [`status`]: status codes, the thread's last error message, the panic boundary;
//! - `handle`: tagged opaque handles and checked argument conversion;
//! - [`options`]: method parameters by name;
//! - [`regions`]: regions given in memory as (id, WKB);
//! - [`job`]: a dataset-to-dataset run, as the command line describes it;
//! - [`run`]: the two entry points and the progress callback;
//! - [`result`]: reading a finished run;
//! - [`score`]: scoring a layout made elsewhere;
//! - [`edits`]: the pins a hand-edited grid layer gives, for a re-layout;
//! - [`crs`]: the working-CRS rule, for hosts that project layers themselves;
//! - [`fields`]: the fields a grid layer adds, for hosts that write layers themselves.
//!
//! The safety contract of every `unsafe extern "C"` function is the one the header states once
//! for all (pointers are NULL or valid for the access described, handles come from this
//! library and are not yet freed, strings are NUL-terminated): hence no per-function
//! `# Safety` sections.
#![allow(clippy::missing_safety_doc)]
#![deny(unsafe_op_in_unsafe_fn)]

// In the order the header lists them (cbindgen follows the declarations); blank lines keep
// rustfmt from sorting them.
pub mod status;

mod handle;

pub mod options;

pub mod regions;

pub mod job;

pub mod run;

pub mod result;

pub mod score;

pub mod edits;

pub mod crs;

pub mod fields;

use std::ffi::{c_char, CStr};

/// `SNAKEGRID_VERSION` as a NUL-terminated string.
const VERSION: &CStr =
    match CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes()) {
        Ok(v) => v,
        Err(_) => panic!("the package version holds no NUL"),
    };

/// The library's version, "MAJOR.MINOR.PATCH". Compare with the SNAKEGRID_VERSION_* macros to
/// check that the header matches the library loaded at run time.
///
/// Never fails. The string is static. Thread safety: safe from any thread.
#[no_mangle]
pub extern "C" fn snakegrid_version() -> *const c_char {
    status::catch(|| Ok(VERSION.as_ptr())).unwrap_or(VERSION.as_ptr())
}

#[cfg(test)]
mod tests {
    /// Every exported function runs its body inside the panic boundary: its body calls one of
    /// the boundary functions (or `read`, the accessors' shared body, which does).
    #[test]
    fn every_export_goes_through_the_panic_boundary() {
        let sources = [
            include_str!("mod.rs"),
            include_str!("status.rs"),
            include_str!("options.rs"),
            include_str!("regions.rs"),
            include_str!("job.rs"),
            include_str!("run.rs"),
            include_str!("result.rs"),
            include_str!("score.rs"),
            include_str!("edits.rs"),
            include_str!("crs.rs"),
            include_str!("fields.rs"),
        ];
        // Built from parts so that this test's own text is not taken for an export.
        let marker = concat!("#[no_", "mangle]");
        let mut exports = 0;
        for source in sources {
            for export in source.split(marker).skip(1) {
                let body = export.split("\n}\n").next().unwrap();
                let name = body.split("fn ").nth(1).unwrap().split('(').next().unwrap();
                let wrapped = ["guard(", "guard_free(", "catch(", "read("]
                    .iter()
                    .any(|b| body.contains(b));
                assert!(wrapped, "{name} is not wrapped in the panic boundary");
                exports += 1;
            }
        }
        // handle.rs exports nothing; the count catches a module left out of the list above.
        assert_eq!(exports, 55);
    }
}
