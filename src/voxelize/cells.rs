//! The cells of a volumetric billboard: a box as two triangular prisms. Moved to the
//! shared core ([`billow_core::cells`]); re-exported here under its old path.

pub use billow_core::cells::*;
