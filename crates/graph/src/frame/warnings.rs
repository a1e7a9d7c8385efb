//! What a frame says once about its settings (its log's warnings): what they leave out of the answer.

use super::settings::{Component, FrameSettings, LightMap, Method};

/// `--defensive 0` with a CDF: a VPL the CDF gives no importance is never drawn, yet the estimator counts
/// only what it draws. Allowed (the thesis's CDFs have no defensive share), said once per frame.
pub(super) fn defensive_warning(s: &FrameSettings) -> Option<String> {
    let cdf = !matches!(s.sampling_method(), Method::Uniform | Method::All | Method::Reference);
    (s.defensive == 0.0 && cdf && s.component != Component::Direct).then(|| {
        "--defensive 0: a VPL its CDF gives no importance (no gather point's importance reaches it) is never drawn, so its light is missing: the estimate is biased (as the thesis's CDFs are)".to_string()
    })
}

/// What an `rsm` light map cannot see: said once per frame.
pub(super) fn rsm_warning(s: &FrameSettings) -> Option<String> {
    let LightMap::Rsm { fov_deg } = s.light_map else { return None };
    let omega = s.light_map.solid_angle();
    let missing = 1.0 - omega / (4.0 * std::f64::consts::PI);
    Some(format!(
        "rsm ({fov_deg}° field of view): the map covers {omega:.3} sr around each light, so {:.1} % of each light's emitted flux (I · (4π − Ω) = {:.3} W per W/sr) reaches no VPL",
        100.0 * missing,
        4.0 * std::f64::consts::PI - omega
    ))
}
