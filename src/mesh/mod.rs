//! Meshes, node sets and the gmsh .msh 4.1 reader.
