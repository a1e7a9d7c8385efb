//! Instance, validation collector, device choice and the [`Gpu`] handle.

use crate::error::{Error, Result, VkContext};
use ash::{ext, khr, vk};
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_void, CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, PoisonError};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create a [`Gpu`].
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Enable `VK_LAYER_KHRONOS_validation` and collect its messages in [`Gpu::validation`].
    pub validation: bool,
    /// Pick the first device whose name contains this (case-insensitive). `None`: the `BOUNCE_DEVICE`
    /// environment variable, else the first discrete GPU, else integrated, else any (lavapipe).
    pub device: Option<String>,
    /// Extra instance extensions (the window system's surface extensions, for presenting).
    pub instance_extensions: Vec<&'static CStr>,
    /// Enable VK_KHR_swapchain (required then: a device without it is not picked).
    pub swapchain: bool,
}

/// Validation messages of one device (warnings and errors), in arrival order.
#[derive(Debug, Default)]
pub struct ValidationLog {
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().unwrap_or_else(PoisonError::into_inner).clone()
    }
    pub fn count(&self) -> usize {
        self.messages.lock().unwrap_or_else(PoisonError::into_inner).len()
    }
    pub fn clear(&self) {
        self.messages.lock().unwrap_or_else(PoisonError::into_inner).clear();
    }
    fn push(&self, m: String) {
        self.messages.lock().unwrap_or_else(PoisonError::into_inner).push(m);
    }
}

/// VUIDs we deliberately do not count, each with the reason. Empty: bounce is validation-clean.
const SUPPRESSED_VUIDS: &[&str] = &[];

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // Only the validation layer's warnings and errors count; the loader's general chatter does not.
    let counted = severity
        .intersects(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        && types
            .intersects(vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE);
    if !counted || data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    // SAFETY: `data` is non-null (checked above), and the Vulkan spec keeps the callback data and every
    // string it points to valid for the duration of this call; the reference does not outlive the call.
    let data = unsafe { &*data };
    let text = |p: *const std::ffi::c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: `p` is non-null (checked) and is one of the callback data's NUL-terminated strings,
            // valid until the callback returns; it is copied into an owned `String` before that.
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    let id = text(data.p_message_id_name);
    if SUPPRESSED_VUIDS.contains(&id.as_str()) {
        return vk::FALSE;
    }
    // SAFETY: `user` is non-null (checked) and is the `Arc::as_ptr` of the `ValidationLog` that
    // `create_messenger` registered; `Shared` keeps that `Arc` (its `validation` field) alive until after
    // `Shared::drop` has destroyed the messenger, so the log is alive whenever the layer can call back.
    // The log is `Sync` (a `Mutex` inside), so callbacks from several threads at once are fine.
    let log = unsafe { &*(user as *const ValidationLog) };
    log.push(format!("[{severity:?}] {id}: {}", text(data.p_message)));
    vk::FALSE
}

/// What `bounce info` prints about a device.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    pub api_version: String,
    pub driver: String,
    pub limits: Vec<(&'static str, String)>,
    pub features: Vec<(&'static str, bool)>,
    pub suitable: std::result::Result<(), String>,
}

pub struct Shared {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub properties: vk::PhysicalDeviceProperties,
    pub name: String,
    pub timestamp_valid_bits: u32,
    /// The subgroup operations compute shaders may use (empty where compute shaders have none).
    pub compute_subgroup_ops: vk::SubgroupFeatureFlags,
    /// Loop iterations one shader invocation may run before the driver cuts its loops short, where the
    /// driver has such a limit ([`crate::workarounds`]). Passes whose invocations loop long split their
    /// work so that each dispatch stays under it.
    pub loop_iteration_limit: Option<u32>,
    /// Whether a timestamp takes its time only when a later command flushes the driver's queue
    /// ([`crate::workarounds`]): [`crate::TimestampPool`] then writes a second one right after it.
    pub timestamp_needs_flush: bool,
    pub push_descriptor: khr::push_descriptor::Device,
    pub debug_utils: Option<ext::debug_utils::Device>,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    pub(crate) command_pool: Mutex<vk::CommandPool>,
    messenger: Option<(ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    validation: Arc<ValidationLog>,
    /// Copies to host memory made so far (`Buffer::read_back`, `Image::read_back`): how the viewer's
    /// tests see that a presented frame reads nothing back.
    readbacks: std::sync::atomic::AtomicU64,
}

/// The device handle: cheap to clone, shared by every resource made from it.
#[derive(Clone)]
pub struct Gpu(Arc<Shared>);

impl std::ops::Deref for Gpu {
    type Target = Shared;
    fn deref(&self) -> &Shared {
        &self.0
    }
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Gpu({})", self.name)
    }
}

fn load_entry() -> Result<ash::Entry> {
    // SAFETY: loading libvulkan runs the system Vulkan loader's initialisation code, which bounce has to
    // trust to use Vulkan at all. The returned `Entry` keeps the library loaded while any clone lives, and
    // `Shared::entry` is dropped only after `Shared::drop` has destroyed the instance.
    unsafe { ash::Entry::load() }.map_err(|e| Error::Loader(e.to_string()))
}

fn device_name(p: &vk::PhysicalDeviceProperties) -> String {
    p.device_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default()
}

fn version_string(v: u32) -> String {
    format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v))
}

