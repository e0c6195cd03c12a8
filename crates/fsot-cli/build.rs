//! `FSOT_COMMIT` (the git commit built, "-dirty" with uncommitted changes; in a
//! packed copy the commit it was packed from; else "unknown"), which raw result
//! files carry, and the
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

/// The short commit of the checkout, with "-dirty" when files differ from it;
/// in a packed copy (a registry's, for `cargo install`), the commit it was packed
/// from, as cargo recorded it.
fn commit() -> String {
    // Git is asked only inside fsot's own checkout, whose root is two folders up:
    // elsewhere it would answer for whatever repository holds the folder.
    if !Path::new("../../.git").exists() {
        return packed_commit().unwrap_or_else(|| "unknown".to_string());
    }
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

/// The commit in `.cargo_vcs_info.json`, which `cargo package` writes into a
/// package packed from a git checkout: `"sha1": "<40 hex digits>"` and
/// `"dirty": true` where files differed from it.
fn packed_commit() -> Option<String> {
    let info = std::fs::read_to_string(".cargo_vcs_info.json").ok()?;
    let at = info.find("\"sha1\"")?;
    let sha = info[at + 6..].split('"').nth(1)?;
    if sha.len() < 7 || !sha.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let dirty = info.split_whitespace().collect::<String>().contains("\"dirty\":true");
    Some(format!("{}{}", &sha[..7], if dirty { "-dirty" } else { "" }))
}
