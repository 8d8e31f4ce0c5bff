//! A deterministic sequence of numbers for the geometry's tests (jittered
//! meshes, random configurations), the same on every platform.

/// The numbers in `[0, 1)` of a 64-bit linear congruential generator started
/// at `seed`, each from its 53 highest bits.
pub(crate) fn numbers(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}