/// Device features bounce needs, with the reason for each (for the error message).
fn check_suitable(instance: &ash::Instance, pd: vk::PhysicalDevice) -> std::result::Result<(), String> {
    // SAFETY: `instance` is alive and `pd` was enumerated from it (both callers pass handles from
    // `instance.enumerate_physical_devices()`).
    let props = unsafe { instance.get_physical_device_properties(pd) };
    if props.api_version < vk::API_VERSION_1_3 {
        return Err(format!("Vulkan 1.3 (it has {})", version_string(props.api_version)));
    }
    // SAFETY: as above: `pd` belongs to the live `instance`.
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    let has = |n: &CStr| exts.iter().any(|e| e.extension_name_as_c_str() == Ok(n));
    if !has(khr::push_descriptor::NAME) {
        return Err("the extension VK_KHR_push_descriptor".into());
    }
    let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut v13).push_next(&mut v12);
    // SAFETY: `pd` belongs to the live `instance` (1.3, so vkGetPhysicalDeviceFeatures2 is core); the pNext
    // chain points at `v13` and `v12`, locals that outlive the call (ash's `push_next` borrows them).
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let f = f2.features;
    for (ok, what) in [
        (v12.shader_buffer_int64_atomics, "the feature shaderBufferInt64Atomics"),
        (f.shader_int64, "the feature shaderInt64"),
        (v13.dynamic_rendering, "the feature dynamicRendering"),
        (v13.synchronization2, "the feature synchronization2"),
        // SPIR-V 1.6 (Vulkan 1.3 target) compiles GLSL `discard` to OpDemoteToHelperInvocation.
        (v13.shader_demote_to_helper_invocation, "the feature shaderDemoteToHelperInvocation"),
        (v13.maintenance4, "the feature maintenance4"),
        (f.geometry_shader, "the feature geometryShader"),
        (f.fragment_stores_and_atomics, "the feature fragmentStoresAndAtomics"),
        (f.vertex_pipeline_stores_and_atomics, "the feature vertexPipelineStoresAndAtomics"),
    ] {
        if ok == vk::FALSE {
            return Err(what.into());
        }
    }
    // SAFETY: `pd` belongs to the live `instance`.
    let qf = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    if !qf.iter().any(|q| q.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)) {
        return Err("a queue with graphics and compute".into());
    }
    Ok(())
}

