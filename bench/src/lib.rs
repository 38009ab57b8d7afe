//! Benchmark models: the bundled ones come from `eom-generated`; spatial
//! chains of 10 and 50 links are generated here at build time.

/// Spatial chain of 10 links (axes z, y, z, …).
pub mod chain10 {
    include!(concat!(env!("OUT_DIR"), "/chain10.rs"));
}

/// Spatial chain of 50 links.
pub mod chain50 {
    include!(concat!(env!("OUT_DIR"), "/chain50.rs"));
}
