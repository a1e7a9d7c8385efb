//! A frame: its settings ([`settings`]), the keys under which its products are kept across frames
//! ([`keys`]), the recipe ([`recipe::build_frame`]: start reading there), chunked submission
//! ([`chunks`]), the renderer that ties them together ([`renderer`]) and progressive rendering under a
//! time budget ([`progressive`]).

pub mod chunks;
pub mod keys;
pub mod progressive;
pub mod reads;
pub mod recipe;
pub mod renderer;
pub mod settings;
pub mod state;
mod warnings;

pub use reads::Setting;
pub use recipe::build_frame;
pub use renderer::{FrameOutput, RenderContext, Renderer};
pub use settings::{
    Component, FaceMode, FrameSettings, LightMap, Method, MisWeights, RisSettings, RisSource, SettingsError,
    Visibility, VplKernel, REALTIME_LEARN_BLOCKED, REALTIME_LEARN_EVERY, REALTIME_LEARN_HYSTERESIS,
    REALTIME_RESERVOIRS,
};
pub use state::FrameState;
