//! `shaderc`, linked so that it works with the system's libraries (Debian's and
//! Ubuntu's split archives included) or built from source where there are none
//! (see build.rs), and the one recipe by which fsot's GLSL becomes SPIR-V.
//!
//! fsot embeds SPIR-V committed under `spirv/`; [`compile_family`] makes the same
//! bytes from `glsl/`. The `regenerate-spirv` binary writes them
//! (`scripts/spirv.sh`), fsot's freshness test compares them, and fsot's
//! `build-shaders` feature compiles them at build time instead.
//!
//! Each `glsl/FAMILY/NAME.comp` gives the constant `NAME` (upper case); a line
//! `// variant SUFFIX: MACRO...` in a `.comp` also compiles it with each MACRO
//! defined, as `NAME_SUFFIX`. `#include "x.glsl"` resolves inside the family's
//! folder (`../fsot/x.glsl` reaches another family's).
pub use shaderc;

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

/// The shader families, each a folder of `glsl/` and a module of fsot.
pub const FAMILIES: [&str; 3] = ["sort", "fsot", "swap"];

/// One compiled shader.
pub struct Shader {
    /// The Rust constant's name: the file's stem, upper case, `_SUFFIX` for a variant.
    pub name: String,
    /// The SPIR-V file's name inside the family's folder.
    pub file: String,
    /// What it was compiled from, for the constant's doc comment.
    pub what: String,
    pub spirv: Vec<u8>,
}

/// Compiles every shader and variant of `glsl_root/family`, in file-name order,
/// on as many threads as the machine has (the bytes do not depend on it).
/// With `debug_names`, the SPIR-V keeps OpName/OpMemberName (for reflection);
/// fsot embeds it without. Source names are relative (`glsl/FAMILY/NAME.comp`)
/// so the bytes do not depend on where the checkout lies.
pub fn compile_family(glsl_root: &Path, family: &str, debug_names: bool) -> Result<Vec<Shader>, String> {
    let dir = glsl_root.join(family);
    let mut entries: Vec<_> = fs::read_dir(&dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{}: {e}", dir.display()))?;
    entries.sort();
    let mut jobs = Vec::new();
    for path in entries {
        if path.extension().and_then(|e| e.to_str()) != Some("comp") {
            continue;
        }
        let stem = path.file_stem().and_then(|s| s.to_str()).ok_or("shader name not UTF-8")?.to_string();
        let source = fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut variants = vec![(stem.to_uppercase(), None)];
        for line in source.lines() {
            if let Some((suffix, mac)) =
                line.trim().strip_prefix("// variant ").and_then(|r| r.split_once(':'))
            {
                variants.push((
                    format!("{}_{}", stem.to_uppercase(), suffix.trim()),
                    Some(mac.trim().to_string()),
                ));
            }
        }
        let source_name = format!("glsl/{family}/{stem}.comp");
        for (name, define) in variants {
            jobs.push(Job { source: source.clone(), source_name: source_name.clone(), name, define });
        }
    }
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(jobs.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut done: Vec<Option<Result<Shader, String>>> = (0..jobs.len()).map(|_| None).collect();
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    let mut out = Vec::new();
                    let compiler = match shaderc::Compiler::new() {
                        Ok(c) => c,
                        Err(e) => return Err(format!("shaderc: {e}")),
                    };
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(job) = jobs.get(i) else { return Ok(out) };
                        out.push((i, compile(&compiler, &dir, family, job, debug_names)));
                    }
                })
            })
            .collect();
        for worker in workers {
            for (i, shader) in worker.join().expect("a shader compiler thread panicked")? {
                done[i] = Some(shader);
            }
        }
        Ok::<(), String>(())
    })?;
    done.into_iter().map(|s| s.expect("every shader was compiled")).collect()
}

/// One shader or variant to compile.
struct Job {
    source: String,
    source_name: String,
    name: String,
    define: Option<String>,
}

