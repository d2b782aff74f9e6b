//! billow: bakes meshes into image-based level-of-detail assets.
pub mod import;
pub mod inspect;
pub mod procgen;
pub mod provenance;
pub mod rng;
pub mod scene;
pub mod texture;
