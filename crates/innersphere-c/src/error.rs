//! Status codes, the thread-local error message, and the guard that keeps panics in Rust.

use innersphere::Error;
use std::cell::{Cell, RefCell};
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
    static LAST_STATUS: Cell<c_int> = const { Cell::new(IST_OK) };
}

/// Remembers `code` and `message` as this thread's last error.
pub(crate) fn set_error(code: c_int, message: &str) {
    let c = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST.with(|l| *l.borrow_mut() = c);
    LAST_STATUS.with(|s| s.set(code));
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
            set_error(code, &message);
            code
        }
        Err(p) => {
            set_error(IST_ERR_PANIC, &panic_message(p.as_ref()));
            IST_ERR_PANIC
        }
    }
}

/// Runs `f` for a pointer result: NULL (and the last error set) on failure or panic.
pub(crate) fn pointer<T>(f: impl FnOnce() -> Result<Box<T>, Fail>) -> *mut T {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(b)) => Box::into_raw(b),
        Ok(Err(Fail(code, message))) => {
            set_error(code, &message);
            std::ptr::null_mut()
        }
        Err(p) => {
            set_error(IST_ERR_PANIC, &panic_message(p.as_ref()));
            std::ptr::null_mut()
        }
    }
}

fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
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

/// The status of the last failing call on this thread (IST_OK when none failed yet): also
/// for the calls that answer NULL on failure (ist_tree_load, ist_tree_build, …), so a C
/// program can tell a missing file (IST_ERR_IO) from a corrupt one (IST_ERR_CORRUPT_TREE)
/// or a mesh that is no solid (IST_ERR_MESH) without reading the message.
#[no_mangle]
pub extern "C" fn ist_last_status() -> c_int {
    LAST_STATUS.with(|s| s.get())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panics_message_names_its_payload() {
        let m = panic_message(&"the payload");
        assert!(
            m.starts_with("innersphere panicked") && m.ends_with(": the payload"),
            "{m}"
        );
        let m = panic_message(&String::from("a String payload"));
        assert!(m.ends_with(": a String payload"), "{m}");
        assert!(panic_message(&42u8).ends_with(": unknown panic"));
    }

    #[test]
    fn a_panic_is_a_status_and_a_message_not_an_unwind() {
        let code = status(|| panic!("boom"));
        assert_eq!(code, IST_ERR_PANIC);
        assert_eq!(ist_last_status(), IST_ERR_PANIC);
        let m = unsafe { std::ffi::CStr::from_ptr(ist_last_error()) };
        assert!(m.to_str().unwrap().ends_with(": boom"));
    }

    #[test]
    fn every_library_error_has_its_status() {
        let io = Error::Io {
            path: "x".into(),
            source: std::io::Error::other("gone"),
        };
        assert_eq!(Fail::from(io).0, IST_ERR_IO);
        assert_eq!(Fail::from(Error::Output("o".into())).0, IST_ERR_IO);
        assert_eq!(Fail::from(Error::InvalidMesh("m".into())).0, IST_ERR_MESH);
        assert_eq!(
            Fail::from(Error::UnsupportedFormat("f".into())).0,
            IST_ERR_MESH
        );
        let parse = Error::Parse {
            path: "p".into(),
            format: "stl",
            message: "short".into(),
        };
        assert_eq!(Fail::from(parse).0, IST_ERR_MESH);
        assert_eq!(
            Fail::from(Error::CorruptTree("t".into())).0,
            IST_ERR_CORRUPT_TREE
        );
        let pose = innersphere::Pose::new(
            innersphere::glam::DVec3::NAN,
            innersphere::glam::DQuat::IDENTITY,
        )
        .unwrap_err();
        assert_eq!(Fail::from(Error::Pose(pose)).0, IST_ERR_POSE);
        assert_eq!(
            Fail::from(Error::InvalidOption("k".into())).0,
            IST_ERR_INVALID_ARGUMENT
        );
    }
}
