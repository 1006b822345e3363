//! Pose groups: the calibration samples that name the same pose (`config`), or without a name
//! share the same joint values bit for bit, numbered from 0 in order of first appearance.
//!
//! A set of millions of poses fills a map of millions of entries, whose look-ups miss the cache
//! one after the other. The samples are instead cut into shards by a bit field of their key's
//! hash (every sample of a pose in one shard): each shard's map, a fraction of the size, finds
//! the first sample of each of its samples' poses on a core of its own, and one pass in sample
//! order numbers the poses. The numbers are those of one map filled in sample order, whatever
//! the number of shards or threads.

use std::collections::HashMap;
use std::hash::{BuildHasher, BuildHasherDefault, Hash, Hasher};

use crate::data::CompactString;

/// What makes two calibration samples one pose: the same config name, or without one the
/// same joint values (row order, equal bits).
#[derive(Clone, Copy, Debug)]
pub(super) enum PoseKey<'a> {
    Named(&'a CompactString),
    Unnamed(&'a [f64]),
}

impl PoseKey<'_> {
    /// The key's hash by `state` (a named and an unnamed key never compare equal, whatever
    /// their hashes).
    pub(super) fn hash_by(&self, state: &impl BuildHasher) -> u64 {
        let mut h = state.build_hasher();
        match self {
            PoseKey::Named(name) => name.as_str().hash(&mut h),
            PoseKey::Unnamed(q) => {
                h.write_u8(1);
                for v in q.iter() {
                    h.write_u64(v.to_bits());
                }
            }
        }
        h.finish()
    }
}

/// A [`PoseKey`] and its hash, as a key of a map whose hasher passes the hash on
/// ([`Prehashed`]): the hash is made once, beside the samples.
#[derive(Clone, Copy, Debug)]
struct Hashed<'a> {
    hash: u64,
    key: PoseKey<'a>,
}

impl Hash for Hashed<'_> {
    fn hash<H: Hasher>(&self, state: &mut H) {
        state.write_u64(self.hash);
    }
}

impl PartialEq for Hashed<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.hash == other.hash
            && match (self.key, other.key) {
                (PoseKey::Named(a), PoseKey::Named(b)) => a == b,
                (PoseKey::Unnamed(a), PoseKey::Unnamed(b)) => {
                    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
                }
                _ => false,
            }
    }
}

impl Eq for Hashed<'_> {}

/// The hasher of [`Hashed`] keys: their hash as it is.
#[derive(Clone, Copy, Debug, Default)]
struct Prehashed(u64);

impl Hasher for Prehashed {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        // Only `write_u64` is called by `Hashed`; anything else is folded in, never ignored.
        for &b in bytes {
            self.0 = self.0.rotate_left(8) ^ u64::from(b);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = v;
    }
}

/// Shards per thread: enough that a slow shard does not hold the others up.
const SHARDS_PER_THREAD: usize = 8;

/// Below this many samples one map does the work (no shards, no threads).
const SHARDED_MIN: usize = 65_536;

/// The lowest bit of the hash's shard field: above the bits a map's bucket index takes (up to
/// 2³² buckets) and below the 7 top bits its control bytes take, so that a shard's map still
/// spreads and tells its keys apart.
const SHARD_SHIFT: u32 = 32;

/// The pose group of each sample `i` (key `key(i)`, whose hash by one hasher is `hashes[i]`),
/// numbered from 0 in order of first appearance, and the number of groups.
pub(super) fn pose_groups<'a>(
    key: &(impl Fn(usize) -> PoseKey<'a> + Sync),
    hashes: &[u64],
) -> (Vec<usize>, usize) {
    let n = hashes.len();
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    // The first sample of each sample's pose.
    let first: Vec<usize> = if n < SHARDED_MIN || threads == 1 {
        firsts(key, hashes, 0..n)
    } else {
        let shards = (threads * SHARDS_PER_THREAD).next_power_of_two();
        let shard_of = |h: u64| (h >> SHARD_SHIFT) as usize & (shards - 1);
        // Each shard's samples in sample order (a counting sort by shard).
        let mut starts = vec![0usize; shards + 1];
        for &h in &hashes[..n] {
            starts[shard_of(h) + 1] += 1;
        }
        for s in 0..shards {
            starts[s + 1] += starts[s];
        }
        let mut fill = starts.clone();
        let mut order = vec![0usize; n];
        for (i, &h) in hashes[..n].iter().enumerate() {
            let s = shard_of(h);
            order[fill[s]] = i;
            fill[s] += 1;
        }
        let found = dh_core::parallel::map(shards, |s| {
            firsts(key, hashes, order[starts[s]..starts[s + 1]].iter().copied())
        });
        match found {
            Some(found) => {
                let mut first = vec![0usize; n];
                for (s, f) in found.into_iter().enumerate() {
                    for (&i, v) in order[starts[s]..starts[s + 1]].iter().zip(f) {
                        first[i] = v;
                    }
                }
                first
            }
            // Only a lost result gets here (a worker's panic reaches the caller).
            None => firsts(key, hashes, 0..n),
        }
    };
    // A sample that is its pose's first opens the next group; the others take its group.
    let mut groups = Vec::with_capacity(n);
    let mut count = 0;
    for (i, &f) in first.iter().enumerate() {
        if f == i {
            groups.push(count);
            count += 1;
        } else {
            let g = groups[f];
            groups.push(g);
        }
    }
    (groups, count)
}

