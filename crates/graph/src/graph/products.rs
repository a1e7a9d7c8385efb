//! What [`super::Graph::cached`] keeps: a bundle of typed handles ([`Products`]) taken apart into
//! untyped ones ([`RawHandle`]) and put back together in the same order.

use super::Handle;
use bounce_device::{Buffer, Image};

/// A resource handle without its type, for [`Products`].
#[derive(Clone, Copy, Debug)]
pub struct RawHandle {
    pub(super) id: usize,
    pub(super) image: bool,
}

/// A bundle of handles a pass (or a few passes) produces, that [`Graph::cached`] can keep and lend back.
/// Implemented for handles, tuples and the passes' output structs ([`crate::products!`]).
pub trait Products: Copy {
    /// The handles, in a fixed order.
    fn handles(&self, out: &mut Vec<RawHandle>);
    /// The same bundle from handles in [`Products::handles`] order.
    fn from_handles(it: &mut dyn Iterator<Item = RawHandle>) -> Self;
}

impl Products for Handle<Image> {
    fn handles(&self, out: &mut Vec<RawHandle>) {
        out.push(RawHandle { id: self.id, image: true });
    }
    fn from_handles(it: &mut dyn Iterator<Item = RawHandle>) -> Self {
        let h = it.next().expect("a product bundle lost a handle");
        assert!(h.image, "a cached product changed type (buffer where an image was kept)");
        Handle::new(h.id)
    }
}

impl Products for Handle<Buffer> {
    fn handles(&self, out: &mut Vec<RawHandle>) {
        out.push(RawHandle { id: self.id, image: false });
    }
    fn from_handles(it: &mut dyn Iterator<Item = RawHandle>) -> Self {
        let h = it.next().expect("a product bundle lost a handle");
        assert!(!h.image, "a cached product changed type (image where a buffer was kept)");
        Handle::new(h.id)
    }
}

impl<A: Products, B: Products> Products for (A, B) {
    fn handles(&self, out: &mut Vec<RawHandle>) {
        self.0.handles(out);
        self.1.handles(out);
    }
    fn from_handles(it: &mut dyn Iterator<Item = RawHandle>) -> Self {
        let a = A::from_handles(it);
        (a, B::from_handles(it))
    }
}

/// `products!(Struct { field, ... })`: implement [`Products`] for a struct whose fields are handles or
/// other products.
#[macro_export]
macro_rules! products {
    ($t:ident { $($f:ident),+ $(,)? }) => {
        impl $crate::graph::Products for $t {
            fn handles(&self, out: &mut Vec<$crate::graph::RawHandle>) {
                $( $crate::graph::Products::handles(&self.$f, out); )+
            }
            fn from_handles(it: &mut dyn Iterator<Item = $crate::graph::RawHandle>) -> Self {
                $t { $( $f: $crate::graph::Products::from_handles(it), )+ }
            }
        }
    };
}
