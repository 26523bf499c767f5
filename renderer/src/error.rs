use ash::vk;

/// Everything that can go wrong in the renderer, worded for the person who has to fix it.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(
        "cannot load the Vulkan loader (libvulkan.so.1): {0}\n\
         On Debian or Ubuntu install it with a CPU driver:\n    \
         sudo apt-get install libvulkan1 mesa-vulkan-drivers"
    )]
    LoaderMissing(String),

    #[error(
        "no Vulkan device found.\n\
         Install a driver; for the CPU driver lavapipe on Debian or Ubuntu:\n    \
         sudo apt-get install mesa-vulkan-drivers"
    )]
    NoDevice,

    #[error("no Vulkan device name contains RRF_DEVICE={wanted:?}; available devices: {available}")]
    DeviceNotFound { wanted: String, available: String },

    #[error("Vulkan device {device:?} is unsuitable: {reason}")]
    UnsuitableDevice { device: String, reason: String },

    #[error(
        "the Khronos validation layer (VK_LAYER_KHRONOS_validation) is required but missing.\n\
         On Debian or Ubuntu: sudo apt-get install vulkan-validationlayers"
    )]
    ValidationLayerMissing,

    #[error("Vulkan call {call} failed: {result}")]
    Vulkan { call: &'static str, result: vk::Result },

    #[error("GPU memory allocation of {:.1} MiB for {name:?} failed: {source}", *bytes as f64 / 1048576.0)]
    Allocation {
        name: String,
        bytes: u64,
        #[source]
        source: gpu_allocator::AllocationError,
    },

    #[error("{0}")]
    Invalid(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Attaches the name of the Vulkan entry point to a raw `vk::Result`.
pub(crate) trait VkContext<T> {
    fn vk(self, call: &'static str) -> Result<T>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> Result<T> {
        self.map_err(|result| Error::Vulkan { call, result })
    }
}
