//! Premultiplied-alpha compositing and opacity correction: moved to the shared rendering
//! core ([`billow_core::compositing`]); re-exported here under its old path.

pub use billow_core::compositing::*;
