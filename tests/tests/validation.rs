//! The validation collector itself: it must catch a deliberately invalid call, on the device that made
//! it and no other.

use bounce_device::{vk, Gpu, GpuOptions};

#[test]
fn collector_catches_an_invalid_call_per_device() {
    let bad = Gpu::new(&GpuOptions { validation: true, ..GpuOptions::default() }).expect("device");
    let clean = Gpu::new(&GpuOptions { validation: true, ..GpuOptions::default() }).expect("device");
    // VUID-VkBufferCreateInfo-size-00912: a buffer's size must be greater than 0.
    let info = vk::BufferCreateInfo::default().size(0).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
    if let Ok(b) = unsafe { bad.device.create_buffer(&info, None) } {
        unsafe { bad.device.destroy_buffer(b, None) };
    }
    let msgs = bad.validation().messages();
    assert!(!msgs.is_empty(), "the invalid vkCreateBuffer was not reported");
    assert!(msgs.iter().any(|m| m.contains("00912")), "unexpected messages: {msgs:?}");
    assert_eq!(clean.validation().count(), 0, "messages leaked to another device: {:?}", clean.validation().messages());
}

#[test]
fn a_device_without_validation_collects_nothing() {
    let g = Gpu::new(&GpuOptions::default()).expect("device");
    assert!(!g.validation_enabled());
    assert_eq!(g.validation().count(), 0);
}

#[test]
fn an_unknown_device_name_is_a_clear_error() {
    let e = Gpu::new(&GpuOptions { device: Some("no-such-device-xyz".into()), ..GpuOptions::default() }).unwrap_err();
    let m = e.to_string();
    assert!(m.contains("no-such-device-xyz") && m.contains("available"), "{m}");
}

/// Synchronization validation is on wherever validation is (tests, `--validation`): two writes of one
/// buffer with no barrier between them are reported as a hazard. (Lavapipe runs commands in order, so
/// without it a missing barrier could never fail a test.)
#[test]
fn synchronization_validation_catches_a_missing_barrier() {
    let gpu = Gpu::new(&GpuOptions { validation: true, ..GpuOptions::default() }).expect("device");
    let b = bounce_device::Buffer::new(&gpu, &bounce_device::BufferDesc::storage("hazard", 256)).expect("buffer");
    gpu.submit(|cmd| unsafe {
        gpu.device.cmd_fill_buffer(cmd, b.raw, 0, vk::WHOLE_SIZE, 1);
        gpu.device.cmd_fill_buffer(cmd, b.raw, 0, vk::WHOLE_SIZE, 2);
    })
    .expect("submit");
    let msgs = gpu.validation().messages();
    assert!(msgs.iter().any(|m| m.contains("WRITE_AFTER_WRITE")), "no hazard reported: {msgs:?}");
}
