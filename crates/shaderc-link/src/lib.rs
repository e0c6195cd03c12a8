//! Re-exports `shaderc`, linked so that it works with Debian 12's libraries.
//! Used only by fsot's `build.rs`.
pub use shaderc;
