//! Instance, physical device choice, logical device, one compute queue, the memory
//! allocator and the validation layer's messages.

use std::ffi::{c_void, CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::check;
use crate::error::{Error, Result};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to make a context.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Enable VK_LAYER_KHRONOS_validation and collect its messages (an error if the
    /// layer is missing).
    pub validation: bool,
    /// Pick the device whose name contains this text, or whose index this is
    /// [default: the `FSOT_DEVICE` variable, else the first discrete GPU, else any].
    pub device: Option<String>,
}

impl ContextOptions {
    /// The command line's options: `device` as given, the validation layer on
    /// when the `FSOT_VALIDATION` variable is 1.
    pub fn from_env(device: Option<String>) -> Self {
        let validation = std::env::var("FSOT_VALIDATION").map(|v| v == "1").unwrap_or(false);
        Self { validation, device }
    }
}

/// What fsot needs to know about the chosen device.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    pub driver: String,
    pub device_type: vk::PhysicalDeviceType,
    pub subgroup_size: u32,
    pub max_storage_buffer_range: u64,
    pub max_workgroup_invocations: u32,
    pub max_shared_memory: u32,
    pub timestamp_period_ns: f32,
    pub float_atomic_add: bool,
    /// shaderInt64 and shaderBufferInt64Atomics (fixed-point accumulators).
    pub int64_atomics: bool,
    /// Subgroup ballot operations in compute shaders (the radix sort needs them).
    pub subgroup_ballot: bool,
}

/// Everything that owns Vulkan objects, dropped in the right order.
pub struct Shared {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub device: ash::Device,
    pub physical_device: vk::PhysicalDevice,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub allocator: ManuallyDrop<Mutex<Allocator>>,
    pub info: DeviceInfo,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    messages: *mut Mutex<Vec<String>>,
    /// False when a host renderer owns the instance and device (`Context::wrap`).
    owns_device: bool,
}

/// A device made by a host application (a renderer) for fsot to work on. fsot
/// never destroys these handles; the host keeps them alive while the Context
/// lives. `int64_atomics` and `float_atomic_add` say which of those features the
/// host enabled on the device (the Vulkan optimizer needs the first; the second
/// is optional).
#[derive(Clone)]
pub struct ExternalDevice {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue_family: u32,
    pub queue_index: u32,
    pub int64_atomics: bool,
    pub float_atomic_add: bool,
}

// The raw pointer is a Box we own; the Mutex makes it safe to share.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

/// A Vulkan context; cheap to clone (shared ownership).
#[derive(Clone)]
pub struct Context {
    pub(crate) shared: Arc<Shared>,
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if !user.is_null() && !data.is_null() {
        let text = unsafe { (*data).message_as_c_str() }
            .map(|m| m.to_string_lossy().into_owned())
            .unwrap_or_default();
        let sink = unsafe { &*(user as *const Mutex<Vec<String>>) };
        if let Ok(mut list) = sink.lock() {
            list.push(format!("{severity:?}: {text}"));
        }
    }
    vk::FALSE
}

