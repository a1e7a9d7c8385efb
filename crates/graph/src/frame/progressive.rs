//! Progressive rendering under a time budget (`bounce render --time-limit`, `bounce bench
//! --time-limits`, and the viewer's still frames through [`frame_settings`] and [`VplSets`]): frame k
//! renders with seed `seed + k` and is added to a running mean (f64 on the host), until the budget would
//! be exceeded. Every frame is an unbiased estimate of the same image (each sampled method is unbiased for
//! the VPL sum given any CDF, the reference for the one-bounce integral), so the mean is too, and its
//! variance falls as 1/frames. The frames share one CDF seed (`--cdf-seed`, else the first frame's seed),
//! as the viewer's do: the importance and CDF are built once per VPL set and kept by the graph, and the
//! other frames of the set record only the gather.
//!
//! **VPL sets.** One set of VPLs (their places in their texels, [`FrameSettings::vpl_seed`]) is one
//! quadrature of the light's directions: the frames of one set converge to that set's VPL sum, which is
//! the one-bounce image only on average over sets (BENCHMARKS.md, "What the VPL sum converges to"). So
//! a progressive render moves on to a new set once the frames on the current one have taken
//! [`VPL_SET_RATIO`] times what a new set costs (its maps, importance, CDF and end balls): the sets take
//! at most 1/28 of the time, and the mean converges to the one-bounce image itself, the sets' error
//! falling as 1/time with the frames'. Of a render's error e = σ²/n + q²/s (n frames of variance σ²,
//! s sets of quadrature variance q², n·F + s·L = T), the best share of time for the sets is
//! q√L / (σ√F + q√L), which depends on the scene and the map resolution; the error is flat around it,
//! and shares of 1/4, 1/10 and 1/28 measured the same aggregate (BENCHMARKS.md). Where the light side
//! is free (a GPU at a small map resolution) a set lasts two frames. A pinned `vpl_seed` (`--cdf-seed`,
//! `bench --reference all`) keeps one set, as do the reference (no VPLs) and `realtime` (its reuse
//! follows the VPLs).
//!
//! The reference is the exception ([`frame_settings`]): its frames keep the seed and continue the
//! pixel's Owen-scrambled Sobol sequence (frame k takes samples k · spp .. (k + 1) · spp), so their mean
//! is that of one stratified set of F · spp points, whose variance falls faster than 1/F. Each point is
//! still uniform, so the mean stays unbiased. Measured: BENCHMARKS.md, "The path tracer's frames".
//!
//! `all` and the direct component are the same every frame: they render one frame, whatever the budget.
//! `realtime`'s frames are averaged raw (its denoised output is biased by design; the denoiser does not
//! run); they reuse one another's reservoirs, so they are correlated, and the mean's error falls slower
//! than 1/frames.
//!
//! The budget counts the frames' wall time, not the start-up before them (device, pipelines, scene
//! upload). The first frame always runs; another runs where half of it fits in what is left, judged by
//! the last frame's time (after the first, which also made what the others keep, less the GPU time of the
//! passes that made it), so that the frames end about as near the budget as whole frames allow (a frame
//! that draws a new VPL set costs more than the one before it).

use super::renderer::{FrameOutput, Renderer};
use super::settings::{Component, FrameSettings, Method};
use crate::graph::fingerprint;
use anyhow::Result;
use std::time::{Duration, Instant};

/// The accumulated result of [`render_for`].
pub struct Progressive {
    /// The mean of the frames' radiance.
    pub radiance: Vec<[f32; 4]>,
    pub frames: u32,
    /// Wall time of the frames.
    pub wall: Duration,
    /// The last frame (its timings, warnings, size).
    pub last: FrameOutput,
    /// Sum of every frame's GPU time, if the device has timestamps.
    pub gpu_ms: Option<f64>,
    /// The VPL set of each frame ([`VplSets`]).
    pub sets: Vec<u32>,
}

/// Whether more than one frame can change the mean: `all` (every VPL) and the direct component are the
/// same every frame, so one frame is their converged result.
pub fn averages(s: &FrameSettings) -> bool {
    s.method != Method::All && s.component != Component::Direct
}

