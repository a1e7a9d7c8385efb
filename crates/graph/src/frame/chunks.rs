//! Chunked submission: a frame whose work is too long for one submission (the VPL tiles of `all`, the
//! sample batches of `reference`) runs as consecutive chunks of `[0, total)`, each its own graph,
//! submission and wait, with a progress report between them. The chunks of one frame add into the same
//! temporal radiance image, and each chunk after the first finds the frame's static products kept by
//! the graph, so it records only the gather (or the reference).

use crate::graph::{Executed, PassTiming};
use anyhow::Result;
use std::ops::Range;

/// Call `run(chunk, is_last)` for consecutive chunks of at most `per_chunk` units covering
/// `0..total`, and `progress(done, total)` after each.
pub fn for_each_chunk(
    total: u32,
    per_chunk: u32,
    progress: &mut dyn FnMut(u64, u64),
    mut run: impl FnMut(Range<u32>, bool) -> Result<()>,
) -> Result<()> {
    let per_chunk = per_chunk.max(1);
    let mut first = 0u32;
    loop {
        let last = first.saturating_add(per_chunk).min(total);
        run(first..last, last >= total)?;
        progress(last as u64, total as u64);
        first = last;
        if first >= total {
            return Ok(());
        }
    }
}

/// What a frame's chunks report together: every recorded pass with its time, the passes the first
/// chunk culled, and warnings.
#[derive(Default)]
pub struct FrameLog {
    pub timings: Vec<PassTiming>,
    pub ran: Vec<&'static str>,
    pub skipped: Vec<&'static str>,
    pub warnings: Vec<String>,
    chunks: usize,
}

impl FrameLog {
    pub fn add(&mut self, done: &Executed) {
        self.timings.extend(done.timings.iter().cloned());
        self.ran.extend(done.ran.iter().copied());
        if self.chunks == 0 {
            self.skipped = done.skipped.clone();
        }
        self.chunks += 1;
    }
}
