//! What changes from frame to frame ([`FrameState`]): the camera and lights, what the last frame and the
//! last frame that kept the histories saw ([`View`]), and the resources the graph keeps across frames.

use crate::camera::Camera;
use crate::graph::Retained;
use crate::shader_types::Light;

/// What a frame saw: its camera, its lights and its VPLs' key ([`super::keys::Keys::vpls`]).
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    pub camera: Camera,
    pub lights: Vec<Light>,
    pub vpls: u64,
}

/// What changes from frame to frame: the camera, the lights, and the resources the graph keeps across
/// frames.
pub struct FrameState {
    pub camera: Camera,
    /// The point lights, in the scene's local coordinates (as `Scene::lights`).
    pub lights: Vec<Light>,
    pub retained: Retained,
    /// What the last frame rendered saw (its camera: reprojection's `FrameUniforms::prev_view_proj`).
    pub previous: Option<View>,
    /// What the last frame that used the histories (`Retained::histories_used`) saw: frames between it and
    /// the next that keeps them (the viewer's still frames) must not have changed it, or the histories are
    /// forgotten (`Retained::forget_histories`). The VPLs too: the next frame weighs its reservoirs'
    /// history with the VPLs the frame before it had (`Graph::replaced`), which after a still frame that
    /// moved on to a new VPL set are not the ones they were drawn with.
    pub history_view: Option<View>,
    /// `Method::Realtime` frames rendered since the renderer began or its frame cache was cleared: each
    /// draws its random numbers from it and the seed, so the frames whose reservoirs it reuses are
    /// independent draws. Only realtime frames count, so that a sequence's images do not depend on what
    /// else the renderer drew before (`bench` renders the ground truth first, or reads it from disk).
    pub realtime_frames: u64,
}

impl FrameState {
    /// Forget the histories where a frame that kept none moved the view or changed the VPLs since the last
    /// that did: their motion (last frame's camera against theirs) or their VPLs would be wrong.
    pub(super) fn forget_moved_histories(&mut self) {
        if self.history_view.is_some() && self.history_view != self.previous {
            self.retained.forget_histories();
            self.history_view = None;
        }
    }

    /// After a frame whose VPLs had the key `vpls`: what the next one compares against.
    pub(super) fn frame_done(&mut self, vpls: u64) {
        let seen = View { camera: self.camera, lights: self.lights.clone(), vpls };
        if self.retained.histories_used() {
            self.history_view = Some(seen.clone());
        }
        self.retained.next_frame();
        self.previous = Some(seen);
    }
}
