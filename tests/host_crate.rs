//! A renderer's crate outside the workspace (`examples/host-crate`) depends on
//! fsot in one line and builds, on fsot as `cargo package` packs it for a
//! registry: only the files its manifest's `include` names, in a package under
//! crates.io's 10 MiB limit. It builds with the default features and with
//! `default-features = false`, where no shader compiler is found (shaderc's
//! lookup pointed at an empty folder): neither build has shaderc or cmake in its
//! dependency tree, and without Vulkan neither ash nor gpu-allocator. The
//! host's program then makes a CPU mask through the public API. The command
//! line's package, packed beside it, builds on that same packed library.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

mod common;

/// crates.io's default limit on a package's compressed size.
const REGISTRY_LIMIT: u64 = 10 * 1024 * 1024;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn target() -> PathBuf {
    root().join("target/host-crate")
}

fn run(what: &mut Command) -> String {
    let out = what.output().unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{what:?}:\n{text}");
    text
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

/// Cargo packs a workspace whose crates depend on each other (each resolved
/// against the others as if published) from 1.90 on.
fn cargo_packs_workspaces() -> bool {
    let said = run(cargo().arg("--version"));
    let version: Vec<u32> = said
        .split_whitespace()
        .nth(1)
        .unwrap_or("")
        .split('.')
        .take(2)
        .filter_map(|p| p.parse().ok())
        .collect();
    version >= vec![1, 90]
}

/// Whether this test cannot run here (a cargo too old to pack the workspace).
fn skipped() -> bool {
    !cargo_packs_workspaces()
        && common::skip("cargo packs a workspace whose crates depend on each other from 1.90 on")
}

/// fsot's and the command line's packages, unpacked.
struct Unpacked {
    fsot: PathBuf,
    cli: PathBuf,
}

/// The workspace's crates packed for a registry, once per process, and fsot's
/// and the command line's packages unpacked (as a registry's copies are, but with
/// the files' times of the unpacking, so that a build here sees every change).
fn unpacked() -> &'static Unpacked {
    static UNPACKED: OnceLock<Unpacked> = OnceLock::new();
    UNPACKED.get_or_init(|| {
        let target = target();
        let packages = target.join("package");
        let _ = std::fs::remove_dir_all(&packages);
        run(cargo()
            .args(["package", "--workspace", "--no-verify", "--allow-dirty", "--offline"])
            .arg("--target-dir")
            .arg(&target)
            .current_dir(root()));
        let unpacked = target.join("unpacked");
        let _ = std::fs::remove_dir_all(&unpacked);
        std::fs::create_dir_all(&unpacked).unwrap();
        let unpack = |name: &str| {
            let packed = packed(&packages, name);
            let size = std::fs::metadata(&packed).unwrap().len();
            assert!(size < REGISTRY_LIMIT, "{} is {size} bytes, over crates.io's limit", packed.display());
            run(Command::new("tar").arg("-xzmf").arg(&packed).arg("-C").arg(&unpacked));
            unpacked.join(packed.file_stem().unwrap())
        };
        Unpacked { fsot: unpack("fsot"), cli: unpack("fsot-cli") }
    })
}

/// The package `NAME-VERSION.crate` that `cargo package` wrote into `folder`.
fn packed(folder: &Path, name: &str) -> PathBuf {
    let prefix = format!("{name}-");
    let found: Vec<PathBuf> = std::fs::read_dir(folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let file = p.file_name().unwrap().to_string_lossy();
            file.ends_with(".crate")
                && file.strip_prefix(&prefix).is_some_and(|v| v.starts_with(|c: char| c.is_ascii_digit()))
        })
        .collect();
    assert_eq!(found.len(), 1, "packages of {name} in {}: {found:?}", folder.display());
    found.into_iter().next().unwrap()
}

/// The host crate, its manifest's one line pointing at the packed fsot.
fn host_crate() -> &'static Path {
    static HOST: OnceLock<PathBuf> = OnceLock::new();
    HOST.get_or_init(|| {
        let example = root().join("examples/host-crate");
        let manifest = std::fs::read_to_string(example.join("Cargo.toml")).unwrap();
        let line = r#"fsot = { path = "../..", default-features = false }"#;
        assert!(manifest.contains(line), "the host's manifest has no line `{line}`");
        let packed = &unpacked().fsot;
        let manifest =
            manifest.replace(line, &format!("fsot = {{ path = {packed:?}, default-features = false }}"));
        let host = target().join("host");
        let _ = std::fs::remove_dir_all(&host);
        std::fs::create_dir_all(host.join("src")).unwrap();
        std::fs::write(host.join("Cargo.toml"), manifest).unwrap();
        // The workspace's locked versions, which the offline build then keeps.
        std::fs::copy(root().join("Cargo.lock"), host.join("Cargo.lock")).unwrap();
        std::fs::copy(example.join("src/main.rs"), host.join("src/main.rs")).unwrap();
        host
    })
}

fn host_cargo(args: &[&str], empty: &Path) -> String {
    run(cargo()
        .args(args)
        .current_dir(host_crate())
        .env("CARGO_TARGET_DIR", target())
        .env("SHADERC_LIB_DIR", empty)
        .env_remove("VULKAN_SDK"))
}

fn builds_and_runs(features: &[&str], absent: &[&str]) {
    if skipped() {
        return;
    }
    let empty = tempfile::tempdir().unwrap();
    let mut tree = vec!["tree", "--offline", "-e", "normal,build", "--prefix", "none"];
    tree.extend_from_slice(features);
    let deps = host_cargo(&tree, empty.path());
    for name in absent {
        assert!(
            !deps.lines().any(|l| l.split_whitespace().next() == Some(name)),
            "{name} is in the host's dependencies ({features:?}):\n{deps}"
        );
    }
    let mut args = vec!["run", "--offline", "--quiet"];
    args.extend_from_slice(features);
    let said = host_cargo(&args, empty.path());
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

#[test]
fn the_command_line_builds_from_its_package_on_the_packed_library() {
    if skipped() {
        return;
    }
    let patch = format!("patch.crates-io.fsot.path={:?}", unpacked().fsot);
    let said = run(cargo()
        .args(["check", "--offline", "--config", &patch])
        .current_dir(&unpacked().cli)
        .env("CARGO_TARGET_DIR", target()));
    assert!(!said.contains("warning: Patch"), "the packed library was not used:\n{said}");
}
