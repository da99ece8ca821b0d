//! Eight `f32` lanes for the tile kernel ([`super::tile`]), over three back
//! ends chosen at run time ([`RenderKernel`]):
//!
//! * [`Avx2`]: one 256-bit AVX register per vector, through `pulp`'s safe,
//!   run-time-detected x86-64-v3 token (no `unsafe` here: the token can
//!   only be made on a CPU with AVX2, and the kernel is compiled for it
//!   inside `pulp`'s `vectorize`);
//! * [`Portable`]: `wide::f32x8`, what the compile-time target allows (two
//!   SSE registers on baseline x86-64, NEON on aarch64, scalar elsewhere);
//! * [`Reference`]: eight plain `f32`s and one scalar IEEE operation per
//!   lane, the reference the other two are checked against bit for bit.
//!
//! Every back end performs, lane for lane, the same IEEE-754 single
//! precision operation (no fused multiply-add; `min`/`max` are
//! `a < b ? a : b` / `a > b ? a : b`, as the x86 instructions), so a kernel
//! written once over [`Lanes`] gives the same bits on all three.

use serde::{Deserialize, Serialize};
use wide::f32x8;

/// Lanes per vector.
pub(super) const W: usize = 8;

/// Which implementation of the 8-lane operations traces camera tiles. The
/// results are the same bits with every kernel; only the speed differs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum RenderKernel {
    /// [`RenderKernel::Avx2`] when the CPU has it, else
    /// [`RenderKernel::Portable`].
    #[default]
    Auto,
    /// 256-bit AVX2 registers (x86-64 with AVX2 and FMA detected at run
    /// time; FMA is never used, it only names the x86-64-v3 level).
    Avx2,
    /// `wide::f32x8`: SIMD as far as the compile-time target allows.
    Portable,
    /// One scalar operation per lane: the bit-exact reference.
    Reference,
}

impl RenderKernel {
    /// Whether this kernel can run on this CPU ([`RenderKernel::Avx2`]
    /// needs x86-64-v3; the others always run).
    pub fn is_available(self) -> bool {
        match self {
            RenderKernel::Avx2 => avx2_token().is_some(),
            _ => true,
        }
    }

    /// The kernel [`RenderKernel::Auto`] stands for on this CPU.
    pub fn resolve(self) -> RenderKernel {
        match self {
            RenderKernel::Auto if avx2_token().is_some() => RenderKernel::Avx2,
            RenderKernel::Auto => RenderKernel::Portable,
            k => k,
        }
    }
}

/// The x86-64-v3 token when the CPU supports it (detection is cached by
/// `pulp`).
#[cfg(target_arch = "x86_64")]
pub(super) fn avx2_token() -> Option<pulp::x86::V3> {
    pulp::x86::V3::try_new()
}

/// No AVX2 off x86-64.
#[cfg(not(target_arch = "x86_64"))]
pub(super) fn avx2_token() -> Option<()> {
    None
}

