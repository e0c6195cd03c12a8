//! Device choice, and what fsot reads of a device.

use ash::vk;

use super::check;
use super::error::{Error, Result};

/// What a compute user needs to know about the chosen device.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    /// The device's name.
    pub name: String,
    /// The driver's name and version.
    pub driver: String,
    /// Discrete, integrated, CPU, ...
    pub device_type: vk::PhysicalDeviceType,
    /// The PCI vendor id (0x10DE NVIDIA, 0x1002 AMD, 0x8086 Intel, ...).
    pub vendor_id: u32,
    /// Invocations per subgroup.
    pub subgroup_size: u32,
    /// Bytes one storage-buffer binding may hold (maxStorageBufferRange).
    pub max_storage_buffer_range: u64,
    /// Texels one texel-buffer view may hold (maxTexelBufferElements).
    pub max_texel_buffer_elements: u64,
    /// The largest 1-D workgroup: maxComputeWorkGroupInvocations, or
    /// maxComputeWorkGroupSize's x where that is less.
    pub max_workgroup_invocations: u32,
    /// maxComputeSharedMemorySize, in bytes.
    pub max_shared_memory: u32,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period_ns: f32,
    /// shaderBufferFloat32AtomicAdd.
    pub float_atomic_add: bool,
    /// shaderInt64 and shaderBufferInt64Atomics.
    pub int64_atomics: bool,
    /// Subgroup ballot operations in compute shaders (the radix sort needs them).
    pub subgroup_ballot: bool,
    /// Subgroup vote operations in compute shaders.
    pub subgroup_vote: bool,
    /// Subgroup arithmetic (prefix sums) in compute shaders (the radix sort and
    /// the transport need them).
    pub subgroup_arithmetic: bool,
    /// shaderFloat64: 64-bit floats in shaders.
    pub float64: bool,
    /// computeFullSubgroups (VK_EXT_subgroup_size_control): a pipeline can ask
    /// that every subgroup of its workgroups be full (`ComputeDesc::full_subgroups`).
    /// Without it a driver may run a workgroup in smaller subgroups than
    /// `subgroup_size` (Intel's Linux driver does, for shaders that do not ask).
    pub full_subgroups: bool,
}

impl DeviceInfo {
    /// A CPU implementation of Vulkan (lavapipe, SwiftShader).
    pub fn is_cpu(&self) -> bool {
        self.device_type == vk::PhysicalDeviceType::CPU
    }

    /// A GPU known to keep a started workgroup running while another waits on
    /// it (NVIDIA's and AMD's), which a workgroup spinning on another's result
    /// (the radix sort's look-back path) needs; Vulkan does not promise it,
    /// and Apple's and mobile GPUs are known not to keep it.
    pub fn keeps_workgroups_running(&self) -> bool {
        !self.is_cpu() && self.nvidia_or_amd()
    }

    /// Whether a workgroup whose size is a multiple of `subgroup_size` runs as
    /// full subgroups of that size unasked: on CPU implementations and NVIDIA's
    /// and AMD's GPUs (one subgroup size each for these shaders); elsewhere
    /// only where a pipeline asks (`full_subgroups`).
    pub fn fills_subgroups(&self) -> bool {
        self.is_cpu() || self.nvidia_or_amd()
    }

    fn nvidia_or_amd(&self) -> bool {
        matches!(self.vendor_id, 0x10DE | 0x1002)
    }
}

/// The device named by `wanted` (an index, or part of its name, any case), else
/// the first discrete GPU, integrated GPU, virtual GPU, then any other; with a
/// compute queue family each.
pub(crate) fn pick(instance: &ash::Instance, wanted: Option<&str>) -> Result<(vk::PhysicalDevice, u32)> {
    // SAFETY: plain queries on a live instance.
    let devices = check("vkEnumeratePhysicalDevices", unsafe { instance.enumerate_physical_devices() })?;
    let mut candidates = Vec::new();
    for (index, &pd) in devices.iter().enumerate() {
        // SAFETY: `pd` comes from this instance.
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let name = props.device_name_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        // SAFETY: as above.
        let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let Some(family) = families.iter().position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
        else {
            continue;
        };
        let rank = match props.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => 0,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
            vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
            _ => 3,
        };
        candidates.push((rank, index, name, pd, family as u32));
    }
    if candidates.is_empty() {
        return Err(Error::VulkanUnavailable("no Vulkan device with a compute queue".into()));
    }
    if let Some(want) = wanted.filter(|w| !w.trim().is_empty()) {
        let hit = matching(want, candidates.iter().map(|c| (c.1, c.2.as_str())))
            .and_then(|i| candidates.iter().find(|c| c.1 == i));
        return match hit {
            Some(c) => Ok((c.3, c.4)),
            None => Err(Error::VulkanUnavailable(format!(
                "no device matches {want:?}; devices: {}",
                candidates.iter().map(|c| format!("{}: {}", c.1, c.2)).collect::<Vec<_>>().join(", ")
            ))),
        };
    }
    candidates.sort_by_key(|c| (c.0, c.1));
    Ok((candidates[0].3, candidates[0].4))
}

