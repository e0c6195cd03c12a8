//! With the `build-shaders` feature, compiles `glsl/` to SPIR-V into OUT_DIR
//! (the recipe of `crates/shaderc-link`), which the crate then embeds instead
//! of the committed `spirv/`.
//!
//! Always: the `fsot_skip_gpu` cfg when `FSOT_SKIP_GPU_TESTS=1` (GPU tests then show as
//! ignored, not passed).
use std::env;

fn main() {
    #[cfg(feature = "build-shaders")]
    {
        let root = std::path::PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap());
        let out = std::path::PathBuf::from(env::var("OUT_DIR").unwrap()).join("spirv");
        println!("cargo:rerun-if-changed=glsl");
        if let Err(e) = shaderc_link::write_tree(&root.join("glsl"), &out) {
            panic!("{e}");
        }
    }
    println!("cargo::rustc-check-cfg=cfg(fsot_skip_gpu)");
    println!("cargo:rerun-if-env-changed=FSOT_SKIP_GPU_TESTS");
    if env::var("FSOT_SKIP_GPU_TESTS").is_ok_and(|v| v == "1") {
        println!("cargo:rustc-cfg=fsot_skip_gpu");
    }
}
