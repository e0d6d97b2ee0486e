//! Finite element pieces with no shell knowledge: degrees of freedom.

pub mod dof;
pub mod edge_load;
pub mod surface_load;
