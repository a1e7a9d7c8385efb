//! GPU timestamp queries. Respects the queue's `timestampValidBits`: with 0 bits the pool is disabled
//! and reports no times; otherwise results are masked to the valid bits before subtracting.

use crate::error::{Result, VkContext};
use crate::gpu::Gpu;
use ash::vk;

pub struct TimestampPool {
    pool: vk::QueryPool,
    capacity: u32,
    used: u32,
    gpu: Gpu,
}

impl TimestampPool {
    /// A pool for `capacity` timestamps (twice as many queries where each needs a flushing second one).
    pub fn new(gpu: &Gpu, capacity: u32) -> Result<Self> {
        let capacity = if gpu.timestamp_needs_flush { 2 * capacity } else { capacity };
        let pool = if gpu.timestamp_valid_bits == 0 || capacity == 0 {
            vk::QueryPool::null()
        } else {
            let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(capacity);
            // SAFETY: `gpu.device` is alive; `capacity` > 0 here. The pool keeps a `Gpu` clone and destroys the
            // query pool in `Drop`, before the device can go.
            unsafe { gpu.device.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?
        };
        Ok(TimestampPool { pool, capacity, used: 0, gpu: gpu.clone() })
    }

    pub fn enabled(&self) -> bool {
        self.pool != vk::QueryPool::null()
    }

    /// Reset every query; record before the first [`TimestampPool::write`] of a submission.
    pub fn reset(&mut self, cmd: vk::CommandBuffer) {
        self.used = 0;
        if self.enabled() {
            // SAFETY: `self.pool` is a live pool of this device and 0..capacity is its whole range. Caller
            // contract (not checked): `cmd` is `Gpu::submit`'s command buffer, recording under its pool lock,
            // outside a rendering instance.
            unsafe { self.gpu.device.cmd_reset_query_pool(cmd, self.pool, 0, self.capacity) };
        }
    }

    /// Write a timestamp after all earlier work; returns its index, or `None` when disabled or full.
    pub fn write(&mut self, cmd: vk::CommandBuffer) -> Option<u32> {
        if !self.enabled() || self.used >= self.capacity {
            return None;
        }
        let q = self.used;
        self.used += 1;
        // SAFETY: `q` < `capacity` (checked above), so the query exists in the live `self.pool`;
        // synchronization2 is enabled by `create_device`. Caller contract (not checked): `cmd` is recording
        // (as for `reset`) and `reset` was recorded before this write.
        unsafe { self.gpu.device.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, q) };
        if self.gpu.timestamp_needs_flush && self.used < self.capacity {
            // A second timestamp, never read, whose write flushes the driver's queue, so that `q` takes its
            // time now, before the next pass runs (crate::workarounds).
            // SAFETY: as above, for query `self.used` < `capacity`.
            unsafe {
                self.gpu.device.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, self.used)
            };
            self.used += 1;
        }
        Some(q)
    }

    /// Raw tick values of the queries written so far (call after the submission's fence).
    pub fn ticks(&self) -> Result<Vec<u64>> {
        if !self.enabled() || self.used == 0 {
            return Ok(vec![]);
        }
        let mut out = vec![0u64; self.used as usize];
        // SAFETY: `self.pool` is alive and queries 0..used exist (`used` <= `capacity`); `out` holds `used`
        // u64s, matching TYPE_64 and the stride ash passes (size_of::<u64>). Caller contract: called after
        // the fence of the submission that wrote them, else WAIT may block (a hang, not memory unsafety).
        unsafe {
            self.gpu.device.get_query_pool_results(
                self.pool,
                0,
                &mut out,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        Ok(out)
    }

    /// Milliseconds between two queries, with wrap-around inside the valid bits handled.
    pub fn elapsed_ms(&self, ticks: &[u64], begin: u32, end: u32) -> f64 {
        let bits = self.gpu.timestamp_valid_bits;
        let mask = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        let (a, b) = (ticks[begin as usize] & mask, ticks[end as usize] & mask);
        let delta = b.wrapping_sub(a) & mask;
        delta as f64 * self.gpu.limits().timestamp_period as f64 * 1e-6
    }
}

impl Drop for TimestampPool {
    fn drop(&mut self) {
        if self.enabled() {
            // SAFETY: the pool was created from `self.gpu.device`, which this `Gpu` clone keeps alive; no
            // pending command buffer uses it, since every submission waits for its fence before returning.
            unsafe { self.gpu.device.destroy_query_pool(self.pool, None) };
        }
    }
}
