//! Compiles `glsl/` into `spirv/`: `regenerate-spirv [REPO_ROOT]` (default: the
//! workspace root). Run it (scripts/spirv.sh) after changing a shader.
use std::path::PathBuf;

fn main() {
    let root = std::env::args().nth(1).map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("workspace root")
    });
    match shaderc_link::write_tree(&root.join("glsl"), &root.join("spirv")) {
        Ok(n) => println!("{n} shaders written under {}", root.join("spirv").display()),
        Err(e) => {
            eprintln!("regenerate-spirv: {e}");
            std::process::exit(1);
        }
    }
}
