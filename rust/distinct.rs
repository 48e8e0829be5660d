//! Functions of P_D (its log, the log of 1 − P_D) through a table of its distinct values.
//!
//! P_D at a point is a product of a few constants (band values, sector values, 0 on land or
//! out of sight), so over 10⁵ particles of one scan it takes only a handful of distinct
//! values. A function of P_D is evaluated once per distinct value and looked up per
//! particle: cheaper than a `ln` per particle, and the caller picks the function. The
//! binding fills the table with NumPy's `log`, whose AVX-512 kernel differs from libm's
//! `ln` in the last bit for some inputs (0.917 among them), so the particle updaters keep
//! NumPy's bits on every CPU; [`ln_in_place`] is the pure-Rust form.

use crate::batch::{for_each_chunk, CHUNK};
use crate::error::{ModelError, Result};

/// More distinct values than this and a table stops paying: callers apply the function
/// to every element instead.
pub const MAX_DISTINCT: usize = 256;

/// Tables up to this size are applied by branch-free selects over a whole chunk
/// (vectorised); larger ones by a binary search per element.
const FAST: usize = 16;

/// The distinct values of an array: sorted by `f64::total_cmp`, compared by bits, so 0.0
/// and -0.0 are different entries. Never holds NaN.
#[derive(Debug, Clone, PartialEq)]
pub struct Distinct {
    values: Vec<f64>,
}

impl Distinct {
    /// The distinct values of `data`; `None` if it holds NaN or more than `cap` values.
    pub fn of(data: &[f64], cap: usize) -> Option<Distinct> {
        let mut table = Distinct { values: Vec::new() };
        for chunk in data.chunks(CHUNK) {
            // Nearly every chunk holds only values already found: one fast check.
            if table.holds_all(chunk) {
                continue;
            }
            for &v in chunk {
                if table.index(v).is_some() {
                    continue;
                }
                if v.is_nan() || table.values.len() == cap {
                    return None;
                }
                let at = table.values.partition_point(|t| t.total_cmp(&v).is_lt());
                table.values.insert(at, v);
            }
        }
        Some(table)
    }

    pub fn values(&self) -> &[f64] {
        self.values.as_slice()
    }

    /// The entry holding exactly `v` (same bits).
    fn index(&self, v: f64) -> Option<usize> {
        let at = self.values.partition_point(|t| t.total_cmp(&v).is_lt());
        (at < self.values.len() && self.values[at].to_bits() == v.to_bits()).then_some(at)
    }

    /// Whether every element of `data` is in the table (same bits).
    fn holds_all(&self, data: &[f64]) -> bool {
        if self.values.len() > FAST {
            return data.iter().all(|&v| self.index(v).is_some());
        }
        // Entries are distinct, so an element matches at most one: all are in the table when
        // the matches add up to the length. Branch-free passes, as in `select`.
        let mut matched = 0u64;
        for t in &self.values {
            let bits = t.to_bits();
            matched += data.iter().map(|v| (v.to_bits() == bits) as u64).sum::<u64>();
        }
        matched == data.len() as u64
    }

    /// out[i] = image[j] where values()[j] is data[i] (same bits); false if some element is
    /// not in the table (then `out` is meaningless).
    fn select(&self, data: &[f64], image: &[f64], out: &mut [f64]) -> bool {
        if self.values.len() > FAST {
            for (o, &v) in out.iter_mut().zip(data) {
                match self.index(v) {
                    Some(j) => *o = image[j],
                    None => return false,
                }
            }
            return true;
        }
        // One branch-free pass per entry over the whole chunk (vectorises): compare bits,
        // blend in the entry's image. Entries are distinct, so an element matches at most
        // one: all are found when the matches add up to the chunk's length.
        let n = data.len();
        let out = &mut out[..n];
        // The blend is written as a bit mask: an `if` compiles to a branch that mispredicts
        // on interleaved values (~7 ns each).
        let mut matched = 0u64;
        for (t, &y) in self.values.iter().zip(image) {
            let (bits, y) = (t.to_bits(), y.to_bits());
            for i in 0..n {
                let mask = ((data[i].to_bits() == bits) as u64).wrapping_neg();
                out[i] = f64::from_bits((out[i].to_bits() & !mask) | (y & mask));
                matched += mask & 1;
            }
        }
        matched == n as u64
    }

    /// values[i] = image[j] where values()[j] is values[i]: `image` holds f(values()[j]), so
    /// this applies f in place. Every element must be in the table; one that is not is an
    /// error naming it (the elements before it may have been replaced).
    pub fn apply(&self, values: &mut [f64], image: &[f64]) -> Result<()> {
        if image.len() != self.values.len() {
            return Err(ModelError::shape(
                "image",
                format!(
                    "must have {} entries (one per table value), got {}",
                    self.values.len(),
                    image.len()
                ),
            ));
        }
        let missing = for_each_chunk(values, |_, chunk| {
            let mut out = [0.0; CHUNK];
            let out = &mut out[..chunk.len()];
            if self.select(chunk, image, out) {
                chunk.copy_from_slice(out);
                return None;
            }
            // Some value is not in the table: find the first, per element.
            for (i, v) in chunk.iter_mut().enumerate() {
                match self.index(*v) {
                    Some(j) => *v = image[j],
                    None => return Some(i),
                }
            }
            None
        });
        match missing {
            Some(i) => Err(ModelError::invalid(
                "values",
                format!("element {i} is not in the table"),
            )),
            None => Ok(()),
        }
    }
}

