//! What a device must enable for fsot, and what fsot uses where it is enabled:
//! for a renderer that makes its own device and hands it over
//! (`Context::wrap`). fsot's own devices (`Context::new`) enable exactly these.

use std::ffi::CStr;

use super::device::DeviceInfo;

/// Vulkan API version fsot's shaders and calls need (instance and device).
pub const API_VERSION: u32 = ash::vk::API_VERSION_1_2;

/// A capability fsot uses on a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Requirement {
    /// Vulkan's name for it: a feature's member name, or a property.
    pub name: &'static str,
    /// Where a host turns it on: the feature struct that holds it, or, for a
    /// property, that there is nothing to enable (the device has it or not).
    pub enabled_in: &'static str,
    /// The device extension it comes with, if any.
    pub extension: Option<&'static CStr>,
    /// Without it, fsot's optimizer refuses the device (the mask writes into a
    /// host's images need none of these).
    pub required: bool,
    /// What fsot does with it.
    pub used_for: &'static str,
}

impl Requirement {
    /// Does the device have it (enabled, for a wrapped device)?
    pub fn met_by(&self, info: &DeviceInfo) -> bool {
        match self.name {
            "shaderInt64" | "shaderBufferInt64Atomics" => info.int64_atomics,
            "subgroupSupportedOperations: BALLOT" => info.subgroup_ballot,
            "subgroupSupportedOperations: VOTE" => info.subgroup_vote,
            "subgroupSupportedOperations: ARITHMETIC" => info.subgroup_arithmetic,
            "shaderFloat64" => info.float64,
            "shaderBufferFloat32AtomicAdd" => info.float_atomic_add,
            "computeFullSubgroups" => info.full_subgroups,
            "maxComputeWorkGroupInvocations, maxComputeWorkGroupSize[0]: 256" => {
                info.max_workgroup_invocations >= 256
            }
            _ => false,
        }
    }
}

/// Every capability fsot uses, required ones first.
///
/// ```
/// for r in fsot::vk::requirements() {
///     let kind = if r.required { "required" } else { "optional" };
///     println!("{kind}: {} ({}): {}", r.name, r.enabled_in, r.used_for);
/// }
/// assert!(fsot::vk::requirements().iter().any(|r| r.required && r.name == "shaderBufferInt64Atomics"));
/// ```
pub fn requirements() -> &'static [Requirement] {
    const FEATURES: &str = "VkPhysicalDeviceFeatures";
    const FEATURES12: &str = "VkPhysicalDeviceVulkan12Features";
    const PROPERTY: &str = "VkPhysicalDeviceSubgroupProperties in compute (a property: nothing to enable)";
    &[
        Requirement {
            name: "shaderInt64",
            enabled_in: FEATURES,
            extension: None,
            required: true,
            used_for: "64-bit fixed-point sums of the displacements",
        },
        Requirement {
            name: "shaderBufferInt64Atomics",
            enabled_in: FEATURES12,
            extension: None,
            required: true,
            used_for: "the gradient scatter's 64-bit atomic adds",
        },
        Requirement {
            name: "subgroupSupportedOperations: BALLOT",
            enabled_in: PROPERTY,
            extension: None,
            required: true,
            used_for: "the radix sort's digit counts and the transport's ranks",
        },
        Requirement {
            name: "subgroupSupportedOperations: ARITHMETIC",
            enabled_in: PROPERTY,
            extension: None,
            required: true,
            used_for: "the radix sort's and the transport's prefix sums within a subgroup",
        },
        Requirement {
            name: "maxComputeWorkGroupInvocations, maxComputeWorkGroupSize[0]: 256",
            enabled_in: "VkPhysicalDeviceLimits (a limit: nothing to enable)",
            extension: None,
            required: true,
            used_for: "the update's, the gathers' and the second transport pass's workgroups of 256",
        },
        Requirement {
            name: "subgroupSupportedOperations: VOTE",
            enabled_in: PROPERTY,
            extension: None,
            required: false,
            used_for: "the per-lane transport on CPU implementations",
        },
        Requirement {
            name: "shaderFloat64",
            enabled_in: FEATURES,
            extension: None,
            required: false,
            used_for: "d >= 3 targets and the stopping rule on the device (without it: float32 pairs, the host's rule)",
        },
        Requirement {
            name: "shaderBufferFloat32AtomicAdd",
            enabled_in: "VkPhysicalDeviceShaderAtomicFloatFeaturesEXT",
            extension: Some(ash::ext::shader_atomic_float::NAME),
            required: false,
            used_for: "faster scatter by float atomics (runs not bit-reproducible; off with `deterministic`)",
        },
        Requirement {
            name: "computeFullSubgroups",
            enabled_in: "VkPhysicalDeviceSubgroupSizeControlFeaturesEXT",
            extension: Some(ash::ext::subgroup_size_control::NAME),
            required: false,
            used_for: "full subgroups for the passes that rank and sum subgroup by subgroup (the transport, the radix sort's scatter); without it they rely on the driver filling them, which Intel's Linux driver does not",
        },
    ]
}

