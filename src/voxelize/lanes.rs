//! Bit masks from comparisons over a pixel's samples (at most 64 lanes), for the row
//! rasterizer ([`super::fragments`]): the per-sample loops the compiler does not turn
//! into vector code by itself. `AVX` selects 4-lane AVX2 code (only ever instantiated
//! inside the AVX2 build of the row loop, after the CPU was checked); otherwise 2-lane
//! SSE2 (part of x86-64) or, elsewhere, plain scalar code. Every lane is compared
//! exactly, so all versions give the same masks.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Bit `b < n` set where `e + off[b] < 0` (the sign of an edge function at sample `b`).
#[inline(always)]
pub(crate) fn negative<const AVX: bool>(n: usize, e: i64, off: &[i64; 64]) -> u64 {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of x86-64; AVX2 is used only when `AVX` (see the module docs);
    // every load reads inside `off` (`b + 4 ≤ 64`).
    unsafe {
        let mut m = 0u64;
        if AVX {
            let ev = _mm256_set1_epi64x(e);
            let mut b = 0;
            while b < n {
                let o = _mm256_loadu_si256(off.as_ptr().add(b) as *const __m256i);
                let v = _mm256_add_epi64(ev, o);
                m |= (_mm256_movemask_pd(_mm256_castsi256_pd(v)) as u64) << b;
                b += 4;
            }
        } else {
            let ev = _mm_set1_epi64x(e);
            let mut b = 0;
            while b < n {
                let o = _mm_loadu_si128(off.as_ptr().add(b) as *const __m128i);
                let v = _mm_add_epi64(ev, o);
                m |= (_mm_movemask_pd(_mm_castsi128_pd(v)) as u64) << b;
                b += 2;
            }
        }
        m & lanes(n)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let mut m = 0u64;
        for (b, o) in off.iter().enumerate().take(n) {
            m |= (((e + o) as u64) >> 63) << b;
        }
        m
    }
}

/// Bit `b < n` set where `t[b] >= p` (`GT`: `t[b] > p`). No NaN among the `t`.
#[inline(always)]
pub(crate) fn at_least<const AVX: bool, const GT: bool>(n: usize, t: &[f64; 64], p: f64) -> u64 {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: as in `negative`.
    unsafe {
        let mut m = 0u64;
        if AVX {
            let pv = _mm256_set1_pd(p);
            let mut b = 0;
            while b < n {
                let v = _mm256_loadu_pd(t.as_ptr().add(b));
                let c = if GT {
                    _mm256_cmp_pd::<_CMP_GT_OQ>(v, pv)
                } else {
                    _mm256_cmp_pd::<_CMP_GE_OQ>(v, pv)
                };
                m |= (_mm256_movemask_pd(c) as u64) << b;
                b += 4;
            }
        } else {
            let pv = _mm_set1_pd(p);
            let mut b = 0;
            while b < n {
                let v = _mm_loadu_pd(t.as_ptr().add(b));
                let c = if GT {
                    _mm_cmpgt_pd(v, pv)
                } else {
                    _mm_cmpge_pd(v, pv)
                };
                m |= (_mm_movemask_pd(c) as u64) << b;
                b += 2;
            }
        }
        m & lanes(n)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let mut m = 0u64;
        for (b, &x) in t.iter().enumerate().take(n) {
            m |= ((if GT { x > p } else { x >= p }) as u64) << b;
        }
        m
    }
}

/// The low `n` bits.
#[inline(always)]
pub(crate) const fn lanes(n: usize) -> u64 {
    if n >= 64 {
        u64::MAX
    } else {
        (1u64 << n) - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check<const N: usize, const AVX: bool>() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for _ in 0..2000 {
            let off: [i64; 64] = std::array::from_fn(|_| (next() % 2001) as i64 - 1000);
            let t: [f64; 64] = std::array::from_fn(|_| (next() % 64) as f64 * 0.25 - 4.0);
            let e = (next() % 2001) as i64 - 1000;
            let p = (next() % 64) as f64 * 0.25 - 4.0;
            let mut want = [0u64; 3];
            for b in 0..N {
                want[0] |= ((e + off[b] < 0) as u64) << b;
                want[1] |= ((t[b] >= p) as u64) << b;
                want[2] |= ((t[b] > p) as u64) << b;
            }
            assert_eq!(negative::<AVX>(N, e, &off), want[0]);
            assert_eq!(at_least::<AVX, false>(N, &t, p), want[1]);
            assert_eq!(at_least::<AVX, true>(N, &t, p), want[2]);
        }
    }

    #[test]
    fn masks_match_scalar_comparisons() {
        check::<1, false>();
        check::<9, false>();
        check::<16, false>();
        check::<49, false>();
        check::<64, false>();
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            check::<1, true>();
            check::<9, true>();
            check::<16, true>();
            check::<25, true>();
            check::<64, true>();
            return;
        }
        crate::test_support::skip(
            "masks_match_scalar_comparisons (AVX2 lanes)",
            "no AVX2 on this CPU; only the scalar lanes checked",
        );
    }
}