/// Eight `f32` lanes; masks are vectors whose lanes are all ones (true) or
/// all zeros (false).
pub(super) trait Lanes: Copy {
    /// The vector type.
    type V: Copy;
    /// Every lane `x`.
    fn splat(self, x: f32) -> Self::V;
    /// The lanes of `a`.
    fn load(self, a: [f32; W]) -> Self::V;
    /// The lanes as an array.
    fn store(self, v: Self::V) -> [f32; W];
    /// `a + b`.
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a - b`.
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a * b`.
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a / b`.
    fn div(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a < b ? a : b`.
    fn min(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a > b ? a : b`.
    fn max(self, a: Self::V, b: Self::V) -> Self::V;
    /// `|a|`.
    fn abs(self, a: Self::V) -> Self::V;
    /// Mask of `a < b` (false on NaN).
    fn lt(self, a: Self::V, b: Self::V) -> Self::V;
    /// Mask of `a <= b`.
    fn le(self, a: Self::V, b: Self::V) -> Self::V;
    /// Mask of `a == b`.
    fn eq(self, a: Self::V, b: Self::V) -> Self::V;
    /// Bitwise `a & b`.
    fn and(self, a: Self::V, b: Self::V) -> Self::V;
    /// Bitwise `a | b`.
    fn or(self, a: Self::V, b: Self::V) -> Self::V;
    /// Bitwise `a & !b`.
    fn and_not(self, a: Self::V, b: Self::V) -> Self::V;
    /// Lanes of `t` where `mask`, else of `f` (bitwise).
    fn select(self, mask: Self::V, t: Self::V, f: Self::V) -> Self::V;
    /// Bit `i` set where lane `i` of `mask` has its sign bit set.
    fn bitmask(self, mask: Self::V) -> u32;

    /// Mask of `a > b`.
    #[inline(always)]
    fn gt(self, a: Self::V, b: Self::V) -> Self::V {
        self.lt(b, a)
    }
    /// Mask of `a >= b`.
    #[inline(always)]
    fn ge(self, a: Self::V, b: Self::V) -> Self::V {
        self.le(b, a)
    }
    /// Mask of finite lanes.
    #[inline(always)]
    fn is_finite(self, a: Self::V) -> Self::V {
        self.lt(self.abs(a), self.splat(f32::INFINITY))
    }
}

/// All-ones bits as an `f32` (a true mask lane).
const TRUE: f32 = f32::from_bits(u32::MAX);

/// The bit-exact scalar reference: one IEEE operation per lane.
#[derive(Debug, Clone, Copy)]
pub(super) struct Reference;

impl Reference {
    #[inline(always)]
    fn map2(a: [f32; W], b: [f32; W], f: impl Fn(f32, f32) -> f32) -> [f32; W] {
        std::array::from_fn(|i| f(a[i], b[i]))
    }
    #[inline(always)]
    fn bits2(a: [f32; W], b: [f32; W], f: impl Fn(u32, u32) -> u32) -> [f32; W] {
        std::array::from_fn(|i| f32::from_bits(f(a[i].to_bits(), b[i].to_bits())))
    }
    #[inline(always)]
    fn mask(c: bool) -> f32 {
        if c { TRUE } else { 0.0 }
    }
}

impl Lanes for Reference {
    type V = [f32; W];
    #[inline(always)]
    fn splat(self, x: f32) -> Self::V {
        [x; W]
    }
    #[inline(always)]
    fn load(self, a: [f32; W]) -> Self::V {
        a
    }
    #[inline(always)]
    fn store(self, v: Self::V) -> [f32; W] {
        v
    }
    #[inline(always)]
    fn add(self, a: Self::V, b: Self::V) -> Self::V {
        Self::map2(a, b, |x, y| x + y)
    }
    #[inline(always)]
    fn sub(self, a: Self::V, b: Self::V) -> Self::V {
        Self::map2(a, b, |x, y| x - y)
    }
    #[inline(always)]
    fn mul(self, a: Self::V, b: Self::V) -> Self::V {
        Self::map2(a, b, |x, y| x * y)
    }
    #[inline(always)]
    fn div(self, a: Self::V, b: Self::V) -> Self::V {
        Self::map2(a, b, |x, y| x / y)
    }
    #[inline(always)]
    fn min(self, a: Self::V, b: Self::V) -> Self::V {
        Self::map2(a, b, |x, y| if x < y { x } else { y })
    }
    #[inline(always)]
    fn max(self, a: Self::V, b: Self::V) -> Self::V {
        Self::map2(a, b, |x, y| if x > y { x } else { y })
    }
    #[inline(always)]
    fn abs(self, a: Self::V) -> Self::V {
        a.map(f32::abs)
    }
    #[inline(always)]
    fn lt(self, a: Self::V, b: Self::V) -> Self::V {
        Self::map2(a, b, |x, y| Self::mask(x < y))
    }
    #[inline(always)]
    fn le(self, a: Self::V, b: Self::V) -> Self::V {
        Self::map2(a, b, |x, y| Self::mask(x <= y))
    }
    #[inline(always)]
    fn eq(self, a: Self::V, b: Self::V) -> Self::V {
        Self::map2(a, b, |x, y| Self::mask(x == y))
    }
    #[inline(always)]
    fn and(self, a: Self::V, b: Self::V) -> Self::V {
        Self::bits2(a, b, |x, y| x & y)
    }
    #[inline(always)]
    fn or(self, a: Self::V, b: Self::V) -> Self::V {
        Self::bits2(a, b, |x, y| x | y)
    }
    #[inline(always)]
    fn and_not(self, a: Self::V, b: Self::V) -> Self::V {
        Self::bits2(a, b, |x, y| x & !y)
    }
    #[inline(always)]
    fn select(self, mask: Self::V, t: Self::V, f: Self::V) -> Self::V {
        std::array::from_fn(|i| {
            let m = mask[i].to_bits();
            f32::from_bits((t[i].to_bits() & m) | (f[i].to_bits() & !m))
        })
    }
    #[inline(always)]
    fn bitmask(self, mask: Self::V) -> u32 {
        mask.iter()
            .enumerate()
            .fold(0, |m, (i, x)| m | ((x.to_bits() >> 31) << i))
    }
}

/// `wide::f32x8`: SIMD as the compile-time target allows.
#[derive(Debug, Clone, Copy)]
pub(super) struct Portable;

impl Lanes for Portable {
    type V = f32x8;
    #[inline(always)]
    fn splat(self, x: f32) -> Self::V {
        f32x8::splat(x)
    }
    #[inline(always)]
    fn load(self, a: [f32; W]) -> Self::V {
        f32x8::new(a)
    }
    #[inline(always)]
    fn store(self, v: Self::V) -> [f32; W] {
        v.to_array()
    }
    #[inline(always)]
    fn add(self, a: Self::V, b: Self::V) -> Self::V {
        a + b
    }
    #[inline(always)]
    fn sub(self, a: Self::V, b: Self::V) -> Self::V {
        a - b
    }
    #[inline(always)]
    fn mul(self, a: Self::V, b: Self::V) -> Self::V {
        a * b
    }
    #[inline(always)]
    fn div(self, a: Self::V, b: Self::V) -> Self::V {
        a / b
    }
    #[inline(always)]
    fn min(self, a: Self::V, b: Self::V) -> Self::V {
        a.fast_min(b)
    }
    #[inline(always)]
    fn max(self, a: Self::V, b: Self::V) -> Self::V {
        a.fast_max(b)
    }
    #[inline(always)]
    fn abs(self, a: Self::V) -> Self::V {
        a.abs()
    }
    #[inline(always)]
    fn lt(self, a: Self::V, b: Self::V) -> Self::V {
        a.simd_lt(b)
    }
    #[inline(always)]
    fn le(self, a: Self::V, b: Self::V) -> Self::V {
        a.simd_le(b)
    }
    #[inline(always)]
    fn eq(self, a: Self::V, b: Self::V) -> Self::V {
        a.simd_eq(b)
    }
    #[inline(always)]
    fn and(self, a: Self::V, b: Self::V) -> Self::V {
        a & b
    }
    #[inline(always)]
    fn or(self, a: Self::V, b: Self::V) -> Self::V {
        a | b
    }
    #[inline(always)]
    fn and_not(self, a: Self::V, b: Self::V) -> Self::V {
        a & !b
    }
    #[inline(always)]
    fn select(self, mask: Self::V, t: Self::V, f: Self::V) -> Self::V {
        mask.select(t, f)
    }
    #[inline(always)]
    fn bitmask(self, mask: Self::V) -> u32 {
        mask.to_bitmask()
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use avx::Avx2;

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{Lanes, W};
    use core::arch::x86_64::{__m256, _CMP_EQ_OQ, _CMP_LE_OQ, _CMP_LT_OQ};
    use pulp::x86::V3;

    /// 256-bit AVX registers. Holding the x86-64-v3 token proves the CPU
    /// has the instructions; the kernel runs inside `V3::vectorize`, so the
    /// operations below are compiled for AVX2 and inlined.
    #[derive(Debug, Clone, Copy)]
    pub(in crate::render) struct Avx2(pub(in crate::render) V3);

    impl Lanes for Avx2 {
        type V = __m256;
        #[inline(always)]
        fn splat(self, x: f32) -> Self::V {
            self.0.avx._mm256_set1_ps(x)
        }
        #[inline(always)]
        fn load(self, a: [f32; W]) -> Self::V {
            bytemuck::cast(a)
        }
        #[inline(always)]
        fn store(self, v: Self::V) -> [f32; W] {
            bytemuck::cast(v)
        }
        #[inline(always)]
        fn add(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_add_ps(a, b)
        }
        #[inline(always)]
        fn sub(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_sub_ps(a, b)
        }
        #[inline(always)]
        fn mul(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_mul_ps(a, b)
        }
        #[inline(always)]
        fn div(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_div_ps(a, b)
        }
        #[inline(always)]
        fn min(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_min_ps(a, b)
        }
        #[inline(always)]
        fn max(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_max_ps(a, b)
        }
        #[inline(always)]
        fn abs(self, a: Self::V) -> Self::V {
            self.0.avx._mm256_andnot_ps(self.splat(-0.0), a)
        }
        #[inline(always)]
        fn lt(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_cmp_ps::<_CMP_LT_OQ>(a, b)
        }
        #[inline(always)]
        fn le(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_cmp_ps::<_CMP_LE_OQ>(a, b)
        }
        #[inline(always)]
        fn eq(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_cmp_ps::<_CMP_EQ_OQ>(a, b)
        }
        #[inline(always)]
        fn and(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_and_ps(a, b)
        }
        #[inline(always)]
        fn or(self, a: Self::V, b: Self::V) -> Self::V {
            self.0.avx._mm256_or_ps(a, b)
        }
        #[inline(always)]
        fn and_not(self, a: Self::V, b: Self::V) -> Self::V {
            // The intrinsic computes `!first & second`.
            self.0.avx._mm256_andnot_ps(b, a)
        }
        #[inline(always)]
        fn select(self, mask: Self::V, t: Self::V, f: Self::V) -> Self::V {
            self.0.avx._mm256_blendv_ps(f, t, mask)
        }
        #[inline(always)]
        fn bitmask(self, mask: Self::V) -> u32 {
            self.0.avx._mm256_movemask_ps(mask) as u32
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Special values that exercise every comparison and sign rule.
    fn value() -> impl Strategy<Value = f32> {
        prop_oneof![
            Just(0.0f32),
            Just(-0.0),
            Just(f32::INFINITY),
            Just(f32::NEG_INFINITY),
            Just(1.0e30),
            Just(-1.0e30),
            Just(f32::MIN_POSITIVE),
            -1.0e3f32..1.0e3,
            any::<f32>().prop_filter("not NaN", |x| !x.is_nan()),
        ]
    }

    fn lanes() -> impl Strategy<Value = [f32; W]> {
        proptest::array::uniform8(value())
    }

    /// Every operation of one back end, as bits.
    fn all_ops<L: Lanes>(l: L, a: [f32; W], b: [f32; W], m: [f32; W]) -> Vec<[u32; W]> {
        let (va, vb) = (l.load(a), l.load(b));
        let vm = l.lt(l.load(m), l.splat(0.0));
        let out = [
            l.add(va, vb),
            l.sub(va, vb),
            l.mul(va, vb),
            l.div(va, vb),
            l.min(va, vb),
            l.max(va, vb),
            l.abs(va),
            l.lt(va, vb),
            l.le(va, vb),
            l.eq(va, vb),
            l.gt(va, vb),
            l.ge(va, vb),
            l.is_finite(va),
            l.and(l.lt(va, vb), vm),
            l.or(l.lt(va, vb), vm),
            l.and_not(l.le(va, vb), vm),
            l.select(vm, va, vb),
            l.splat(a[3]),
        ];
        let mut bits: Vec<[u32; W]> = out
            .into_iter()
            .map(|v| l.store(v).map(f32::to_bits))
            .collect();
        bits.push([l.bitmask(vm), l.bitmask(l.lt(va, vb)), 0, 0, 0, 0, 0, 0]);
        bits
    }

    proptest! {
        /// The SIMD back ends equal the scalar reference bit for bit on
        /// every operation (NaN-free inputs, as in the kernel; quotients
        /// may still be NaN, e.g. 0 / 0, and must agree too).
        #[test]
        fn back_ends_equal_the_reference(a in lanes(), b in lanes(), m in lanes()) {
            let reference = all_ops(Reference, a, b, m);
            prop_assert_eq!(&all_ops(Portable, a, b, m), &reference);
            #[cfg(target_arch = "x86_64")]
            if let Some(v3) = avx2_token() {
                prop_assert_eq!(&all_ops(Avx2(v3), a, b, m), &reference);
            }
        }
    }

    #[test]
    fn auto_resolves_to_an_available_kernel() {
        let k = RenderKernel::Auto.resolve();
        assert!(k != RenderKernel::Auto && k.is_available());
        assert!(RenderKernel::Reference.is_available() && RenderKernel::Portable.is_available());
    }
}
