//! Prism/plane intersection (VB paper §3.3.2, Appendix A): moved to the shared rendering
//! core ([`billow_core::prism_plane`]); re-exported here under its old path so that
//! `billow::eval::prism_plane::…` keeps compiling.

pub use billow_core::prism_plane::*;