fn create_instance(
    entry: &ash::Entry,
    validation: bool,
    extra_exts: &[*const std::ffi::c_char],
) -> Result<ash::Instance> {
    let app = vk::ApplicationInfo::default()
        .application_name(c"bounce")
        .engine_name(c"bounce")
        .api_version(vk::API_VERSION_1_3);
    let mut layers = vec![];
    let mut exts: Vec<*const std::ffi::c_char> = extra_exts.to_vec();
    if validation {
        // SAFETY: a global command: it needs only the loaded loader in `entry`.
        let available =
            unsafe { entry.enumerate_instance_layer_properties() }.vk("vkEnumerateInstanceLayerProperties")?;
        if !available.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER)) {
            return Err(Error::NoValidationLayer);
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        // Synchronization validation checks every barrier the graph derives (lavapipe runs commands in
        // order, so a missing barrier could not fail a test otherwise). It needs the layer's
        // VK_EXT_validation_features; a layer without it is too old for bounce's tests.
        // SAFETY: a global command on the loaded loader; the layer name is a 'static NUL-terminated string.
        let layer_exts = unsafe { entry.enumerate_instance_extension_properties(Some(VALIDATION_LAYER)) }
            .vk("vkEnumerateInstanceExtensionProperties")?;
        if !layer_exts.iter().any(|e| e.extension_name_as_c_str() == Ok(ext::validation_features::NAME)) {
            return Err(Error::NoValidationLayer);
        }
        exts.push(ext::validation_features::NAME.as_ptr());
    }
    // SAFETY: a global command: it needs only the loaded loader in `entry`.
    let has_debug_utils = unsafe { entry.enumerate_instance_extension_properties(None) }
        .unwrap_or_default()
        .iter()
        .any(|e| e.extension_name_as_c_str() == Ok(ext::debug_utils::NAME));
    if has_debug_utils {
        exts.push(ext::debug_utils::NAME.as_ptr());
    }
    let enabled = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&exts);
    if validation {
        info = info.push_next(&mut features);
    }
    // SAFETY: every pointer reachable from `info` (application info, layer and extension name arrays, the
    // validation-features chain) points at locals of this function or at 'static C strings (`extra_exts`
    // comes from `GpuOptions::instance_extensions`, `&'static CStr`), all alive across the call. The caller
    // owns the returned instance and destroys it (`Shared::drop`, or its error path).
    unsafe { entry.create_instance(&info, None) }.map_err(|result| match result {
        vk::Result::ERROR_INCOMPATIBLE_DRIVER => Error::NoDevice(" (vkCreateInstance: incompatible driver)".into()),
        result => Error::Vk { call: "vkCreateInstance", result },
    })
}

/// The validation messenger: warnings and errors go to `log` (through the user-data pointer).
fn create_messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
    log: &Arc<ValidationLog>,
) -> Result<(ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)> {
    let du = ext::debug_utils::Instance::new(entry, instance);
    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback))
        .user_data(Arc::as_ptr(log) as *mut c_void);
    // SAFETY: `du` was loaded from the live `instance`; `debug_callback` has the PFN's signature and only
    // dereferences `user` as `ValidationLog`, which the caller keeps alive (in `Shared`) until the messenger
    // is destroyed, which happens before the instance (`Shared::drop`, or `with_instance`'s error path).
    let m = unsafe { du.create_debug_utils_messenger(&info, None) }.vk("vkCreateDebugUtilsMessengerEXT")?;
    Ok((du, m))
}

/// The chosen physical device and what bounce reads of it.
struct Picked {
    physical: vk::PhysicalDevice,
    properties: vk::PhysicalDeviceProperties,
    queue_family: u32,
    timestamp_valid_bits: u32,
    compute_subgroup_ops: vk::SubgroupFeatureFlags,
    loop_iteration_limit: Option<u32>,
    timestamp_needs_flush: bool,
}

