//! The compiled SPIR-V agrees with its Rust mirror: every storage block's and
//! texel buffer's binding index, every push-constant struct's member names and
//! offsets, and the layout of the structs inside buffers, read with rspirv (an
//! independent SPIR-V reader) from the shaders compiled here with their names
//! kept (the embedded SPIR-V has none; tests/spirv_fresh.rs ties it to the same
//! GLSL). GLSL and Rust cannot drift apart.
#![cfg(feature = "vulkan")]

use std::collections::HashMap;

use fsot::optimize::vulkan::layout::{
    self, HashPush, LargeMetaHead, LargeSegment, PlateauPush, RuleState, ScatterPush, TransportPush,
    UpdatePush,
};
use fsot::peers::swap::vulkan::layout::{self as swap, SwapOffset, SwapProposal, SwapPush, SwapStats};
use fsot::vk::sort::{self, RadixPush};
use rspirv::dr::{load_bytes, Module, Operand};
use rspirv::spirv::{Decoration, Op, StorageClass};
use std::sync::OnceLock;

/// Every shader of a family, compiled with OpName/OpMemberName kept; the same
/// names as the family the crate embeds.
fn named(family: &str, embedded: &[(&str, &[u8])]) -> &'static [(&'static str, &'static [u8])] {
    type Compiled = Vec<(&'static str, &'static [u8])>;
    static FAMILIES: OnceLock<Vec<(String, Compiled)>> = OnceLock::new();
    let all = FAMILIES.get_or_init(|| {
        let glsl = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl");
        shaderc_link::FAMILIES
            .iter()
            .map(|f| {
                let shaders = shaderc_link::compile_family(&glsl, f, true).unwrap();
                let leaked =
                    shaders
                        .into_iter()
                        .map(|s| (&*s.name.leak(), &*s.spirv.leak()))
                        .collect::<Vec<(&'static str, &'static [u8])>>();
                (f.to_string(), leaked)
            })
            .collect()
    });
    let shaders = &all.iter().find(|(f, _)| f == family).unwrap().1;
    let names: Vec<&str> = shaders.iter().map(|s| s.0).collect();
    let want: Vec<&str> = embedded.iter().map(|s| s.0).collect();
    assert_eq!(names, want, "{family}: the compiled and the embedded shaders differ");
    shaders
}

/// (member name, byte offset) of a Rust struct, in declaration order.
macro_rules! fields {
    ($t:ty; $($f:ident),* $(,)?) => {
        (stringify!($t), std::mem::size_of::<$t>(), vec![$((stringify!($f), std::mem::offset_of!($t, $f))),*])
    };
}

type Mirror = (&'static str, usize, Vec<(&'static str, usize)>);

fn mirrors() -> Vec<Mirror> {
    vec![
        fields!(TransportPush; slice_key, iteration, width, height, frames, spp, dims, taps, slices, cost_slot, large_capacity, order_slot, deferred_capacity, axis_bits, pair_bits),
        fields!(UpdatePush; values, rule, step_t, scale, inv_hits, p0, p1, p2, p3, bias1, bias2, scheduled),
        fields!(PlateauPush; slot, iteration),
        fields!(RuleState; previous, sum, decay_below, stop_below, target, scale, factor, floor_scale, count, window, has_previous, has_target, stopped, stop_iteration, pad),
        fields!(ScatterPush; count),
        fields!(HashPush; key, count),
        fields!(LargeSegment; slice, first, size, pad),
        fields!(RadixPush; shift, blocks, chunks, passes),
        fields!(SwapPush; width, height, frames, offsets, term, inv_sigma2, temperature, pass_key, first, count, batch, retry, last),
        fields!(SwapOffset; dx, dy, dt, weight),
        fields!(SwapProposal; p, q, delta, state),
        fields!(SwapStats; energy, accepted, dropped, uphill, retried),
    ]
}

fn fsot_named() -> &'static [(&'static str, &'static [u8])] {
    named("fsot", fsot::optimize::vulkan::shaders::ALL)
}