/// Frame `k` of a progressive render of `s` on VPL set `set` ([`VplSets`]): the reference's frames
/// continue one stratified sample sequence (same seed, samples `k · spp ..`), until it would run past
/// 2^32 points, where it moves on to the next seed's; every other method's frames take seeds `s.seed + k`,
/// one CDF seed between them, and set `set`'s VPLs (set 0: the VPL seed `s` names; a pinned one for every
/// set).
pub fn frame_settings(s: &FrameSettings, k: u32, set: u32) -> FrameSettings {
    if s.method == Method::Reference {
        let per_seed = ((u32::MAX - s.sample_offset) / s.spp.max(1)).max(1);
        return FrameSettings {
            seed: s.seed.wrapping_add((k / per_seed) as u64),
            sample_offset: s.sample_offset.wrapping_add((k % per_seed) * s.spp),
            ..s.clone()
        };
    }
    let cdf_seed = Some(s.cdf_seed.unwrap_or(s.seed));
    let vpl_seed = match (s.vpl_seed, set) {
        (Some(pinned), _) => Some(pinned),
        (None, 0) => None,
        (None, j) => Some(fingerprint(&(s.vpl_seed_or_derived(), j, "vpl set"))),
    };
    // `realtime`'s frames are averaged raw (each unbiased, the denoised ones not): no denoiser to pay for.
    let denoise = s.denoise && s.method != Method::Realtime;
    FrameSettings { seed: s.seed.wrapping_add(k as u64), cdf_seed, vpl_seed, denoise, ..s.clone() }
}

/// How many times a VPL set's cost the frames on it take before the next set is drawn: the sets take at
/// most 1 / 28 of a progressive render's time. Against 3 and 9 it had the same aggregate (ris, 64², 2 to
/// 32 s, 128² a face, the Cornell box and Sibenik: 0.73 of one set's relMSE, 0.45–0.74 at 32 s) and
/// the least cost at 512² a face, where a set costs most and gains least: BENCHMARKS.md, "What the VPL
/// sum converges to".
pub const VPL_SET_RATIO: f64 = 27.0;

/// Whether a progressive render of `s` draws new VPL sets: a sampled VPL method whose VPL seed is not
/// pinned. The reference has no VPLs; `realtime`'s reservoirs follow their VPLs from frame to frame, and
/// a new set would age them as a moving light does; `all` renders one frame.
fn draws_vpl_sets(s: &FrameSettings) -> bool {
    s.vpl_seed.is_none() && averages(s) && !matches!(s.method, Method::Reference | Method::Realtime)
}

/// Which VPL set a progressive render's next frame takes: a new one once the frames on the current set
/// have taken [`VPL_SET_RATIO`] times its cost, the first frame of a set less one that reuses it. Where
/// the run's first frame did not draw the set (the first set, whose frame also built the voxels, G-buffer
/// and direct light; a restarted run, whose first frame redid what the move changed) the whole first
/// frame counts: an overestimate, so such a set lasts longer. Timed by the caller (wall time: what the
/// render's budget counts).
#[derive(Clone, Debug)]
pub struct VplSets {
    draws: bool,
    set: u32,
    /// Whether the current set's first frame drew it (and nothing else it knows of).
    first_drew_set: bool,
    /// Frames rendered on the current set.
    frames: u32,
    /// Seconds of the current set's first frame, and of its other frames together.
    first_s: f64,
    reused_s: f64,
}

impl VplSets {
    pub fn new(s: &FrameSettings) -> VplSets {
        VplSets { draws: draws_vpl_sets(s), set: 0, first_drew_set: false, frames: 0, first_s: 0.0, reused_s: 0.0 }
    }

    /// The set the next frame takes.
    pub fn set(&self) -> u32 {
        self.set
    }

    /// A new run of frames of `s` (the viewer's mean restarted by a move or a key) that goes on from the
    /// current set, whose maps the renderer still holds.
    pub fn restart(&mut self, s: &FrameSettings) {
        *self = VplSets { set: self.set, ..VplSets::new(s) };
    }

