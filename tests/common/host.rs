//! A host application's own Vulkan objects, made with `ash` the way a renderer
//! makes them (not through fsot): its instance with the validation layer and its
//! own messenger, a device with one compute queue and the lock around it, images
//! and buffers with their memory, and its own submissions and read-backs. Tests
//! hand these to fsot (`Context::wrap`) and check what fsot did to them.

use std::ffi::c_void;
use std::sync::{Arc, Mutex};

use ash::vk;
use fsot::vk::{Context, ExternalDevice, ImageTarget};

/// The messenger's callback: warnings and errors into the host's list.
unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes a valid callback data pointer whose message is a C string.
    let text = unsafe { data.as_ref() }
        .and_then(|d| unsafe { d.message_as_c_str() })
        .map(|m| m.to_string_lossy().into_owned())
        .unwrap_or_default();
    if severity.intersects(
        vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
    ) {
        // SAFETY: `user` is the host's boxed list, alive until the messenger is destroyed.
        let list = unsafe { &*(user as *const Mutex<Vec<String>>) };
        list.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).push(text);
    }
    vk::FALSE
}

/// The host: its instance, device, queue and the lock around its queue.
pub struct Host {
    /// What the validation layer told the host's messenger.
    messages: Box<Mutex<Vec<String>>>,
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    debug: ash::ext::debug_utils::Instance,
    messenger: vk::DebugUtilsMessengerEXT,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub family: u32,
    pub queue: vk::Queue,
    pub lock: Arc<Mutex<()>>,
    int64_atomics: bool,
}

