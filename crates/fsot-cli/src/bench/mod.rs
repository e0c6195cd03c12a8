//! Benchmarks that print figures (run time, throughput, error against time);
//! results are recorded in BENCHMARKS.md with the commands that produced them.
pub mod convergence;
pub mod machine;
pub mod plot;
pub mod scaling;
pub mod scatter;
pub mod sort;
pub mod timing;

pub use scatter::{bench_scatter, ScatterBench};
pub use sort::{bench_sort, SortBench};