impl Context {
    /// Works on a device that a host application made (see `ExternalDevice`);
    /// fsot allocates its own memory on it and submits to the given queue.
    pub fn wrap(external: ExternalDevice) -> Result<Self> {
        let mut info = device_info(&external.instance, external.physical_device);
        info.int64_atomics &= external.int64_atomics;
        info.float_atomic_add &= external.float_atomic_add;
        let queue = unsafe { external.device.get_device_queue(external.queue_family, external.queue_index) };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: external.instance.clone(),
            device: external.device.clone(),
            physical_device: external.physical_device,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })?;
        Ok(Self {
            shared: Arc::new(Shared {
                entry: external.entry,
                instance: external.instance,
                device: external.device,
                physical_device: external.physical_device,
                queue,
                queue_family: external.queue_family,
                allocator: ManuallyDrop::new(Mutex::new(allocator)),
                info,
                debug: None,
                messages: Box::into_raw(Box::new(Mutex::new(Vec::new()))),
                owns_device: false,
            }),
        })
    }

    /// The handles, for handing fsot's device to other code (or to `wrap`).
    pub fn external(&self) -> ExternalDevice {
        let s = &self.shared;
        ExternalDevice {
            entry: s.entry.clone(),
            instance: s.instance.clone(),
            physical_device: s.physical_device,
            device: s.device.clone(),
            queue_family: s.queue_family,
            queue_index: 0,
            int64_atomics: s.info.int64_atomics,
            float_atomic_add: s.info.float_atomic_add,
        }
    }

    pub fn new(options: &ContextOptions) -> Result<Self> {
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| Error::VulkanUnavailable(format!("no Vulkan loader ({e})")))?;
        let mut layers: Vec<*const i8> = Vec::new();
        let mut extensions: Vec<*const i8> = Vec::new();
        if options.validation {
            let available = check("vkEnumerateInstanceLayerProperties", unsafe {
                entry.enumerate_instance_layer_properties()
            })?;
            let found = available
                .iter()
                .any(|l| l.layer_name_as_c_str().map(|n| n == VALIDATION_LAYER).unwrap_or(false));
            if !found {
                return Err(Error::VulkanUnavailable(
                    "validation asked for but VK_LAYER_KHRONOS_validation is not installed".into(),
                ));
            }
            layers.push(VALIDATION_LAYER.as_ptr());
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let app = vk::ApplicationInfo::default().application_name(c"fsot").api_version(vk::API_VERSION_1_2);
        let create = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        let instance = check("vkCreateInstance", unsafe { entry.create_instance(&create, None) })?;
        // From here on, a failure must destroy what was made: build the rest in a
        // helper and clean up the instance if it fails.
        let messages = Box::into_raw(Box::new(Mutex::new(Vec::new())));
        match Self::finish(entry.clone(), instance.clone(), options, messages) {
            Ok(ctx) => Ok(ctx),
            Err(e) => {
                unsafe {
                    instance.destroy_instance(None);
                    drop(Box::from_raw(messages));
                }
                Err(e)
            }
        }
    }

    fn finish(
        entry: ash::Entry,
        instance: ash::Instance,
        options: &ContextOptions,
        messages: *mut Mutex<Vec<String>>,
    ) -> Result<Self> {
        let debug = if options.validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                        | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(on_message))
                .user_data(messages as *mut c_void);
            let messenger = check("vkCreateDebugUtilsMessengerEXT", unsafe {
                loader.create_debug_utils_messenger(&info, None)
            })?;
            Some((loader, messenger))
        } else {
            None
        };
        let destroy_debug =
            |debug: &Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>| {
                if let Some((loader, m)) = debug {
                    unsafe { loader.destroy_debug_utils_messenger(*m, None) };
                }
            };
        let picked = pick_device(&instance, options);
        let (physical_device, queue_family) = match picked {
            Ok(p) => p,
            Err(e) => {
                destroy_debug(&debug);
                return Err(e);
            }
        };
        let info = device_info(&instance, physical_device);
        let priorities = [1.0f32];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let mut float_atomics = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
            .shader_buffer_float32_atomic_add(info.float_atomic_add);
        let mut extensions: Vec<*const i8> = Vec::new();
        let features = vk::PhysicalDeviceFeatures::default().shader_int64(info.int64_atomics);
        let mut features12 =
            vk::PhysicalDeviceVulkan12Features::default().shader_buffer_int64_atomics(info.int64_atomics);
        let mut create = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_features(&features)
            .push_next(&mut features12);
        if info.float_atomic_add {
            extensions.push(ash::ext::shader_atomic_float::NAME.as_ptr());
            create = create.push_next(&mut float_atomics);
        }
        let create = create.enabled_extension_names(&extensions);
        let device = match unsafe { instance.create_device(physical_device, &create, None) } {
            Ok(d) => d,
            Err(result) => {
                destroy_debug(&debug);
                return Err(Error::Vulkan { call: "vkCreateDevice", result });
            }
        };
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        });
        let allocator = match allocator {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_device(None) };
                destroy_debug(&debug);
                return Err(e.into());
            }
        };
        Ok(Self {
            shared: Arc::new(Shared {
                entry,
                instance,
                device,
                physical_device,
                queue,
                queue_family,
                allocator: ManuallyDrop::new(Mutex::new(allocator)),
                info,
                debug,
                messages,
                owns_device: true,
            }),
        })
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.shared.info
    }
    pub fn device(&self) -> &ash::Device {
        &self.shared.device
    }

    /// Validation messages collected so far (empty when validation is off).
    pub fn validation_messages(&self) -> Vec<String> {
        unsafe { &*self.shared.messages }.lock().map(|l| l.clone()).unwrap_or_default()
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            if self.owns_device {
                self.device.destroy_device(None);
                if let Some((loader, m)) = &self.debug {
                    loader.destroy_debug_utils_messenger(*m, None);
                }
                self.instance.destroy_instance(None);
            }
            drop(Box::from_raw(self.messages));
        }
    }
}