/// The device `opts` (or `BOUNCE_DEVICE`) names, else the most suitable one: discrete, integrated,
/// virtual, then CPU; a device that lacks what bounce needs is an error naming what is missing.
fn pick_device(instance: &ash::Instance, opts: &GpuOptions) -> Result<Picked> {
    // SAFETY: `instance` is a live instance (the caller destroys it only after this returns).
    let pds = unsafe { instance.enumerate_physical_devices() }.unwrap_or_default();
    if pds.is_empty() {
        return Err(Error::NoDevice(String::new()));
    }
    let wanted = opts.device.clone().or_else(|| std::env::var("BOUNCE_DEVICE").ok()).filter(|s| !s.is_empty());
    let named: Vec<(vk::PhysicalDevice, vk::PhysicalDeviceProperties)> = pds
        .iter()
        .map(|&pd| {
            // SAFETY: `pd` was just enumerated from the live `instance`.
            let p = unsafe { instance.get_physical_device_properties(pd) };
            (pd, p)
        })
        .collect();
    let (physical, properties) = if let Some(w) = &wanted {
        let wl = w.to_lowercase();
        *named.iter().find(|(_, p)| device_name(p).to_lowercase().contains(&wl)).ok_or_else(|| {
            Error::NoMatchingDevice {
                wanted: w.clone(),
                available: named.iter().map(|(_, p)| device_name(p)).collect::<Vec<_>>().join(", "),
            }
        })?
    } else {
        let rank = |t: vk::PhysicalDeviceType| match t {
            vk::PhysicalDeviceType::DISCRETE_GPU => 0,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
            vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
            vk::PhysicalDeviceType::CPU => 3,
            _ => 4,
        };
        // Prefer suitable devices, then by kind.
        let mut c = named.clone();
        c.sort_by_key(|(pd, p)| (check_suitable(instance, *pd).is_err(), rank(p.device_type)));
        c[0]
    };
    if let Err(what) = check_suitable(instance, physical) {
        return Err(Error::MissingFeature {
            device: device_name(&properties),
            what,
            hint: "; update the driver (for lavapipe: `mesa-vulkan-drivers` from Debian 12 or newer)".into(),
        });
    }
    // SAFETY: `physical` is one of the handles enumerated from the live `instance` above.
    let qfs = unsafe { instance.get_physical_device_queue_family_properties(physical) };
    let queue_family = qfs
        .iter()
        .position(|q| q.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
        .expect("check_suitable found a graphics+compute queue") as u32;
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
    // SAFETY: `physical` belongs to the live `instance` and supports 1.3 (`check_suitable` passed), so
    // VkPhysicalDeviceDriverProperties (1.2) is known to it; the chain points at the local `driver`.
    unsafe { instance.get_physical_device_properties2(physical, &mut p2) };
    Ok(Picked {
        physical,
        properties,
        queue_family,
        timestamp_valid_bits: qfs[queue_family as usize].timestamp_valid_bits,
        compute_subgroup_ops: compute_subgroup_ops(instance, physical),
        loop_iteration_limit: crate::workarounds::loop_iteration_limit(driver.driver_id),
        timestamp_needs_flush: crate::workarounds::timestamp_needs_flush(driver.driver_id),
    })
}

/// The subgroup operations of compute shaders on `pd` (Vulkan 1.1's subgroup properties).
fn compute_subgroup_ops(instance: &ash::Instance, pd: vk::PhysicalDevice) -> vk::SubgroupFeatureFlags {
    let mut sub = vk::PhysicalDeviceSubgroupProperties::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut sub);
    // SAFETY: `pd` was enumerated from the live `instance` (1.3 API, so the call is core); the chain points
    // at the local `sub`, and a driver skips chained structures it does not know (spec, "Valid Usage for
    // Structure Pointer Chains"), so this is also fine for `Gpu::enumerate`'s pre-1.1 devices.
    unsafe { instance.get_physical_device_properties2(pd, &mut p2) };
    if sub.supported_stages.contains(vk::ShaderStageFlags::COMPUTE) {
        sub.supported_operations
    } else {
        vk::SubgroupFeatureFlags::empty()
    }
}

/// The logical device with the features and extensions bounce uses (and the swapchain's if asked).
fn create_device(instance: &ash::Instance, picked: &Picked, opts: &GpuOptions) -> Result<ash::Device> {
    let prio = [1.0f32];
    let qinfo = [vk::DeviceQueueCreateInfo::default().queue_family_index(picked.queue_family).queue_priorities(&prio)];
    let mut dev_exts = vec![khr::push_descriptor::NAME.as_ptr()];
    if opts.swapchain {
        // SAFETY: `picked.physical` was enumerated from the live `instance`.
        let exts = unsafe { instance.enumerate_device_extension_properties(picked.physical) }.unwrap_or_default();
        if !exts.iter().any(|e| e.extension_name_as_c_str() == Ok(khr::swapchain::NAME)) {
            return Err(Error::MissingFeature {
                device: device_name(&picked.properties),
                what: "the extension VK_KHR_swapchain (presenting to a window)".into(),
                hint: String::new(),
            });
        }
        dev_exts.push(khr::swapchain::NAME.as_ptr());
    }
    let mut v13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(true)
        .synchronization2(true)
        .shader_demote_to_helper_invocation(true)
        // Relaxed interface matching: spirv-opt removes fragment inputs a shader never reads (the
        // depth-only dprsm fragment shader), which is legal with maintenance4 (mandatory in 1.3).
        .maintenance4(true);
    // u64 atomics: the gbg importance sums fixed-point contributions (order-independent results).
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default().shader_buffer_int64_atomics(true);
    let base = vk::PhysicalDeviceFeatures::default()
        .shader_int64(true)
        .geometry_shader(true)
        .fragment_stores_and_atomics(true)
        .vertex_pipeline_stores_and_atomics(true);
    let mut f2 = vk::PhysicalDeviceFeatures2::default().features(base).push_next(&mut v13).push_next(&mut v12);
    let dinfo = vk::DeviceCreateInfo::default()
        .queue_create_infos(&qinfo)
        .enabled_extension_names(&dev_exts)
        .push_next(&mut f2);
    // SAFETY: `picked.physical` belongs to the live `instance`; `dinfo` and its chain (`qinfo` with `prio`,
    // the 'static extension names, `f2` → `v13` → `v12`) are locals alive across the call. The queue family
    // exists on this device (`pick_device`); every enabled feature and VK_KHR_push_descriptor were checked by
    // `check_suitable`, VK_KHR_swapchain just above. The caller destroys the device before the instance.
    unsafe { instance.create_device(picked.physical, &dinfo, None) }
        .map_err(|result| Error::Vk { call: "vkCreateDevice", result })
}

