//! The Vulkan instance, with the validation layer and its messages when asked.

use std::ffi::{c_void, CStr};
use std::sync::Mutex;

use ash::vk;

use super::check;
use super::error::{Error, Result};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Where the validation layer's messages go; boxed so its address is stable for
/// the callback.
pub(crate) type MessageSink = Box<Mutex<Vec<String>>>;

/// An instance made by fsot, with its debug messenger when validating.
pub(crate) struct Instance {
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    pub debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if !user.is_null() && !data.is_null() {
        // SAFETY: the layer passes valid callback data for the duration of the call.
        let text = unsafe { (*data).message_as_c_str() }
            .map(|m| m.to_string_lossy().into_owned())
            .unwrap_or_default();
        // SAFETY: `user` is the MessageSink of the context, which outlives the messenger.
        let sink = unsafe { &*(user as *const Mutex<Vec<String>>) };
        if let Ok(mut list) = sink.lock() {
            list.push(format!("{severity:?}: {text}"));
        }
    }
    vk::FALSE
}

impl Instance {
    /// A Vulkan 1.2 instance; with `validation`, VK_LAYER_KHRONOS_validation (an
    /// error if missing) reporting warnings and errors into `sink`.
    pub fn new(validation: bool, sink: &MessageSink) -> Result<Self> {
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
        let mut me = Self { entry, raw, debug: None };
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
                .user_data(&**sink as *const Mutex<Vec<String>> as *mut c_void);
            // SAFETY: the sink outlives the messenger (both owned by the context, messenger destroyed first).
            let messenger = check("vkCreateDebugUtilsMessengerEXT", unsafe {
                loader.create_debug_utils_messenger(&info, None)
            })?;
            me.debug = Some((loader, messenger));
        }
        Ok(me)
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: every object made from the instance is gone (the context drops its device first).
        unsafe {
            if let Some((loader, m)) = &self.debug {
                loader.destroy_debug_utils_messenger(*m, None);
            }
            self.raw.destroy_instance(None);
        }
    }
}