/// What one shader declares.
#[derive(Default)]
struct Reflection {
    names: HashMap<u32, String>,
    member_names: HashMap<(u32, u32), String>,
    offsets: HashMap<(u32, u32), u32>,
    strides: HashMap<u32, u32>,
    bindings: HashMap<u32, u32>,
    /// Struct type id -> member type ids.
    structs: HashMap<u32, Vec<u32>>,
    /// Pointer type id -> pointee; runtime array id -> element.
    pointee: HashMap<u32, u32>,
    element: HashMap<u32, u32>,
    /// (variable, pointer type, storage class).
    variables: Vec<(u32, u32, StorageClass)>,
}

fn word(op: &Operand) -> u32 {
    match op {
        Operand::LiteralBit32(v) => *v,
        Operand::IdRef(v) => *v,
        other => panic!("unexpected operand {other:?}"),
    }
}

fn reflect(module: &Module) -> Reflection {
    let mut r = Reflection::default();
    for i in &module.debug_names {
        match i.class.opcode {
            Op::Name => {
                if let (Operand::IdRef(id), Operand::LiteralString(s)) = (&i.operands[0], &i.operands[1]) {
                    r.names.insert(*id, s.clone());
                }
            }
            Op::MemberName => {
                if let Operand::LiteralString(s) = &i.operands[2] {
                    r.member_names.insert((word(&i.operands[0]), word(&i.operands[1])), s.clone());
                }
            }
            _ => {}
        }
    }
    for i in &module.annotations {
        match (i.class.opcode, &i.operands[..]) {
            (Op::Decorate, [target, Operand::Decoration(Decoration::Binding), value]) => {
                r.bindings.insert(word(target), word(value));
            }
            (Op::Decorate, [target, Operand::Decoration(Decoration::ArrayStride), value]) => {
                r.strides.insert(word(target), word(value));
            }
            (Op::MemberDecorate, [target, member, Operand::Decoration(Decoration::Offset), value]) => {
                r.offsets.insert((word(target), word(member)), word(value));
            }
            _ => {}
        }
    }
    for i in &module.types_global_values {
        let id = i.result_id.unwrap_or(0);
        match i.class.opcode {
            Op::TypeStruct => {
                r.structs.insert(id, i.operands.iter().map(word).collect());
            }
            Op::TypePointer => {
                r.pointee.insert(id, word(&i.operands[1]));
            }
            Op::TypeRuntimeArray | Op::TypeArray => {
                r.element.insert(id, word(&i.operands[0]));
            }
            Op::Variable => {
                if let Operand::StorageClass(class) = i.operands[0] {
                    r.variables.push((id, i.result_type.unwrap_or(0), class));
                }
            }
            _ => {}
        }
    }
    r
}

impl Reflection {
    /// The member names and offsets of struct type `id`.
    fn layout(&self, id: u32) -> Vec<(String, u32)> {
        let n = self.structs[&id].len() as u32;
        (0..n)
            .map(|m| (self.member_names.get(&(id, m)).cloned().unwrap_or_default(), self.offsets[&(id, m)]))
            .collect()
    }

    /// Every struct type by name (the first of a name).
    fn struct_named(&self, name: &str) -> Option<u32> {
        let mut ids: Vec<u32> = self
            .structs
            .keys()
            .copied()
            .filter(|id| self.names.get(id).map(String::as_str) == Some(name))
            .collect();
        ids.sort();
        ids.first().copied()
    }
}

