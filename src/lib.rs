//! fsot: perceptually optimized spatio-temporal sample masks by filtered sliced
//! optimal transport. See the README's architecture section for how the modules
//! fit together.
pub mod backend;
pub mod baselines;
pub mod bench;
pub mod checkpoint;
pub mod cpu_backend;
pub mod error;
pub mod eval;
pub mod gpu;
pub mod io;
pub mod kernel;
pub mod mask;
pub mod method;
pub mod plan;
pub mod problem;
pub mod rng;
pub mod run;
pub mod scene;
pub mod score;
pub mod settings;
pub mod slice;
pub mod step_rule;
pub mod stress;
pub mod targets;
pub mod transport;
pub mod vk;
