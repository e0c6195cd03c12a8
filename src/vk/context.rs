//! A Vulkan context: a device, one compute queue, the memory allocator and a
//! persistent command pool, made here (`Context::new`) or wrapped around a device
//! a host application made (`Context::wrap`). Cheap to clone; `Send + Sync`.
//!
//! Thread safety: Vulkan requires a queue to be used by one thread at a time.
//! Every submission takes the context's queue lock around `vkQueueSubmit`; a host
//! that shares its queue with fsot hands its own lock in (`ExternalDevice::queue_lock`)
//! and takes it around its own submissions. Recording and submitting also hold the
//! context's command lock, so submissions from several threads to one context run
//! one after another (use a context per thread for parallel GPU work).

use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};

use ash::vk::{self, Handle};
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::commands::Commands;
use super::device::{self, DeviceInfo};
use super::error::{Error, Result};
use super::instance::{Instance, MessageSink};

/// How to make a context.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Enable VK_LAYER_KHRONOS_validation and collect its messages (an error if the
    /// layer is missing).
    pub validation: bool,
    /// The device whose index this is or whose name contains this text [default:
    /// the first discrete GPU, else integrated, virtual, any].
    pub device: Option<String>,
}

/// A device made by a host application (a renderer) for fsot to work on. fsot
/// never destroys these handles; the host keeps them alive while the Context
/// lives. `int64_atomics`, `float_atomic_add`, `float64` and `full_subgroups`
/// say which of those features the host enabled on the device (the Vulkan
/// optimizer needs the first; the others are optional: d >= 3 keeps its
/// targets in float64 where it is enabled, else in pairs of float32).
#[derive(Clone)]
pub struct ExternalDevice {
    /// The loader the host's instance was made with.
    pub entry: ash::Entry,
    /// The host's instance.
    pub instance: ash::Instance,
    /// The physical device behind `device`.
    pub physical_device: vk::PhysicalDevice,
    /// The host's logical device.
    pub device: ash::Device,
    /// The family of the queue fsot submits to (it must support compute).
    pub queue_family: u32,
    /// The queue's index in its family.
    pub queue_index: u32,
    /// shaderInt64 and shaderBufferInt64Atomics were both enabled on the device
    /// (the shaders use 64-bit integers and atomics on them).
    pub int64_atomics: bool,
    /// shaderBufferFloat32AtomicAdd was enabled on the device.
    pub float_atomic_add: bool,
    /// shaderFloat64 was enabled on the device.
    pub float64: bool,
    /// VK_EXT_subgroup_size_control was enabled on the device with its
    /// computeFullSubgroups feature: fsot's passes that rely on full subgroups
    /// then ask for them. Without it they rely on the driver filling every
    /// subgroup of a workgroup whose size is a multiple of the subgroup size,
    /// which Intel's Linux driver does not do (it runs such a shader in smaller
    /// subgroups unless asked): enable it on such a device.
    pub full_subgroups: bool,
    /// The lock the host takes around its own submissions to this queue; fsot
    /// takes it around each of its submissions. None: the host does not submit to
    /// this queue while fsot works on it (fsot then locks its own).
    pub queue_lock: Option<Arc<Mutex<()>>>,
}

/// Everything that owns Vulkan objects, destroyed in order in `Drop`.
pub(crate) struct Shared {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub device: ash::Device,
    pub physical_device: vk::PhysicalDevice,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub queue_index: u32,
    pub queue_lock: Arc<Mutex<()>>,
    pub commands: ManuallyDrop<Mutex<Commands>>,
    pub allocator: ManuallyDrop<Mutex<Allocator>>,
    pub info: DeviceInfo,
    /// The process's instance the device was made on (None for a wrapped
    /// device): fsot destroys the device, never the instance.
    owned: Option<&'static Instance>,
    messages: MessageSink,
}

/// A Vulkan context; cheap to clone (shared ownership).
#[derive(Clone)]
pub struct Context {
    pub(crate) shared: Arc<Shared>,
}