/// Checks a shader family against its binding tables (storage blocks by block
/// name, texel buffers by variable name); returns the names seen.
fn check_family(
    family: &str,
    shaders: &[(&str, &[u8])],
    blocks: &[(&str, u32)],
    texels: &[(&str, u32)],
    bindings: u32,
) -> Vec<String> {
    let mirrors = mirrors();
    let mut seen = Vec::new();
    for (shader, spirv) in shaders {
        let module = load_bytes(spirv).unwrap_or_else(|e| panic!("{family}/{shader}: {e:?}"));
        let r = reflect(&module);
        for &(var, ptr, class) in &r.variables {
            let block = r.pointee[&ptr];
            // Storage blocks go by their block's name, texel buffers by their own.
            let table = match class {
                StorageClass::StorageBuffer | StorageClass::Uniform => Some((r.names.get(&block), blocks)),
                StorageClass::UniformConstant => Some((r.names.get(&var), texels)),
                _ => None,
            };
            if let Some((name, table)) = table {
                let name = name.cloned().unwrap_or_default();
                let binding = r.bindings[&var];
                let expected = table.iter().find(|b| b.0 == name).map(|b| b.1);
                assert_eq!(expected, Some(binding), "{family}/{shader}: {name:?} at binding {binding}");
                assert!(binding < bindings, "{family}/{shader}: binding {binding} outside the layout");
                seen.push(name);
            }
            if class == StorageClass::PushConstant {
                // `uniform Push { Struct pc; }`: its one member is the mirrored struct.
                let inner = r.structs[&block][0];
                assert_eq!(r.offsets[&(block, 0)], 0, "{family}/{shader}: push block offset");
                let inner_name = r.names[&inner].clone();
                let mirror = mirrors.iter().find(|m| m.0 == inner_name);
                let mirror =
                    mirror.unwrap_or_else(|| panic!("{family}/{shader}: no Rust mirror of {inner_name}"));
                let want: Vec<(String, u32)> =
                    mirror.2.iter().map(|(f, o)| (f.to_string(), *o as u32)).collect();
                assert_eq!(r.layout(inner), want, "{family}/{shader}: push struct {inner_name}");
            }
        }
        // Structs inside buffers.
        for name in ["LargeSegment", "RuleState", "SwapOffset", "SwapProposal", "SwapStats"] {
            if let Some(id) = r.struct_named(name) {
                let m = mirrors.iter().find(|m| m.0 == name).unwrap();
                let want: Vec<(String, u32)> = m.2.iter().map(|(f, o)| (f.to_string(), *o as u32)).collect();
                assert_eq!(r.layout(id), want, "{shader}: {name}");
                seen.push(format!("struct {name}"));
            }
        }
        if let Some(meta) = r.struct_named("LargeMeta") {
            seen.push("struct LargeMeta".to_string());
            let got = r.layout(meta);
            let head = [
                ("large_count", std::mem::offset_of!(LargeMetaHead, large_count)),
                ("large_segments", std::mem::offset_of!(LargeMetaHead, large_segments)),
                ("large_overflow", std::mem::offset_of!(LargeMetaHead, large_overflow)),
                ("loop_cut", std::mem::offset_of!(LargeMetaHead, loop_cut)),
                ("segments", std::mem::size_of::<LargeMetaHead>()),
            ];
            let want: Vec<(String, u32)> = head.iter().map(|(f, o)| (f.to_string(), *o as u32)).collect();
            assert_eq!(got, want, "{shader}: LargeMeta");
            let array = r.structs[&meta][4];
            assert_eq!(
                r.strides[&array] as usize,
                std::mem::size_of::<LargeSegment>(),
                "{shader}: segment stride"
            );
        }
    }
    seen.sort();
    seen.dedup();
    seen
}

#[test]
fn every_fsot_binding_and_struct_matches_its_rust_mirror() {
    let b = &layout::binding::BLOCKS;
    let t = &layout::binding::TEXEL_VARIABLES;
    let seen = check_family("fsot", fsot_named(), b, t, layout::binding::BINDINGS);
    // The structs inside buffers were found and checked (a rename would drop the check).
    for name in ["LargeSegment", "RuleState", "LargeMeta"] {
        assert!(seen.contains(&format!("struct {name}")), "no fsot pass declares {name}");
    }
    // Every Rust binding is used by some pass (no stale entry in the mirror).
    for (name, _) in b.iter().chain(t) {
        assert!(seen.iter().any(|s| s == name), "binding {name} is in the Rust mirror but in no fsot pass");
    }
    assert_eq!((b.len() + t.len()) as u32, layout::binding::BINDINGS);
}

