//! Exact unsigned distance from voxel centres to the mesh surface.