/// Devices in the order fsot prefers them, with a compute queue family each.
fn pick_device(instance: &ash::Instance, options: &ContextOptions) -> Result<(vk::PhysicalDevice, u32)> {
    let devices = check("vkEnumeratePhysicalDevices", unsafe { instance.enumerate_physical_devices() })?;
    let mut candidates = Vec::new();
    for (index, &pd) in devices.iter().enumerate() {
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let name = props.device_name_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
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
    let wanted = options.device.clone().or_else(|| std::env::var("FSOT_DEVICE").ok());
    if let Some(want) = wanted.filter(|w| !w.is_empty()) {
        let hit = candidates.iter().find(|c| {
            want.parse::<usize>().map(|i| i == c.1).unwrap_or(false)
                || c.2.to_lowercase().contains(&want.to_lowercase())
        });
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

fn device_info(instance: &ash::Instance, pd: vk::PhysicalDevice) -> DeviceInfo {
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup).push_next(&mut driver);
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let props = props2.properties;
    let mut atomics = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
    let mut features12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut plain2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut features12);
    unsafe { instance.get_physical_device_features2(pd, &mut plain2) };
    let int64_atomics =
        plain2.features.shader_int64 == vk::TRUE && features12.shader_buffer_int64_atomics == vk::TRUE;
    let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut atomics);
    let extensions = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let has_atomic_ext = extensions.iter().any(|e| {
        e.extension_name_as_c_str().map(|n| n == ash::ext::shader_atomic_float::NAME).unwrap_or(false)
    });
    if has_atomic_ext {
        unsafe { instance.get_physical_device_features2(pd, &mut features2) };
    }
    let name = props.device_name_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let driver_name =
        driver.driver_name_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let driver_info =
        driver.driver_info_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    DeviceInfo {
        name,
        driver: format!("{driver_name} {driver_info}").trim().to_string(),
        device_type: props.device_type,
        subgroup_size: subgroup.subgroup_size,
        max_storage_buffer_range: props.limits.max_storage_buffer_range as u64,
        max_workgroup_invocations: props.limits.max_compute_work_group_invocations,
        max_shared_memory: props.limits.max_compute_shared_memory_size,
        timestamp_period_ns: props.limits.timestamp_period,
        float_atomic_add: has_atomic_ext && atomics.shader_buffer_float32_atomic_add == vk::TRUE,
        int64_atomics,
        subgroup_ballot: subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE)
            && subgroup.supported_operations.contains(vk::SubgroupFeatureFlags::BALLOT),
    }
}

/// Keeps CString alive for callers that build names at run time.
pub fn c_string(s: &str) -> CString {
    CString::new(s).unwrap_or_default()
}
