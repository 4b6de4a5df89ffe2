//! Runtime choice of wider vector instructions for the product paths: on an
//! x86-64 CPU with AVX2, each band of a product runs in a copy of the kernel's band
//! loop compiled with AVX2 enabled; elsewhere, the portable kernel function.
//!
//! **Same bits.** The band loops ([`parallel::product_band`], [`parallel::free_band`],
//! [`reduced::apply_band`]) are `#[inline(always)]`, so each is compiled a second time
//! inside a function here that carries `#[target_feature(enable = "avx2")]`: the same
//! Rust arithmetic in the same order, only with wider registers (and VEX encodings)
//! available. Rust never contracts `a * b + c` into a fused multiply-add (nor does this
//! module enable `fma`), and AVX2's `f64`/`f32` lanes round as SSE2's do, so every
//! output has the portable build's bits (`tests/parallel/block.rs` compares them).
//!
//! **The `unsafe`.** Calling a `target_feature` function from code compiled without the
//! feature is `unsafe`: the caller must know the CPU has it. Each call here is made
//! only after [`avx2`] has said so (`is_x86_feature_detected!`, cached by std). The
//! kernel itself keeps `forbid(unsafe_code)`.
//!
//! What this reaches: the three product paths' bands, which `hydrorattle_parallel`
//! owns. A whole step is generic code spread over many functions that are not all
//! inlined; a `target_feature` wrapper around it would widen only what the optimiser
//! happens to inline, so whole steps get AVX2 from the x86-64-v3 build
//! (`.cargo/x86-64-v3.toml`, docs/BENCHMARKS.md) instead.

use hydrorattle::linalg::Block;
use hydrorattle::noise::reduced;
use hydrorattle::parallel::{self, Parallel};
use hydrorattle::{Hydro, ParticleError};

/// Vectors of `f64` (`glam::DVec3`) and blocks (`glam::DMat3`, the compact copy's slots).
type V3 = <f64 as hydrorattle::Real>::V3;
type M3 = <f64 as hydrorattle::Real>::M3;

/// Whether this CPU runs the AVX2 copies (always `false` off x86-64). Setting the
/// environment variable `HYDRORATTLE_PORTABLE` (to anything) turns them off, for a
/// comparison on the same machine.
pub fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        static ON: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        *ON.get_or_init(|| {
            std::env::var_os("HYDRORATTLE_PORTABLE").is_none()
                && std::is_x86_feature_detected!("avx2")
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// [`parallel::products`] in `f64` (symmetric blocks, `hydrorattle::linalg::Sym`, or
/// general ones), each band in the AVX2 copy when [`avx2`] holds: the same bits.
pub fn products<const K: usize>(
    par: &dyn Parallel,
    a: &[impl Block<f64>],
    n: usize,
    x: [&[V3]; K],
    y: [&mut [V3]; K],
    z: &mut [V3],
) {
    #[cfg(target_arch = "x86_64")]
    if avx2() {
        let _ = parallel::by_bands_then_reduce::<f64, (), K>(par, n, y, z, |t, yt, zt| {
            // SAFETY: `avx2()` checked that this CPU has AVX2.
            unsafe { x86::product_band::<_, K>(a, n, t, x, yt, zt) };
            Ok(())
        });
        return;
    }
    parallel::products::<f64, K>(par, a, n, x, y, z);
}

/// [`parallel::free_products`] in `f64` (the recompute path), each band in the AVX2
/// copy when [`avx2`] holds: the same bits and errors.
#[allow(clippy::too_many_arguments)]
pub fn free_products<const K: usize>(
    par: &dyn Parallel,
    level: Hydro,
    eta: f64,
    pos: &[V3],
    radius: &[f64],
    x: [&[V3]; K],
    y: [&mut [V3]; K],
    z: &mut [V3],
) -> Result<(), ParticleError> {
    #[cfg(target_arch = "x86_64")]
    if avx2() {
        let n = pos.len();
        return parallel::by_bands_then_reduce::<f64, _, K>(par, n, y, z, |t, yt, zt| {
            // SAFETY: `avx2()` checked that this CPU has AVX2.
            unsafe { x86::free_band::<K>((level, eta, pos, radius), t, x, yt, zt) }
        });
    }
    parallel::free_products::<f64, K>(par, level, eta, pos, radius, x, y, z)
}

/// [`reduced::apply_k`] in `f64` (the compact `f32` copy), each band in the AVX2 copy
/// when [`avx2`] holds: the same bits.
pub fn compact_products<const K: usize>(
    par: &dyn Parallel,
    copy: &[M3],
    n: usize,
    x: [&[V3]; K],
    y: [&mut [V3]; K],
    z: &mut [V3],
) {
    #[cfg(target_arch = "x86_64")]
    if avx2() {
        let _ = parallel::by_bands_then_reduce::<f64, (), K>(par, n, y, z, |t, yt, zt| {
            // SAFETY: `avx2()` checked that this CPU has AVX2.
            unsafe { x86::apply_band::<K>(copy, n, t, x, yt, zt) };
            Ok(())
        });
        return;
    }
    reduced::apply_k::<f64, K>(par, copy, n, x, y, z);
}

/// The AVX2 copies: the kernel's inlined band loops compiled with the feature on.
#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::{M3, V3};
    use hydrorattle::linalg::Block;
    use hydrorattle::noise::reduced;
    use hydrorattle::parallel;
    use hydrorattle::{Hydro, ParticleError};

    /// [`parallel::product_band`] with AVX2. Safety: the CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn product_band<B: Block<f64>, const K: usize>(
        a: &[B],
        n: usize,
        t: usize,
        x: [&[V3]; K],
        y: [&mut [V3]; K],
        z: [&mut [V3]; K],
    ) {
        parallel::product_band::<f64, K>(a, n, t, x, y, z);
    }

    /// [`parallel::free_band`] with AVX2. Safety: the CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn free_band<const K: usize>(
        pairs: (Hydro, f64, &[V3], &[f64]),
        t: usize,
        x: [&[V3]; K],
        y: [&mut [V3]; K],
        z: [&mut [V3]; K],
    ) -> Result<(), ParticleError> {
        parallel::free_band::<f64, K>(pairs, t, x, y, z)
    }

    /// [`reduced::apply_band`] with AVX2. Safety: the CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn apply_band<const K: usize>(
        copy: &[M3],
        n: usize,
        t: usize,
        x: [&[V3]; K],
        y: [&mut [V3]; K],
        z: [&mut [V3]; K],
    ) {
        reduced::apply_band::<f64, K>(copy, n, t, x, y, z);
    }
}
