//! Criterion benches of softrod; see `benches/*.rs` and `docs/performance.md`.
