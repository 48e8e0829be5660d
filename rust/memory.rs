//! Fallible allocation for every buffer whose size a caller controls (grids, per-cell and
//! per-input arrays, trees, scan buffers): a size that overflows or memory the allocator
//! refuses is a [`ModelError::Memory`] naming the argument that asked for it, which the
//! binding raises as Python's MemoryError, where `vec![..; n]` would abort the process.

use crate::error::{ModelError, Result};

/// The bytes `n` values of `T` need (saturating: only reported).
fn bytes_of<T>(n: usize) -> u128 {
    n as u128 * std::mem::size_of::<T>().max(1) as u128
}

/// An empty vector with room for exactly `n` values.
pub(crate) fn with_room<T>(argument: &'static str, n: usize) -> Result<Vec<T>> {
    let mut values = Vec::new();
    values
        .try_reserve_exact(n)
        .map_err(|_| ModelError::memory(argument, bytes_of::<T>(n)))?;
    Ok(values)
}

/// `n` copies of `fill`.
pub(crate) fn filled<T: Clone>(argument: &'static str, n: usize, fill: T) -> Result<Vec<T>> {
    let mut values = with_room(argument, n)?;
    values.resize(n, fill);
    Ok(values)
}

/// The values of `iter`, with room reserved for the most it says it can yield (every
/// caller passes an iterator whose upper bound is exact, so `extend` never grows it).
pub(crate) fn collected<T>(argument: &'static str, iter: impl IntoIterator<Item = T>) -> Result<Vec<T>> {
    let iter = iter.into_iter();
    let (lower, upper) = iter.size_hint();
    let mut values = with_room(argument, upper.unwrap_or(lower))?;
    values.extend(iter);
    Ok(values)
}

/// A copy of `values`.
#[cfg_attr(not(feature = "python"), allow(dead_code))]
pub(crate) fn copied<T: Clone>(argument: &'static str, values: &[T]) -> Result<Vec<T>> {
    let mut copy = with_room(argument, values.len())?;
    copy.extend_from_slice(values);
    Ok(copy)
}

/// The product of `factors` (a buffer's length), refused when it overflows usize.
pub(crate) fn product(argument: &'static str, factors: &[usize]) -> Result<usize> {
    factors
        .iter()
        .try_fold(1usize, |total, f| total.checked_mul(*f))
        .ok_or_else(|| {
            let bytes = factors.iter().fold(1u128, |total, f| total.saturating_mul(*f as u128));
            ModelError::memory(argument, bytes.saturating_mul(8))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn too_much_memory_is_an_error_naming_the_argument() {
        let err = filled::<f64>("edges", usize::MAX / 4, 0.0).unwrap_err();
        assert_eq!(err, ModelError::memory("edges", (usize::MAX / 4) as u128 * 8));
        assert!(err.to_string().starts_with("edges: needs "), "{err}");
        assert_eq!(with_room::<u8>("gates", usize::MAX).unwrap_err().argument(), "gates");
        assert_eq!(product("edges", &[usize::MAX, 2]).unwrap_err().argument(), "edges");
        assert_eq!(product("edges", &[3, 4]).unwrap(), 12);
    }

    #[test]
    fn the_helpers_give_what_the_infallible_forms_give() {
        assert_eq!(filled("n", 3, 1.5).unwrap(), vec![1.5; 3]);
        assert_eq!(collected("n", (0..4).map(|i| i * 2)).unwrap(), vec![0, 2, 4, 6]);
        assert_eq!(copied("n", &[1, 2]).unwrap(), vec![1, 2]);
        assert_eq!(with_room::<f64>("n", 7).unwrap().capacity(), 7);
    }
}
