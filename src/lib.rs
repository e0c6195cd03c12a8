//! fsot: perceptually optimized spatio-temporal sample masks by filtered sliced
//! optimal transport. See the README's architecture section for how the modules
//! fit together.
/// The bytes of one embedded SPIR-V file: committed under `spirv/` (made from
/// `glsl/` by `scripts/spirv.sh`), or compiled into OUT_DIR at build time with
/// the `build-shaders` feature.
#[cfg(all(feature = "vulkan", not(feature = "build-shaders")))]
macro_rules! spirv {
    ($file:literal) => {
        include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/spirv/", $file))
    };
}
#[cfg(all(feature = "vulkan", feature = "build-shaders"))]
macro_rules! spirv {
    ($file:literal) => {
        include_bytes!(concat!(env!("OUT_DIR"), "/spirv/", $file))
    };
}
/// One shader family's constants (`spirv/FAMILY.rs`, or OUT_DIR's with `build-shaders`).
#[cfg(all(feature = "vulkan", not(feature = "build-shaders")))]
macro_rules! spirv_module {
    ($family:literal) => {
        include!(concat!(env!("CARGO_MANIFEST_DIR"), "/spirv/", $family, ".rs"));
    };
}
#[cfg(all(feature = "vulkan", feature = "build-shaders"))]
macro_rules! spirv_module {
    ($family:literal) => {
        include!(concat!(env!("OUT_DIR"), "/spirv/", $family, ".rs"));
    };
}

pub mod backend;
pub mod baselines;
pub mod checkpoint;
pub mod cpu_backend;
pub mod csf;
pub mod display;
pub mod error;
#[cfg(feature = "vulkan")]
pub mod gpu;
pub mod io;
pub mod kernel;
pub mod mask;
pub mod method;
pub mod plan;
pub mod problem;
pub mod quality;
#[cfg(feature = "vulkan")]
pub mod renderer;
pub mod rng;
pub mod run;
pub mod sampler;
pub mod scene;
pub mod score;
pub mod settings;
pub mod slice;
pub mod step_rule;
pub mod targets;
pub mod transport;
#[cfg(feature = "vulkan")]
pub mod vk;