#[test]
fn every_sort_binding_and_struct_matches_its_rust_mirror() {
    let (b, t) = (&sort::binding::BLOCKS, &sort::binding::TEXEL_VARIABLES);
    let seen = check_family("sort", named("sort", fsot::vk::shaders::ALL), b, t, sort::binding::BINDINGS);
    for (name, _) in b.iter().chain(t) {
        assert!(seen.iter().any(|s| s == name), "binding {name} is in the Rust mirror but in no sort pass");
    }
    assert_eq!((b.len() + t.len()) as u32, sort::binding::BINDINGS);
    assert_eq!(t.map(|v| v.1), sort::binding::TEXELS);
}

#[test]
fn every_swap_binding_and_struct_matches_its_rust_mirror() {
    let seen = check_family(
        "swap",
        named("swap", fsot::peers::swap::vulkan::shaders::ALL),
        &swap::binding::BLOCKS,
        &[],
        swap::binding::BINDINGS,
    );
    for (name, _) in swap::binding::BLOCKS {
        assert!(seen.iter().any(|s| s == name), "binding {name} is in the Rust mirror but in no swap pass");
    }
    for name in ["SwapOffset", "SwapProposal", "SwapStats"] {
        assert!(seen.contains(&format!("struct {name}")), "no swap pass declares {name}");
    }
    assert_eq!(swap::binding::BLOCKS.len() as u32, swap::binding::BINDINGS);
}

#[test]
fn a_mirror_that_drifted_is_caught() {
    // Two bindings swapped in the Rust table: the check must fail.
    let mut drifted = layout::binding::BLOCKS;
    (drifted[0].1, drifted[2].1) = (drifted[2].1, drifted[0].1);
    let caught = std::panic::catch_unwind(|| {
        let t = &layout::binding::TEXEL_VARIABLES;
        check_family("fsot", fsot_named(), &drifted, t, layout::binding::BINDINGS);
    });
    assert!(caught.is_err(), "a swapped binding went unnoticed");
    let mut drifted = layout::binding::TEXEL_VARIABLES;
    (drifted[0].1, drifted[1].1) = (drifted[1].1, drifted[0].1);
    let caught = std::panic::catch_unwind(|| {
        let b = &layout::binding::BLOCKS;
        check_family("fsot", fsot_named(), b, &drifted, layout::binding::BINDINGS);
    });
    assert!(caught.is_err(), "a swapped texel binding went unnoticed");
}

#[test]
fn the_cpu_passes_read_through_texel_views_and_no_other_pass_does() {
    // A texel view is read where some instruction of a function loads its variable.
    for (shader, spirv) in fsot_named() {
        let module = load_bytes(spirv).unwrap();
        let r = reflect(&module);
        let loaded = |var: u32| {
            module.functions.iter().flat_map(|f| &f.blocks).flat_map(|b| &b.instructions).any(|i| {
                i.class.opcode == Op::Load && i.operands.first().is_some_and(|o| *o == Operand::IdRef(var))
            })
        };
        let mut used: Vec<String> = r
            .variables
            .iter()
            .filter(|v| v.2 == StorageClass::UniformConstant && loaded(v.0))
            .map(|v| r.names.get(&v.0).cloned().unwrap_or_default())
            .collect();
        used.sort();
        let want: &[&str] = if shader.starts_with("TRANSPORT_LANE") {
            &["sample_texels", "tap_texels"]
        } else if *shader == "SLICE_ORDER_COUNT" {
            &["tap_texels"]
        } else if shader.starts_with("UPDATE_TEXELS") {
            &["acc_texels", "first_texels", "sample_texels", "second_texels"]
        } else {
            &[]
        };
        assert_eq!(used, want, "{shader}");
    }
}

