//! fsot's WGSL include in a renderer's module, through naga (the tests of the
//! include; naga is a dev-dependency of fsot alone, so the command line's tests,
//! which share `common`, do not take this module).

/// A renderer's WGSL module with fsot's WGSL include (`wgsl/fsot.wgsl`) put into
/// it, as the include asks, parsed and validated by naga and written as SPIR-V.
pub fn compile_wgsl(source: &str) -> Vec<u8> {
    let module = wgsl_module(source);
    let info =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::empty())
            .validate(&module)
            .unwrap_or_else(|e| panic!("the WGSL does not validate: {e:?}"));
    // With names, which the tests read back.
    let mut options = naga::back::spv::Options::default();
    options.flags |= naga::back::spv::WriterFlags::DEBUG;
    let words = naga::back::spv::write_vec(&module, &info, &options, None)
        .unwrap_or_else(|e| panic!("no SPIR-V from the WGSL: {e}"));
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// A renderer's WGSL `source` with fsot's WGSL include put into it, parsed.
pub fn wgsl_module(source: &str) -> naga::Module {
    let include = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl/fsot.wgsl");
    let text = format!(
        "{source}
{}",
        std::fs::read_to_string(include).unwrap()
    );
    naga::front::wgsl::parse_str(&text).unwrap_or_else(|e| {
        panic!(
            "the WGSL does not parse:
{}",
            e.emit_to_string(&text)
        )
    })
}
