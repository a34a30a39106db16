//! Trees: load, build, save, free.

use crate::error::{pointer, status, Fail};
use crate::types::ist_build_options;
use crate::{path_arg, reference};
use innersphere::build::PackingOptions;
use innersphere::{BuildOptions, Mesh, Resolution, SharedTree, SphereTree};
use std::ffi::{c_char, c_int};

/// An Inner Sphere Tree (opaque; immutable, shareable between threads).
pub struct ist_tree {
    pub(crate) tree: SharedTree,
}

/// The library's default build options (128 voxels along the longest side, no minimum
/// radius, no refinement, no sphere limit).
#[no_mangle]
pub extern "C" fn ist_build_options_default() -> ist_build_options {
    ist_build_options {
        voxel_size: 0.0,
        resolution: 128,
        min_radius: 0.0,
        refine_steps: 0,
        max_spheres: 0,
        unit: crate::types::IST_UNIT_MM,
    }
}

/// The library's unit of `ist_build_options::unit`.
fn unit(u: c_int) -> Result<innersphere::mesh::Unit, Fail> {
    use innersphere::mesh::Unit;
    Ok(match u {
        crate::types::IST_UNIT_MM => Unit::Mm,
        crate::types::IST_UNIT_CM => Unit::Cm,
        crate::types::IST_UNIT_M => Unit::M,
        crate::types::IST_UNIT_IN => Unit::In,
        _ => {
            return Err(Fail::arg(format!(
            "unit {u} is none of IST_UNIT_MM (0), IST_UNIT_CM (1), IST_UNIT_M (2), IST_UNIT_IN (3)"
        )))
        }
    })
}

fn build_options(o: &ist_build_options) -> Result<BuildOptions, Fail> {
    let resolution = if o.voxel_size > 0.0 {
        Resolution::VoxelSize(o.voxel_size)
    } else if o.voxel_size == 0.0 && o.resolution > 0 {
        Resolution::Cells(o.resolution)
    } else {
        return Err(Fail::arg(format!(
            "the build needs voxel_size > 0 or resolution > 0 (voxel_size {}, resolution {})",
            o.voxel_size, o.resolution
        )));
    };
    let max_spheres = if o.max_spheres == 0 {
        PackingOptions::default().max_spheres
    } else {
        usize::try_from(o.max_spheres).map_err(|_| Fail::arg("max_spheres is too large"))?
    };
    Ok(BuildOptions {
        resolution,
        packing: PackingOptions {
            min_radius: o.min_radius,
            max_spheres,
            refine_steps: o.refine_steps,
        },
        ..BuildOptions::default()
    })
}

/// Loads a tree file (`ist build`'s output). NULL on error (ist_last_error says why).
///
/// # Safety
/// `path` is NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn ist_tree_load(path: *const c_char) -> *mut ist_tree {
    pointer(|| {
        let path = unsafe { path_arg(path, "path") }?;
        let tree = SphereTree::load(&path)?;
        Ok(Box::new(ist_tree {
            tree: SharedTree::new(tree),
        }))
    })
}

/// Builds the tree of a mesh file (.stl, .obj, .ply, .off, optionally .gz) with `opts`
/// (NULL: ist_build_options_default()). Takes seconds to minutes. NULL on error.
///
/// # Safety
/// `mesh_path` is NULL or a NUL-terminated string; `opts` is NULL or points to options.
#[no_mangle]
pub unsafe extern "C" fn ist_tree_build(
    mesh_path: *const c_char,
    opts: *const ist_build_options,
) -> *mut ist_tree {
    pointer(|| {
        let path = unsafe { path_arg(mesh_path, "mesh_path") }?;
        let o = if opts.is_null() {
            ist_build_options_default()
        } else {
            *unsafe { reference(opts, "opts") }?
        };
        let unit = unit(o.unit)?;
        let mesh = Mesh::load_in(&path, unit)?;
        let mut tree = SphereTree::build(&mesh, &build_options(&o)?)?;
        tree.meta.source = Some(innersphere::tree::MeshSource::of_unit(&path, &mesh, unit));
        Ok(Box::new(ist_tree {
            tree: SharedTree::new(tree),
        }))
    })
}

/// A new handle to the same tree with the mesh it was built from (a mesh file, in the unit the
/// tree recorded for its source, else mm), for ist_refined_distance; `tree` itself is unchanged (pairs made from it have no mesh). About
/// a second per jaw arch. NULL on error: a file that is not a mesh, or not this tree's
/// source (IST_ERR_MESH).
///
/// # Safety
/// `tree` is NULL or a live tree; `mesh_path` is NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn ist_tree_with_mesh(
    tree: *const ist_tree,
    mesh_path: *const c_char,
) -> *mut ist_tree {
    pointer(|| {
        let t = unsafe { reference(tree, "tree") }?;
        let path = unsafe { path_arg(mesh_path, "mesh_path") }?;
        let unit = t
            .tree
            .meta
            .source
            .as_ref()
            .map(|s| s.unit)
            .unwrap_or_default();
        let mesh = Mesh::load_in(&path, unit)?;
        Ok(Box::new(ist_tree {
            tree: t.tree.clone().with_mesh(&mesh)?,
        }))
    })
}

/// Writes `tree` to `path` (whole or not at all; never over an input of the same call).
///
/// # Safety
/// `tree` is NULL or from ist_tree_load / ist_tree_build; `path` NULL or NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn ist_tree_save(tree: *const ist_tree, path: *const c_char) -> c_int {
    status(|| {
        let t = unsafe { reference(tree, "tree") }?;
        let path = unsafe { path_arg(path, "path") }?;
        t.tree.save(&path)?;
        Ok(())
    })
}

/// Number of leaf spheres of `tree` (0 for NULL).
///
/// # Safety
/// `tree` is NULL or a live tree.
#[no_mangle]
pub unsafe extern "C" fn ist_tree_leaf_count(tree: *const ist_tree) -> usize {
    unsafe { tree.as_ref() }.map_or(0, |t| t.tree.leaf_count())
}

/// Frees a tree (NULL is accepted). Pairs built on it keep their own reference.
///
/// # Safety
/// `tree` is NULL or from ist_tree_load / ist_tree_build / ist_tree_with_mesh, not freed
/// before.
#[no_mangle]
pub unsafe extern "C" fn ist_tree_free(tree: *mut ist_tree) {
    if !tree.is_null() {
        let _ = std::panic::catch_unwind(|| drop(unsafe { Box::from_raw(tree) }));
    }
}
