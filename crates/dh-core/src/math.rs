//! Elementary functions computed by the same code on every platform: the `libm` crate (Rust's
//! port of musl's libm), not the platform's (glibc on Linux, Rust's own port in WebAssembly),
//! so that the CLI and the web page compute the same bits where these are used.
//!
//! Used in the forward kinematics of the proofs (`Chain::fk`, [`crate::PreparedFk`]): there
//! `libm`'s `sincos` also costs fewer instructions than glibc's (about 100 against 135 a call,
//! callgrind on x86-64).

/// `(sin x, cos x)` of `x` in radians, with one argument reduction for both.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_the_platform_within_an_ulp() {
        for k in -2000..=2000 {
            let x = f64::from(k) * 0.00377;
            let (s, c) = sin_cos(x);
            let (s0, c0) = x.sin_cos();
            assert!(
                (s - s0).abs() <= f64::EPSILON * s0.abs().max(1e-300),
                "sin {x}"
            );
            assert!(
                (c - c0).abs() <= f64::EPSILON * c0.abs().max(1e-300),
                "cos {x}"
            );
        }
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
    }
}
