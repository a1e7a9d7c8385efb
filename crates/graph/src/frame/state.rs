//! What changes from frame to frame ([`FrameState`]): the camera and lights, those of the last frame and
//! of the last frame that kept the histories, and the resources the graph keeps across frames.

use crate::camera::Camera;
use crate::graph::Retained;
use crate::shader_types::Light;

/// What changes from frame to frame: the camera, the lights, and the resources the graph keeps across
/// frames.
pub struct FrameState {
    pub camera: Camera,
    /// The point lights, in the scene's local coordinates (as `Scene::lights`).
    pub lights: Vec<Light>,
    pub retained: Retained,
    /// The camera of the last frame rendered (reprojection's `FrameUniforms::prev_view_proj`).
    pub previous_camera: Option<Camera>,
    /// The lights of the last frame rendered.
    pub previous_lights: Option<Vec<Light>>,
    /// The camera and lights of the last frame that used the histories (`Retained::histories_used`): frames between
    /// it and the next that keeps them (the viewer's still frames) must not have moved either, or the
    /// histories are forgotten (`Retained::forget_histories`).
    pub history_view: Option<(Camera, Vec<Light>)>,
    /// `Method::Realtime` frames rendered since the renderer began or its frame cache was cleared: each
    /// draws its random numbers from it and the seed, so the frames whose reservoirs it reuses are
    /// independent draws. Only realtime frames count, so that a sequence's images do not depend on what
    /// else the renderer drew before (`bench` renders the ground truth first, or reads it from disk).
    pub realtime_frames: u64,
}

impl FrameState {
    /// Forget the histories where a frame that kept none moved the view since the last that did: their
    /// motion (last frame's camera against theirs) would be wrong.
    pub(super) fn forget_moved_histories(&mut self) {
        let last_view = self.previous_camera.zip(self.previous_lights.clone());
        if self.history_view.is_some() && self.history_view != last_view {
            self.retained.forget_histories();
            self.history_view = None;
        }
    }

    /// After a frame: what the next one compares against.
    pub(super) fn frame_done(&mut self) {
        if self.retained.histories_used() {
            self.history_view = Some((self.camera, self.lights.clone()));
        }
        self.retained.next_frame();
        self.previous_camera = Some(self.camera);
        self.previous_lights = Some(self.lights.clone());
    }
}