    /// Records a frame of `seconds` on the current set; the next frame may take a new one.
    pub fn frame_done(&mut self, seconds: f64) {
        if self.frames == 0 {
            self.first_s = seconds;
        } else {
            self.reused_s += seconds;
        }
        self.frames += 1;
        if !self.draws || self.frames < 2 {
            return;
        }
        let reuse = self.reused_s / (self.frames - 1) as f64;
        let cost = if self.first_drew_set { (self.first_s - reuse).max(0.0) } else { self.first_s };
        if self.reused_s >= VPL_SET_RATIO * cost {
            *self = VplSets { set: self.set + 1, first_drew_set: true, frames: 0, reused_s: 0.0, ..*self };
        }
    }
}

/// Whether a progressive render `elapsed` into `budget`, whose next frame should take `next`, renders
/// it: where it would end nearer the budget with it than without it, i.e. where half of it fits. So
/// every method's time is the budget to within about half a frame, over or under: a method of long frames is
/// neither given a whole frame more (a second frame whenever time was left let mis run 1.3–2.6× a 0.5 s
/// budget) nor cut a whole frame short.
pub fn another_frame(elapsed: Duration, next: Duration, budget: Duration) -> bool {
    elapsed + next / 2 <= budget
}

/// Render frames of `s` (seeds `s.seed`, `s.seed + 1`, …, VPL sets as [`VplSets`] says) until `budget`,
/// and average them.
/// `progress(frames, elapsed)` is called after each frame.
pub fn render_for(
    r: &mut Renderer,
    s: &FrameSettings,
    budget: Duration,
    progress: &mut dyn FnMut(u32, Duration),
) -> Result<Progressive> {
    let t0 = Instant::now();
    let mut sum: Vec<[f64; 4]> = vec![];
    let (mut frames, mut gpu_ms) = (0u32, Some(0.0));
    let mut previous = Duration::ZERO;
    let (mut vpl_sets, mut sets) = (VplSets::new(s), vec![]);
    let last = loop {
        sets.push(vpl_sets.set());
        let f = r.render(&frame_settings(s, frames, vpl_sets.set()))?;
        // `realtime`'s raw estimate, each frame unbiased, not its denoised output, which is not.
        let estimate = f.raw.as_ref().unwrap_or(&f.radiance);
        sum.resize(estimate.len(), [0.0; 4]);
        for (a, p) in sum.iter_mut().zip(estimate) {
            for c in 0..4 {
                a[c] += p[c] as f64;
            }
        }
        frames += 1;
        gpu_ms = gpu_ms.zip(f.gpu_ms()).map(|(a, b)| a + b);
        let elapsed = t0.elapsed();
        progress(frames, elapsed);
        let this_frame = elapsed - previous;
        previous = elapsed;
        vpl_sets.frame_done(this_frame.as_secs_f64());
        // The first frame also made what the next keeps (maps, G-buffer, CDF): the next costs it less
        // that GPU time (all of it without timestamps; what the host does each frame stays in).
        let kept = Duration::from_secs_f64(f.kept_gpu_ms().unwrap_or(0.0).max(0.0) / 1e3);
        let next = if frames == 1 { this_frame.saturating_sub(kept) } else { this_frame };
        if !another_frame(elapsed, next, budget) || !averages(s) {
            break f;
        }
    };
    let n = frames as f64;
    let radiance =
        sum.iter().map(|a| [(a[0] / n) as f32, (a[1] / n) as f32, (a[2] / n) as f32, (a[3] / n) as f32]).collect();
    Ok(Progressive { radiance, frames, wall: t0.elapsed(), last, gpu_ms, sets })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames of 0.3 s in a 0.5 s budget: a second (ending at 0.6 s, 0.1 over) is nearer than stopping
    /// at 0.3 (0.2 under); frames of 0.4 s: one (0.1 under, not 0.3 over). Many short frames fill it.
    #[test]
    fn the_frames_end_as_near_the_budget_as_whole_frames_allow() {
        let ms = Duration::from_millis;
        let ends = |frame: u64| {
            let mut elapsed = ms(frame);
            while another_frame(elapsed, ms(frame), ms(500)) {
                elapsed += ms(frame);
            }
            elapsed
        };
        assert_eq!(ends(300), ms(600));
        assert_eq!(ends(400), ms(400));
        assert_eq!(ends(700), ms(700));
        assert_eq!(ends(30), ms(510));
        assert_eq!(ends(25), ms(500));
    }

    fn sampled() -> FrameSettings {
        FrameSettings { method: Method::Gbg, component: Component::Indirect, ..FrameSettings::default() }
    }

    /// Frame seconds `times` through the schedule: the set each frame took.
    fn sets_of(s: &FrameSettings, times: &[f64]) -> Vec<u32> {
        let mut v = VplSets::new(s);
        times
            .iter()
            .map(|&t| {
                let set = v.set();
                v.frame_done(t);
                set
            })
            .collect()
    }

    /// A set costs 1 s over a 1 s frame that reuses it: a set's frames take 27 s beyond its first, so
    /// the sets take 1 / 28 of the time; the first set, whose cost is taken as its whole first frame (an
    /// overestimate, 3 s here), lasts longer.
    #[test]
    fn a_set_lasts_until_its_frames_took_the_ratio_times_its_cost() {
        let n = VPL_SET_RATIO as usize;
        let mut times = vec![3.0];
        times.extend(vec![1.0; 3 * n]);
        for _ in 1..10 {
            times.push(2.0);
            times.extend(vec![1.0; n]);
        }
        let sets = sets_of(&sampled(), &times);
        assert!(sets[..=3 * n].iter().all(|&s| s == 0), "{sets:?}");
        for j in 1..10u32 {
            let first = 3 * n + 1 + (n + 1) * (j as usize - 1);
            assert!(sets[first..first + n + 1].iter().all(|&s| s == j), "set {j}: {sets:?}");
        }
    }

    /// Where a new set costs nothing over a frame, a set lasts two frames (its cost must be measured by
    /// one that reuses it); a pinned VPL seed, the reference and `realtime` keep one set.
    #[test]
    fn free_sets_last_two_frames_and_pinned_ones_forever() {
        let n = VPL_SET_RATIO as usize;
        // Set 0's cost is its whole first frame (1 s): n more frames.
        let sets = sets_of(&sampled(), &vec![1.0; n + 7]);
        assert!(sets[..=n].iter().all(|&s| s == 0), "{sets:?}");
        assert_eq!(&sets[n + 1..], [1, 1, 2, 2, 3, 3]);
        // A restarted run goes on from the set it had reached; its first frame did not draw it, so it
        // counts whole, as the first set's does.
        let mut v = VplSets::new(&sampled());
        for _ in 0..n + 2 {
            v.frame_done(1.0);
        }
        assert_eq!(v.set(), 1);
        v.restart(&sampled());
        let mut after = vec![];
        for _ in 0..n + 2 {
            after.push(v.set());
            v.frame_done(1.0);
        }
        assert!(after[..=n].iter().all(|&s| s == 1) && after[n + 1] == 2, "{after:?}");
        for s in [
            FrameSettings { vpl_seed: Some(3), ..sampled() },
            FrameSettings { method: Method::Reference, ..sampled() },
            FrameSettings { method: Method::Realtime, ..sampled() },
            FrameSettings { method: Method::All, ..sampled() },
        ] {
            assert!(sets_of(&s, &[0.0; 40]).iter().all(|&s| s == 0), "{:?}", s.method);
        }
    }

    /// Set 0 is the VPL set a single frame of `s` draws; every later set draws its own; a pinned seed stays.
    #[test]
    fn each_set_draws_its_own_vpls() {
        use crate::frame::keys::vpl_offset;
        let s = sampled();
        let offsets: Vec<[f32; 2]> = (0..8).map(|j| vpl_offset(&frame_settings(&s, j, j))).collect();
        assert_eq!(offsets[0], vpl_offset(&FrameSettings { cdf_seed: Some(s.seed), ..s.clone() }));
        for (i, a) in offsets.iter().enumerate() {
            assert!(offsets[i + 1..].iter().all(|b| b != a), "{offsets:?}");
        }
        let pinned = FrameSettings { vpl_seed: Some(9), ..s };
        assert_eq!(frame_settings(&pinned, 5, 5).vpl_seed, Some(9));
    }
}
