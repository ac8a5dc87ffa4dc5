//! Criterion benches of softrod; see `benches/*.rs` and `docs/performance.md`.

pub mod rod_scenes;