impl Context {
    /// A context on a device of its own, chosen by `options`, made on the
    /// process's Vulkan instance (one per validation setting, made by the first
    /// context and kept for the process's life; dropping the context destroys
    /// its device only). With validation, `validation_messages` collects the
    /// layer's messages that name this context's device, queue or command
    /// buffer, and those that name no context's.
    pub fn new(options: &ContextOptions) -> Result<Self> {
        let instance = Instance::shared(options.validation)?;
        // Listening from here: what making the device says reaches this context.
        let messages = MessageSink::default();
        instance.listen(&messages);
        let (physical_device, queue_family) = device::pick(&instance.raw, options.device.as_deref())?;
        let info = device::info(&instance.raw, physical_device);
        let priorities = [1.0f32];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let mut float_atomics = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
            .shader_buffer_float32_atomic_add(info.float_atomic_add);
        let mut full_subgroups =
            vk::PhysicalDeviceSubgroupSizeControlFeaturesEXT::default().compute_full_subgroups(true);
        let mut extensions: Vec<*const i8> = Vec::new();
        let features = vk::PhysicalDeviceFeatures::default()
            .shader_int64(info.int64_atomics)
            .shader_float64(info.float64);
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
        if info.full_subgroups {
            extensions.push(ash::ext::subgroup_size_control::NAME.as_ptr());
            create = create.push_next(&mut full_subgroups);
        }
        let create = create.enabled_extension_names(&extensions);
        // SAFETY: the create info and everything it points to live until the call returns.
        let device = unsafe { instance.raw.create_device(physical_device, &create, None) }
            .map_err(|result| Error::Vulkan { call: "vkCreateDevice", result })?;
        let external = ExternalDevice {
            entry: instance.entry.clone(),
            instance: instance.raw.clone(),
            physical_device,
            device,
            queue_family,
            queue_index: 0,
            int64_atomics: info.int64_atomics,
            float_atomic_add: info.float_atomic_add,
            float64: info.float64,
            full_subgroups: info.full_subgroups,
            queue_lock: None,
        };
        Self::build(external, info, Some((instance, messages)))
    }

    /// Works on a device that a host application made (see `ExternalDevice`); fsot
    /// allocates its own memory and command pool on it and submits to the given
    /// queue under the queue lock.
    ///
    /// The queue family must be one of the physical device's, with compute, and
    /// the queue's index within its queue count, and the physical device must
    /// support Vulkan `API_VERSION` (1.2): an error otherwise, before the queue is
    /// asked for.
    ///
    /// # Safety
    /// fsot cannot check these of a device it did not make:
    /// - `device` was made from `physical_device` of `instance`, with each
    ///   feature whose flag is set (both features for `int64_atomics`; the
    ///   extension and its feature for `full_subgroups`), and with
    ///   the queue `queue_index` of `queue_family` where the physical device has
    ///   that queue (checked above);
    /// - `instance` was made with an `apiVersion` of at least `API_VERSION`
    ///   (Vulkan 1.2; the physical device's own version is checked above), and
    ///   `entry` is the loader it was made with;
    /// - the instance and the device stay alive until this context and
    ///   everything made with it (buffers, images, runs, clones) are dropped;
    /// - every other submission to the queue takes `queue_lock` (with None, no
    ///   other submits to it while the context lives).
    pub unsafe fn wrap(external: ExternalDevice) -> Result<Self> {
        // SAFETY: plain queries on the host's live instance.
        let version =
            unsafe { external.instance.get_physical_device_properties(external.physical_device).api_version };
        if version < crate::vk::API_VERSION {
            return Err(Error::VulkanUnavailable(format!(
                "the device supports Vulkan {}.{}; fsot needs 1.2",
                vk::api_version_major(version),
                vk::api_version_minor(version)
            )));
        }
        // SAFETY: a plain query on the host's live instance.
        let families = unsafe {
            external.instance.get_physical_device_queue_family_properties(external.physical_device)
        };
        let family = families.get(external.queue_family as usize).ok_or_else(|| {
            Error::invalid(format!(
                "queue family {} of a device with {}",
                external.queue_family,
                families.len()
            ))
        })?;
        if !family.queue_flags.contains(vk::QueueFlags::COMPUTE) {
            return Err(Error::invalid(format!("queue family {} has no compute", external.queue_family)));
        }
        if external.queue_index >= family.queue_count {
            return Err(Error::invalid(format!(
                "queue {} of a family of {}",
                external.queue_index, family.queue_count
            )));
        }
        let mut info = device::info(&external.instance, external.physical_device);
        info.int64_atomics &= external.int64_atomics;
        info.float_atomic_add &= external.float_atomic_add;
        info.float64 &= external.float64;
        info.full_subgroups &= external.full_subgroups;
        Self::build(external, info, None)
    }

