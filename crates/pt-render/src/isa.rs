//! Running a method's inner loop compiled for the processor's wider instructions.
//!
//! The binary is built for baseline x86-64 (SSE2) so that it runs on any x86-64 machine, a
//! cluster's older nodes included. On x86-64-v3 processors (AVX2, FMA, BMI: Intel since 2013,
//! AMD since 2015) each method's per-sample work runs compiled for those instructions instead,
//! chosen at run time: [`best`] calls its closure from a function compiled for them, and the
//! closure's body and whatever it inlines (traversal, BSDFs, lights) are compiled into that
//! function. A function left outlined keeps the baseline instructions, so the methods' hot
//! routines are `#[inline(always)]`. One left outlined shows in `perf report --sort sym` as a
//! symbol of its own beside `run_v3`: the suite's scenes were checked so (environment maps,
//! sky, spectra, volume grids, hair, rough plastic and dielectrics had 5-40% of their samples
//! outside it, and run 3-14% faster inside). Those routines carry the attribute in release
//! builds only (`#[cfg_attr(not(debug_assertions), inline(always))]`): inlined everywhere they
//! made the tests' build (which keeps debug assertions) take 9.5 minutes instead of 6.5, and the
//! results are the same bits either way (`v3_variants_match_portable_bit_for_bit`). Measured (2026-12-05, `farm-bench` pairs, whole
//! process): building everything for x86-64-v3 made BDPT on the Cornell box 1.42x and
//! `volpath` in fog 2.17x faster than this baseline build, the light tracer 1.12x.
//!
//! Images are bit-identical either way: Rust never fuses a multiply and an add on its own, and
//! glam and libm choose their code paths the same way under both.

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by [`force_baseline`].
static BASELINE_ONLY: AtomicBool = AtomicBool::new(false);

/// From now on, [`best`] runs the baseline variant (`true`) or the best one the processor has
/// (`false`, the default), on every thread: for the tests and benchmarks that compare the two,
/// which must give the same bits.
pub fn force_baseline(on: bool) {
    BASELINE_ONLY.store(on, Ordering::Relaxed);
}

/// Runs `work`, compiled for x86-64-v3 when this processor has it (the check is made once by
/// std and cached) and for baseline x86-64 otherwise. Callers pass a closure marked
/// `#[inline(always)]`, so that its body is compiled into each variant.
#[inline(always)]
pub fn best<R>(work: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if has_x86_64_v3() && !BASELINE_ONLY.load(Ordering::Relaxed) {
        // SAFETY: the processor supports every feature `run_v3` is compiled for.
        #[allow(unsafe_code)]
        return unsafe { run_v3(work) };
    }
    work()
}

/// Calls `work` from code compiled for x86-64-v3 (AVX2, FMA, BMI1/2, LZCNT, POPCNT, MOVBE);
/// `work`'s body is inlined here. Callers must check [`has_x86_64_v3`] first.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,movbe")]
fn run_v3<R>(work: impl FnOnce() -> R) -> R {
    work()
}

/// Whether this processor has the x86-64-v3 features [`best`] compiles for
/// (detected once by std and cached): every method's inner loop and the traversal benchmarks run
/// code compiled for them when it has.
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn has_x86_64_v3() -> bool {
    std::is_x86_feature_detected!("avx2")
        && std::is_x86_feature_detected!("fma")
        && std::is_x86_feature_detected!("bmi1")
        && std::is_x86_feature_detected!("bmi2")
        && std::is_x86_feature_detected!("lzcnt")
        && std::is_x86_feature_detected!("popcnt")
        && std::is_x86_feature_detected!("movbe")
}