/// One shader or variant of a family, by the recipe.
fn compile(
    compiler: &shaderc::Compiler,
    dir: &Path,
    family: &str,
    job: &Job,
    debug_names: bool,
) -> Result<Shader, String> {
    let Job { source, source_name, name, define } = job;
    let defines: Vec<&str> = define.iter().flat_map(|m| m.split_whitespace()).collect();
    let shown = format!("glsl/{family}");
    let spirv = compile_source(compiler, source, source_name, dir, &shown, &defines, debug_names)
        .map_err(|e| format!("{source_name} ({name}) failed to compile:\n{e}"))?;
    let what = match define {
        Some(m) => format!("`{source_name}` with `{m}`"),
        None => format!("`{source_name}`"),
    };
    Ok(Shader { file: format!("{}.spv", name.to_lowercase()), name: name.clone(), what, spirv })
}

/// Compiles one compute shader by the recipe (Vulkan 1.2, SPIR-V 1.3,
/// optimised, warnings as errors; with `debug_names` its names kept), each of
/// `defines` a macro defined: `#include "x"` reads `include_dir/x`, named
/// `shown_dir/x` in the SPIR-V so its bytes do not depend on where the files lie.
pub fn compile_source(
    compiler: &shaderc::Compiler,
    source: &str,
    source_name: &str,
    include_dir: &Path,
    shown_dir: &str,
    defines: &[&str],
    debug_names: bool,
) -> Result<Vec<u8>, String> {
    let mut options = shaderc::CompileOptions::new().map_err(|e| format!("shaderc: {e}"))?;
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    options.set_target_spirv(shaderc::SpirvVersion::V1_3);
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    options.set_warnings_as_errors();
    if debug_names {
        options.set_generate_debug_info();
    }
    for m in defines {
        options.add_macro_definition(m, None);
    }
    let include_dir = include_dir.to_path_buf();
    let shown_dir = shown_dir.to_string();
    options.set_include_callback(move |included, _kind, _from, _depth| {
        let path = include_dir.join(included);
        fs::read_to_string(&path)
            .map(|content| shaderc::ResolvedInclude {
                resolved_name: format!("{shown_dir}/{included}"),
                content,
            })
            .map_err(|e| format!("cannot include {}: {e}", path.display()))
    });
    let artifact = compiler
        .compile_into_spirv(source, shaderc::ShaderKind::Compute, source_name, "main", Some(&options))
        .map_err(|e| e.to_string())?;
    Ok(artifact.as_binary_u8().to_vec())
}

/// The Rust module that embeds a family: one constant per shader, read with
/// fsot's `spirv!` macro, and `ALL`.
pub fn module_source(family: &str, shaders: &[Shader]) -> String {
    let mut out = format!("// Generated by scripts/spirv.sh from glsl/{family}/*.comp: do not edit.\n");
    for s in shaders {
        writeln!(
            out,
            "/// SPIR-V of {}.\npub const {}: &[u8] = spirv!(\"{family}/{}\");",
            s.what, s.name, s.file
        )
        .unwrap();
    }
    let list: Vec<String> = shaders.iter().map(|s| format!("(\"{0}\", {0})", s.name)).collect();
    writeln!(
        out,
        "/// Every shader of the family, by name.\npub const ALL: &[(&str, &[u8])] = &[{}];",
        list.join(", ")
    )
    .unwrap();
    out
}

/// Writes every family of `glsl_root` under `spirv_root`: `FAMILY/*.spv` and
/// `FAMILY.rs`, removing SPIR-V files no shader makes any more.
pub fn write_tree(glsl_root: &Path, spirv_root: &Path) -> Result<usize, String> {
    let mut written = 0;
    for family in FAMILIES {
        let shaders = compile_family(glsl_root, family, false)?;
        let dir = spirv_root.join(family);
        fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        for old in fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))? {
            let old = old.map_err(|e| e.to_string())?.path();
            let stale = old.extension().and_then(|e| e.to_str()) == Some("spv")
                && !shaders.iter().any(|s| old.file_name().and_then(|n| n.to_str()) == Some(s.file.as_str()));
            if stale {
                fs::remove_file(&old).map_err(|e| format!("{}: {e}", old.display()))?;
            }
        }
        for s in &shaders {
            fs::write(dir.join(&s.file), &s.spirv).map_err(|e| format!("{}: {e}", s.file))?;
        }
        let module = spirv_root.join(format!("{family}.rs"));
        fs::write(&module, module_source(family, &shaders))
            .map_err(|e| format!("{}: {e}", module.display()))?;
        written += shaders.len();
    }
    Ok(written)
}
