//! The Vulkan instance, device, queue and memory allocator, and their orderly teardown.

use std::ffi::{c_char, CStr};
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use gpu_allocator::AllocatorDebugSettings;

use crate::backend::device_info::DeviceInfo;
use crate::backend::validation::{messenger_info, Validation, ValidationLog};
use crate::error::{Error, Result, VkContext};

/// The Vulkan API version rrf is written against (dynamic rendering is core in 1.3).
pub const API_VERSION: u32 = vk::API_VERSION_1_3;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create a [`Context`].
#[derive(Clone, Debug)]
pub struct ContextOptions {
    pub validation: Validation,
    /// Case-insensitive substring of the device name to use instead of the preferred device.
    pub device: Option<String>,
    /// Extra instance extensions (for example for a window surface).
    pub instance_extensions: Vec<&'static CStr>,
    /// Extra device extensions (for example the swapchain).
    pub device_extensions: Vec<&'static CStr>,
}

impl ContextOptions {
    /// Options from the environment: `RRF_VALIDATION` and `RRF_DEVICE`.
    pub fn from_env() -> Self {
        Self {
            validation: Validation::from_env(),
            device: std::env::var("RRF_DEVICE").ok().filter(|s| !s.is_empty()),
            instance_extensions: Vec::new(),
            device_extensions: Vec::new(),
        }
    }
}

/// What [`Context::finish`] found while tearing down.
#[derive(Debug, Default)]
pub struct TeardownReport {
    /// Validation warnings and errors over the whole life of the context, teardown included.
    pub validation_messages: u32,
    /// Names of GPU allocations that were still alive at teardown.
    pub leaked: Vec<String>,
}

impl TeardownReport {
    pub fn is_clean(&self) -> bool {
        self.validation_messages == 0 && self.leaked.is_empty()
    }
}

/// One Vulkan device with one queue that does graphics, compute and transfer.
pub struct Context {
    entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub info: DeviceInfo,
    debug: Option<Debug>,
    command_pool: vk::CommandPool,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    /// Boxed so that the messenger callback's pointer stays valid when the context moves.
    validation: Box<ValidationLog>,
    torn_down: bool,
    /// Creation steps taken so far, and the one that is to fail (see `fail_at_step`).
    steps: AtomicU32,
    fail_at_step: AtomicU32,
}

struct Debug {
    instance: ash::ext::debug_utils::Instance,
    device: ash::ext::debug_utils::Device,
    messenger: vk::DebugUtilsMessengerEXT,
}

/// What `Context::new` has made so far; dropped, it destroys them, children first, so that a
/// failed creation leaks nothing. [`Partial::keep`] hands them over to the context.
struct Partial {
    instance: ash::Instance,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    device: Option<ash::Device>,
    command_pool: vk::CommandPool,
}

impl Partial {
    /// Keeps everything alive (the context owns it now) and returns the messenger.
    fn keep(self) -> Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)> {
        let mut this = ManuallyDrop::new(self);
        this.messenger.take()
    }
}

