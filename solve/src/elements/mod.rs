//! Element kernels: the linear tetrahedron (`tet`) and the 6-node
//! zero-thickness interface element (`interface`).

pub mod interface;
pub mod tet;
