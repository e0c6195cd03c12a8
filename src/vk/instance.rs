//! The Vulkan instance fsot makes its own devices on (`Context::new`): one per
//! process for each validation setting, made on first use and kept until the
//! process ends; each context makes and destroys only its device. Drivers have
//! failed when a process creates and destroys many instances (NVIDIA's has been
//! seen to give wrong `SubgroupLocalInvocationId` after about eleven cycles, and
//! to fail device creation after about ten), and a test binary or a host that
//! makes several contexts would do exactly that.
//!
//! With validation, the layer's messages go to the contexts that listen
//! (`Instance::listen`, from before a context makes its device): a message goes
//! to the contexts whose device, queue or command buffer it names, and one that
//! names none of them (objects of no context's, or only non-dispatchable ones)
//! to every live context of the instance.

use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex, Weak};

use ash::vk;

use super::check;
use super::error::{Error, Result};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Where a context's validation messages go.
pub(crate) type MessageSink = Arc<Mutex<Vec<String>>>;

/// A context listening for the messages that name its handles.
struct Listener {
    /// Raw dispatchable handles: the device, its queue, the command buffer.
    handles: Vec<u64>,
    sink: Weak<Mutex<Vec<String>>>,
}

/// An instance made by fsot; with validation, its debug messenger (made once,
/// never destroyed, like the instance) writes to the listeners.
pub(crate) struct Instance {
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    listeners: Mutex<Vec<Listener>>,
}

/// The process's instances, without and with validation.
static SHARED: Mutex<[Option<&'static Instance>; 2]> = Mutex::new([None, None]);

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if user.is_null() || data.is_null() {
        return vk::FALSE;
    }
    // SAFETY: the layer passes valid callback data for the duration of the call.
    let data = unsafe { &*data };
    // SAFETY: as above; the message is a C string or null.
    let text =
        unsafe { data.message_as_c_str() }.map(|m| m.to_string_lossy().into_owned()).unwrap_or_default();
    let named: Vec<u64> = if data.p_objects.is_null() {
        Vec::new()
    } else {
        // SAFETY: `p_objects` points to `object_count` entries for the call's duration.
        unsafe { std::slice::from_raw_parts(data.p_objects, data.object_count as usize) }
            .iter()
            .map(|o| o.object_handle)
            .collect()
    };
    // SAFETY: `user` is the listeners of a leaked, never dropped `Instance`.
    let listeners = unsafe { &*(user as *const Mutex<Vec<Listener>>) };
    let Ok(listeners) = listeners.lock() else { return vk::FALSE };
    let live: Vec<(&Listener, MessageSink)> =
        listeners.iter().filter_map(|l| l.sink.upgrade().map(|s| (l, s))).collect();
    let named_by = |l: &Listener| l.handles.iter().any(|h| named.contains(h));
    let owners = live.iter().filter(|(l, _)| named_by(l)).count();
    let line = format!("{severity:?}: {text}");
    for (_, sink) in live.iter().filter(|(l, _)| owners == 0 || named_by(l)) {
        if let Ok(mut list) = sink.lock() {
            list.push(line.clone());
        }
    }
    vk::FALSE
}

impl Instance {
    /// The process's Vulkan 1.2 instance, with VK_LAYER_KHRONOS_validation when
    /// `validation` (an error if missing), made on the first call.
    pub fn shared(validation: bool) -> Result<&'static Self> {
        let mut made = SHARED.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some(instance) = made[validation as usize] {
            return Ok(instance);
        }
        let instance = Self::make(validation)?;
        made[validation as usize] = Some(instance);
        Ok(instance)
    }

    /// Sends the validation messages that name no listener's handles to `sink`
    /// while it lives, and once `own` gives it its handles, those that name them.
    pub fn listen(&self, sink: &MessageSink) {
        let mut listeners = self.listeners.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        listeners.retain(|l| l.sink.strong_count() > 0);
        listeners.push(Listener { handles: Vec::new(), sink: Arc::downgrade(sink) });
    }

    /// Gives `sink`'s listener its context's raw dispatchable handles.
    pub fn own(&self, sink: &MessageSink, handles: Vec<u64>) {
        let mut listeners = self.listeners.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some(l) = listeners.iter_mut().find(|l| std::ptr::eq(l.sink.as_ptr(), Arc::as_ptr(sink))) {
            l.handles = handles;
        }
    }

    fn make(validation: bool) -> Result<&'static Self> {
        // SAFETY: loads the system's Vulkan loader; its functions are only called through ash.
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| Error::VulkanUnavailable(format!("no Vulkan loader ({e})")))?;
        let mut layers: Vec<*const i8> = Vec::new();
        let mut extensions: Vec<*const i8> = Vec::new();
        if validation {
            // SAFETY: a plain query on a loaded entry.
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
        let app = vk::ApplicationInfo::default()
            .application_name(c"fsot")
            .api_version(super::requirements::API_VERSION);
        let create = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        // SAFETY: the create info and the names it points to live until the call returns.
        let raw = check("vkCreateInstance", unsafe { entry.create_instance(&create, None) })?;
        // Kept for the process's life: nothing destroys it.
        let me: &'static Self = Box::leak(Box::new(Self { entry, raw, listeners: Mutex::new(Vec::new()) }));
        if validation {
            let loader = ash::ext::debug_utils::Instance::new(&me.entry, &me.raw);
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
                .user_data(&me.listeners as *const Mutex<Vec<Listener>> as *mut c_void);
            // SAFETY: the listeners live as long as the leaked instance, as does the messenger.
            let made = unsafe { loader.create_debug_utils_messenger(&info, None) };
            if let Err(result) = made {
                // SAFETY: nothing was made from the instance; it is not shared yet.
                unsafe { me.raw.destroy_instance(None) };
                return Err(Error::Vulkan { call: "vkCreateDebugUtilsMessengerEXT", result });
            }
        }
        Ok(me)
    }
}
