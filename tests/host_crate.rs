//! A renderer's crate outside the workspace (`examples/host-crate`) depends on
//! fsot by path in one line and builds, with the default features and with
//! `default-features = false`, where no shader compiler is found (shaderc's
//! lookup pointed at an empty folder): neither build has shaderc or cmake in its
//! dependency tree, and without Vulkan neither ash nor gpu-allocator. The
//! host's program then makes a CPU mask through the public API.

use std::path::{Path, PathBuf};
use std::process::Command;

fn host_crate() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/host-crate")
}

fn cargo(args: &[&str], empty: &Path) -> String {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/host-crate");
    let out = Command::new(cargo)
        .args(args)
        .current_dir(host_crate())
        .env("CARGO_TARGET_DIR", target)
        .env("SHADERC_LIB_DIR", empty)
        .env_remove("VULKAN_SDK")
        .output()
        .unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "cargo {}:\n{text}", args.join(" "));
    text
}

fn builds_and_runs(features: &[&str], absent: &[&str]) {
    let empty = tempfile::tempdir().unwrap();
    let mut tree = vec!["tree", "--offline", "-e", "normal,build", "--prefix", "none"];
    tree.extend_from_slice(features);
    let deps = cargo(&tree, empty.path());
    for name in absent {
        assert!(
            !deps.lines().any(|l| l.split_whitespace().next() == Some(name)),
            "{name} is in the host's dependencies ({features:?}):\n{deps}"
        );
    }
    let mut run = vec!["run", "--offline", "--quiet"];
    run.extend_from_slice(features);
    let said = cargo(&run, empty.path());
    assert!(said.contains("made a 16x16x4 mask, 2048 samples"), "{said}");
}

#[test]
fn a_host_crate_builds_with_vulkan_and_no_shader_compiler() {
    builds_and_runs(&[], &["shaderc", "shaderc-sys", "cmake", "clap", "indicatif", "ctrlc", "colorvideovdp"]);
}

#[test]
fn a_host_crate_builds_without_vulkan() {
    builds_and_runs(
        &["--no-default-features"],
        &[
            "ash",
            "gpu-allocator",
            "shaderc",
            "shaderc-sys",
            "cmake",
            "clap",
            "indicatif",
            "ctrlc",
            "colorvideovdp",
        ],
    );
}
