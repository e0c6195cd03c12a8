//! Finds the shader compiler's libraries the way the `shaderc` crate does, and
//! adds what a distribution's layout needs:
//!
//! 1. the folder: `SHADERC_LIB_DIR`, else `$VULKAN_SDK/lib`, else pkg-config's
//!    `shaderc`, else the multiarch folder of the target (`/usr/lib/<arch>-linux-gnu`,
//!    then `/usr/lib64`, `/usr/lib`; `/usr/local/lib` on macOS) - the `shaderc`
//!    crate searches in the same order, so both agree;
//! 2. when that folder holds `libshaderc_combined.a` (linked statically) and also
//!    glslang's and SPIRV-Tools' own static archives, its combined archive lacks
//!    them (Debian's and Ubuntu's packages split them out): link those that are
//!    there, in dependency order;
//! 3. when the folder holds only a shared `libshaderc` (Fedora, Arch, Homebrew),
//!    nothing more is needed;
//! 4. when it holds neither, the `shaderc` crate builds shaderc from its bundled
//!    source (cmake, a C++ compiler, python3 and git needed), complete in itself:
//!    nothing more is needed either.
use std::env;
use std::path::{Path, PathBuf};

fn main() {
    for var in ["SHADERC_LIB_DIR", "VULKAN_SDK", "PKG_CONFIG_PATH"] {
        println!("cargo:rerun-if-env-changed={var}");
    }
    let Some(dir) = search_dir() else { return };
    let static_combined = dir.join("libshaderc_combined.a").exists();
    if !static_combined {
        // A shared library, or none: the shaderc crate links it or builds from source.
        return;
    }
    // glslang (Debian 12 splits it into five archives; newer releases into fewer)
    // and SPIRV-Tools, each linked only where present.
    let split = [
        "glslang",
        "MachineIndependent",
        "GenericCodeGen",
        "OSDependent",
        "OGLCompiler",
        "SPIRV",
        "SPIRV-Tools-opt",
        "SPIRV-Tools",
    ];
    let present: Vec<&str> =
        split.iter().copied().filter(|lib| dir.join(format!("lib{lib}.a")).exists()).collect();
    if present.is_empty() {
        return; // a combined archive that is complete (shaderc's own build)
    }
    println!("cargo:rustc-link-search=native={}", dir.display());
    for lib in present {
        println!("cargo:rustc-link-lib=static={lib}");
    }
}

/// The folder the `shaderc` crate links from (see the module comment).
fn search_dir() -> Option<PathBuf> {
    if let Ok(dir) = env::var("SHADERC_LIB_DIR") {
        return Some(PathBuf::from(dir));
    }
    if let Ok(sdk) = env::var("VULKAN_SDK") {
        return Some(Path::new(&sdk).join("lib"));
    }
    if let Some(dir) = pkg_config_libdir() {
        return Some(dir);
    }
    let os = env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    match os.as_str() {
        "linux" => {
            let debian_arch = if arch == "x86" { "i386".to_string() } else { arch.clone() };
            let multiarch = PathBuf::from(format!("/usr/lib/{debian_arch}-linux-gnu"));
            if multiarch.exists() {
                Some(multiarch)
            } else if arch == "x86_64" && Path::new("/usr/lib64").exists() {
                Some(PathBuf::from("/usr/lib64"))
            } else {
                Some(PathBuf::from("/usr/lib"))
            }
        }
        "macos" => Some(PathBuf::from("/usr/local/lib")).filter(|p| p.exists()),
        _ => None,
    }
}

/// `pkg-config --variable=libdir shaderc`, where pkg-config and the file exist.
fn pkg_config_libdir() -> Option<PathBuf> {
    let out =
        std::process::Command::new("pkg-config").args(["--variable=libdir", "shaderc"]).output().ok()?;
    let dir = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (out.status.success() && !dir.is_empty()).then(|| PathBuf::from(dir))
}
