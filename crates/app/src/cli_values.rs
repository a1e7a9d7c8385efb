//! The value parsers of `cli`'s flags: each turns one argument into its value or says what it expected.

#[cfg(feature = "lab")]
use super::Learn;

#[cfg(feature = "lab")]
pub(super) fn parse_learn(s: &str) -> Result<Learn, String> {
    match s {
        "auto" => Ok(Learn::Auto),
        "off" => Ok(Learn::Floor(0.0)),
        _ => s.parse::<f32>().map(Learn::Floor).map_err(|_| format!("expected auto, off or a number, got {s:?}")),
    }
}

/// A wall-time budget: a positive number of seconds, at most 10⁶ (11.6 days; beyond that a `Duration`
/// cannot always hold it).
pub(super) fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t > 0.0 && t <= 1e6 => Ok(t),
        _ => Err(format!("expected a positive number of seconds up to 1e6, got {s:?}")),
    }
}

pub(super) fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("expected on or off, got {s:?}")),
    }
}
