//! The fuzz targets' bodies (`harness.rs`), shared with the stable
//! regression test `crates/lab/tests/fuzz_regressions.rs`, which replays
//! `fuzz/regressions/` through them.

pub mod harness;
