//! The known per-axis noise of each calibration sample ([`Sigmas`]), held once while every
//! sample has the same: a large set usually gives every row one sigma, and a list of them
//! costs 32 bytes per sample (64 MB on 2 000 000 samples).

use nalgebra::Vector3;

/// The per-axis standard deviation (metres) of each calibration sample, `None` where the
/// sample gives none, in sample order. Bit for bit the values pushed: a run of equal values
/// (equal bits) from the first sample on is held as one value and a count.
#[derive(Clone, Debug, Default)]
pub(crate) struct Sigmas {
    /// The value of every sample while they are all the same (equal bits).
    same: Option<Option<Vector3<f64>>>,
    /// The number of samples.
    len: usize,
    /// Each sample's value, once two differ (then `same` is `None`).
    each: Vec<Option<Vector3<f64>>>,
}

/// Whether `a` and `b` have the same bits (so `-0.0` and `0.0` differ and a NaN equals itself).
fn same_bits(a: &Option<Vector3<f64>>, b: &Option<Vector3<f64>>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => a
            .iter()
            .zip(b.iter())
            .all(|(x, y)| x.to_bits() == y.to_bits()),
        _ => false,
    }
}

impl Sigmas {
    /// Appends the sigma of the next sample.
    pub(crate) fn push(&mut self, s: Option<Vector3<f64>>) {
        match &self.same {
            _ if self.len == 0 => self.same = Some(s),
            Some(v) if same_bits(v, &s) => {}
            Some(v) => {
                // The first differing value: every sample so far had `v`.
                let v = *v;
                self.each = Vec::with_capacity(self.len + 1);
                self.each.resize(self.len, v);
                self.each.push(s);
                self.same = None;
            }
            None => self.each.push(s),
        }
        self.len += 1;
    }

    /// The sigma of sample `i` (panics out of range, as a slice would).
    pub(crate) fn get(&self, i: usize) -> Option<Vector3<f64>> {
        assert!(i < self.len, "sample {i} of {}", self.len);
        match self.same {
            Some(v) => v,
            None => self.each[i],
        }
    }

    /// Each sample's sigma, in order.
    pub(crate) fn iter(&self) -> impl Iterator<Item = Option<Vector3<f64>>> + '_ {
        (0..self.len).map(|i| self.get(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn collected(values: &[Option<Vector3<f64>>]) -> Sigmas {
        let mut s = Sigmas::default();
        for v in values {
            s.push(*v);
        }
        s
    }

    #[test]
    fn the_values_come_back_in_order() {
        let a = Some(Vector3::new(1e-5, 2e-5, 3e-5));
        let b = Some(Vector3::new(1e-5, 2e-5, 4e-5));
        for values in [
            vec![],
            vec![a],
            vec![a, a, a],
            vec![None, None],
            vec![a, a, b, a],
            vec![None, a],
            vec![a, None, a],
        ] {
            let s = collected(&values);
            assert_eq!(s.iter().count(), values.len());
            assert_eq!(s.iter().collect::<Vec<_>>(), values);
            for (i, v) in values.iter().enumerate() {
                assert_eq!(s.get(i), *v);
            }
        }
    }

    #[test]
    fn equal_values_are_held_once_and_bits_decide() {
        let a = Some(Vector3::new(5e-5, 5e-5, 5e-5));
        let s = collected(&[a; 1000]);
        assert!(s.each.is_empty());
        // 0.0 and -0.0 are equal numbers with different bits: both are kept as given.
        let z = Some(Vector3::new(0.0, 0.0, 0.0));
        let nz = Some(Vector3::new(-0.0, 0.0, 0.0));
        let s = collected(&[z, nz]);
        assert_eq!(s.get(1).unwrap()[0].to_bits(), (-0.0f64).to_bits());
        assert_eq!(s.get(0).unwrap()[0].to_bits(), 0.0f64.to_bits());
    }

    #[test]
    #[should_panic(expected = "sample 3 of 3")]
    fn out_of_range_panics() {
        collected(&[None, None, None]).get(3);
    }
}
