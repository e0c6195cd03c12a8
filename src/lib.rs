//! fsot: perceptually optimized spatio-temporal sample masks by filtered sliced
//! optimal transport.
pub mod cpu;
pub mod error;
pub mod eval;
pub mod gpu;
pub mod io;
pub mod kernel;
pub mod mask;
pub mod optimize;
pub mod optimizer;
pub mod problem;
pub mod rng;
pub mod score;
pub mod slice;
pub mod targets;
pub mod transport;