/// For each sample of `at` (in increasing order), the first sample of `at` with its key.
fn firsts<'a>(
    key: &impl Fn(usize) -> PoseKey<'a>,
    hashes: &[u64],
    at: impl ExactSizeIterator<Item = usize>,
) -> Vec<usize> {
    let mut map: HashMap<Hashed<'_>, usize, BuildHasherDefault<Prehashed>> =
        HashMap::with_capacity_and_hasher(at.len(), BuildHasherDefault::default());
    at.map(|i| {
        *map.entry(Hashed {
            hash: hashes[i],
            key: key(i),
        })
        .or_insert(i)
    })
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::hash_map::RandomState;

    /// The groups of keys numbered one at a time by a plain map of their values.
    fn by_one_map(keys: &[PoseKey<'_>]) -> (Vec<usize>, usize) {
        let mut ids: HashMap<String, usize> = HashMap::new();
        let groups = keys
            .iter()
            .map(|k| {
                let text = match k {
                    PoseKey::Named(c) => format!("n{c}"),
                    PoseKey::Unnamed(q) => {
                        format!("u{:?}", q.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
                    }
                };
                let next = ids.len();
                *ids.entry(text).or_insert(next)
            })
            .collect();
        (groups, ids.len())
    }

    /// Sharded or not, the groups are those of one map filled in sample order: names that
    /// repeat far apart and out of order, unnamed samples whose joint values repeat, a name
    /// equal to another key's text, and `0.0` against `-0.0` (different bits, different poses).
    #[test]
    fn sharded_groups_are_those_of_one_map() {
        let names: Vec<CompactString> = (0..5000)
            .map(|k| format!("pose {}", (k * 7919) % 3001).into())
            .collect();
        let values: Vec<[f64; 2]> = (0..700)
            .map(|k| match k % 3 {
                0 => [0.0, (k % 50) as f64],
                1 => [-0.0, (k % 50) as f64],
                _ => [0.25, 1e-300 * (k % 40) as f64],
            })
            .collect();
        for n in [10, SHARDED_MIN - 1, SHARDED_MIN + 4321] {
            let keys: Vec<PoseKey<'_>> = (0..n)
                .map(|i| {
                    if i % 5 == 2 {
                        PoseKey::Unnamed(&values[(i * 31) % values.len()])
                    } else {
                        PoseKey::Named(&names[(i * 13) % names.len()])
                    }
                })
                .collect();
            let state = RandomState::new();
            let hashes: Vec<u64> = keys.iter().map(|k| k.hash_by(&state)).collect();
            assert_eq!(pose_groups(&|i| keys[i], &hashes), by_one_map(&keys), "{n}");
        }
    }

    /// Keys whose hashes all fall in one shard (the worst split) are still told apart.
    #[test]
    fn one_crowded_shard_still_tells_keys_apart() {
        let names: Vec<CompactString> = (0..SHARDED_MIN + 10)
            .map(|k| format!("p{}", k % 1000).into())
            .collect();
        let keys: Vec<PoseKey<'_>> = names.iter().map(PoseKey::Named).collect();
        let state = RandomState::new();
        // The shard field cleared in every hash.
        let hashes: Vec<u64> = keys
            .iter()
            .map(|k| k.hash_by(&state) & !(0xffff << SHARD_SHIFT))
            .collect();
        let (groups, count) = pose_groups(&|i| keys[i], &hashes);
        assert_eq!(count, 1000);
        assert_eq!((groups, count), by_one_map(&keys));
    }
}
