//! A bounding-volume hierarchy over the triangles of a mesh.
