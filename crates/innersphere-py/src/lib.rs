//! The Python module `innersphere` (its native part `innersphere._innersphere`): a thin shell
//! over the Rust library. Every type and function here converts its arguments, calls the
//! library and converts the answer; the numbers are the library's own (the same as `ist
//! query` and `ist replay` print).
//!
//! Conventions (as the C ABI's): every library error becomes a Python exception with the
//! library's message (`OSError` for the operating system's file errors, `ValueError` for
//! everything else the caller can get wrong: bad options, meshes, tree files, poses, shapes);
//! poses with a NaN or an infinity are refused; long work (builds, batch queries) runs with
//! the interpreter released.

mod contact_map;
mod convert;
mod haptic;
mod motion;
mod occlude;
mod pair;
mod plan;
mod results;
mod shapes;
mod splint;
mod tree;

use pyo3::prelude::*;

/// Inner Sphere Trees: collision detection, proximity and penetration volume between rigid
/// 3D models at haptic rates (the native part; import `innersphere`).
#[pymodule]
fn _innersphere(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<tree::Tree>()?;
    m.add_class::<pair::Pair>()?;
    m.add_class::<results::DistanceResult>()?;
    m.add_class::<results::PenetrationResult>()?;
    m.add_class::<haptic::Haptic>()?;
    m.add_class::<haptic::Tick>()?;
    m.add_function(wrap_pyfunction!(motion::load_motion, m)?)?;
    m.add_function(wrap_pyfunction!(contact_map::contact_map, m)?)?;
    m.add_function(wrap_pyfunction!(splint::splint, m)?)?;
    m.add_function(wrap_pyfunction!(plan::plan, m)?)?;
    m.add_function(wrap_pyfunction!(shapes::arch_pair, m)?)?;
    m.add_function(wrap_pyfunction!(occlude::occlude, m)?)?;
    Ok(())
}
