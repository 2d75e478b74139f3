//! The problems ribbar solves: the pull-out test (`pullout`, nonlinear,
//! from a model's node sets), the linear-elastic perfect-bond pull-out
//! (`linear_elastic`, the linear benchmark) and a single material point
//! under a strain/stress path (`material_point`).

pub mod linear_elastic;
pub mod material_point;
pub mod pullout;
