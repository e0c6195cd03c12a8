//! The committed SPIR-V is what the GLSL compiles to: every shader and variant
//! of `glsl/`, compiled now with shaderc by the same recipe, equals the bytes
//! under `spirv/` and the ones the crate embeds, and `spirv/FAMILY.rs` lists
//! exactly them. A shader changed without `scripts/spirv.sh` fails here.
#![cfg(feature = "vulkan")]

use std::fs;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every difference between what `glsl/` compiles to and what `spirv/` holds.
fn drift(spirv_root: &Path, family: &str, embedded: &[(&str, &[u8])]) -> Vec<String> {
    let shaders = shaderc_link::compile_family(&root().join("glsl"), family, false).unwrap();
    let mut found = Vec::new();
    for s in &shaders {
        let path = spirv_root.join(family).join(&s.file);
        match fs::read(&path) {
            Ok(bytes) if bytes == s.spirv => {}
            Ok(_) => found.push(format!("{family}/{} differs from its GLSL", s.file)),
            Err(_) => found.push(format!("{family}/{} is missing", s.file)),
        }
        match embedded.iter().find(|(name, _)| *name == s.name) {
            Some((_, bytes)) if *bytes == s.spirv.as_slice() => {}
            Some(_) => found.push(format!("the embedded {} differs from its GLSL", s.name)),
            None => found.push(format!("{} is not embedded", s.name)),
        }
    }
    for entry in fs::read_dir(spirv_root.join(family)).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if !shaders.iter().any(|s| s.file == name) {
            found.push(format!("{family}/{name} comes from no shader"));
        }
    }
    if embedded.len() != shaders.len() {
        found.push(format!("{family}: {} embedded, {} compiled", embedded.len(), shaders.len()));
    }
    let module = fs::read_to_string(spirv_root.join(format!("{family}.rs"))).unwrap_or_default();
    if module != shaderc_link::module_source(family, &shaders) {
        found.push(format!("{family}.rs does not list the compiled shaders"));
    }
    found
}

/// A family's embedded shaders: (name, SPIR-V).
type Family = &'static [(&'static str, &'static [u8])];

fn families() -> [(&'static str, Family); 3] {
    [
        ("sort", fsot::vk::shaders::ALL),
        ("fsot", fsot::optimize::vulkan::shaders::ALL),
        ("swap", fsot::peers::swap::vulkan::shaders::ALL),
    ]
}

#[test]
fn the_committed_spirv_is_what_the_glsl_compiles_to() {
    for (family, embedded) in families() {
        let found = drift(&root().join("spirv"), family, embedded);
        assert!(found.is_empty(), "run scripts/spirv.sh: {}", found.join("; "));
    }
}

#[test]
fn a_stale_or_stray_spirv_file_is_caught() {
    // A copy of spirv/sort with one byte changed and one file too many.
    let copy = tempfile::tempdir().unwrap();
    let dir = copy.path().join("sort");
    fs::create_dir(&dir).unwrap();
    for entry in fs::read_dir(root().join("spirv/sort")).unwrap() {
        let path = entry.unwrap().path();
        fs::copy(&path, dir.join(path.file_name().unwrap())).unwrap();
    }
    fs::copy(root().join("spirv/sort.rs"), copy.path().join("sort.rs")).unwrap();
    assert!(drift(copy.path(), "sort", fsot::vk::shaders::ALL).is_empty());
    let victim = dir.join("scan_apply.spv");
    let mut bytes = fs::read(&victim).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    fs::write(&victim, bytes).unwrap();
    fs::write(dir.join("retired.spv"), [3, 2, 35, 7]).unwrap();
    let found = drift(copy.path(), "sort", fsot::vk::shaders::ALL);
    assert!(found.iter().any(|f| f.contains("scan_apply.spv differs")), "{found:?}");
    assert!(found.iter().any(|f| f.contains("retired.spv comes from no shader")), "{found:?}");
}