/// Bytes of workgroup (shared) memory a shader declares with these
/// specialization constants: its Workgroup variables' sizes, the array lengths
/// evaluated from the module's constants and spec constant operations (scalars
/// of 32 bits or less, booleans, take 4 bytes).
fn shared_bytes(spirv: &[u8], spec: &[u32]) -> u64 {
    let module = load_bytes(spirv).unwrap();
    let mut spec_ids = HashMap::new();
    for i in &module.annotations {
        if let (Op::Decorate, [target, Operand::Decoration(Decoration::SpecId), id]) =
            (i.class.opcode, &i.operands[..])
        {
            spec_ids.insert(word(target), word(id) as usize);
        }
    }
    let (mut value, mut parts, mut size) = (HashMap::new(), HashMap::new(), HashMap::new());
    let mut pointee = HashMap::new();
    let mut shared = 0u64;
    for i in &module.types_global_values {
        let id = i.result_id.unwrap_or(0);
        let ops = &i.operands;
        match i.class.opcode {
            Op::TypeInt | Op::TypeFloat => {
                size.insert(id, u64::from(word(&ops[0]).max(32) / 8));
            }
            Op::TypeBool => {
                size.insert(id, 4);
            }
            Op::TypeVector => {
                size.insert(id, size[&word(&ops[0])] * u64::from(word(&ops[1])));
            }
            // (Sized where the element is: not the blocks around runtime arrays.)
            Op::TypeArray => {
                if let Some(element) = size.get(&word(&ops[0])) {
                    size.insert(id, element * value[&word(&ops[1])]);
                }
            }
            Op::TypeStruct => {
                if let Some(members) = ops.iter().map(|m| size.get(&word(m))).sum::<Option<u64>>() {
                    size.insert(id, members);
                }
            }
            Op::TypePointer => {
                pointee.insert(id, word(&ops[1]));
            }
            Op::Constant => {
                value.insert(id, u64::from(word(&ops[0])));
            }
            Op::SpecConstant => {
                let default = u64::from(word(&ops[0]));
                let given = spec_ids.get(&id).and_then(|k| spec.get(*k)).map(|&v| u64::from(v));
                value.insert(id, given.unwrap_or(default));
            }
            Op::SpecConstantComposite => {
                parts.insert(id, ops.iter().map(|c| value[&word(c)]).collect::<Vec<u64>>());
            }
            Op::SpecConstantOp => {
                let Operand::LiteralSpecConstantOpInteger(op) = ops[0] else { panic!("{ops:?}") };
                let arg = |k: usize| value[&word(&ops[k])];
                let v = match op {
                    Op::IMul => arg(1) * arg(2),
                    Op::IAdd => arg(1) + arg(2),
                    Op::ISub => arg(1) - arg(2),
                    Op::UDiv => arg(1) / arg(2),
                    Op::CompositeExtract => parts[&word(&ops[1])][word(&ops[2]) as usize],
                    // Not an array length: any value.
                    _ => 0,
                };
                value.insert(id, v);
            }
            Op::Variable if ops[0] == Operand::StorageClass(StorageClass::Workgroup) => {
                shared += size[&pointee[&i.result_type.unwrap()]];
            }
            _ => {}
        }
    }
    shared
}

#[test]
fn the_sort_shapes_count_the_shared_memory_their_passes_declare() {
    // Every pass of a block shape with the constants the sort gives it: the
    // largest declares exactly what `SortShape::fits` counts, so a device
    // with a byte less refuses the shape.
    for (workgroup, items, subgroup) in
        [(64u32, 32u32, 8u32), (32, 64, 4), (256, 8, 32), (256, 16, 64), (32, 32, 4)]
    {
        let shape = sort::SortShape::fits(workgroup, items, subgroup, 1024, u32::MAX).unwrap();
        let spec = [shape.workgroup, shape.items, shape.subgroups, shape.block];
        let (name, most) = fsot::vk::shaders::ALL
            .iter()
            .filter(|(name, _)| !name.contains("lane") && !name.contains("args"))
            .map(|(name, spirv)| (*name, shared_bytes(spirv, &spec)))
            .max_by_key(|s| s.1)
            .unwrap();
        let most = u32::try_from(most).unwrap();
        assert!(sort::SortShape::fits(workgroup, items, subgroup, 1024, most).is_some(), "{name}: {most}");
        assert!(
            sort::SortShape::fits(workgroup, items, subgroup, 1024, most - 1).is_none(),
            "{name}: {most}"
        );
    }
}
