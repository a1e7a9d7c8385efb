//! `bounce info`: every Vulkan device, whether bounce can use it (and what it lacks if not), and the
//! features and limits bounce depends on, on stdout.

use crate::error;
use anyhow::Result;
use bounce_device::Gpu;
use std::io::Write;

pub fn run(out: &mut dyn Write) -> Result<()> {
    let devices = Gpu::enumerate().map_err(error::device)?;
    if devices.is_empty() {
        return Err(error::device(bounce_device::Error::NoDevice(String::new())));
    }
    for d in devices {
        writeln!(out, "{} ({:?}), Vulkan {}, driver {}", d.name, d.kind, d.api_version, d.driver)?;
        match &d.suitable {
            Ok(()) => writeln!(out, "  usable by bounce: yes")?,
            Err(what) => writeln!(out, "  usable by bounce: no (lacks {what})")?,
        }
        for (k, v) in &d.features {
            writeln!(out, "  feature {k}: {v}")?;
        }
        for (k, v) in &d.limits {
            writeln!(out, "  limit {k}: {v}")?;
        }
    }
    Ok(())
}
