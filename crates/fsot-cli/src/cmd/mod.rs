//! One file per command: each turns its flags into a library call, with the
//! progress bar and Ctrl-C wired to the run; `env.rs` reads the environment.
pub mod bench;
pub mod env;
pub mod eval;
pub mod optimize;
pub mod plan;
pub mod score;
pub mod stress;
