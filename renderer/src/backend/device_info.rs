//! What `rrf info` reports about the Vulkan device: identity, driver and the limits that
//! bound the renderer (image size, storage buffer range for network weights, workgroups,
//! push constants, timestamps for `rrf bench`).

use ash::vk;
use serde::Serialize;

#[derive(Clone, Debug, Serialize)]
pub struct DeviceInfo {
    pub name: String,
    pub device_type: String,
    pub vendor_id: u32,
    pub device_id: u32,
    pub api_version: String,
    pub driver_name: String,
    pub driver_info: String,
    pub validation: bool,
    pub limits: Limits,
}

#[derive(Clone, Debug, Serialize)]
pub struct Limits {
    pub max_image_dimension_2d: u32,
    pub max_storage_buffer_range: u32,
    pub max_uniform_buffer_range: u32,
    pub max_push_constants_size: u32,
    pub max_compute_shared_memory_size: u32,
    pub max_compute_work_group_invocations: u32,
    pub max_compute_work_group_size: [u32; 3],
    pub max_compute_work_group_count: [u32; 3],
    pub max_color_attachments: u32,
    pub subgroup_size: u32,
    /// Nanoseconds per timestamp tick; `None` when the queue cannot write timestamps.
    pub timestamp_period_ns: Option<f32>,
}

impl DeviceInfo {
    pub(crate) fn query(instance: &ash::Instance, device: vk::PhysicalDevice, validation: bool) -> Self {
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver).push_next(&mut subgroup);
        // SAFETY: property query on a device of this instance (Vulkan 1.2 core).
        unsafe { instance.get_physical_device_properties2(device, &mut props2) };
        let p = props2.properties;
        let l = p.limits;
        let text = |r: Result<&std::ffi::CStr, _>| r.map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let device_type = match p.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
            vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
            vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
            vk::PhysicalDeviceType::CPU => "CPU",
            _ => "other",
        };
        Self {
            name: text(p.device_name_as_c_str()),
            device_type: device_type.to_string(),
            vendor_id: p.vendor_id,
            device_id: p.device_id,
            api_version: format!(
                "{}.{}.{}",
                vk::api_version_major(p.api_version),
                vk::api_version_minor(p.api_version),
                vk::api_version_patch(p.api_version)
            ),
            driver_name: text(driver.driver_name_as_c_str()),
            driver_info: text(driver.driver_info_as_c_str()),
            validation,
            limits: Limits {
                max_image_dimension_2d: l.max_image_dimension2_d,
                max_storage_buffer_range: l.max_storage_buffer_range,
                max_uniform_buffer_range: l.max_uniform_buffer_range,
                max_push_constants_size: l.max_push_constants_size,
                max_compute_shared_memory_size: l.max_compute_shared_memory_size,
                max_compute_work_group_invocations: l.max_compute_work_group_invocations,
                max_compute_work_group_size: l.max_compute_work_group_size,
                max_compute_work_group_count: l.max_compute_work_group_count,
                max_color_attachments: l.max_color_attachments,
                subgroup_size: subgroup.subgroup_size,
                timestamp_period_ns: (l.timestamp_compute_and_graphics == vk::TRUE).then_some(l.timestamp_period),
            },
        }
    }
}

impl std::fmt::Display for DeviceInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let l = &self.limits;
        writeln!(f, "device      {} ({})", self.name, self.device_type)?;
        writeln!(f, "driver      {} {}", self.driver_name, self.driver_info)?;
        writeln!(f, "Vulkan      {}", self.api_version)?;
        writeln!(f, "validation  {}", if self.validation { "on" } else { "off" })?;
        writeln!(f, "limits")?;
        writeln!(f, "  max image 2D              {}", l.max_image_dimension_2d)?;
        writeln!(f, "  max storage buffer range  {} MiB", l.max_storage_buffer_range >> 20)?;
        writeln!(f, "  max uniform buffer range  {} KiB", l.max_uniform_buffer_range >> 10)?;
        writeln!(f, "  max push constants        {} B", l.max_push_constants_size)?;
        writeln!(f, "  compute shared memory     {} KiB", l.max_compute_shared_memory_size >> 10)?;
        writeln!(
            f,
            "  compute workgroup         {} invocations, size {:?}",
            l.max_compute_work_group_invocations, l.max_compute_work_group_size
        )?;
        writeln!(f, "  subgroup size             {}", l.subgroup_size)?;
        match l.timestamp_period_ns {
            Some(ns) => write!(f, "  timestamps                {ns} ns per tick"),
            None => write!(f, "  timestamps                not supported"),
        }
    }
}
