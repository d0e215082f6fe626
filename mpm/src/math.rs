//! The core's one `math` module: the arithmetic of the particle passes (a portable build and
//! an AVX2/FMA build of the same source, chosen at run time: `algorithm.md` §2 allows a
//! CPU-feature dispatch; the one audited `unsafe` module of `style.md`), and the float
//! helpers of the hot loops.
//!
//! The passes are written once, generic over `Arith`: every product-and-sum of a transfer
//! kernel (P2G, velocity gradient, force scatter, FLIP gather, re-extrapolation, stress
//! update) goes through `madd`, which is `a·b + c` with two roundings in the `Portable`
//! build (bitwise the results of the solver before the dispatch existed) and one fused
//! rounding in the `Fma` build. `Arith::run` runs a strip's loop: for `Fma` inside a
//! function compiled with `avx2,fma` enabled, so the loop (inlined into it) uses the FMA
//! instructions and the VEX encodings.
//!
//! The two builds differ in the last bits of every fused product-and-sum (one rounding
//! instead of two: at most ½ ulp per operation); each is deterministic and independent of the
//! thread count on its own (`tests/kernels.rs`).

/// Which arithmetic the particle passes use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Kernel {
    /// Plain `a·b + c` (two roundings): the same results on every x86-64 (and other) CPU.
    #[default]
    Portable,
    /// Fused multiply-add with AVX2 encodings; only where the CPU has AVX2 and FMA.
    Fma,
}

impl Kernel {
    /// The fastest kernel this CPU runs: [`Kernel::Fma`] where AVX2 and FMA are present.
    pub fn detect() -> Kernel {
        if fma_available() {
            Kernel::Fma
        } else {
            Kernel::Portable
        }
    }

    /// Whether this CPU can run the kernel.
    pub fn available(self) -> bool {
        match self {
            Kernel::Portable => true,
            Kernel::Fma => fma_available(),
        }
    }

    /// Name (`portable`, `fma`).
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Portable => "portable",
            Kernel::Fma => "fma",
        }
    }
}

/// Whether the CPU has AVX2 and FMA (cached by the standard library after the first call).
pub fn fma_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The arithmetic of one build of the passes.
pub trait Arith: Copy + Send + Sync + 'static {
    /// `a·b + c` with one rounding.
    const FMA: bool;
    /// Run `f` (a strip's loop) compiled for this arithmetic.
    fn run<R>(f: impl FnOnce() -> R) -> R;
}

/// `a·b + c`: fused (one rounding) in the `Fma` build, two roundings in `Portable`.
#[inline(always)]
pub fn madd<A: Arith>(a: f64, b: f64, c: f64) -> f64 {
    if A::FMA { a.mul_add(b, c) } else { a * b + c }
}

/// The portable build.
#[derive(Debug, Clone, Copy)]
pub struct Portable;

/// The AVX2/FMA build.
#[derive(Debug, Clone, Copy)]
pub struct Fma;

impl Arith for Portable {
    const FMA: bool = false;
    #[inline(always)]
    fn run<R>(f: impl FnOnce() -> R) -> R {
        f()
    }
}

impl Arith for Fma {
    const FMA: bool = true;
    #[inline(always)]
    fn run<R>(f: impl FnOnce() -> R) -> R {
        #[cfg(target_arch = "x86_64")]
        {
            // Checked here, once per strip (a cached flag), so that no caller can reach the
            // feature-enabled code on a CPU without the features.
            assert!(
                fma_available(),
                "the FMA kernel needs a CPU with AVX2 and FMA"
            );
            // SAFETY: `with_avx2_fma` is only a `#[target_feature]` wrapper; calling it is sound
            // when the CPU has those features, which the assertion above has just checked.
            #[allow(unsafe_code)]
            unsafe {
                with_avx2_fma(f)
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            // `mul_add` is still exact-fused (in software where there is no instruction).
            f()
        }
    }
}

/// Call `f` inside a function compiled with AVX2 and FMA enabled: `f`, called once here and
/// built from `#[inline(always)]` pieces, is inlined and compiled with those features.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn with_avx2_fma<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// `x.floor() as i64` for every x (NaN gives 0, out-of-range values saturate) without the
/// out-of-line libm `floor` of baseline x86-64: the truncating cast, one down where it
/// rounded up (negative non-integers).
#[inline(always)]
pub fn floor_i64(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) > x {
        i.saturating_sub(1)
    } else {
        i
    }
}

/// floor(x) as a float and as an integer, for |x| < 2³¹: the low 32 bits of x + 1.5·2⁵²
/// hold round(x) (a saturating `as i32` cast costs a dozen instructions).
#[inline(always)]
pub fn floor_both(x: f64) -> (f64, i32) {
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    let t = x + MAGIC;
    let r = t - MAGIC;
    let i = t.to_bits() as u32 as i32;
    if r > x { (r - 1.0, i - 1) } else { (r, i) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn portable_rounds_twice_fma_once() {
        // a·b = 1 − 2⁻⁶⁰ exactly: two roundings give 1 − 1 = 0, one rounding gives −2⁻⁶⁰.
        let a = 1.0 + 2f64.powi(-30);
        let b = 1.0 - 2f64.powi(-30);
        let c = -1.0;
        assert_eq!(madd::<Portable>(a, b, c), a * b + c);
        assert_eq!(madd::<Portable>(a, b, c), 0.0);
        if fma_available() {
            let r = Fma::run(|| madd::<Fma>(a, b, c));
            assert_eq!(r, -(2f64.powi(-60)));
        }
    }

    #[test]
    fn detect_picks_an_available_kernel() {
        assert!(Kernel::detect().available());
        assert!(Kernel::Portable.available());
    }

    #[test]
    fn floor_i64_matches_floor_cast_at_the_edges() {
        for x in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            -1.0,
            1.0 - f64::EPSILON,
            -f64::MIN_POSITIVE,
            4_503_599_627_370_495.5,
            -4_503_599_627_370_495.5,
            9.3e18,
            -9.3e18,
            9_223_372_036_854_775_807.0,
            -9_223_372_036_854_775_808.0,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ] {
            assert_eq!(floor_i64(x), x.floor() as i64, "x = {x:e}");
        }
    }

    proptest! {
        #[test]
        fn floor_i64_is_floor(x in proptest::num::f64::ANY) {
            prop_assert_eq!(floor_i64(x), x.floor() as i64);
        }
    }
}