/// The first required capability `info` lacks, if any.
pub fn missing(info: &DeviceInfo) -> Option<&'static Requirement> {
    requirements().iter().find(|r| r.required && !r.met_by(info))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn device(on: bool) -> DeviceInfo {
        DeviceInfo {
            name: "a device".into(),
            driver: String::new(),
            device_type: ash::vk::PhysicalDeviceType::DISCRETE_GPU,
            vendor_id: 0x10DE,
            subgroup_size: 32,
            max_storage_buffer_range: 1 << 30,
            max_texel_buffer_elements: 1 << 27,
            max_workgroup_invocations: if on { 1024 } else { 128 },
            max_shared_memory: 49152,
            timestamp_period_ns: 1.0,
            float_atomic_add: on,
            int64_atomics: on,
            subgroup_ballot: on,
            subgroup_vote: on,
            subgroup_arithmetic: on,
            float64: on,
            full_subgroups: on,
        }
    }

    #[test]
    fn a_device_with_every_capability_meets_every_requirement_and_one_with_none_meets_none() {
        assert!(requirements().iter().all(|r| r.met_by(&device(true))));
        assert!(requirements().iter().all(|r| !r.met_by(&device(false))));
        assert_eq!(missing(&device(true)), None);
    }

    #[test]
    fn a_device_without_a_required_capability_is_missing_it_and_optional_ones_are_never_missing() {
        let mut no_ballot = device(true);
        no_ballot.subgroup_ballot = false;
        assert_eq!(missing(&no_ballot).map(|r| r.name), Some("subgroupSupportedOperations: BALLOT"));
        let mut no_prefix_sums = device(true);
        no_prefix_sums.subgroup_arithmetic = false;
        assert_eq!(missing(&no_prefix_sums).map(|r| r.name), Some("subgroupSupportedOperations: ARITHMETIC"));
        let mut no_atomics = device(true);
        no_atomics.int64_atomics = false;
        assert_eq!(missing(&no_atomics).map(|r| r.name), Some("shaderInt64"));
        let small = DeviceInfo { max_workgroup_invocations: 255, ..device(true) };
        assert_eq!(
            missing(&small).map(|r| r.name),
            Some("maxComputeWorkGroupInvocations, maxComputeWorkGroupSize[0]: 256")
        );
        let mut bare = device(true);
        (bare.float64, bare.float_atomic_add, bare.subgroup_vote, bare.full_subgroups) =
            (false, false, false, false);
        assert_eq!(missing(&bare), None);
        let required: Vec<&str> = requirements().iter().filter(|r| r.required).map(|r| r.name).collect();
        assert_eq!(
            required,
            [
                "shaderInt64",
                "shaderBufferInt64Atomics",
                "subgroupSupportedOperations: BALLOT",
                "subgroupSupportedOperations: ARITHMETIC",
                "maxComputeWorkGroupInvocations, maxComputeWorkGroupSize[0]: 256"
            ]
        );
    }
}
