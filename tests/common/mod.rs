//! Helpers shared by the integration tests.
#![allow(dead_code)]

use fsot::vk::{Context, ContextOptions};

/// A Vulkan context with the validation layer on. GPU tests are mandatory (CI
/// installs lavapipe and the layer); set FSOT_SKIP_GPU_TESTS=1 to skip them on a
/// machine without Vulkan. Returns None only then.
pub fn gpu_context() -> Option<Context> {
    if std::env::var("FSOT_SKIP_GPU_TESTS").map(|v| v == "1").unwrap_or(false) {
        eprintln!("FSOT_SKIP_GPU_TESTS=1: skipping a GPU test");
        return None;
    }
    let ctx = Context::new(&ContextOptions { validation: true, device: None })
        .unwrap_or_else(|e| panic!("Vulkan with validation is required for this test: {e}"));
    Some(ctx)
}

/// Fails the test if the validation layer said anything.
pub fn assert_no_validation_messages(ctx: &Context) {
    let messages = ctx.validation_messages();
    assert!(
        messages.is_empty(),
        "{} validation layer messages, the first:\n{}",
        messages.len(),
        messages.iter().take(3).cloned().collect::<Vec<_>>().join("\n")
    );
}