    /// The rest of a context around a device; on failure, what was made here is
    /// destroyed (an owned device included).
    fn build(
        external: ExternalDevice,
        info: DeviceInfo,
        owned: Option<(&'static Instance, MessageSink)>,
    ) -> Result<Self> {
        let device = external.device.clone();
        let made = (|| -> Result<(Commands, Allocator)> {
            let commands = Commands::new(&device, external.queue_family)?;
            let allocator = Allocator::new(&AllocatorCreateDesc {
                instance: external.instance.clone(),
                device: device.clone(),
                physical_device: external.physical_device,
                debug_settings: Default::default(),
                buffer_device_address: false,
                allocation_sizes: Default::default(),
            });
            match allocator {
                Ok(a) => Ok((commands, a)),
                Err(e) => {
                    // SAFETY: nothing was submitted with these commands.
                    unsafe { commands.destroy(&device) };
                    Err(e.into())
                }
            }
        })();
        let (commands, allocator) = match made {
            Ok(m) => m,
            Err(e) => {
                if owned.is_some() {
                    // SAFETY: the device was made by `new` and nothing else uses it yet.
                    unsafe { device.destroy_device(None) };
                }
                return Err(e);
            }
        };
        // SAFETY: the family and index name a queue the device was created with.
        let queue = unsafe { device.get_device_queue(external.queue_family, external.queue_index) };
        let (owned, messages) = match owned {
            Some((instance, messages)) => {
                let handles = [device.handle().as_raw(), queue.as_raw(), commands.command_buffer().as_raw()];
                instance.own(&messages, handles.to_vec());
                (Some(instance), messages)
            }
            None => (None, MessageSink::default()),
        };
        Ok(Self {
            shared: Arc::new(Shared {
                entry: external.entry,
                instance: external.instance,
                device,
                physical_device: external.physical_device,
                queue,
                queue_family: external.queue_family,
                queue_index: external.queue_index,
                queue_lock: external.queue_lock.unwrap_or_default(),
                commands: ManuallyDrop::new(Mutex::new(commands)),
                allocator: ManuallyDrop::new(Mutex::new(allocator)),
                info,
                owned,
                messages,
            }),
        })
    }

    /// The handles, for handing this context's device to other code (or to `wrap`,
    /// which then shares this context's queue lock).
    pub fn external(&self) -> ExternalDevice {
        let s = &self.shared;
        ExternalDevice {
            entry: s.entry.clone(),
            instance: s.instance.clone(),
            physical_device: s.physical_device,
            device: s.device.clone(),
            queue_family: s.queue_family,
            queue_index: s.queue_index,
            int64_atomics: s.info.int64_atomics,
            float_atomic_add: s.info.float_atomic_add,
            float64: s.info.float64,
            full_subgroups: s.info.full_subgroups,
            queue_lock: Some(s.queue_lock.clone()),
        }
    }

    /// What the device is and can do.
    pub fn info(&self) -> &DeviceInfo {
        &self.shared.info
    }
    /// The logical device.
    pub fn device(&self) -> &ash::Device {
        &self.shared.device
    }

    /// Validation messages collected so far (empty when validation is off, and
    /// on a wrapped device: the host's instance has the host's messenger).
    pub fn validation_messages(&self) -> Vec<String> {
        self.shared.messages.lock().map(|l| l.clone()).unwrap_or_default()
    }

    /// The memory allocator, locked.
    pub(crate) fn allocator(&self) -> Result<MutexGuard<'_, Allocator>> {
        self.shared
            .allocator
            .lock()
            .map_err(|_| Error::invalid("the GPU memory allocator's lock is poisoned"))
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        // SAFETY: the last reference is gone: no buffer, pipeline or submission
        // uses the device; the device is idle before anything is destroyed.
        unsafe {
            // Best effort: a lost device is torn down anyway. A host's device:
            // only fsot's queue, under the queue lock (the host may be using its
            // other queues, which vkDeviceWaitIdle would need to itself).
            if self.owned.is_some() {
                let _ = self.device.device_wait_idle();
            } else {
                let _lock = self.queue_lock.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
                let _ = self.device.queue_wait_idle(self.queue);
            }
            // A panic in a recording poisons the lock; the pool and fence go all the same.
            let commands = self.commands.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            commands.destroy(&self.device);
            drop(commands);
            ManuallyDrop::drop(&mut self.commands);
            ManuallyDrop::drop(&mut self.allocator);
            if self.owned.is_some() {
                self.device.destroy_device(None);
            }
        }
    }
}