impl Drop for Partial {
    fn drop(&mut self) {
        // SAFETY: `Context::new` made each handle and nothing else was created from them; each
        // is destroyed once, children before parents. Null handles are ignored.
        unsafe {
            if let Some(device) = &self.device {
                device.destroy_command_pool(self.command_pool, None);
                device.destroy_device(None);
            }
            if let Some((fns, messenger)) = &self.messenger {
                fns.destroy_debug_utils_messenger(*messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

impl Context {
    pub fn new(options: &ContextOptions) -> Result<Self> {
        // SAFETY: loading the Vulkan loader runs its initialisation code; nothing else is
        // running Vulkan in this process yet.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| Error::LoaderMissing(e.to_string()))?;
        let validation = Box::new(ValidationLog::default());

        // SAFETY: plain enumeration queries on a loaded entry.
        let layers = unsafe { entry.enumerate_instance_layer_properties() }.vk("vkEnumerateInstanceLayerProperties")?;
        let has_layer = layers.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
        let use_validation = match options.validation {
            Validation::Off => false,
            Validation::IfAvailable if !has_layer => {
                eprintln!(
                    "warning: the Vulkan validation layer is not installed, running without it \
                     (Debian/Ubuntu: apt-get install vulkan-validationlayers)"
                );
                false
            }
            Validation::IfAvailable => true,
            Validation::Required if !has_layer => return Err(Error::ValidationLayerMissing),
            Validation::Required => true,
        };

        // SAFETY: plain enumeration queries on a loaded entry.
        let mut available = unsafe { entry.enumerate_instance_extension_properties(None) }
            .vk("vkEnumerateInstanceExtensionProperties")?;
        if use_validation {
            available.extend(
                // SAFETY: as above, for a layer the loader listed.
                unsafe { entry.enumerate_instance_extension_properties(Some(VALIDATION_LAYER)) }
                    .vk("vkEnumerateInstanceExtensionProperties")?,
            );
        }
        let has_debug_utils = available.iter().any(|e| e.extension_name_as_c_str() == Ok(ash::ext::debug_utils::NAME));
        let has_validation_features = use_validation
            && available.iter().any(|e| e.extension_name_as_c_str() == Ok(ash::ext::validation_features::NAME));
        if use_validation && options.validation == Validation::Required && !has_validation_features {
            return Err(Error::ValidationLayerMissing);
        }

        let mut extensions: Vec<*const c_char> = options.instance_extensions.iter().map(|e| e.as_ptr()).collect();
        if has_debug_utils {
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        if has_validation_features {
            extensions.push(ash::ext::validation_features::NAME.as_ptr());
        }
        let layer_names = if use_validation { vec![VALIDATION_LAYER.as_ptr()] } else { vec![] };
        let app = vk::ApplicationInfo::default().application_name(c"rrf").engine_name(c"rrf").api_version(API_VERSION);
        // Chained into instance creation so that messages from vkCreateInstance and
        // vkDestroyInstance are counted too.
        let mut instance_messenger = messenger_info(&validation);
        let mut instance_info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layer_names)
            .enabled_extension_names(&extensions);
        if has_debug_utils {
            instance_info = instance_info.push_next(&mut instance_messenger);
        }
        // Synchronization validation, on top of the core checks: a missing or too weak barrier
        // between passes, or between frames in flight, is reported like any other error.
        let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut validation_features =
            vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
        if has_validation_features {
            instance_info = instance_info.push_next(&mut validation_features);
        }
        // SAFETY: every pointer in the create info outlives the call.
        let instance = unsafe { entry.create_instance(&instance_info, None) }.map_err(|result| match result {
            vk::Result::ERROR_INCOMPATIBLE_DRIVER => Error::NoDevice,
            result => Error::Vulkan { call: "vkCreateInstance", result },
        })?;

        // From here on, an early return destroys what was made (`Partial`'s drop).
        let mut made = Partial { instance, messenger: None, device: None, command_pool: vk::CommandPool::null() };
        let instance = made.instance.clone();
        if has_debug_utils {
            let fns = ash::ext::debug_utils::Instance::new(&entry, &instance);
            // SAFETY: the callback's user data (the boxed log) outlives the messenger.
            let messenger = unsafe { fns.create_debug_utils_messenger(&messenger_info(&validation), None) }
                .vk("vkCreateDebugUtilsMessengerEXT")?;
            made.messenger = Some((fns, messenger));
        }

        let (physical_device, queue_family) = select_device(&instance, options.device.as_deref())?;
        let info = DeviceInfo::query(&instance, physical_device, use_validation);

        let device_extensions: Vec<*const c_char> = options.device_extensions.iter().map(|e| e.as_ptr()).collect();
        let priorities = [1.0];
        let queues =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
        // Dynamic rendering (core in 1.3) replaces render pass objects for the G-buffer pass.
        // Barriers are recorded with vkCmdPipelineBarrier2 (synchronization2, also core in 1.3).
        let mut vulkan13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true).synchronization2(true);
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&device_extensions)
            .push_next(&mut vulkan13);
        // SAFETY: the physical device came from this instance; the create info outlives the call.
        let device = unsafe { instance.create_device(physical_device, &device_info, None) }.vk("vkCreateDevice")?;
        made.device = Some(device.clone());
        // SAFETY: the device was created with one queue of this family.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };

        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: the create info outlives the call.
        let command_pool = unsafe { device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
        made.command_pool = command_pool;

        // Leaks are reported by name in `finish`, not logged by the allocator.
        let mut debug_settings = AllocatorDebugSettings::default();
        debug_settings.log_leaks_on_shutdown = false;
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings,
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|source| Error::Allocation { name: "allocator".into(), bytes: 0, source })?;

        let debug = made.keep().map(|(instance_fns, messenger)| Debug {
            device: ash::ext::debug_utils::Device::new(&instance, &device),
            instance: instance_fns,
            messenger,
        });

        let context = Self {
            entry,
            instance,
            physical_device,
            device,
            queue,
            queue_family,
            info,
            debug,
            command_pool,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            validation,
            torn_down: false,
            steps: AtomicU32::new(0),
            fail_at_step: AtomicU32::new(u32::MAX),
        };
        context.set_name(context.queue, "main queue");
        context.set_name(context.command_pool, "one-shot command pool");
        Ok(context)
    }

    /// The loaded Vulkan entry points (for extensions made outside the context, such as a
    /// window surface).
    pub fn entry(&self) -> &ash::Entry {
        &self.entry
    }

    /// Validation warnings and errors reported so far.
    pub fn validation_messages(&self) -> u32 {
        self.validation.count()
    }

    /// The validation log, for tests that want to print what went wrong.
    pub fn validation_log(&self) -> &ValidationLog {
        &self.validation
    }

    pub(crate) fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        // A panic while holding the lock leaves the allocator itself consistent.
        self.allocator.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Names a Vulkan object so that validation messages and GPU debuggers show it.
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        let Some(debug) = &self.debug else { return };
        let Ok(name) = std::ffi::CString::new(name) else { return };
        let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
        // SAFETY: the handle belongs to this device. Naming is best effort.
        let _ = unsafe { debug.device.set_debug_utils_object_name(&info) };
    }

    /// Counts a creation step that can fail, and fails it if it is the one `fail_at_step`
    /// names.
    pub(crate) fn step(&self, call: &'static str) -> Result<()> {
        let step = self.steps.fetch_add(1, Ordering::SeqCst);
        if self.fail_at_step.load(Ordering::SeqCst) == step {
            return Err(Error::Vulkan { call, result: vk::Result::ERROR_OUT_OF_DEVICE_MEMORY });
        }
        Ok(())
    }

    /// For tests of error paths: makes creation step `step` fail with
    /// `VK_ERROR_OUT_OF_DEVICE_MEMORY`, as a real allocation failure would. Steps are counted
    /// from 0 over the context's life ([`Context::steps_taken`]): buffers, images, pipelines,
    /// one-shot submissions, frame slots. `None` turns the injection off.
    pub fn fail_at_step(&self, step: Option<u32>) {
        self.fail_at_step.store(step.unwrap_or(u32::MAX), Ordering::SeqCst);
    }

    /// Creation steps taken so far.
    pub fn steps_taken(&self) -> u32 {
        self.steps.load(Ordering::SeqCst)
    }

    /// Opens a named region of `cmd` that validation messages and GPU debuggers show.
    pub fn begin_label(&self, cmd: vk::CommandBuffer, name: &str) {
        let Some(debug) = &self.debug else { return };
        let Ok(name) = std::ffi::CString::new(name) else { return };
        // SAFETY: `cmd` is recording; the label is closed by `end_label`.
        unsafe { debug.device.cmd_begin_debug_utils_label(cmd, &vk::DebugUtilsLabelEXT::default().label_name(&name)) };
    }

    /// Closes the region `begin_label` opened.
    pub fn end_label(&self, cmd: vk::CommandBuffer) {
        if let Some(debug) = &self.debug {
            // SAFETY: pairs with a `begin_label` on the same command buffer.
            unsafe { debug.device.cmd_end_debug_utils_label(cmd) };
        }
    }

    /// Records commands with `record`, submits them and waits for them to finish.
    pub fn submit_once<R>(&self, record: impl FnOnce(vk::CommandBuffer) -> R) -> Result<R> {
        self.step("vkQueueSubmit")?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool belongs to this device and is used from one thread at a time.
        let cmd = unsafe { self.device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?[0];
        let result = (|| {
            let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            // SAFETY: `cmd` is a fresh primary command buffer of this device.
            unsafe { self.device.begin_command_buffer(cmd, &begin) }.vk("vkBeginCommandBuffer")?;
            let value = record(cmd);
            // SAFETY: `cmd` is recording, and `record` left no render pass or query open.
            unsafe { self.device.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;
            // SAFETY: a plain fence of this device.
            let fence =
                unsafe { self.device.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
            let cmds = [cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            // SAFETY: the queue is used from one thread at a time; `cmd` is executable and
            // the fence unsignalled.
            let waited = unsafe { self.device.queue_submit(self.queue, &submit, fence) }
                .vk("vkQueueSubmit")
                // SAFETY: the fence was just submitted with the work.
                .and_then(|()| unsafe { self.device.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences"));
            // SAFETY: the fence's work finished, or was never submitted.
            unsafe { self.device.destroy_fence(fence, None) };
            waited.map(|()| value)
        })();
        // SAFETY: the buffer's work finished (the fence was waited for) or never started; a
        // failed wait is a lost device, where freeing is still allowed.
        unsafe { self.device.free_command_buffers(self.command_pool, &[cmd]) };
        result
    }

    /// Tears everything down in order and reports what was left alive and what the validation
    /// layer said over the context's whole life.
    pub fn finish(mut self) -> TeardownReport {
        self.teardown()
    }

    fn teardown(&mut self) -> TeardownReport {
        if self.torn_down {
            return TeardownReport::default();
        }
        self.torn_down = true;
        // SAFETY: this is the last use of the device; every handle destroyed here was created
        // by this context and is destroyed exactly once, children before parents.
        unsafe {
            let _ = self.device.device_wait_idle();
            let leaked = self.allocator().generate_report().allocations.into_iter().map(|a| a.name).collect();
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_command_pool(self.command_pool, None);
            self.device.destroy_device(None);
            if let Some(debug) = self.debug.take() {
                debug.instance.destroy_debug_utils_messenger(debug.messenger, None);
            }
            self.instance.destroy_instance(None);
            TeardownReport { validation_messages: self.validation.count(), leaked }
        }
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        let report = self.teardown();
        for name in &report.leaked {
            eprintln!("error: GPU resource {name:?} was still alive when the Vulkan context was destroyed");
        }
    }
}

/// Picks the device: the one whose name contains `wanted`, or else the preferred kind
/// (discrete, then integrated, virtual, CPU). Returns it with its universal queue family.
fn select_device(instance: &ash::Instance, wanted: Option<&str>) -> Result<(vk::PhysicalDevice, u32)> {
    // SAFETY: enumeration and property queries on a live instance.
    let devices = unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    if devices.is_empty() {
        return Err(Error::NoDevice);
    }
    let named: Vec<(vk::PhysicalDevice, vk::PhysicalDeviceProperties)> =
        // SAFETY: a property query on a device the instance listed.
        devices.iter().map(|&d| (d, unsafe { instance.get_physical_device_properties(d) })).collect();
    let name_of = |p: &vk::PhysicalDeviceProperties| {
        p.device_name_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
    };

    let candidates: Vec<_> = match wanted {
        Some(wanted) => {
            let lower = wanted.to_lowercase();
            let matching: Vec<_> =
                named.iter().filter(|(_, p)| name_of(p).to_lowercase().contains(&lower)).cloned().collect();
            if matching.is_empty() {
                let available = named.iter().map(|(_, p)| format!("{:?}", name_of(p))).collect::<Vec<_>>().join(", ");
                return Err(Error::DeviceNotFound { wanted: wanted.to_string(), available });
            }
            matching
        }
        None => named,
    };
    let rank = |t: vk::PhysicalDeviceType| match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    };
    let mut rejected = Vec::new();
    let mut usable: Vec<_> = candidates
        .into_iter()
        .filter_map(|(device, props)| match universal_queue(instance, device, &props) {
            Ok(family) => Some((rank(props.device_type), device, family)),
            Err(reason) => {
                rejected.push(Error::UnsuitableDevice { device: name_of(&props), reason });
                None
            }
        })
        .collect();
    usable.sort_by_key(|(rank, _, _)| *rank);
    match usable.first() {
        Some(&(_, device, family)) => Ok((device, family)),
        None => Err(rejected.into_iter().next().unwrap_or(Error::NoDevice)),
    }
}

fn universal_queue(
    instance: &ash::Instance,
    device: vk::PhysicalDevice,
    props: &vk::PhysicalDeviceProperties,
) -> std::result::Result<u32, String> {
    if props.api_version < API_VERSION {
        return Err(format!(
            "it supports Vulkan {}.{}, rrf needs 1.3",
            vk::api_version_major(props.api_version),
            vk::api_version_minor(props.api_version)
        ));
    }
    // SAFETY: property query on a device of this instance.
    let families = unsafe { instance.get_physical_device_queue_family_properties(device) };
    let wanted = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    families
        .iter()
        .position(|f| f.queue_flags.contains(wanted))
        .map(|i| i as u32)
        .ok_or_else(|| "it has no queue family with both graphics and compute".to_string())
}
