//! One file per command: each turns its flags into a library call, with the
//! progress bar and Ctrl-C wired to the run; `env.rs` reads the environment.

/// `print!` and `println!` to standard output that give an error to return
/// (a closed pipe, a full disk) where theirs would panic.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*)
            .map_err(|e| fsot::error::Error::io("cannot write to standard output", e))
    }};
}
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
            .map_err(|e| fsot::error::Error::io("cannot write to standard output", e))
    }};
}

pub mod bench;
pub mod env;
pub mod eval;
pub mod optimize;
pub mod plan;
pub mod score;
pub mod stress;
