//! Re-exports `shaderc`, linked so that it works with the system's libraries
//! (Debian's and Ubuntu's split archives included) or built from source where
//! there are none (see build.rs). Used only by fsot's `build.rs`.
pub use shaderc;