/// The index of the device `want` names among (index, name) pairs: a number
/// is an index alone (a number past the list names no device, never a name
/// holding its digits: "RTX 3090" names that card); other text, the first name
/// holding it (any case).
fn matching<'a>(want: &str, devices: impl Iterator<Item = (usize, &'a str)>) -> Option<usize> {
    let want = want.trim();
    let mut devices = devices;
    match want.parse::<usize>() {
        Ok(i) => devices.find(|d| d.0 == i),
        Err(_) => devices.find(|d| d.1.to_lowercase().contains(&want.to_lowercase())),
    }
    .map(|d| d.0)
}

/// What the device offers.
pub(crate) fn info(instance: &ash::Instance, pd: vk::PhysicalDevice) -> DeviceInfo {
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup).push_next(&mut driver);
    // SAFETY: the chained structs live until the call returns.
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let props = props2.properties;
    // SAFETY: a plain query.
    let extensions = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let has = |name: &std::ffi::CStr| extensions.iter().any(|e| e.extension_name_as_c_str() == Ok(name));
    let has_atomic_ext = has(ash::ext::shader_atomic_float::NAME);
    let has_size_control = has(ash::ext::subgroup_size_control::NAME);
    let mut features12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut atomics = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
    let mut size_control = vk::PhysicalDeviceSubgroupSizeControlFeaturesEXT::default();
    // An extension's feature struct is chained only where the device has it.
    let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut features12);
    if has_atomic_ext {
        features2 = features2.push_next(&mut atomics);
    }
    if has_size_control {
        features2 = features2.push_next(&mut size_control);
    }
    // SAFETY: the chained structs live until the call returns.
    unsafe { instance.get_physical_device_features2(pd, &mut features2) };
    let features = features2.features;
    let float64 = features.shader_float64 == vk::TRUE;
    let int64_atomics =
        features.shader_int64 == vk::TRUE && features12.shader_buffer_int64_atomics == vk::TRUE;
    let text =
        |c: Result<&std::ffi::CStr, _>| c.map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let driver_name = text(driver.driver_name_as_c_str());
    let driver_info = text(driver.driver_info_as_c_str());
    DeviceInfo {
        name: text(props.device_name_as_c_str()),
        driver: format!("{driver_name} {driver_info}").trim().to_string(),
        device_type: props.device_type,
        vendor_id: props.vendor_id,
        subgroup_size: subgroup.subgroup_size,
        max_storage_buffer_range: props.limits.max_storage_buffer_range as u64,
        max_texel_buffer_elements: props.limits.max_texel_buffer_elements as u64,
        max_workgroup_invocations: props
            .limits
            .max_compute_work_group_invocations
            .min(props.limits.max_compute_work_group_size[0]),
        max_shared_memory: props.limits.max_compute_shared_memory_size,
        timestamp_period_ns: props.limits.timestamp_period,
        float_atomic_add: has_atomic_ext && atomics.shader_buffer_float32_atomic_add == vk::TRUE,
        int64_atomics,
        subgroup_ballot: subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE)
            && subgroup.supported_operations.contains(vk::SubgroupFeatureFlags::BALLOT),
        subgroup_vote: subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE)
            && subgroup.supported_operations.contains(vk::SubgroupFeatureFlags::VOTE),
        subgroup_arithmetic: subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE)
            && subgroup.supported_operations.contains(vk::SubgroupFeatureFlags::ARITHMETIC),
        float64,
        full_subgroups: has_size_control && size_control.compute_full_subgroups == vk::TRUE,
    }
}

#[cfg(test)]
mod tests {
    use super::matching;

    #[test]
    fn a_device_is_named_by_its_index_alone_or_by_part_of_its_name() {
        let devices = [(0, "llvmpipe (LLVM 17.0.6, 256 bits)"), (1, "NVIDIA H100 80GB HBM3")];
        let pick = |want| matching(want, devices.iter().copied());
        assert_eq!(pick("1"), Some(1), "index 1, not the first name holding a 1");
        assert_eq!(pick(" 0 "), Some(0));
        assert_eq!(pick("7"), None, "a number past the list, though a name holds a 7");
        assert_eq!(pick("H100"), Some(1), "a model number with its letters: a name");
        assert_eq!(pick("nvidia"), Some(1));
        assert_eq!(pick(" LLVMpipe "), Some(0));
        assert_eq!(pick("radeon"), None);
    }
}