/// `values[i] = ln(values[i])` (ln 0 = -inf), ln taken once per distinct value where there
/// are few: the core's own log P_D. Bit for bit the per-element `f64::ln`.
pub fn ln_in_place(values: &mut [f64]) {
    let table = Distinct::of(values, MAX_DISTINCT);
    if let Some(table) = table {
        // (a table holds at most MAX_DISTINCT values)
        let image: Vec<f64> = table.values().iter().map(|v| v.ln()).collect();
        if table.apply(values, &image).is_ok() {
            return;
        }
    }
    // Many distinct values (the table's error cannot happen: they are its own values).
    values.iter_mut().for_each(|v| *v = v.ln());
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Any data (signed zeros, NaN, ±inf, few or many distinct values, lengths across
        /// chunks): the table holds exactly the distinct bit patterns, or is refused for NaN
        /// or too many; applying a function through it is applying it per element.
        #[test]
        fn a_table_is_its_distinct_values_and_apply_is_per_element(
            pool in prop::collection::vec(prop_oneof![
                4 => (0u32..1000).prop_map(|k| f64::from(k) / 999.0),
                1 => Just(-0.0), 1 => Just(0.0), 1 => Just(f64::NAN),
                1 => Just(f64::INFINITY), 1 => Just(f64::NEG_INFINITY)], 1..40),
            picks in prop::collection::vec(any::<prop::sample::Index>(), 0..3000),
            cap in prop_oneof![Just(MAX_DISTINCT), 1usize..20],
        ) {
            let data: Vec<f64> = picks.iter().map(|i| pool[i.index(pool.len())]).collect();
            let mut distinct: Vec<u64> = data.iter().map(|v| v.to_bits()).collect();
            distinct.sort_unstable();
            distinct.dedup();
            match Distinct::of(&data, cap) {
                None => prop_assert!(data.iter().any(|v| v.is_nan()) || distinct.len() > cap),
                Some(table) => {
                    let mut held: Vec<u64> = table.values().iter().map(|v| v.to_bits()).collect();
                    held.sort_unstable();
                    prop_assert_eq!(held, distinct);
                    let image: Vec<f64> = table.values().iter().map(|v| (v * 3.0 + 1.0).ln()).collect();
                    let mut got = data.clone();
                    table.apply(&mut got, &image).unwrap();
                    for (g, v) in got.iter().zip(&data) {
                        prop_assert_eq!(g.to_bits(), (v * 3.0 + 1.0).ln().to_bits());
                    }
                }
            }
        }
    }

    #[test]
    fn distinct_values_sorted_by_bits() {
        let data = [0.4, 0.0, 0.4, 1.0, -0.0, 0.0, 0.38, 0.4];
        let table = Distinct::of(&data, 10).unwrap();
        let bits: Vec<u64> = table.values().iter().map(|v| v.to_bits()).collect();
        assert_eq!(
            bits,
            [-0.0f64, 0.0, 0.38, 0.4, 1.0]
                .iter()
                .map(|v| v.to_bits())
                .collect::<Vec<_>>()
        );
        assert_eq!(table.index(-0.0), Some(0));
        assert_eq!(table.index(0.0), Some(1));
        assert_eq!(table.index(0.5), None);
        assert_eq!(Distinct::of(&data, 4), None); // five distinct values
                                                  // -0.0 and 0.0 compare equal: the exact search tells them apart.
        let mut out = data;
        table.apply(&mut out, &[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
        assert_eq!(out, [4.0, 2.0, 4.0, 5.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(Distinct::of(&[0.1, f64::NAN], 10), None);
        assert_eq!(Distinct::of(&[], 10).unwrap().values(), &[] as &[f64]);
    }

    #[test]
    fn more_values_than_the_fast_entries() {
        // 40 distinct values, the later ones found by binary search; in scrambled order.
        let data: Vec<f64> = (0..4000).map(|k| ((k * 7919) % 40) as f64 / 40.0).collect();
        let table = Distinct::of(&data, MAX_DISTINCT).unwrap();
        assert_eq!(table.values().len(), 40);
        let image: Vec<f64> = table.values().iter().map(|v| v * 3.0).collect();
        let mut out = data.clone();
        table.apply(&mut out, &image).unwrap();
        for (d, o) in data.iter().zip(&out) {
            assert_eq!(*o, d * 3.0);
        }
    }

    #[test]
    fn apply_reports_a_value_not_in_the_table() {
        let table = Distinct::of(&[0.2, 0.4], 4).unwrap();
        let mut values = [0.4, 0.3, 0.2];
        let err = table.apply(&mut values, &[1.0, 2.0]).unwrap_err();
        assert_eq!(err, ModelError::invalid("values", "element 1 is not in the table"));
        assert_eq!(table.apply(&mut [0.4], &[1.0]).unwrap_err().argument(), "image");
        let mut values = [0.4, 0.2, 0.4];
        table.apply(&mut values, &[1.0, 2.0]).unwrap();
        assert_eq!(values, [2.0, 1.0, 2.0]);
        // Past the parallel threshold, the first missing element over all chunks.
        let mut values = vec![0.2; 100_000];
        values[70_123] = 0.5;
        values[90_000] = 0.5;
        let err = table.apply(&mut values, &[1.0, 2.0]).unwrap_err();
        assert_eq!(err, ModelError::invalid("values", "element 70123 is not in the table"));
    }

    #[test]
    fn ln_in_place_is_per_element_ln() {
        // Few distinct values (the table), then many (the per-element fallback), over enough
        // elements to run in parallel chunks.
        for distinct in [5usize, 1000] {
            let data: Vec<f64> = (0..100_003)
                .map(|k| ((k * 31) % distinct) as f64 / distinct as f64)
                .collect();
            let mut got = data.clone();
            ln_in_place(&mut got);
            for (d, g) in data.iter().zip(&got) {
                assert_eq!(g.to_bits(), d.ln().to_bits(), "ln({d})");
            }
            assert_eq!(got[0], f64::NEG_INFINITY); // ln 0
        }
    }
}
