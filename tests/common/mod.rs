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
/// such skips are expected on this machine: then it says SKIPPED and the
/// caller returns. Returns whether to skip.
#[must_use]
pub fn skip(reason: &str) -> bool {
    if std::env::var("FSOT_ALLOW_SKIPS").map(|v| v == "1").unwrap_or(false) {
        eprintln!("SKIPPED (FSOT_ALLOW_SKIPS=1): {reason}");
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

/// Compiles a compute shader against `glsl/include` (the public include) with
/// glslangValidator for Vulkan 1.2; None when glslangValidator is missing and
/// the skip is allowed (`skip`).
pub fn compile_glsl(source: &str) -> Option<Vec<u8>> {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("shader.comp");
    std::fs::write(&src, source).unwrap();
    let include = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl/include");
    let out = dir.path().join("shader.spv");
    let run = std::process::Command::new("glslangValidator")
        .args(["-V", "--target-env", "vulkan1.2"])
        .arg(format!("-I{}", include.display()))
        .arg(&src)
        .arg("-o")
        .arg(&out)
        .output();
    let Ok(run) = run else {
        let _ = skip("glslangValidator is not installed (scripts/install-deps.sh installs it)");
        return None;
    };
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stdout));
    Some(std::fs::read(out).unwrap())
}

/// Sorts `keys` and `vals` by all 32 bits with a sort made with
/// `SortCount::Device(count)`: the count written to that buffer, the dispatches
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
    ctx.submit(|cmd| sort.record(cmd, 32, None)).unwrap();
    (sort.keys().download(keys.len()).unwrap(), sort.vals().download(keys.len()).unwrap())
}
