//! Deciding which voxel centres lie inside the mesh.
