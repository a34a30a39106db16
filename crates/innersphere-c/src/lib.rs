//! The C ABI of innersphere: opaque handles (`ist_tree`, `ist_pair`, `ist_haptic`), plain
//! `#[repr(C)]` structs, `int` status codes with a thread-local message, and no panic ever
//! unwinding into C. The header `include/innersphere.h` is generated from this crate by
//! cbindgen (`tests/header.rs` fails when it is stale). Every function is a thin shell over
//! the Rust API: the same answers, bit for bit.
#![allow(non_camel_case_types)]

mod batch;
mod error;
mod haptic;
mod query;
mod tree;
mod types;

pub use error::*;
pub use haptic::*;
pub use query::*;
pub use tree::*;
pub use types::*;

use std::ffi::{c_char, CStr};
use std::path::PathBuf;

/// The library's version, e.g. "0.1.0" (static; do not free).
#[no_mangle]
pub extern "C" fn ist_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// `p` as a reference, or the NULL error naming `what`.
unsafe fn reference<'a, T>(p: *const T, what: &str) -> Result<&'a T, Fail> {
    unsafe { p.as_ref() }.ok_or_else(|| Fail::null(what))
}

/// `p` as a mutable reference, or the NULL error naming `what`.
unsafe fn mutable<'a, T>(p: *mut T, what: &str) -> Result<&'a mut T, Fail> {
    unsafe { p.as_mut() }.ok_or_else(|| Fail::null(what))
}

/// A NUL-terminated path (any bytes on Unix; UTF-8 elsewhere).
unsafe fn path_arg(p: *const c_char, what: &str) -> Result<PathBuf, Fail> {
    if p.is_null() {
        return Err(Fail::null(what));
    }
    let c = unsafe { CStr::from_ptr(p) };
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        Ok(PathBuf::from(std::ffi::OsStr::from_bytes(c.to_bytes())))
    }
    #[cfg(not(unix))]
    {
        c.to_str()
            .map(PathBuf::from)
            .map_err(|_| Fail::arg(format!("{what} is not UTF-8")))
    }
}

use error::Fail;
