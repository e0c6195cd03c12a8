//! The README's code blocks build: its Rust blocks are doctests (src/lib.rs
//! includes the README), its GLSL block compiles against the public include
//! with shaderc, and its TOML block is a dependency table naming fsot.

mod common;

fn blocks(language: &str) -> Vec<String> {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let mut out = Vec::new();
    let mut current: Option<String> = None;
    for line in readme.lines() {
        match (&mut current, line.trim_start().strip_prefix("```")) {
            (None, Some(info)) if info.split(',').next() == Some(language) => current = Some(String::new()),
            (Some(block), Some("")) => {
                out.push(std::mem::take(block));
                current = None;
            }
            (Some(block), _) => {
                block.push_str(line);
                block.push('\n');
            }
            _ => {}
        }
    }
    out
}

#[test]
fn the_readme_shader_compiles_against_the_include() {
    let shaders = blocks("glsl");
    assert_eq!(shaders.len(), 1, "the README's GLSL blocks");
    let spirv = common::compile_glsl(&shaders[0]);
    assert_eq!(&spirv[..4], &0x0723_0203u32.to_le_bytes());
}

#[test]
fn the_readme_dependency_table_names_fsot_both_ways() {
    let tables = blocks("toml");
    assert_eq!(tables.len(), 1, "the README's TOML blocks");
    let uncommented: String =
        tables[0].lines().map(|l| l.trim_start_matches("# ")).collect::<Vec<_>>().join("\n");
    let mut lines = uncommented.lines();
    let header = lines.next().unwrap();
    let alternatives: Vec<&str> = lines.collect();
    assert_eq!(alternatives.len(), 2, "with and without Vulkan");
    for alternative in alternatives {
        let table: toml::Table = toml::from_str(&format!("{header}\n{alternative}")).unwrap();
        let fsot = table["dependencies"]["fsot"].as_table().unwrap();
        assert!(fsot.contains_key("path"), "{alternative}");
    }
    assert!(uncommented.contains("default-features = false"));
}

#[test]
fn the_readme_rust_blocks_are_doctests() {
    let rust = blocks("rust");
    assert!(rust.len() >= 2, "the README's Rust blocks");
    let lib = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/src/lib.rs")).unwrap();
    assert!(lib.contains("#[doc = include_str!(\"../README.md\")]"));
}
