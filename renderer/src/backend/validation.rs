//! The Khronos validation layer's messages, counted.
//!
//! Every warning and error that reaches the debug messenger is counted and kept (the first
//! few in full), so that a test can fail on any of them and a user can see them on stderr.

use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;

use ash::vk;

/// How many messages are kept in full; the count goes on past it.
const KEPT_MESSAGES: usize = 64;

/// Message ids that are reported but not counted. Each entry needs a comment saying why it is
/// harmless. Keep it empty unless a driver or layer bug forces an entry.
const ALLOWED_MESSAGE_IDS: &[&str] = &[];

/// Whether to turn the validation layer on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Validation {
    /// Never load the layer.
    Off,
    /// Load the layer when it is installed; warn on stderr when it is not.
    IfAvailable,
    /// Fail context creation when the layer is not installed (tests).
    Required,
}

impl Validation {
    /// `RRF_VALIDATION=0` turns validation off, `RRF_VALIDATION=required` makes it mandatory;
    /// otherwise it is on when available.
    pub fn from_env() -> Self {
        match std::env::var("RRF_VALIDATION").as_deref() {
            Ok("0") | Ok("off") => Validation::Off,
            Ok("required") => Validation::Required,
            _ => Validation::IfAvailable,
        }
    }
}

/// Messages the validation layer reported, shared with the messenger callback.
#[derive(Default)]
pub struct ValidationLog {
    count: AtomicU32,
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    /// Warnings and errors reported so far.
    pub fn count(&self) -> u32 {
        self.count.load(Ordering::SeqCst)
    }

    /// The first messages reported, in full.
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }

    fn record(&self, severity: vk::DebugUtilsMessageSeverityFlagsEXT, id: &str, text: &str) {
        let level = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) { "error" } else { "warning" };
        let line = format!("vulkan {level}: [{id}] {text}");
        eprintln!("{line}");
        if ALLOWED_MESSAGE_IDS.contains(&id) {
            return;
        }
        self.count.fetch_add(1, Ordering::SeqCst);
        if let Ok(mut messages) = self.messages.lock() {
            if messages.len() < KEPT_MESSAGES {
                messages.push(line);
            }
        }
    }
}

/// Severities the messenger listens to: everything that is counted.
pub(crate) fn messenger_info(log: &ValidationLog) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(on_message))
        .user_data(log as *const ValidationLog as *mut c_void)
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: `user` is the `ValidationLog` that the context keeps alive (boxed, at a fixed
    // address) until after the messenger and the instance are destroyed; `data` is valid for
    // the duration of the call.
    let (log, data) = unsafe { (&*(user as *const ValidationLog), &*data) };
    let text = |p: *const std::ffi::c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: non-null strings from the layer are NUL-terminated.
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    log.record(severity, &text(data.p_message_id_name), &text(data.p_message));
    vk::FALSE
}
