//! Mesh file formats: STL (binary and ASCII), OBJ, PLY, OFF, each optionally gzip-compressed.
