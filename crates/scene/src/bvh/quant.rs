//! The second box of a threaded box record ([`super::FlatBvh::threaded`]): where the record after a box
//! is a box too (its first child, or the first kept box below it), the box record carries that box
//! packed into its own, so that a step of the stackless walk which meets the box also tests the next one
//! and moves past both.
//!
//! Owns: the packing ([`pack`], mirrored by `bvh_hit_packed_box` in `glsl/shared/bvh.glsl`) and the
//! pairing of records ([`pair_records`]).
//!
//! **Why.** A step reads a record's three texels whatever it holds: llvmpipe runs both sides of the
//! box-or-triangle branch under masks, so a box step fetched the triangle's third texel and left it
//! unused. That texel now holds the next box and its link, so a met box whose successor is a box costs
//! one step for both.
//!
//! **The packing, and why it changes no answer.** Inside parent box [lo, hi], axis j of the packed box
//! is [lo_j + q_j·s_j, hi_j − q'_j·s_j], s = (hi − lo)·2^-16, with 16-bit q and q' (word j: q in the low
//! half, q' in the high one). Each operation is one f32 rounding, in this order, on the GPU (`precise`)
//! and here, so both compute the same planes, and [`pack`] takes the largest q and q' whose planes still
//! hold the exact box (q = q' = 0 is the parent's box itself, which always does). The shader then runs
//! the exact box test (`bvh_hit_box`) on a box around the same triangles, which culls nothing that the
//! exact box would let through. A flushed denormal only moves a plane to the parent's, outwards.

use super::flat::{GpuThreadRec, THREAD_TRI};
use glam::Vec3;

/// The packed coordinates' unit, as a fraction of the parent box's extent (exact in f32).
const UNIT: f32 = 1.0 / 65536.0;
const Q_MAX: u32 = 65535;

/// The planes of packed box `q` inside [lo, hi], in the shader's f32 arithmetic.
pub fn unpack(lo: [f32; 3], hi: [f32; 3], q: [u32; 3]) -> (Vec3, Vec3) {
    let (mut plo, mut phi) = (Vec3::ZERO, Vec3::ZERO);
    for j in 0..3 {
        let s = (hi[j] - lo[j]) * UNIT;
        plo[j] = lo[j] + (q[j] & 0xffff) as f32 * s;
        phi[j] = hi[j] - (q[j] >> 16) as f32 * s;
    }
    (plo, phi)
}

/// Box [clo, chi] packed into its parent [lo, hi] as tightly as the 16-bit planes allow, or None where
/// it does not lie inside the parent.
pub fn pack(lo: [f32; 3], hi: [f32; 3], clo: [f32; 3], chi: [f32; 3]) -> Option<[u32; 3]> {
    let inside = (0..3).all(|j| lo[j] <= clo[j] && clo[j] <= chi[j] && chi[j] <= hi[j]);
    if !inside || ![lo, hi, clo, chi].iter().flatten().all(|v| v.is_finite()) {
        return None;
    }
    Some(std::array::from_fn(|j| {
        let s = (hi[j] - lo[j]) * UNIT;
        // The estimate in f64, then down until the f32 plane holds the box (at 0 it is the parent's).
        let guess = |gap: f32| if s > 0.0 { ((gap as f64 / s as f64).floor() as u32).min(Q_MAX) } else { 0 };
        let mut q = guess(clo[j] - lo[j]);
        while q > 0 && lo[j] + q as f32 * s > clo[j] {
            q -= 1;
        }
        let mut r = guess(hi[j] - chi[j]);
        while r > 0 && hi[j] - r as f32 * s < chi[j] {
            r -= 1;
        }
        q | r << 16
    }))
}

/// Gives every box record whose successor is a box that box, packed, in its third texel (`c`, as the
/// bits of the words) and the successor's link in `pad2`; 0 in `pad2` means no pair (a link is never 0:
/// it points past its own record).
pub fn pair_records(records: &mut [GpuThreadRec]) {
    for i in 0..records.len() {
        let r = records[i];
        if r.link == THREAD_TRI {
            continue;
        }
        let next = records.get(i + 1).filter(|n| n.link != THREAD_TRI);
        let packed = next.and_then(|n| Some((n.link, pack(r.a, r.b, n.a, n.b)?)));
        let (link, words) = packed.unwrap_or((0, [0; 3]));
        records[i].c = words.map(f32::from_bits);
        records[i].pad2 = link;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_packed_box_holds_the_box_and_is_tight() {
        let mut r = crate::bvh::test_uniforms(0x9e37_79b9_7f4a_7c15u64);
        for k in 0..20_000 {
            // Parents from a millimetre to a kilometre, far from the origin or not, some flat.
            let scale = 10f32.powi(k % 7 - 3);
            let lo = Vec3::new(r(), r(), r()) * 1e3 - 500.0;
            let ext = Vec3::new(r(), r(), if k % 5 == 0 { 0.0 } else { r() }) * scale;
            let hi = lo + ext;
            let a = lo + ext * Vec3::new(r(), r(), r());
            let b = (a + ext * Vec3::new(r(), r(), r())).min(hi);
            let q = pack(lo.into(), hi.into(), a.into(), b.into()).expect("inside");
            let (plo, phi) = unpack(lo.into(), hi.into(), q);
            assert!(plo.cmple(a).all() && phi.cmpge(b).all(), "{lo} {hi}: {a} {b} packed as {plo} {phi}");
            assert!(plo.cmpge(lo).all() && phi.cmple(hi).all());
            // Tight: within two units of the box on every side, or a few ulps where those are coarser.
            let slack = ((hi - lo) * UNIT * 2.0).max(a.abs().max(b.abs()) * 4.0 * f32::EPSILON);
            assert!((a - plo).cmple(slack).all() && (phi - b).cmple(slack).all(), "{lo} {hi}: {a} {b}");
        }
        // Not inside its parent, or not finite: no pair.
        assert_eq!(pack([0.0; 3], [1.0; 3], [-0.5, 0.0, 0.0], [0.5; 3]), None);
        assert_eq!(pack([0.0; 3], [1.0; 3], [f32::NAN, 0.0, 0.0], [0.5; 3]), None);
    }
}
