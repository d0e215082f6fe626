//! Run-time choice of the arithmetic of the particle passes: a portable build and an
//! AVX2/FMA build of the same source (`algorithm.md` §2 allows a CPU-feature dispatch). The
//! types live in the core's one `math` module ([`fracture_mpm::math`], the audited `unsafe`
//! module of `style.md`); this module re-exports them under the 2D solver's name.
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

pub use fracture_mpm::math::{Arith, Fma, Kernel, Portable, fma_available, madd};
