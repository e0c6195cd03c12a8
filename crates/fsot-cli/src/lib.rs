//! The tools of the fsot command line that the library does not carry: the
//! evaluation against independent judges (`eval`), the benchmarks (`bench`) and
//! the stress tests (`stress`).
pub mod bench;
pub mod eval;
pub mod stress;
