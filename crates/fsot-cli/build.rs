//! `FSOT_COMMIT` (the git commit built, "-dirty" with uncommitted changes;
//! "unknown" outside a checkout), which raw result files carry, and the
//! `fsot_skip_gpu` cfg when `FSOT_SKIP_GPU_TESTS=1` (GPU tests then show as
//! ignored, not passed).
use std::{env, path::Path};

fn main() {
    println!("cargo:rustc-env=FSOT_COMMIT={}", commit());
    // A commit or a staged change moves HEAD or the index; an edit to the sources
    // moves neither, so the sources are watched too ("-dirty" then shows).
    for watched in ["../../.git/HEAD", "../../.git/index", "../../src", "../../glsl", "src"] {
        if Path::new(watched).exists() {
            println!("cargo:rerun-if-changed={watched}");
        }
    }
    println!("cargo::rustc-check-cfg=cfg(fsot_skip_gpu)");
    println!("cargo:rerun-if-env-changed=FSOT_SKIP_GPU_TESTS");
    if env::var("FSOT_SKIP_GPU_TESTS").is_ok_and(|v| v == "1") {
        println!("cargo:rustc-cfg=fsot_skip_gpu");
    }
}

/// The short commit of the checkout, with "-dirty" when files differ from it.
fn commit() -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match git(&["rev-parse", "--short", "HEAD"]) {
        Some(head) => match git(&["status", "--porcelain", "--untracked-files=no"]) {
            Some(changes) if !changes.is_empty() => format!("{head}-dirty"),
            _ => head,
        },
        None => "unknown".to_string(),
    }
}