impl Gpu {
    /// Every device the loader sees, with what bounce needs and whether each has it.
    pub fn enumerate() -> Result<Vec<DeviceInfo>> {
        let entry = load_entry()?;
        let instance = create_instance(&entry, false, &[])?;
        // SAFETY: `instance` was just created and is destroyed only at the end of this function.
        let pds = unsafe { instance.enumerate_physical_devices() }.unwrap_or_default();
        let mut out = vec![];
        for pd in pds {
            // SAFETY: `pd` was enumerated from the live `instance`.
            let p = unsafe { instance.get_physical_device_properties(pd) };
            let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
            let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut v13);
            // SAFETY: `pd` belongs to the live 1.3 `instance`; the chain points at the local `v13`, which a
            // pre-1.3 driver skips (unknown chained structures are ignored, per the spec).
            unsafe { instance.get_physical_device_features2(pd, &mut f2) };
            let f = f2.features;
            let l = p.limits;
            // SAFETY: `pd` was enumerated from the live `instance`.
            let qf = unsafe { instance.get_physical_device_queue_family_properties(pd) };
            let ts_bits = qf.first().map(|q| q.timestamp_valid_bits).unwrap_or(0);
            out.push(DeviceInfo {
                name: device_name(&p),
                kind: p.device_type,
                api_version: version_string(p.api_version),
                driver: format!("{:#x}", p.driver_version),
                limits: vec![
                    ("maxImageDimension2D", l.max_image_dimension2_d.to_string()),
                    ("maxImageArrayLayers", l.max_image_array_layers.to_string()),
                    ("maxStorageBufferRange", l.max_storage_buffer_range.to_string()),
                    ("maxComputeWorkGroupInvocations", l.max_compute_work_group_invocations.to_string()),
                    ("maxComputeWorkGroupCount", format!("{:?}", l.max_compute_work_group_count)),
                    ("maxPushConstantsSize", l.max_push_constants_size.to_string()),
                    ("timestampPeriod (ns)", l.timestamp_period.to_string()),
                    ("timestampValidBits (queue 0)", ts_bits.to_string()),
                    ("maxComputeSharedMemorySize", l.max_compute_shared_memory_size.to_string()),
                    ("subgroup operations in compute shaders", format!("{:?}", compute_subgroup_ops(&instance, pd))),
                ],
                features: vec![
                    ("dynamicRendering", v13.dynamic_rendering != 0),
                    ("synchronization2", v13.synchronization2 != 0),
                    ("geometryShader", f.geometry_shader != 0),
                    ("fragmentStoresAndAtomics", f.fragment_stores_and_atomics != 0),
                    ("vertexPipelineStoresAndAtomics", f.vertex_pipeline_stores_and_atomics != 0),
                    ("shaderFloat64", f.shader_float64 != 0),
                    ("shaderInt64", f.shader_int64 != 0),
                ],
                suitable: check_suitable(&instance, pd),
            });
        }
        // SAFETY: this instance has no child objects (no device or messenger was created from it; physical
        // devices are not created objects) and is not used after this line.
        unsafe { instance.destroy_instance(None) };
        Ok(out)
    }

    pub fn new(opts: &GpuOptions) -> Result<Gpu> {
        let entry = load_entry()?;
        let exts: Vec<*const std::ffi::c_char> = opts.instance_extensions.iter().map(|e| e.as_ptr()).collect();
        let instance = create_instance(&entry, opts.validation, &exts)?;
        // From here on, a failure must destroy what exists: wrap the rest.
        // `entry` outlives the instance: dropping the last Entry unloads the Vulkan loader.
        match Self::with_instance(entry.clone(), instance.clone(), opts) {
            Ok(g) => Ok(g),
            Err(e) => {
                // SAFETY: `with_instance` failed, and each of its error paths destroys what it created from
                // the instance (device, messenger) before returning; nothing else holds this instance, and
                // `entry` (the loader) is still alive here.
                unsafe { instance.destroy_instance(None) };
                Err(e)
            }
        }
    }

    fn with_instance(entry: ash::Entry, instance: ash::Instance, opts: &GpuOptions) -> Result<Gpu> {
        let validation = Arc::new(ValidationLog::default());
        // SAFETY: a global command: it needs only the loaded loader in `entry`.
        let has_debug_utils = unsafe { entry.enumerate_instance_extension_properties(None) }
            .unwrap_or_default()
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(ext::debug_utils::NAME));
        let messenger = match opts.validation && has_debug_utils {
            true => Some(create_messenger(&entry, &instance, &validation)?),
            false => None,
        };
        // From here on, a failure must destroy the messenger too.
        let made = pick_device(&instance, opts).and_then(|picked| {
            let device = create_device(&instance, &picked, opts)?;
            let parts = (entry, instance.clone(), device, picked, validation);
            Self::with_device(parts, has_debug_utils, messenger.clone())
        });
        if made.is_err() {
            if let Some((du, m)) = &messenger {
                // SAFETY: `m` was created from `instance` by `create_messenger` and nothing else will destroy
                // it: `made` is an error, so no `Shared` took the copy handed to `with_device`; the device made
                // on this path (if any) was already destroyed. NOTE: by now the `ValidationLog` that `m`'s user
                // data points at has been dropped (the `validation` Arc moved into the closure above and went
                // with it), so this relies on no callback firing during the destroy call itself.
                unsafe { du.destroy_debug_utils_messenger(*m, None) };
            }
        }
        made
    }

    /// The allocator, the command pool and the handle, around a created device.
    fn with_device(
        (entry, instance, device, picked, validation): (
            ash::Entry,
            ash::Instance,
            ash::Device,
            Picked,
            Arc<ValidationLog>,
        ),
        has_debug_utils: bool,
        messenger: Option<(ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    ) -> Result<Gpu> {
        let fail = |e: Error| {
            // SAFETY: `device` was created by the caller and no `Gpu` owns it yet; every path that calls
            // `fail` has destroyed the device's children first (the allocator is dropped before it), and the
            // device is not used after `fail` returns.
            unsafe { device.destroy_device(None) };
            e
        };
        // SAFETY: `create_device` asked for exactly one queue (index 0) of `picked.queue_family`.
        let queue = unsafe { device.get_device_queue(picked.queue_family, 0) };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: picked.physical,
            debug_settings: {
                let mut d = gpu_allocator::AllocatorDebugSettings::default();
                d.log_leaks_on_shutdown = cfg!(debug_assertions);
                d
            },
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|source| fail(Error::Alloc { name: "allocator".into(), source }))?;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(picked.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER | vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: `device` is alive; the queue family is the one the device was created with. The pool is
        // destroyed in `Shared::drop` (before the device) or is never made here.
        let command_pool = match unsafe { device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool") {
            Ok(p) => p,
            Err(e) => {
                drop(allocator);
                return Err(fail(e));
            }
        };
        let push_descriptor = khr::push_descriptor::Device::new(&instance, &device);
        let debug_utils = has_debug_utils.then(|| ext::debug_utils::Device::new(&instance, &device));
        Ok(Gpu(Arc::new(Shared {
            entry,
            instance,
            physical: picked.physical,
            device,
            queue,
            queue_family: picked.queue_family,
            name: device_name(&picked.properties),
            properties: picked.properties,
            timestamp_valid_bits: picked.timestamp_valid_bits,
            compute_subgroup_ops: picked.compute_subgroup_ops,
            loop_iteration_limit: picked.loop_iteration_limit,
            timestamp_needs_flush: picked.timestamp_needs_flush,
            push_descriptor,
            debug_utils,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            command_pool: Mutex::new(command_pool),
            messenger,
            validation,
            readbacks: Default::default(),
        })))
    }

    /// How many copies to host memory ([`crate::Buffer::read_back`], [`crate::Image::read_back`]) this
    /// device has made.
    pub fn readbacks(&self) -> u64 {
        self.0.readbacks.load(std::sync::atomic::Ordering::Relaxed)
    }

    pub(crate) fn count_readback(&self) {
        self.0.readbacks.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }

    /// This device's validation messages (empty unless created with `validation: true`).
    pub fn validation(&self) -> &ValidationLog {
        &self.0.validation
    }

    pub fn validation_enabled(&self) -> bool {
        self.0.messenger.is_some()
    }

    pub fn limits(&self) -> &vk::PhysicalDeviceLimits {
        &self.properties.limits
    }

    /// Give a Vulkan object a name that shows in validation messages and RenderDoc.
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(du) = &self.debug_utils {
            let Ok(c) = CString::new(name) else { return };
            let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&c);
            // A failed name is cosmetic; ignore it.
            // SAFETY: `du` was loaded for `self.device`, and `info` borrows `c`, alive across the call.
            // Caller contract (not checked): `handle` is an object of this device that no other thread is
            // using (vkSetDebugUtilsObjectNameEXT synchronises it externally); bounce names only handles it
            // has just created and not yet shared.
            let _ = unsafe { du.set_debug_utils_object_name(&info) };
        }
    }

    /// Open a debug-utils label region on `cmd` (no-op without debug utils).
    pub fn begin_label(&self, cmd: vk::CommandBuffer, name: &str) {
        if let Some(du) = &self.debug_utils {
            let c = CString::new(name).unwrap_or_default();
            let label = vk::DebugUtilsLabelEXT::default().label_name(&c);
            // SAFETY: `label` borrows `c` across the call. Caller contract (not checked): `cmd` is the command
            // buffer `Gpu::submit` passed to its closure, so it is in the recording state and its pool is
            // locked by this thread for the whole recording.
            unsafe { du.cmd_begin_debug_utils_label(cmd, &label) };
        }
    }

    pub fn end_label(&self, cmd: vk::CommandBuffer) {
        if let Some(du) = &self.debug_utils {
            // SAFETY: caller contract, as in `begin_label`: `cmd` is `Gpu::submit`'s command buffer, recording
            // under the pool lock, with a label region opened by `begin_label` still open.
            unsafe { du.cmd_end_debug_utils_label(cmd) };
        }
    }

    pub fn wait_idle(&self) -> Result<()> {
        // SAFETY: `self.device` is alive while `self` is. NOTE: vkDeviceWaitIdle also requires host access
        // to the device's queue to be externally synchronised; that holds only while no other thread is in
        // `submit`/`submit_synced` or presenting on a clone of this `Gpu` (not enforced: no lock is taken).
        unsafe { self.device.device_wait_idle() }.vk("vkDeviceWaitIdle")?;
        Ok(())
    }

    pub(crate) fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        // SAFETY: the last `Gpu` is gone, so no other thread can touch the queue (vkDeviceWaitIdle's external
        // synchronisation), and every resource that held a clone has already been destroyed.
        let _ = unsafe { self.device.device_wait_idle() };
        let pool = *self.command_pool.get_mut().unwrap_or_else(PoisonError::into_inner);
        // SAFETY: the device is idle, so no command buffer of the pool is pending; the pool belongs to
        // `self.device` and nothing can lock it any more (`&mut self`).
        unsafe { self.device.destroy_command_pool(pool, None) };
        // SAFETY: this is the only place the allocator is dropped and the field is not touched afterwards.
        // It frees its memory blocks through `self.device`, still alive here; every allocation was already
        // returned by the `Buffer`/`Image` drops (each of which held a `Gpu`).
        unsafe { ManuallyDrop::drop(&mut self.allocator) };
        // SAFETY: every child of the device is gone: resources (they held `Gpu` clones), the command pool and
        // the allocator's memory above; the device is idle and not used after this.
        unsafe { self.device.destroy_device(None) };
        if let Some((du, m)) = self.messenger.take() {
            // SAFETY: `m` was created from `self.instance`, which is still alive, and its user data
            // (`self.validation`) is alive too: fields are dropped only after this body.
            unsafe { du.destroy_debug_utils_messenger(m, None) };
        }
        // SAFETY: the instance's children (device, messenger) were destroyed above; `self.entry`, which keeps
        // the loader loaded, is dropped only after this body.
        unsafe { self.instance.destroy_instance(None) };
    }
}
