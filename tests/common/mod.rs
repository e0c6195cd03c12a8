//! Helpers shared by the integration tests.
#![allow(dead_code)]

#[cfg(feature = "vulkan")]
pub mod host;

#[cfg(feature = "vulkan")]
use fsot::vk::{Context, ContextOptions};

/// A Vulkan context with the validation layer on. GPU tests are mandatory (CI
/// installs lavapipe and the layer): without Vulkan they fail. On a machine
/// without Vulkan, FSOT_SKIP_GPU_TESTS=1 at build time marks them ignored
/// (`fsot_skip_gpu`, from build.rs), so the harness reports them as skipped.
#[cfg(feature = "vulkan")]
pub fn gpu_context() -> Context {
    Context::new(&ContextOptions { validation: true, device: None })
        .unwrap_or_else(|e| panic!("Vulkan with validation is required for this test: {e}"))
}

/// A test that cannot run here (a device of the other class, a missing
/// capability or tool) fails with `reason`, unless FSOT_ALLOW_SKIPS=1 says
/// such skips are expected on this machine: then it says SKIPPED on the
/// process's stderr (past the harness's capture, so a skipped test that the
/// harness reports as ok is seen to be a skip) and the caller returns.
/// Returns whether to skip.
#[must_use]
pub fn skip(reason: &str) -> bool {
    if std::env::var("FSOT_ALLOW_SKIPS").map(|v| v == "1").unwrap_or(false) {
        let test = std::thread::current().name().unwrap_or("a test").to_string();
        let line = format!("SKIPPED (FSOT_ALLOW_SKIPS=1) {test}: {reason}\n");
        std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes()).unwrap();
        return true;
    }
    panic!("cannot run here: {reason} (FSOT_ALLOW_SKIPS=1 allows the skip)");
}

/// Fails the test if the validation layer said anything.
#[cfg(feature = "vulkan")]
pub fn assert_no_validation_messages(ctx: &Context) {
    let messages = ctx.validation_messages();
    assert!(
        messages.is_empty(),
        "{} validation layer messages, the first:\n{}",
        messages.len(),
        messages.iter().take(3).cloned().collect::<Vec<_>>().join("\n")
    );
}

/// Compiles a compute shader against `glsl/include` (the public include) by
/// shaderc-link's recipe, keeping its names; panics with the compiler's
/// message when it does not compile.
pub fn compile_glsl(source: &str) -> Vec<u8> {
    let include = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl/include");
    let compiler = shaderc_link::shaderc::Compiler::new().expect("shaderc");
    shaderc_link::compile_source(&compiler, source, "shader.comp", &include, "glsl/include", &[], true)
        .unwrap_or_else(|e| panic!("the shader does not compile:\n{e}"))
}

/// Sorts `keys` and `vals` by all 32 bits with a sort made with
/// `SortCount::device(count)`: the count written to that buffer, the dispatches
/// sized on the device (indirect); the sorted pairs read back.
#[cfg(feature = "vulkan")]
pub fn sort_with_device_count(
    ctx: &Context,
    sort: &mut fsot::vk::RadixSort,
    count: &mut fsot::vk::Buffer,
    keys: &[u32],
    vals: &[u32],
) -> (Vec<u32>, Vec<u32>) {
    count.upload(&[keys.len() as u32]).unwrap();
    sort.upload_pairs(keys, vals).unwrap();
    // SAFETY: the sort outlives this submission, which is waited for.
    ctx.submit(|cmd| unsafe { sort.record(cmd, 32, None) }).unwrap();
    (sort.keys().download(keys.len()).unwrap(), sort.vals().download(keys.len()).unwrap())
}
