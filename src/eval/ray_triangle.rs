//! Watertight ray/triangle intersection (Woop, Benthin, Wald 2013): moved to the shared
//! rendering core ([`billow_core::ray_triangle`]); re-exported here under its old path so
//! that `billow::eval::ray_triangle::…` keeps compiling.

pub use billow_core::ray_triangle::*;