impl Host {
    /// A host whose device has 64-bit buffer atomics on (the Vulkan optimizer
    /// needs them) or not; fails without Vulkan, as every GPU test does.
    pub fn new(int64_atomics: bool) -> Self {
        drop(super::gpu_context()); // the same requirement as every GPU test
                                    // SAFETY: loading the system's Vulkan loader.
        let entry = unsafe { ash::Entry::load() }.expect("a Vulkan loader");
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_2);
        let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        let extensions = [ash::ext::debug_utils::NAME.as_ptr()];
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        // SAFETY: the create info and its arrays live through the call.
        let instance = unsafe { entry.create_instance(&info, None) }.expect("an instance with validation");
        let debug = ash::ext::debug_utils::Instance::new(&entry, &instance);
        let messages: Box<Mutex<Vec<String>>> = Box::default();
        let messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(on_message))
            .user_data(&*messages as *const Mutex<Vec<String>> as *mut c_void);
        // SAFETY: the callback is a plain function valid for the program's life.
        let messenger = unsafe { debug.create_debug_utils_messenger(&messenger_info, None) }.unwrap();
        // SAFETY: plain queries on a live instance.
        let physical = unsafe { instance.enumerate_physical_devices() }.unwrap()[0];
        // SAFETY: as above.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let family =
            families.iter().position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE)).unwrap() as u32;
        let priorities = [1.0f32];
        let queues =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
        let features = vk::PhysicalDeviceFeatures::default().shader_int64(int64_atomics);
        let mut features12 =
            vk::PhysicalDeviceVulkan12Features::default().shader_buffer_int64_atomics(int64_atomics);
        let create = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_features(&features)
            .push_next(&mut features12);
        // SAFETY: the create info and what it points to live through the call.
        let device = unsafe { instance.create_device(physical, &create, None) }.unwrap();
        // SAFETY: the queue was created with the device.
        let queue = unsafe { device.get_device_queue(family, 0) };
        let lock = Arc::new(Mutex::new(()));
        Self {
            messages,
            entry,
            instance,
            debug,
            messenger,
            physical,
            device,
            family,
            queue,
            lock,
            int64_atomics,
        }
    }

    /// fsot's context on the host's device, sharing its queue lock.
    pub fn fsot(&self) -> Context {
        // SAFETY: the host's live device, made with the features it claims; each
        // test drops its fsot contexts before the host.
        unsafe { Context::wrap(self.external()) }.unwrap()
    }

    /// What the host hands fsot: its device, queue and queue lock.
    #[allow(dead_code)] // not every test binary wraps by hand
    pub fn external(&self) -> ExternalDevice {
        ExternalDevice {
            entry: self.entry.clone(),
            instance: self.instance.clone(),
            physical_device: self.physical,
            device: self.device.clone(),
            queue_family: self.family,
            queue_index: 0,
            int64_atomics: self.int64_atomics,
            float_atomic_add: false,
            float64: false,
            full_subgroups: false,
            queue_lock: Some(self.lock.clone()),
        }
    }

    fn memory_type(&self, bits: u32, flags: vk::MemoryPropertyFlags) -> u32 {
        // SAFETY: a plain query.
        let props = unsafe { self.instance.get_physical_device_memory_properties(self.physical) };
        (0..props.memory_type_count)
            .find(|&i| bits & (1 << i) != 0 && props.memory_types[i as usize].property_flags.contains(flags))
            .expect("a memory type")
    }

    fn bind_memory(
        &self,
        requirements: vk::MemoryRequirements,
        flags: vk::MemoryPropertyFlags,
    ) -> vk::DeviceMemory {
        let info = vk::MemoryAllocateInfo::default()
            .allocation_size(requirements.size)
            .memory_type_index(self.memory_type(requirements.memory_type_bits, flags));
        // SAFETY: a valid allocate info.
        unsafe { self.device.allocate_memory(&info, None) }.unwrap()
    }

    /// The host's own 2-D array image with its memory.
    pub fn image(
        &self,
        format: vk::Format,
        w: u32,
        h: u32,
        layers: u32,
        usage: vk::ImageUsageFlags,
    ) -> HostImage {
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: w, height: h, depth: 1 })
            .mip_levels(1)
            .array_layers(layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: a valid create info on a live device.
        let image = unsafe { self.device.create_image(&info, None) }.unwrap();
        // SAFETY: the image was just made.
        let memory = self.bind_memory(
            unsafe { self.device.get_image_memory_requirements(image) },
            vk::MemoryPropertyFlags::DEVICE_LOCAL,
        );
        // SAFETY: fresh memory of the image's requirements.
        unsafe { self.device.bind_image_memory(image, memory, 0) }.unwrap();
        let target = ImageTarget {
            image,
            format,
            width: w,
            height: h,
            layers,
            usage,
            layout_before: vk::ImageLayout::UNDEFINED,
            layout_after: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        };
        HostImage { target, memory }
    }

    /// A host-visible buffer of the host's.
    pub fn buffer(&self, size: u64, usage: vk::BufferUsageFlags) -> (vk::Buffer, vk::DeviceMemory) {
        let info = vk::BufferCreateInfo::default().size(size).usage(usage);
        // SAFETY: a valid create info.
        let buffer = unsafe { self.device.create_buffer(&info, None) }.unwrap();
        // SAFETY: the buffer was just made.
        let memory = self.bind_memory(
            unsafe { self.device.get_buffer_memory_requirements(buffer) },
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT,
        );
        // SAFETY: fresh memory of the buffer's requirements.
        unsafe { self.device.bind_buffer_memory(buffer, memory, 0) }.unwrap();
        (buffer, memory)
    }

    pub fn read_memory(&self, memory: vk::DeviceMemory, bytes: usize) -> Vec<u8> {
        // SAFETY: host-visible, coherent memory no submission is writing now.
        unsafe {
            let at = self.device.map_memory(memory, 0, bytes as u64, vk::MemoryMapFlags::empty()).unwrap();
            let out = std::slice::from_raw_parts(at as *const u8, bytes).to_vec();
            self.device.unmap_memory(memory);
            out
        }
    }

    /// Records `record` and submits it on the host's queue under its lock; waits.
    pub fn run(&self, record: impl FnOnce(vk::CommandBuffer)) {
        let d = &self.device;
        // SAFETY: objects made and destroyed here; the queue is used under the lock.
        unsafe {
            let pool = d
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default().queue_family_index(self.family),
                    None,
                )
                .unwrap();
            let alloc = vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1);
            let cmd = d.allocate_command_buffers(&alloc).unwrap()[0];
            d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).unwrap();
            record(cmd);
            d.end_command_buffer(cmd).unwrap();
            let fence = d.create_fence(&vk::FenceCreateInfo::default(), None).unwrap();
            let cmds = [cmd];
            {
                let _queue = self.lock.lock().unwrap();
                d.queue_submit(self.queue, &[vk::SubmitInfo::default().command_buffers(&cmds)], fence)
                    .unwrap();
            }
            d.wait_for_fences(&[fence], true, u64::MAX).unwrap();
            d.destroy_fence(fence, None);
            d.destroy_command_pool(pool, None);
        }
    }

    /// The image's bytes, read back with the host's own copy from
    /// SHADER_READ_ONLY_OPTIMAL (where fsot left it).
    pub fn read_image(&self, image: &HostImage, texel_bytes: usize) -> Vec<u8> {
        let t = &image.target;
        let bytes = t.width as usize * t.height as usize * t.layers as usize * texel_bytes;
        let (buffer, memory) = self.buffer(bytes as u64, vk::BufferUsageFlags::TRANSFER_DST);
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(t.layers);
        self.run(|cmd| {
            let to_src = vk::ImageMemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::SHADER_READ)
                .dst_access_mask(vk::AccessFlags::TRANSFER_READ)
                .old_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
                .new_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(t.image)
                .subresource_range(range);
            let region = vk::BufferImageCopy::default()
                .image_subresource(
                    vk::ImageSubresourceLayers::default()
                        .aspect_mask(vk::ImageAspectFlags::COLOR)
                        .layer_count(t.layers),
                )
                .image_extent(vk::Extent3D { width: t.width, height: t.height, depth: 1 });
            let to_host = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ);
            // SAFETY: `cmd` is being recorded; the image and buffer are alive.
            unsafe {
                self.device.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::DependencyFlags::empty(),
                    &[],
                    &[],
                    &[to_src],
                );
                self.device.cmd_copy_image_to_buffer(
                    cmd,
                    t.image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    buffer,
                    &[region],
                );
                self.device.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::HOST,
                    vk::DependencyFlags::empty(),
                    &[to_host],
                    &[],
                    &[],
                );
            }
        });
        let out = self.read_memory(memory, bytes);
        self.free_buffer(buffer, memory);
        out
    }

    pub fn free_buffer(&self, buffer: vk::Buffer, memory: vk::DeviceMemory) {
        // SAFETY: no submission uses them (every one was waited for).
        unsafe {
            self.device.destroy_buffer(buffer, None);
            self.device.free_memory(memory, None);
        }
    }

    pub fn free_image(&self, image: HostImage) {
        // SAFETY: as above.
        unsafe {
            self.device.destroy_image(image.target.image, None);
            self.device.free_memory(image.memory, None);
        }
    }

    /// Fails the test if the validation layer told the host's messenger anything.
    pub fn assert_silent(&self) {
        let messages = self.messages.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).clone();
        assert!(messages.is_empty(), "validation: {}", messages.join("\n"));
    }
}

impl Drop for Host {
    fn drop(&mut self) {
        // SAFETY: fsot's contexts are gone and nothing is pending; the host
        // destroys what it made (fsot never does).
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_device(None);
            self.debug.destroy_debug_utils_messenger(self.messenger, None);
            self.instance.destroy_instance(None);
        }
    }
}

/// An image of the host's with its memory, and what fsot is told of it.
pub struct HostImage {
    pub target: ImageTarget,
    pub memory: vk::DeviceMemory,
}
