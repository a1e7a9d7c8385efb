//! What the graph keeps across frames ([`Retained`]): cached products by name and key, temporal
//! resources by name, and the histories' use by frame.

use super::Res;
use bounce_device::sync::Access;
use std::collections::HashMap;

/// A kept resource and its last access.
pub(super) struct Kept {
    pub(super) res: Res,
    pub(super) last: Access,
}

/// The products of one [`Graph::cached`] name: the key they were made under and their resources, in
/// [`Products::handles`] order.
pub(super) struct Product {
    pub(super) key: u64,
    pub(super) resources: Vec<Kept>,
}

/// A temporal resource: what it was made for (description and key) and the resource.
pub(super) struct TemporalSlot {
    pub(super) fingerprint: u64,
    pub(super) kept: Kept,
}

/// What the graph keeps across frames: cached products by name and temporal resources by name. Owned by
/// whoever renders frames (the `Renderer`'s frame state) and lent to each graph.
#[derive(Default)]
pub struct Retained {
    pub(super) products: HashMap<&'static str, Product>,
    pub(super) temporal: HashMap<String, TemporalSlot>,
    /// Per history name: how many frames have used it (its two slots swap at each), and the last frame
    /// that did.
    pub(super) histories: HashMap<String, (u64, u64)>,
    pub(super) frame: u64,
}

impl Retained {
    /// Forget everything kept: the next graph records every pass it needs.
    pub fn clear(&mut self) {
        self.products.clear();
        self.temporal.clear();
        self.histories.clear();
    }
    /// Forget every history ([`Graph::history_image`], [`Graph::history_buffer`]): the next frame that uses
    /// one starts it anew. For a view changed by frames that kept none (their motion is not the histories').
    pub fn forget_histories(&mut self) {
        for name in std::mem::take(&mut self.histories).into_keys() {
            (0..2).for_each(|k| _ = self.temporal.remove(&format!("{name}#{k}")));
        }
    }
    /// Whether the current frame (since the last [`Retained::next_frame`]) used a history.
    pub fn histories_used(&self) -> bool {
        self.histories.values().any(|&(_, frame)| frame == self.frame)
    }
    /// Start a new frame.
    pub fn next_frame(&mut self) {
        self.frame += 1;
    }
    /// Names of the cached products held now (diagnostics and tests).
    pub fn product_names(&self) -> Vec<&'static str> {
        let mut v: Vec<_> = self.products.keys().copied().collect();
        v.sort_unstable();
        v
    }
}
