//! Status codes, the thread-local error message, and the guard that keeps panics in Rust.

use innersphere::Error;
use std::cell::RefCell;
use std::ffi::{c_char, c_int, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Success.
pub const IST_OK: c_int = 0;
/// A required pointer argument was NULL.
pub const IST_ERR_NULL: c_int = 1;
/// An argument is out of range or malformed (a path that is not UTF-8, k = 0, an index past
/// the end, a NaN option).
pub const IST_ERR_INVALID_ARGUMENT: c_int = 2;
/// A pose is not a rigid transform (non-finite, a quaternion that cannot be normalised, a
/// matrix that is not a rotation).
pub const IST_ERR_POSE: c_int = 3;
/// A file could not be read or written.
pub const IST_ERR_IO: c_int = 4;
/// A mesh file could not be parsed, or the mesh is no usable solid.
pub const IST_ERR_MESH: c_int = 5;
/// A tree file is corrupt, truncated or not a tree file.
pub const IST_ERR_CORRUPT_TREE: c_int = 6;
/// The library panicked (a bug: please report it with ist_last_error()).
pub const IST_ERR_PANIC: c_int = 7;

thread_local! {
    static LAST: RefCell<CString> = RefCell::new(CString::default());
}

/// Remembers `message` as this thread's last error.
pub(crate) fn set_error(message: &str) {
    let c = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST.with(|l| *l.borrow_mut() = c);
}

/// A failure: its status and message.
pub(crate) struct Fail(pub c_int, pub String);

impl Fail {
    pub(crate) fn null(what: &str) -> Fail {
        Fail(IST_ERR_NULL, format!("{what} is NULL"))
    }
    pub(crate) fn arg(message: impl Into<String>) -> Fail {
        Fail(IST_ERR_INVALID_ARGUMENT, message.into())
    }
}

impl From<Error> for Fail {
    fn from(e: Error) -> Fail {
        let code = match &e {
            Error::Io { .. } | Error::Output(_) => IST_ERR_IO,
            Error::Parse { .. } | Error::UnsupportedFormat(_) | Error::InvalidMesh(_) => {
                IST_ERR_MESH
            }
            Error::CorruptTree(_) => IST_ERR_CORRUPT_TREE,
            Error::Pose(_) => IST_ERR_POSE,
            _ => IST_ERR_INVALID_ARGUMENT,
        };
        Fail(code, e.to_string())
    }
}

/// Runs `f`; a failure or a panic sets the last error and returns its status.
pub(crate) fn status(f: impl FnOnce() -> Result<(), Fail>) -> c_int {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => IST_OK,
        Ok(Err(Fail(code, message))) => {
            set_error(&message);
            code
        }
        Err(p) => {
            set_error(&panic_message(p));
            IST_ERR_PANIC
        }
    }
}

/// Runs `f` for a pointer result: NULL (and the last error set) on failure or panic.
pub(crate) fn pointer<T>(f: impl FnOnce() -> Result<Box<T>, Fail>) -> *mut T {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(b)) => Box::into_raw(b),
        Ok(Err(Fail(_, message))) => {
            set_error(&message);
            std::ptr::null_mut()
        }
        Err(p) => {
            set_error(&panic_message(p));
            std::ptr::null_mut()
        }
    }
}

fn panic_message(p: Box<dyn std::any::Any + Send>) -> String {
    let what = p
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    format!("innersphere panicked (a bug, please report it): {what}")
}

/// The message of the last failing call on this thread ("" when none failed yet). The
/// pointer stays valid until the next failing call on the same thread; do not free it.
#[no_mangle]
pub extern "C" fn ist_last_error() -> *const c_char {
    LAST.with(|l| l.borrow().as_ptr())
}
